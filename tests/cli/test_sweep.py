"""Tests of ``wormgear sweep`` (the command: options, outputs, limits, messages)."""

from __future__ import annotations

import csv
import io
import json
import math
import sys
import warnings

import numpy as np
import pytest

from tests.support.paths import CONFIGS, MCH50
from wormgear_cli.cli import app
from wormgear_cli.errors import UsageError
from wormgear_cli.spec.loader import FIELD_BY_PATH


def run(runner, *args):
    return runner.invoke(app, ["sweep", *map(str, args)])


def parse_csv(text):
    rows = list(csv.reader(io.StringIO(text)))
    return rows[0], [[float(v) for v in r] for r in rows[1:]]


def test_csv_columns_and_values_match_json(runner, mch50_path):
    args = (mch50_path, "--i", "2:10:5", "--l-mm", "100:300:4", "--unit", "deg")
    r_csv = run(runner, *args, "--format", "csv")
    r_json = run(runner, *args, "--format", "json")
    assert r_csv.exit_code == 0 and r_json.exit_code == 0
    assert r_csv.stderr == "" and r_json.stderr == ""
    header, rows = parse_csv(r_csv.stdout)
    assert header[:5] == ["i", "l_mm", "gear_transmission_error", "total_transmission_error", "total_backlash"]
    doc = json.loads(r_json.stdout)
    assert doc["unit"] == "deg" and doc["columns"] == header and len(doc["points"]) == 20 == len(rows)
    for row, point in zip(rows, doc["points"]):
        for name, v in zip(header, row):
            assert v == pytest.approx(point[name], rel=1e-11)
    assert [p["i"] for p in doc["points"][:5]] == [2.0, 2.0, 2.0, 2.0, 4.0]  # row-major, i outermost
    assert {f["id"] for f in doc["summary"]["findings"]} == {"l_more_sensitive_than_i", "l_gain_fades_beyond_200mm",
                                                            "i_matters_below_6"}


def test_units_scale(runner, mch50_path):
    a = json.loads(run(runner, mch50_path, "--i", "8:8:1", "--l-mm", "202.5:202.5:1", "--format", "json",
                       "--unit", "deg").stdout)["points"][0]
    b = json.loads(run(runner, mch50_path, "--i", "8:8:1", "--l-mm", "202.5:202.5:1", "--format", "json",
                       "--unit", "arcsec").stdout)["points"][0]
    assert b["total_backlash"] == pytest.approx(3600 * a["total_backlash"], rel=1e-13)
    assert b["gear_te_phi_deg"] == a["gear_te_phi_deg"]


def test_table_is_deterministic_and_summarises(runner, mch50_path):
    args = (mch50_path, "--i", "2:10:30", "--l-mm", "100:300:40")
    r1, r2 = run(runner, *args), run(runner, *args)
    assert r1.exit_code == 0 and r1.stdout_bytes == r2.stdout_bytes and r1.stderr == ""
    out = r1.stdout
    caption = " ".join(out.split())
    assert ("showing i = 2, 2.55172, ..., 10 (16 of 30: every 2nd and the last) and l = 100, 120.513, ..., 300 "
            "(11 of 40: every 4th and the last); all points: --format csv") in caption
    assert out.count("holds") == 3
    assert "gear TE falls 50.2 % from l = 100 to 200 mm and" in out and "33.4 % from 200 to 300 mm" in out


@pytest.mark.parametrize("args, message", [
    (("--i", "2:10:0"), '--i "2:10:0": N must be at least 1, got 0'),
    (("--i", "2:10:-3"), '--i "2:10:-3": N must be at least 1, got -3'),
    (("--i", "2:10:2.5"), '--i "2:10:2.5": N "2.5" is not a whole number'),
    (("--l-mm", "300:100:5"), '--l-mm "300:100:5": STOP (100) is less than START (300)'),
    (("--i", "two:10:5"), '--i "two:10:5": START "two" is not a number'),
    (("--l-mm", "100:x:5"), '--l-mm "100:x:5": STOP "x" is not a number'),
    (("--i", "0:10:5"), '--i "0:10:5": values must be > 0 (START is 0)'),
    (("--l-mm", "-50:100:3"), '--l-mm "-50:100:3": values must be > 0 (START is -50)'),
    (("--i", "2:10:1"), '--i "2:10:1": N = 1 needs START = STOP (got 2 and 10)'),
    (("--i", "1e-300:1e-300:1"), '--i "1e-300:1e-300:1": values must be from 0.01 to 1000 (got 1e-300)'),
    (("--i", "0.005:2:3"), '--i "0.005:2:3": values must be from 0.01 to 1000 (got 0.005)'),
    (("--i", "8:1001:3"), '--i "8:1001:3": values must be from 0.01 to 1000 (got 1001)'),
    (("--i", "8:8:1", "--l-mm", "1e-300:1e-300:1", "-f", "csv"),
     '--l-mm "1e-300:1e-300:1": values must be from 0.1 to 100000 [mm] (got 1e-300)'),
    (("--l-mm", "100:1e6:3"), '--l-mm "100:1e6:3": values must be from 0.1 to 100000 [mm] (got 1e+06)'),
    (("--i", "2:10"), '--i "2:10": expected START:STOP:N (N values from START to STOP inclusive), e.g. 2:10:9'),
    (("--i", "inf:10:3"), '--i "inf:10:3": START "inf" is not a finite number'),
    ((), "nothing to sweep: give --i START:STOP:N and/or --l-mm START:STOP:N, or --param KEY=START:STOP:N"),
    (("--i", "2:4:3", "--shard", "3/2"), '--shard "3/2": expected K/N with 1 <= K <= N, e.g. 2/8, or auto in a job array'),
    (("--i", "2:4:3", "--shard", "x"), '--shard "x": expected K/N with whole numbers, e.g. 2/8, or auto in a job array'),
    (("--i", "2:4:3", "--module-mm", "-1"), "--module-mm -1: expected a module from 0.05 to 100 [mm]"),
    (("--i", "2:4:3", "--min-pinion-teeth", "12"), "--min-pinion-teeth applies only with --module-mm"),
    (("--i", "2:4:3", "--l-mm", "10:20:3", "--module-mm", "2.5"),
     "no design left: at --module-mm 2.5 every point of the grid has a gear with fewer than 17 teeth; raise l, "
     "or lower --min-pinion-teeth"),
    (("--param", "worm_pair.lead_eror_mm=0:0.05:3"),
     "--param worm_pair.lead_eror_mm: unknown spec key (did you mean worm_pair.lead_error_mm?)"),
    (("--param", "stiffness.model=0:1:2"),
     '--param stiffness.model: not a numeric key (it takes one of "iso6336", "empirical"); only single numbers '
     "can be swept"),
    (("--param", "gear_pair.pressure_angle_deg=10:45:3"),
     "--param gear_pair.pressure_angle_deg: value 45 is out of range, expected "
     + FIELD_BY_PATH["gear_pair.pressure_angle_deg"].expected()),
    (("--param", "gear_pair.pinion.teeth=16:17:3"),
     '--param gear_pair.pinion.teeth "16:17:3": the key takes whole numbers, but the range gives 16.5; choose N '
     "so that (STOP - START)/(N - 1) is whole"),
    (("--param", "worm_pair.lead_error_mm=0:0.05:3", "--param", "worm_pair.lead_error_mm=0:0.01:2"),
     "--param worm_pair.lead_error_mm: given twice; give each key once"),
    (("--param", "worm_pair.lead_error_mm=0:0.05:3", "--i", "2:3:2"),
     "--param cannot be combined with --i, --l-mm, --stage, --module-mm, --hold or --min-pinion-teeth; run two sweeps (--param names its stage in the key: stage.N.KEY)"),
])
def test_bad_input_exits_2_with_one_message(runner, mch50_path, args, message):
    r = run(runner, mch50_path, *args, "--format", "csv")
    assert r.exit_code == 2
    assert r.stderr == f"error: {message}\n"
    assert r.stdout == ""


def test_missing_drive_file(runner, tmp_path):
    r = run(runner, tmp_path / "nope.toml", "--i", "2:3:2")
    assert r.exit_code == 2 and r.stderr == f"error: {tmp_path / 'nope.toml'}: file not found\n"


@pytest.mark.parametrize("extra", [(), ("--module-mm", "2.5"), ("--hold", "torque")])
def test_shards_concatenate_to_the_full_csv(runner, mch50_path, extra):
    args = (mch50_path, "--i", "2:10:7", "--l-mm", "60:300:13", "--format", "csv", *extra)
    full = run(runner, *args)
    assert full.exit_code == 0
    parts = [run(runner, *args, "--shard", f"{k}/5") for k in range(1, 6)]
    assert all(p.exit_code == 0 for p in parts)
    header = parts[0].stdout_bytes.split(b"\n", 1)[0] + b"\n"
    assert all(p.stdout_bytes.startswith(header) for p in parts)
    joined = header + b"".join(p.stdout_bytes[len(header):] for p in parts)
    assert joined == full.stdout_bytes
    assert len(full.stdout.splitlines()) > 2


def test_param_shards_concatenate(runner, mch50_path):
    args = (mch50_path, "--param", "worm_pair.lead_error_mm=0:0.05:3", "--param", "gear_pair.pinion.teeth=16:20:3",
            "--format", "csv")
    full = run(runner, *args).stdout_bytes
    parts = [run(runner, *args, "--shard", f"{k}/4").stdout_bytes for k in range(1, 5)]
    header = full.split(b"\n", 1)[0] + b"\n"
    assert header + b"".join(p[len(header):] for p in parts) == full


def test_json_shard_carries_its_points_only(runner, mch50_path):
    doc = json.loads(run(runner, mch50_path, "--i", "2:10:3", "--l-mm", "100:300:3", "--format", "json",
                         "--shard", "2/2").stdout)
    assert doc["shard"] == {"k": 2, "n": 2, "first_point": 4, "stop_point": 9, "total_points": 9}
    assert len(doc["points"]) == 5 and "summary" not in doc
    assert run(runner, mch50_path, "--i", "2:10:3", "--shard", "1/2").exit_code == 2  # table needs the grid


def test_module_mode_reports_whole_teeth(runner, mch50_path):
    r = run(runner, mch50_path, "--i", "2:10:9", "--l-mm", "40:300:14", "--module-mm", "2.5", "--format", "json")
    doc = json.loads(r.stdout)
    assert doc["columns"][-4:] == ["z1", "z2", "i_used", "l_used_mm"] and doc["min_pinion_teeth"] == 17
    pts = doc["points"]
    assert len(pts) + doc["skipped"] == 9 * 14 and doc["skipped"] > 0
    for p in pts:
        assert isinstance(p["z1"], int) and isinstance(p["z2"], int)
        assert min(p["z1"], p["z2"]) >= 17
        assert p["i_used"] == pytest.approx(p["z1"] / p["z2"], rel=1e-15)
        assert p["l_used_mm"] == pytest.approx(2.5 * (p["z1"] + p["z2"]) / 2, rel=1e-15)
        assert abs(p["l_used_mm"] - p["l_mm"]) <= 2.5 / 4 + 1e-9  # nearest reachable centre distance
    low = json.loads(run(runner, mch50_path, "--i", "2:10:9", "--l-mm", "40:300:14", "--module-mm", "2.5",
                         "--min-pinion-teeth", "12", "--format", "json").stdout)
    assert len(low["points"]) > len(pts)


def test_param_sweep_reproduces_analyze(runner, mch50_path, mch50_spec):
    from wormgear_cli.analysis.accuracy import INFO_COLUMNS, METRIC_COLUMNS, analyze
    from wormgear_cli.analysis.figures import FIGURE_COLUMNS, figures
    from wormgear_cli.spec.loader import with_values
    from wormgear_cli.units import to_unit

    r = run(runner, mch50_path, "--param", "worm_pair.lead_error_mm=0:0.05:3",
            "--param", "gear_pair.pinion.teeth=16:20:3", "--format", "csv", "--unit", "arcsec")
    assert r.exit_code == 0 and r.stderr == ""
    header, rows = parse_csv(r.stdout)
    keys = ["worm_pair.lead_error_mm", "gear_pair.pinion.teeth"]
    assert header == keys + list(METRIC_COLUMNS) + list(INFO_COLUMNS) + list(FIGURE_COLUMNS)
    assert [(row[0], row[1]) for row in rows] == [(e, z) for e in (0.0, 0.025, 0.05) for z in (16, 18, 20)]
    for row in rows:
        spec = with_values(mch50_spec, {keys[0]: row[0], keys[1]: int(row[1])})
        result = analyze(spec)
        expected = {**result.metrics("arcsec"),
                    **{k: float(to_unit(v, "arcsec")) for k, v in figures(spec, result).items()}}
        assert row[2:] == [expected[c] for c in header[2:]]  # exact: same floats, repr round-trip


def test_a_grade_sweep_shows_its_effect_on_the_budget_and_the_acceptance_test(runner, tmp_path):
    """Issue 19, item 8: the paper's total has no pitch deviations, so a grade sweep leaves it alone; the
    budget's totals and the ISO 230-2 figures carry the grade (each row against analyze's JSON and check's
    predicted figure, computed by their own commands)."""

    drive = CONFIGS / "rotary-table-precision.toml"
    r = run(runner, str(drive), "--param", "gear_pair.output_gear.accuracy_grade=3:7:5", "--format", "json")
    pts = json.loads(r.stdout)["points"]
    te = [p["total_transmission_error"] for p in pts]
    assert max(te) == min(te)  # the paper's model: no pitch deviations
    stat = [p["budget_amplitude_statistical"] for p in pts]
    iso_m = [p["iso230_M"] for p in pts]
    assert all(b > a for a, b in zip(stat, stat[1:])) and iso_m[-1] > iso_m[0]
    for p in (pts[0], pts[-1]):
        path = tmp_path / f"g{p['gear_pair.output_gear.accuracy_grade']}.toml"
        text = drive.read_text(encoding="utf-8").replace("\n[requirements]\n",
                                                         "\n[requirements]\nmax_iso230_M_arcsec = 1.0\n", 1)
        grade = p["gear_pair.output_gear.accuracy_grade"]
        path.write_text(text.replace("accuracy_grade = 4", f"accuracy_grade = {grade}", 1), encoding="utf-8")
        doc = json.loads(runner.invoke(app, ["analyze", str(path), "-f", "json"]).stdout)["total_with_budget"]
        assert p["budget_amplitude_statistical"] == pytest.approx(doc["transmission_error_amplitude_statistical"],
                                                                  rel=1e-12)
        assert p["budget_range_peak"] == pytest.approx(doc["transmission_error_range_peak"], rel=1e-12)
        rows = json.loads(runner.invoke(app, ["check", str(path), "-f", "json"]).stdout)["files"][0]["requirements"]
        row = next(q for q in rows if q["key"] == "requirements.max_iso230_M_arcsec")
        assert p["iso230_M"] == pytest.approx(row["value_arcsec"], rel=1e-12)
    summary = run(runner, str(drive), "--param", "gear_pair.output_gear.accuracy_grade=3:7:5").stdout
    assert "lowest total TE  │ 9.29 arcsec at every point" in summary
    assert "lowest budget TE │ " in summary and "accuracy_grade = 3 " in summary


def test_param_json(runner, mch50_path):
    doc = json.loads(run(runner, mch50_path, "--param", "loads.gear_normal_force_N=0:2000:5", "--format",
                         "json").stdout)
    te = [p["gear_transmission_error"] for p in doc["points"]]
    assert len(te) == 5 and all(b > a for a, b in zip(te, te[1:]))  # more load, more TE
    assert doc["summary"]["best"]["total_transmission_error"]["loads.gear_normal_force_N"] == 0.0


def test_output_file_and_input_protection(runner, mch50_path, tmp_path):
    out = tmp_path / "grid.csv"
    r = run(runner, mch50_path, "--i", "2:10:3", "--l-mm", "100:300:3", "--format", "csv", "-o", out)
    assert r.exit_code == 0 and r.stdout == "" and out.read_text().startswith("i,l_mm,")
    r = run(runner, mch50_path, "--i", "2:10:3", "--format", "csv", "-o", mch50_path)
    assert r.exit_code == 2 and "refusing to overwrite the input file" in r.stderr


def test_plot_writes_png(runner, mch50_path, tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "surface.png"
    r = run(runner, mch50_path, "--i", "2:10:9", "--l-mm", "100:300:11", "--plot", png, "--format", "csv")
    assert r.exit_code == 0, r.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    one = tmp_path / "param.png"
    r = run(runner, mch50_path, "--param", "worm_pair.lead_error_mm=0:0.05:4", "--plot", one)
    assert r.exit_code == 0 and one.read_bytes()[:4] == b"\x89PNG"


def test_plot_without_matplotlib_gives_the_install_hint(runner, mch50_path, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # makes `import matplotlib` raise ImportError
    r = run(runner, mch50_path, "--i", "2:10:3", "--plot", tmp_path / "x.png")
    assert r.exit_code == 2
    assert r.stderr == "error: plotting needs matplotlib: pip install matplotlib\n"
    assert not (tmp_path / "x.png").exists()


def _drive_with(tmp_path, name, **keys):
    """The MCH50 drive file with top-level-in-section keys replaced (like sed on the file)."""
    import re

    from tests.support.paths import MCH50

    text = MCH50.read_text()
    for key, value in keys.items():
        text, n = re.subn(rf"(?m)^{key} = .*$", f"{key} = {value}", text)
        assert n == 1, key
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.fixture
def zero_te_drive(tmp_path):
    """No gear eccentricity and no gear tooth load: the paper's Delta phi_cc is 0 for every phi."""
    return _drive_with(tmp_path, "zero.toml", gear_centre_distance_error_mm=0, gear_normal_force_N=0)


@pytest.mark.parametrize("grid", [("--i", "2:10:3", "--l-mm", "100:300:3"), ("--l-mm", "100:300:3")])
def test_findings_are_na_when_gear_te_is_zero(runner, zero_te_drive, grid):
    doc_run = run(runner, zero_te_drive, *grid, "--format", "json")
    assert doc_run.exit_code == 0, doc_run.stderr
    assert doc_run.stderr == ""
    doc = json.loads(doc_run.stdout)
    # the model: with Delta e = 0 and delta1 = 0 the gear TE vanishes at every point
    assert all(p["gear_transmission_error"] == 0.0 for p in doc["points"])
    found = {f["id"]: f for f in doc["summary"]["findings"]}
    assert found["l_more_sensitive_than_i"]["holds"] is None
    assert found["l_gain_fades_beyond_200mm"]["holds"] is None
    reason = ("not testable on this grid: gear TE is 0 everywhere (the spec has no gear eccentricity and no gear "
              "tooth load), so its relative changes are undefined")
    assert found["l_more_sensitive_than_i"]["statement"] == reason
    assert found["l_gain_fades_beyond_200mm"]["statement"] == reason
    table = run(runner, zero_te_drive, *grid)
    assert table.exit_code == 0 and table.stderr == ""
    assert "holds" not in table.stdout and table.stdout.count("n/a") == 3


def test_findings_stay_testable_without_eccentricity_but_with_load(tmp_path, runner):
    """Delta e = 0 alone leaves the load term delta1 sin(alpha)/R2 > 0: the checks still run."""
    path = _drive_with(tmp_path, "noecc.toml", gear_centre_distance_error_mm=0)
    doc = json.loads(run(runner, path, "--i", "2:10:3", "--l-mm", "100:300:3", "--format", "json").stdout)
    assert all(p["gear_transmission_error"] > 0 for p in doc["points"])
    assert all(f["holds"] is not None for f in doc["summary"]["findings"])


@pytest.mark.parametrize("args, message", [
    (("--i", "2:10:1e20"), '--i "2:10:1e20": N = 1e20 is more than the limit of 10000000 values per axis'),
    (("--l-mm", "100:300:10000001"),
     '--l-mm "100:300:10000001": N = 10000001 is more than the limit of 10000000 values per axis'),
    (("--param", "worm_pair.lead_error_mm=0:1:1e20"),
     '--param worm_pair.lead_error_mm "0:1:1e20": N = 1e20 is more than the limit of 100000 values in a --param '
     "sweep"),
    (("--i", "2:10:1e9", "--l-mm", "100:300:1e9"),
     '--i "2:10:1e9": N = 1e9 is more than the limit of 10000000 values per axis'),
])
@pytest.mark.parametrize("fmt", ["table", "json", "csv"])
def test_huge_n_exits_2_naming_the_option(runner, mch50_path, args, message, fmt):
    r = run(runner, mch50_path, *args, "--format", fmt)
    assert (r.exit_code, r.stderr, r.stdout) == (2, f"error: {message}\n", "")


@pytest.mark.parametrize("args, message", [
    (("--i", "2:10:1e7", "--format", "table"),
     "--i x --l-mm: 10000000 x 1 = 10000000 points are more than the limit of 2000000 for --format table (it "
     "holds the whole grid); use --format csv or fewer values"),
    (("--i", "2:10:1000", "--l-mm", "100:300:101", "--format", "json"),
     "--i x --l-mm: 1000 x 101 = 101000 points are more than the limit of 100000 for --format json (it holds "
     "every point as an object); use --format csv, fewer values or --shard K/N"),
    (("--i", "2:10:1e7", "--l-mm", "100:300:1e7", "--format", "csv", "-o", "OUT"),
     "--i x --l-mm: 10000000 x 10000000 = 100000000000000 points are more than the limit of 1000000000 for "
     "--format csv (about 2.5 us per point); split it with --shard K/N"),
    (("--i", "2:10:1e7", "--l-mm", "100:300:1e7", "--format", "csv"),
     "--i x --l-mm: 10000000 x 10000000 = 100000000000000 points are more than the limit of 1000000000 for "
     "--format csv (about 2.5 us per point); split it with --shard K/N"),
    (("--i", "2:10:1e7", "--l-mm", "100:300:1e7", "--format", "csv", "--shard", "2/1000"),
     "--i x --l-mm: 10000000 x 10000000 = 100000000000000 points (100000000000 in this shard) are more than the "
     "limit of 1000000000 for --format csv (about 2.5 us per point); split it with --shard K/N"),
    (("--i", "2:10:2000", "--l-mm", "100:300:1001", "--format", "csv", "--plot", "PLOT"),
     "--i x --l-mm: 2000 x 1001 = 2002000 points are more than the limit of 2000000 for --plot (it holds the "
     "whole grid); plot a coarser grid"),
])
def test_point_limits_are_checked_before_building_anything(runner, mch50_path, tmp_path, monkeypatch, args,
                                                            message):
    from wormgear_cli.analysis import sweep as core

    def no_arrays(self):
        raise AssertionError("an axis was built before the size check")

    monkeypatch.setattr(core.RangeSpec, "values", no_arrays)
    args = [str(tmp_path / "out.csv") if a == "OUT" else str(tmp_path / "p.png") if a == "PLOT" else a
            for a in args]
    r = run(runner, mch50_path, *args)
    assert (r.exit_code, r.stderr, r.stdout) == (2, f"error: {message}\n", "")
    assert list(tmp_path.iterdir()) == []


def test_a_shard_of_a_huge_grid_runs(runner, mch50_path):
    """Per-axis limits allow big grids to be sharded; this shard has 100 points."""
    r = run(runner, mch50_path, "--i", "2:10:2e6", "--l-mm", "100:300:2e6", "--format", "csv",
            "--shard", "3/40000000000")
    assert r.exit_code == 0, r.stderr
    header, rows = parse_csv(r.stdout)
    assert len(rows) == 100
    step_l = 200 / (2e6 - 1)
    # points 200..299 of the row-major list: i index 0, l indices 200..299
    expected_l = [100 + k * step_l for k in range(200, 300)]
    assert [row[1] for row in rows] == pytest.approx(expected_l, rel=1e-11)  # CSV has 12 digits
    assert all(row[0] == 2.0 for row in rows)


def test_param_grid_size_is_limited(runner, mch50_path):
    r = run(runner, mch50_path, "--param", "worm_pair.lead_error_mm=0:1:1000", "--param",
            "gear_pair.pinion.teeth=10:1009:1000", "--format", "csv")
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr == ("error: --param: 1000 x 1000 = 1000000 points are more than the limit of 100000 points of "
                        "a --param sweep (each point is a full analyze, about 1.3 ms); use fewer values\n")
    r = run(runner, mch50_path, "--param", "worm_pair.lead_error_mm=0:1:50001", "--format", "json")
    assert r.exit_code == 2 and r.stderr == ("error: --param: 50001 = 50001 points are more than the limit of 50000 "
                                             "for --format json (it holds every point as an object); use --format "
                                             "csv or --shard K/N\n")
    r = run(runner, mch50_path, "--param", "worm_pair.lead_error_mm=0:1:100001", "--format", "csv")
    assert r.exit_code == 2 and r.stderr == ('error: --param worm_pair.lead_error_mm "0:1:100001": N = 100001 is '
                                             "more than the limit of 100000 values in a --param sweep\n")


def test_param_csv_streams_rows_to_stdout(runner, mch50_path, tmp_path, monkeypatch):
    args = (mch50_path, "--param", "worm_pair.lead_error_mm=0:0.05:6", "--format", "csv")
    out = tmp_path / "p.csv"
    assert run(runner, *args, "-o", out).exit_code == 0
    streamed = run(runner, *args)
    assert streamed.exit_code == 0 and streamed.stdout == out.read_text()  # same bytes either way
    # streamed: rows computed before a failure are already out (nothing is held back)
    from wormgear_cli.analysis import sweep as core
    from wormgear_cli.errors import UsageError

    real = core.param_rows

    def failing(*a, **k):
        for n, item in enumerate(real(*a, **k)):
            if n == 150:
                raise UsageError("stop")
            yield item

    monkeypatch.setattr(core, "param_rows", failing)
    r = run(runner, mch50_path, "--param", "worm_pair.lead_error_mm=0:0.05:200", "--format", "csv")
    assert r.exit_code == 2 and r.stderr == "error: stop\n"
    header, rows = parse_csv(r.stdout)
    assert header[0] == "worm_pair.lead_error_mm" and len(rows) == 100
    assert [row[0] for row in rows] == pytest.approx(list(np.linspace(0, 0.05, 200)[:100]), rel=1e-15)


@pytest.mark.parametrize("module, message", [
    ("1e-300", "--module-mm 1e-300: expected a module from 0.05 to 100 [mm]"),
    ("0.04", "--module-mm 0.04: expected a module from 0.05 to 100 [mm]"),
    ("101", "--module-mm 101: expected a module from 0.05 to 100 [mm]"),
    ("nan", "--module-mm nan: expected a module from 0.05 to 100 [mm]"),
])
def test_module_outside_the_physical_range_exits_2(runner, mch50_path, module, message):
    r = run(runner, mch50_path, "--i", "2:10:3", "--module-mm", module, "--format", "csv")
    assert (r.exit_code, r.stderr, r.stdout) == (2, f"error: {message}\n", "")


def test_module_tooth_counts_stay_whole_and_positive(runner, mch50_path):
    r = run(runner, mch50_path, "--i", "2:4:3", "--l-mm", "1:2:3", "--module-mm", "0.05", "--format", "json")
    assert r.exit_code == 0, r.stderr
    pts = json.loads(r.stdout)["points"]
    assert pts
    for p in pts:
        assert p["z1"] > 0 and p["z2"] > 0
        assert p["z1"] + p["z2"] == round(2 * p["l_mm"] / 0.05)  # the tooth sum for l at this module
    r = run(runner, mch50_path, "--i", "2:4:3", "--l-mm", "100:1e5:2", "--module-mm", "0.05", "--format", "csv")
    assert r.exit_code == 2 and r.stderr == (
        "error: --module-mm 0.05: l = 100000 mm needs 4e+06 teeth (z1 + z2 = 2 l / m); at most 1000000 are "
        "supported, use a larger module or a shorter --l-mm range\n")


@pytest.mark.parametrize("args, message", [
    (("--i", "2:2:1", "--l-mm", "200:200:1"),
     "--plot needs at least 2 values of i or of l (a single point has no curve to draw)"),
    (("--l-mm", "200:200:1"), "--plot needs at least 2 values of i or of l (a single point has no curve to draw)"),
    (("--param", "worm_pair.lead_error_mm=0.01:0.01:1"),
     "--plot needs at least 2 values of a --param key (a single point has no curve to draw)"),
    (("--param", "worm_pair.lead_error_mm=0:0.05:2", "--param", "gear_pair.pinion.teeth=16:20:3",
      "--param", "loads.gear_normal_force_N=0:1:2"), "--plot draws one or two --param keys, got 3"),
])
@pytest.mark.parametrize("fmt", ["csv", "json", "table"])
def test_infeasible_plot_fails_before_any_output(runner, mch50_path, tmp_path, monkeypatch, args, message, fmt):
    from wormgear_cli.analysis import sweep as core

    def no_work(*a, **k):
        raise AssertionError("the sweep ran before the plot check")

    monkeypatch.setattr(core, "RatioDistanceSweep", no_work)
    monkeypatch.setattr(core, "param_rows", no_work)
    png = tmp_path / "p.png"
    r = run(runner, mch50_path, *args, "--plot", png, "--format", fmt)
    assert (r.exit_code, r.stderr, r.stdout) == (2, f"error: {message}\n", "")
    assert not png.exists()


def test_effect_parameters_are_refused_with_a_reason(runner, mch50_path, mch50_spec):
    from wormgear_cli.analysis.accuracy import analyze
    from wormgear_cli.spec.loader import with_values

    # the reason: [effects.*] do not enter the analyze metrics, so every row would be the same
    with_effect = with_values(mch50_spec, {"effects.bearing_clearance.clearance_arcsec": 8.0})
    assert with_effect.effects  # the key is a valid spec key ...
    assert analyze(with_effect).metrics("arcsec") == analyze(mch50_spec).metrics("arcsec")  # ... without effect
    r = run(runner, mch50_path, "--param", "effects.bearing_clearance.clearance_arcsec=0:8:2", "--format", "csv")
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr == ("error: --param effects.bearing_clearance.clearance_arcsec: effect parameters cannot be "
                        "swept with --param (the [effects.*] tables feed simulate and diagnose, not the analyze "
                        "metrics of a sweep); vary it in the drive file and run wormgear simulate\n")



def _heat_columns(table: str) -> list[float]:
    """The l values heading the first heat map (all its parts), in order."""
    first = table[:table.index("total TE at the output")]
    heads = [ln for ln in first.splitlines() if ln.startswith("┃ i \\ l")]
    return [float(c) for h in heads for c in h.strip("┃ ").split("┃")[1:]]


def test_the_heat_map_shows_every_l_of_the_papers_grid(runner, mch50_path):
    """--l-mm 100:300:11 (the help's example) shows all eleven columns, l = 200 mm included."""
    r = run(runner, mch50_path, "--i", "2:10:9", "--l-mm", "100:300:11")
    assert r.exit_code == 0
    assert _heat_columns(r.stdout) == [100.0 + 20.0 * k for k in range(11)]
    assert "showing" not in r.stdout


@pytest.mark.parametrize("n", [13, 21, 30, 41, 101])
def test_a_subsampled_heat_map_keeps_even_steps_and_says_which(runner, mch50_path, n):
    import numpy as np

    r = run(runner, mch50_path, "--l-mm", f"100:300:{n}")
    assert r.exit_code == 0
    shown = _heat_columns(r.stdout)
    grid = np.linspace(100, 300, n)
    assert shown[0] == 100 and shown[-1] == 300 and len(shown) <= 12
    steps = np.diff(shown)
    assert np.allclose(steps[:-1], steps[0], atol=0.01)  # even, but for a shorter last step to the end
    assert all(np.isclose(grid, v, atol=0.01).any() for v in shown)
    caption = " ".join(r.stdout.split())
    k = round(steps[0] / (200 / (n - 1)))
    ordinal = {2: "2nd", 3: "3rd"}.get(k, f"{k}th")
    assert f"({len(shown)} of {n}: every {ordinal}" in caption
    assert "all points: --format csv" in caption


@pytest.mark.parametrize("fmt", ["csv", "json"])
def test_designs_skipped_by_the_module_are_said_on_stderr(runner, mch50_path, fmt):
    """(i, l) = (8, 150) at m = 2.5: the pinion would have 150 / 9 / 1.25 = 13.3 -> 13 teeth < 17."""
    r = run(runner, mch50_path, "--i", "4:8:2", "--l-mm", "150:250:2", "--module-mm", "2.5", "-f", fmt)
    assert r.exit_code == 0, r.stderr
    assert r.stderr == ("note: 1 design skipped: at m = 2.5 mm the smaller gear would have fewer than 17 teeth "
                        "(--min-pinion-teeth)\n")
    r = run(runner, mch50_path, "--i", "4:8:2", "--l-mm", "150:250:2", "-f", fmt)
    assert r.exit_code == 0 and r.stderr == ""
def test_the_core_names_stage_and_the_command_line_says_dash_dash_stage(runner):
    """The core's message names the API's parameter (``stage``); the command shows its own flag there."""
    drive = "configs/radar-pedestal-2start.toml"
    r = run(runner, drive, "--i", "2:4:3", "--l-mm", "100:200:3", "--stage", "2", "--format", "csv")
    assert r.exit_code == 2
    assert r.stderr.startswith(f"error: --stage 2: stage 2 of {drive} is a worm stage")


# --- --figures: the sign-off figures of each whole-tooth design ----------------------------------


def _analyze_csv(runner, path):
    r = runner.invoke(app, ["analyze", str(path), "--format", "csv", "--unit", "arcsec"])
    assert r.exit_code in (0, 1), r.stderr
    rows = list(csv.reader(io.StringIO(r.stdout)))
    return dict(zip(rows[0], rows[1]))


FIGURES = ("budget_amplitude_linear", "budget_amplitude_statistical", "budget_amplitude_peak", "budget_range_peak",
           "iso230_A", "iso230_E", "iso230_B", "iso230_M")


@pytest.mark.parametrize(("config", "swept", "teeth", "hold", "edits"), [
    # the legacy precision table states its forces: held as they are (force)
    ("rotary-table-precision.toml", ("--i", "5:5:1", "--l-mm", "150:150:1", "--module-mm", "2"), (125, 25), "force",
     (("teeth = 180 ", "teeth = 125 "), ("teeth = 20 ", "teeth = 25 "))),
    # the HEQ5 derives its loads from the output torque: the torque held (its motor gears at m = 1)
    ("heq5-spur-worm.toml", ("--i", "6:6:1", "--l-mm", "35:35:1", "--module-mm", "1", "--min-pinion-teeth", "9"), (60, 10), "torque",
     (("teeth = 9 ", "teeth = 10 "), ("teeth = 47 ", "teeth = 60 "))),
    # the radar's bull gear after a worm and a spur gearmotor: their loads follow the torque too
    ("radar-pedestal-2start.toml", ("--i", "6:6:1", "--l-mm", "500:500:1", "--module-mm", "4"), (214, 36), "torque",
     (("teeth = 25 ", "teeth = 36 "), ("teeth = 200 ", "teeth = 214 "))),
])
def test_figures_are_what_analyze_prints_for_the_design_written_as_a_file(runner, tmp_path, config, swept, teeth,
                                                                          hold, edits):
    """Independent path: the design written as a drive file (its tooth counts edited in the text) and
    run through ``wormgear analyze --format csv``.  Its totals equal the sweep row's own (the sweep's
    vectorised model) and its sign-off figures the row's --figures columns, to the printed digits."""
    text = (CONFIGS / config).read_text()
    for old, new in edits:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    design = tmp_path / config
    design.write_text(text)
    want = _analyze_csv(runner, design)
    r = run(runner, CONFIGS / config, *swept, "--hold", hold, "--figures", "--format", "csv")
    assert r.exit_code == 0, r.stderr
    rows = list(csv.DictReader(io.StringIO(r.stdout)))
    assert len(rows) == 1 and (int(rows[0]["z1"]), int(rows[0]["z2"])) == teeth
    for name in ("total_transmission_error", "total_backlash", *FIGURES):
        assert float(rows[0][name]) == pytest.approx(float(want[name]), rel=1e-11), name  # the CSV prints 12 digits


def test_figures_columns_follow_the_figures_of_analyze():
    from wormgear_cli.analysis import figures, sweep

    assert sweep.FIGURE_COLUMNS == tuple(figures.FIGURE_COLUMNS) == FIGURES
    assert set(FIGURES) <= sweep.ANGLE_COLUMNS


def test_figures_change_with_the_design_and_the_tables_show_e(runner):
    """A larger wheel at the same module lowers the statistical total and E (fewer arcseconds per
    micrometre); the table view adds their heat maps."""
    r = run(runner, CONFIGS / "rotary-table-precision.toml", "--i", "9:9:1", "--l-mm", "200:300:2", "--module-mm", "2",
            "--figures", "--format", "json")
    assert r.exit_code == 0, r.stderr
    small, large = json.loads(r.stdout)["points"]
    assert large["budget_amplitude_statistical"] < small["budget_amplitude_statistical"]
    assert large["iso230_E"] < small["iso230_E"]
    r = run(runner, CONFIGS / "rotary-table-precision.toml", "--i", "9:9:1", "--l-mm", "200:300:2", "--module-mm", "2",
            "--figures")
    assert r.exit_code == 0 and "ISO 230-2 E on the [test_plan] (range)" in " ".join(r.stdout.split())


@pytest.mark.parametrize(("args", "message"), [
    (("--i", "3:9:4", "--figures"), "--figures needs --module-mm: the budget and ISO 230-2 figures are those of "
                                    "whole-tooth designs (give the module to snap to, e.g. --module-mm 2)"),
    (("--param", "worm_pair.lead_error_mm=0:0.05:3", "--figures"),
     "--figures is for --i/--l-mm sweeps; a --param sweep carries the budget and ISO 230-2 figures already"),
    (("--i", "2:10:1000", "--l-mm", "100:300:101", "--module-mm", "1", "--figures", "--format", "csv"),
     "--i x --l-mm: 1000 x 101 = 101000 points are more than the limit of 100000 for --figures (each design is a "
     "full analysis with its budget and acceptance test, about 50 ms); use fewer values or --shard K/N"),
])
def test_figures_refused_where_they_cannot_be_made(runner, mch50_path, args, message):
    r = run(runner, mch50_path, *args)
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr == f"error: {message}\n"


def test_figures_skip_a_design_the_drive_file_does_not_hold_for_and_say_why(runner, tmp_path):
    """A graded gear of 1067 teeth is beyond ISO 1328-1's scope (at most 1000): that design has no
    figures, so it is left out with a note naming the first one (it had stopped the whole run); the
    other designs' rows are those of the same sweep without --figures."""
    drive = tmp_path / "graded.toml"
    assert runner.invoke(app, ["new", str(drive)]).exit_code == 0
    text = drive.read_text()
    assert text.count("# accuracy_grade = 6") == 2
    drive.write_text(text.replace("# accuracy_grade = 6", "accuracy_grade = 5"))
    args = (drive, "--i", "8:8:1", "--l-mm", "100:400:4", "--module-mm", "0.5", "-f", "csv")
    plain = list(csv.DictReader(io.StringIO(run(runner, *args).stdout)))
    r = run(runner, *args, "--figures")
    assert r.exit_code == 0
    rows = list(csv.DictReader(io.StringIO(r.stdout)))
    assert [(row["z1"], row["z2"]) for row in rows] == [("356", "44"), ("711", "89")]
    assert [{k: row[k] for k in plain[0]} for row in rows] == plain[:2]
    assert r.stderr == (f"note: 2 designs skipped by --figures: the drive file does not hold for them (narrow "
                        f"--i/--l-mm to the designs it does); the first, i = 8, l = 300 mm (1067/133 teeth): {drive}: "
                        "stage 2 (spur): gear.accuracy_grade: teeth 1067 outside ISO 1328-1:2013's scope [5, 1000] "
                        "(its formulas are not extrapolated); give the deviations explicitly instead\n")


@pytest.mark.parametrize("extra", [(), ("--hold", "torque"), ("--module-mm", "100"), ("--module-mm", "1", "--hold",
                                                                                           "torque")])
def test_the_axes_physical_ranges_give_finite_rows_and_no_numpy_warning(runner, mch50_path, extra):
    """The corners of --i 0.01..1000 and --l-mm 0.1 mm..100 m: every value finite, nothing on stderr but
    the skipped-designs note (1e-300 had given inf rows and numpy's RuntimeWarnings)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = run(runner, mch50_path, "--i", "0.01:1000:5", "--l-mm", "0.1:100000:5", "-f", "csv", *extra)
    assert r.exit_code == 0, r.output
    assert all(line.startswith("note: ") for line in r.stderr.splitlines())
    rows = list(csv.reader(io.StringIO(r.stdout)))
    assert len(rows) > 1 and all(math.isfinite(float(v)) for row in rows[1:] for v in row if v != "")


def test_api_sweep_checks_the_same_ranges():
    import wormgear_cli.api as wg

    with pytest.raises(UsageError) as e:
        wg.sweep(MCH50, i=8, l_mm="1e-300:1e-300:1")
    assert str(e.value) == '--l-mm "1e-300:1e-300:1": values must be from 0.1 to 100000 [mm] (got 1e-300)'
    with pytest.raises(UsageError) as e:
        wg.sweep(MCH50, i=[2.0, 4000.0])
    assert str(e.value) == "--i: values must be from 0.01 to 1000 (got 4000)"
