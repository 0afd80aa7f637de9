"""``wormgear measure``: ISO 230-2 figures (hand-worked), order amplitudes, aliasing, labels, output."""

from __future__ import annotations

import csv
import io
import json
import math
import sys

import numpy as np
import pytest

from tests.support.iso230_hand import HAND
from tests.support.paths import ROOT
from wormgear_cli.cli import app
from wormgear_cli.measurement.iso230 import iso230_figures

# reversal B_i = up - down: 2 - 0 = 2, 4 - 1 = 3, -1 - 3 = -4
#   B = max |B_i| = 4 (signed -4), mean reversal = (2 + 3 - 4) / 3 = 1/3
# R_i(up) = 4 s: 4, 0, 8 -> R(up) = 8; R_i(down): 8, 4, 12 -> R(down) = 12
# R_i = max(2 s_up + 2 s_down + |B_i|, R_i(up), R_i(down)):
#   max(2+4+2, 4, 8) = 8;  max(0+2+3, 0, 4) = 5;  max(4+6+4, 8, 12) = 14  -> R = 14
# E(up) = 4 - (-1) = 5; E(down) = 3 - 0 = 3; E = max(2,4,-1,0,1,3) - min(...) = 4 - (-1) = 5
# mean bidirectional (up + down)/2: 1, 2.5, 1 -> M = 1.5
# A(up): max(2+2, 4+0, -1+4) = 4, min(2-2, 4-0, -1-4) = -5 -> 9
# A(down): max(0+4, 1+2, 3+6) = 9, min(0-4, 1-2, 3-6) = -4 -> 13
# A = max(4, 9) - min(-5, -4) = 14
EXPECTED = {"A": 14.0, "A_forward": 9.0, "A_reverse": 13.0, "B": 4.0, "B_signed": -4.0, "B_mean": 1.0 / 3.0,
            "B_mean_abs": 1.0 / 3.0, "E": 5.0, "E_forward": 5.0, "E_reverse": 3.0, "M": 1.5, "R": 14.0,
            "R_forward": 8.0, "R_reverse": 12.0}
ARCSEC = math.pi / 648000.0


def hand_csv(tmp_path, name="hand.csv"):
    lines = ["# hand-worked ISO 230-2 example", "angle_deg,error_arcsec,direction,run"]
    for run in range(3):
        for d in (1, -1):
            for target in (0.0, 120.0, 240.0) if d > 0 else (240.0, 120.0, 0.0):
                lines.append(f"{target},{HAND[(target, d)][run]},{d},{run}")
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


def invoke(runner, *args):
    return runner.invoke(app, ["measure", *map(str, args)])


def test_iso230_core_on_the_hand_example():
    ang, err, dirs = [], [], []
    for (target, d), values in HAND.items():
        for v in values:
            ang.append(math.radians(target))
            err.append(v)
            dirs.append(d)
    f = iso230_figures(np.array(ang), np.array(err, dtype=float), np.array(dirs, dtype=float))
    assert f.A == pytest.approx(14) and f.A_up == pytest.approx(9) and f.A_down == pytest.approx(13)
    assert f.B == pytest.approx(4) and f.B_signed == pytest.approx(-4) and f.B_mean == pytest.approx(1 / 3)
    assert f.E == pytest.approx(5) and f.E_up == pytest.approx(5) and f.E_down == pytest.approx(3)
    assert f.M == pytest.approx(1.5)
    assert f.R == pytest.approx(14) and f.R_up == pytest.approx(8) and f.R_down == pytest.approx(12)
    t = f.targets
    assert list(t.n_up) == [3, 3, 3] and list(t.n_down) == [3, 3, 3]
    assert t.mean_up == pytest.approx([2, 4, -1]) and t.mean_down == pytest.approx([0, 1, 3])
    assert t.s_up == pytest.approx([1, 0, 2]) and t.s_down == pytest.approx([2, 1, 3])
    assert t.reversal == pytest.approx([2, 3, -4])
    assert t.r_bi == pytest.approx([8, 5, 14])
    assert f.notes == ()


def test_measure_json_on_the_hand_example(runner, tmp_path):
    result = invoke(runner, hand_csv(tmp_path), "--format", "json")
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["unit"] == "arcsec"
    assert doc["rows"] == 18 and doc["targets"] == 3
    assert doc["runs_per_target"] == {"forward": [3, 3], "reverse": [3, 3]}
    for key, value in EXPECTED.items():
        assert doc["iso230_2"][key] == pytest.approx(value), key
    rows = doc["per_target"]
    assert [r["target_deg"] for r in rows] == [0.0, 120.0, 240.0]
    assert [r["s_reverse"] for r in rows] == pytest.approx([2, 1, 3])
    assert [r["mean_bidirectional"] for r in rows] == pytest.approx([1, 2.5, 1])
    assert [r["R"] for r in rows] == pytest.approx([8, 5, 14])


def test_measure_unit_conversion(runner, tmp_path):
    doc = json.loads(invoke(runner, hand_csv(tmp_path), "-f", "json", "--unit", "arcmin").stdout)
    assert doc["unit"] == "arcmin"
    assert doc["iso230_2"]["B"] == pytest.approx(4 / 60)
    doc = json.loads(invoke(runner, hand_csv(tmp_path), "-f", "json", "--unit", "urad").stdout)
    assert doc["iso230_2"]["A"] == pytest.approx(14 * ARCSEC * 1e6)


def test_measure_csv_is_the_per_target_table(runner, tmp_path):
    result = invoke(runner, hand_csv(tmp_path), "--format", "csv")
    assert result.exit_code == 0
    rows = list(csv.DictReader(io.StringIO(result.stdout)))
    assert list(rows[0]) == ["target_deg", "n_forward", "n_reverse", "mean_forward_arcsec", "s_forward_arcsec",
                             "mean_reverse_arcsec", "s_reverse_arcsec", "mean_bidirectional_arcsec",
                             "reversal_arcsec", "R_forward_arcsec", "R_reverse_arcsec", "R_arcsec",
                             "below_resolution"]
    # at 120 deg the three forward readings are all 4 (HAND): s there is below one step (1 arcsec), not 0
    assert [r["below_resolution"] for r in rows] == ["", "forward", ""]
    assert [r["s_forward_arcsec"] for r in rows][1] == ""
    assert [float(r["reversal_arcsec"]) for r in rows] == pytest.approx([2, 3, -4])
    assert [int(r["n_forward"]) for r in rows] == [3, 3, 3]


def test_measure_table_shows_the_figures(runner, tmp_path):
    result = invoke(runner, hand_csv(tmp_path))
    assert result.exit_code == 0
    out = result.stdout
    assert "ISO 230-2 figures [arcsec]" in out
    line = next(ln for ln in out.splitlines() if "accuracy A" in ln)
    assert line.split()[-3:] == ["14.00", "9.00", "13.00"]
    line = next(ln for ln in out.splitlines() if "largest B_i, signed" in ln)
    assert "-4.00" in line


def test_output_is_deterministic_and_written_atomically(runner, tmp_path):
    data = hand_csv(tmp_path)
    first = invoke(runner, data, "-f", "json").stdout
    assert invoke(runner, data, "-f", "json").stdout == first
    out = tmp_path / "report.json"
    result = invoke(runner, data, "-f", "json", "-o", out)
    assert result.exit_code == 0 and result.stdout == ""
    assert out.read_text() == first
    result = invoke(runner, data, "-o", data)  # a .csv name: the CSV format, onto the input
    assert result.exit_code == 2
    # refused before any work: no report, no other message first
    assert result.stderr == f"error: {data}: refusing to overwrite the input file; choose another -o\n"


def test_target_grouping_tolerance_and_one_direction_only(runner, tmp_path):
    # 10 and 10.0000001 deg (1e-7 deg apart) are one target; no reverse rows at all (two forward runs;
    # without the run column the repeated visits could be reverse ones, and the figures are withheld:
    # test_repeated_targets_without_direction_or_run_withhold_the_one_direction_figures)
    path = tmp_path / "fwd.csv"
    path.write_text("angle_deg,error_arcsec,run\n10,1,1\n10.0000001,3,2\n50,2,1\n50,2,2\n")
    doc = json.loads(invoke(runner, path, "-f", "json").stdout)
    assert doc["targets"] == 2
    assert doc["per_target"][0]["n_forward"] == 2
    assert doc["per_target"][0]["s_forward"] == pytest.approx(math.sqrt(2))  # 1, 3 -> s = sqrt(2)
    iso = doc["iso230_2"]
    assert iso["B"] is None and iso["M"] is None and iso["A"] is None and iso["R"] is None
    # A(up) = max(2 + 2 sqrt 2, 2 + 0) - min(2 - 2 sqrt 2, 2 - 0) = 4 sqrt 2
    assert iso["A_forward"] == pytest.approx(4 * math.sqrt(2))
    assert iso["E_forward"] == pytest.approx(0.0)
    assert any("no reverse" in n for n in doc["notes"])
    assert not any("same target more than once" in w for w in doc["warnings"])  # runs say it: no mix-up


def test_single_run_leaves_s_r_and_a_undefined(runner, tmp_path):
    path = tmp_path / "single.csv"
    path.write_text("angle_deg,error_arcsec,direction\n0,1,1\n0,-2,-1\n90,3,1\n90,0,-1\n")
    doc = json.loads(invoke(runner, path, "-f", "json").stdout)
    iso = doc["iso230_2"]
    assert iso["A"] is None and iso["R"] is None
    assert doc["per_target"][0]["s_forward"] is None
    # E over means 1, -2, 3, 0 = 5; B_i = 3, 3 -> B = 3; M over (-0.5, 1.5) = 2
    assert iso["E"] == pytest.approx(5) and iso["B"] == pytest.approx(3) and iso["M"] == pytest.approx(2)
    assert any("single run" in n for n in doc["notes"])


# --- order amplitudes ----------------------------------------------------------------------------------------


def plan_csv(tmp_path, targets_deg, runs=2, name="plan.csv", noise=0.05, seed=0):
    """Rows from a drive written directly here: 5" sin(theta + 30 deg) + 1.2" sin(8 theta - 60 deg)
    common to both directions, 6" of lost motion (forward - reverse = -6")."""
    rng = np.random.default_rng(seed)
    lines = ["angle_deg,error_arcsec,direction,run"]
    for run in range(runs):
        for d in (1, -1):
            for a in targets_deg:
                th = math.radians(a)
                e = (5.0 * math.sin(th + math.radians(30)) + 1.2 * math.sin(8 * th - math.radians(60))
                     - 3.0 * d + rng.normal(0, noise))
                lines.append(f"{a!r},{e!r},{d},{run}")
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


def jittered_targets(n=24, seed=1):
    rng = np.random.default_rng(seed)
    return [float(a) for a in np.arange(n) * 360.0 / n + rng.uniform(-3.0, 3.0, n)]


def items_by_order(doc):
    return {it["order"]: it for it in doc["orders"]["items"]}


def test_orders_recovered_on_jittered_targets(runner, tmp_path):
    path = plan_csv(tmp_path, jittered_targets())
    doc = json.loads(invoke(runner, path, "-f", "json", "--orders", "1,8,240,300").stdout)
    items = items_by_order(doc)
    assert all(it["status"] == "fitted" and it["aliased_with"] == [] for it in items.values())
    assert items[1.0]["common"]["amplitude"] == pytest.approx(5.0, abs=0.1)
    assert items[1.0]["common"]["phase_deg"] == pytest.approx(30.0, abs=1.5)
    assert items[8.0]["common"]["amplitude"] == pytest.approx(1.2, abs=0.1)
    assert items[8.0]["common"]["phase_deg"] == pytest.approx(-60.0, abs=5)
    assert items[240.0]["common"]["amplitude"] == pytest.approx(0.0, abs=0.15)
    assert items[1.0]["differential"]["amplitude"] == pytest.approx(0.0, abs=0.1)
    # differential mode = half the reversal: forward - reverse = -6 -> -3
    assert doc["orders"]["differential_offset"] == pytest.approx(-3.0, abs=0.05)
    assert doc["iso230_2"]["B_mean"] == pytest.approx(-6.0, abs=0.1)


def test_aliasing_reported_for_24_even_targets(runner, tmp_path):
    path = plan_csv(tmp_path, [15.0 * j for j in range(24)])
    result = invoke(runner, path, "-f", "json", "--orders", "1,12,240,300")
    doc = json.loads(result.stdout)
    items = items_by_order(doc)
    # 240 = 10 x 24 samples per turn: constant on the targets; 300 = 12 x 24 + 12: looks like 12
    assert items[240.0]["status"] == "aliased" and items[240.0]["aliased_with"] == [0.0]
    assert items[300.0]["status"] == "aliased" and items[300.0]["aliased_with"] == [12.0]
    assert items[12.0]["status"] == "folded" and items[12.0]["aliased_with"] == [300.0]
    assert items[240.0]["common"]["amplitude"] is None
    assert items[1.0]["status"] == "fitted"
    assert items[1.0]["common"]["amplitude"] == pytest.approx(5.0, abs=0.1)
    notes = "\n".join(doc["notes"])
    assert "order 240 is aliased onto the offset by the target spacing" in notes
    assert "order 300 is aliased by the target spacing onto order 12" in notes
    # the table says so too
    table = invoke(runner, path, "--orders", "1,12,240,300").stdout
    assert "aliased ~ offset" in table and "aliased ~ 12" in table


def test_drive_labels_and_default_orders(runner, tmp_path, mch50_path, mch50_spec):
    path = plan_csv(tmp_path, jittered_targets(36, 2), runs=2)
    doc = json.loads(invoke(runner, path, "--drive", mch50_path, "-f", "json").stdout)
    assert doc["drive"] == mch50_spec.drive.name
    items = items_by_order(doc)
    # MCH50: i_c = 144 / 18 = 8, z1 = 144, n_w = 8 * 30 = 240; harmonics 1..3 of each
    assert sorted(items) == [1, 2, 3, 8, 16, 24, 144, 240, 288, 432, 480, 720]
    assert items[1.0]["label"] == "output gear (table)"
    assert items[8.0]["label"] == "intermediate shaft (pinion and wheel)"
    assert items[144.0]["label"] == "spur mesh"
    assert items[240.0]["label"] == "worm shaft and worm mesh"
    assert items[16.0]["label"] == "2nd harmonic of intermediate shaft (pinion and wheel)"
    assert items[8.0]["common"]["amplitude"] == pytest.approx(1.2, abs=0.15)
    # with --orders the labels follow the orders that match the drive
    doc = json.loads(invoke(runner, path, "--drive", mch50_path, "-f", "json", "--orders", "8,5").stdout)
    items = items_by_order(doc)
    assert items[8.0]["label"] == "intermediate shaft (pinion and wheel)"
    assert items[5.0]["label"] is None
    doc = json.loads(invoke(runner, path, "--drive", mch50_path, "-f", "json", "--harmonics", "1").stdout)
    assert sorted(items_by_order(doc)) == [1, 8, 144, 240]


def test_too_many_orders_for_the_targets_are_unresolved(runner, tmp_path):
    path = plan_csv(tmp_path, [0.0, 50.0, 130.0, 200.0, 290.0])  # 5 targets: offset + 2 orders
    doc = json.loads(invoke(runner, path, "-f", "json", "--orders", "1,8,3").stdout)
    assert [it["status"] for it in doc["orders"]["items"]] == ["fitted", "fitted", "unresolved"]
    assert "order 3 not fitted: too few distinct angles (5) for 7 coefficients" in "\n".join(doc["notes"])


def test_without_drive_default_orders(runner, tmp_path):
    doc = json.loads(invoke(runner, hand_csv(tmp_path), "-f", "json").stdout)
    assert [it["order"] for it in doc["orders"]["items"]] == [1.0, 2.0, 3.0, 4.0]
    assert all(it["label"] is None for it in doc["orders"]["items"])


@pytest.mark.parametrize("bad", ["1,x", "0", "-2", "1,,2", "nan"])
def test_bad_orders_exit_2(runner, tmp_path, bad):
    result = invoke(runner, hand_csv(tmp_path), "--orders", bad)
    assert result.exit_code == 2
    item = [t.strip() for t in bad.split(",")]
    first_bad = next(t for t in item if not (t.replace(".", "", 1).isdigit() and float(t) > 0))
    assert result.stderr == f"error: --orders: expected positive numbers separated by commas, got {first_bad!r}\n"


def test_bad_drive_exits_2(runner, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[drive\n")
    result = invoke(runner, hand_csv(tmp_path), "--drive", bad)
    assert result.exit_code == 2 and result.stderr.startswith("error: ")
    assert "Traceback" not in result.stderr


# --- plot ----------------------------------------------------------------------------------------------------


def test_plot_written(runner, tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "chart.png"
    result = invoke(runner, hand_csv(tmp_path), "-f", "json", "--plot", png)
    assert result.exit_code == 0, result.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert result.stderr.endswith(f"wrote {png}\n")  # every file written is announced, --plot too


def test_plot_bad_suffix_and_missing_matplotlib(runner, tmp_path, monkeypatch):
    result = invoke(runner, hand_csv(tmp_path), "--plot", tmp_path / "chart.bmp")
    assert result.exit_code == 2
    assert result.stderr == f"error: {tmp_path / 'chart.bmp'}: --plot expects a file ending in .png, .svg, .pdf\n"
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib now raises ImportError
    result = invoke(runner, hand_csv(tmp_path), "--plot", tmp_path / "chart.png")
    assert result.exit_code == 2
    assert result.stderr == "error: plotting needs matplotlib: pip install matplotlib\n"
    assert not (tmp_path / "chart.png").exists()


def test_help_has_an_example(runner):
    result = runner.invoke(app, ["measure", "--help"])
    assert result.exit_code == 0
    assert "Example: wormgear measure" in result.stdout


def test_absurd_orders_are_refused(runner):
    from tests.support.paths import CONFIGS

    r = runner.invoke(app, ["measure", str(CONFIGS / "mch50-warm.csv"), "--orders", "1,1e9"])
    assert r.exit_code == 2
    assert r.stderr == ("error: --orders: 1e9 is above 100000 cycles per revolution, finer than angle "
                        "readings resolve\n")


def test_repeated_targets_without_direction_or_run_withhold_the_one_direction_figures(runner, tmp_path):
    """Up/down visits flattened into one block with neither column: forward and reverse cannot be
    told apart, so s, R, A, E are withheld (not a forward repeatability from mixed visits), and the
    unread header cells are named for --map."""
    path = tmp_path / "flat.csv"
    # one up/down run over 3 targets, +5 arcsec reversal: 0, 10, 20 up, then 20, 10, 0 down
    path.write_text("Position,Deviation,Richtung\n0,5,1\n10,6,1\n20,5,1\n20,0,-1\n10,1,-1\n0,0,-1\n")
    result = invoke(runner, path, "--map", "angle_deg=Position", "--map", "error_arcsec=Deviation", "-f", "json")
    assert result.exit_code == 0
    doc = json.loads(result.stdout)
    assert doc["iso230_2"]["R"] is None and doc["iso230_2"]["A"] is None and doc["iso230_2"]["E"] is None
    assert "columns not read: Richtung" in result.stderr
    mapped = invoke(runner, path, "--map", "angle_deg=Position", "--map", "error_arcsec=Deviation",
                    "--map", "direction=Richtung", "-f", "json")
    assert json.loads(mapped.stdout)["iso230_2"]["B"] == pytest.approx(5.0)  # mean up - mean down at each target


# --- a named pipe (FIFO) is read once ---------------------------------------------------------------------------------


def _feed_fifo(fifo, data: bytes, done, broken: list) -> None:
    """Write ``data`` into ``fifo`` once (noting a reader that closes it unread); then, until ``done``, open
    and close it whenever a reader has it open, so a reader opening it a second time (the fault) gets an
    end of file instead of waiting forever for a writer that is gone."""
    import errno
    import os
    import time

    try:
        with open(fifo, "wb") as fh:
            fh.write(data)
    except BrokenPipeError:
        broken.append("the reader closed the pipe unread")
    while not done.is_set():
        try:
            fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
        except OSError as e:
            if e.errno != errno.ENXIO:
                raise
            time.sleep(0.05)
            continue
        os.close(fd)
        time.sleep(0.05)


@pytest.mark.parametrize("source", ["table", "guide log"])
def test_a_named_pipe_is_read_once_and_gives_what_the_file_gives(runner, tmp_path, monkeypatch, source):
    """``measure`` on a FIFO had read it twice (a line count for the memory check, then the parser) and
    hung; the result is now the regular file's, byte for byte (same name, other directory)."""
    import os
    import threading

    if source == "table":  # over 64 KiB: more than a pipe's buffer, so an unread close breaks the writer
        data = "angle_deg,error_arcsec,direction,run\n" + "".join(
            f"{a},{math.sin(math.radians(a)) + 0.1 * r},{d},{r}\n"
            for r in range(4) for d in (1, -1) for a in range(3600))
    else:
        data = (ROOT / "tests/data/telescope/cge-pro-180.guidelog.txt").read_text(encoding="utf-8")
    (tmp_path / "file").mkdir()
    (tmp_path / "pipe").mkdir()
    (tmp_path / "file" / "m.csv").write_text(data, encoding="utf-8")
    os.mkfifo(tmp_path / "pipe" / "m.csv")
    monkeypatch.chdir(tmp_path / "file")
    expected = runner.invoke(app, ["measure", "m.csv", "-f", "json"])
    assert expected.exit_code == 0, expected.stderr
    monkeypatch.chdir(tmp_path / "pipe")
    done, reopened = threading.Event(), []
    writer = threading.Thread(target=_feed_fifo, args=("m.csv", data.encode(), done, reopened), daemon=True)
    writer.start()
    try:
        result = runner.invoke(app, ["measure", "m.csv", "-f", "json"])
    finally:
        done.set()
        writer.join()
    assert reopened == []
    assert result.exit_code == 0, result.stderr
    assert result.stdout == expected.stdout
