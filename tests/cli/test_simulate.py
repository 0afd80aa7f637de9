"""Tests of ``wormgear simulate`` (the command: dense scan, --at rows, formats, options, messages)."""

from __future__ import annotations

import csv
import io
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.support.paths import MCH50
from wormgear_cli.analysis.accuracy import analyze
from wormgear_cli.analysis.simulate import compliance
from wormgear_cli.cli import app
from wormgear_cli.spec.loader import load_spec
from wormgear_cli.units import RAD_PER_UNIT

AS = RAD_PER_UNIT["arcsec"]
WORM_STAGE = ("worm_lead_error", "worm_eccentricity", "wheel_radial_composite", "wheel_eccentricity")


@pytest.fixture(scope="module")
def spec():
    return load_spec(MCH50)


def _dense(runner, *args):
    res = runner.invoke(app, ["simulate", str(MCH50), *args])
    assert res.exit_code == 0, res.stderr
    rows = list(csv.reader(io.StringIO(res.stdout)))
    return rows[0], np.array(rows[1:], dtype=float), res


def test_dense_csv_columns_and_rows(runner):
    header, data, _ = _dense(runner, "--points", "90", "--revs", "2")
    assert header == ["angle_deg", "forward_arcsec", "reverse_arcsec", "common_arcsec", "lost_motion_arcsec"]
    assert data.shape == (90, 5)
    np.testing.assert_allclose(data[:, 0], np.arange(90) * 8.0)
    np.testing.assert_allclose(data[:, 3], (data[:, 1] + data[:, 2]) / 2)
    np.testing.assert_allclose(data[:, 4], data[:, 2] - data[:, 1])


def test_unit_option_scales(runner):
    _, arcsec, _ = _dense(runner, "--points", "40")
    header, deg, _ = _dense(runner, "--points", "40", "--unit", "deg")
    assert header[1] == "forward_deg"
    np.testing.assert_allclose(deg[:, 1:], arcsec[:, 1:] / 3600.0, rtol=1e-9, atol=1e-15)


def test_same_input_same_bytes(runner):
    a = runner.invoke(app, ["simulate", str(MCH50), "--points", "300", "-f", "json"])
    b = runner.invoke(app, ["simulate", str(MCH50), "--points", "300", "-f", "json"])
    assert a.exit_code == 0 and a.stdout == b.stdout


def test_json_document(runner, spec):
    res = runner.invoke(app, ["simulate", str(MCH50), "--points", "3200", "-f", "json", "--phases",
                              "aligned-reversal"])
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["unit"] == "arcsec" and doc["points"] == 3200
    assert len(doc["curve"]["forward"]) == 3200
    total_bl = analyze(spec).angles["total_backlash"] / AS
    assert doc["analyze"]["total_backlash"] == pytest.approx(total_bl)
    assert doc["summary"]["lost_motion"]["max"] == pytest.approx(total_bl, rel=1e-9)
    assert set(doc["sources"]) >= set(WORM_STAGE) | {"gear_eccentricity"}
    assert doc["predicted"]["centre_distance_um_per_K"] < 0


def _write_data(path: Path, angles, directions, extra=None, comments=("# test rig 3", "# operator: X")):
    cols = ["angle_deg", "direction", "note"] + (list(extra) if extra else [])
    lines = list(comments) + [",".join(cols)]
    for k, (a, d) in enumerate(zip(angles, directions)):
        cells = [a, d, f'"row {k}, ok"'] + ([str(v[k]) for v in extra.values()] if extra else [])
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n")


def test_at_equals_dense_curve_and_keeps_rows(runner, tmp_path):
    _, dense, res = _dense(runner, "--points", "720")
    angles = [row.split(",")[0] for row in res.stdout.splitlines()[1:]]
    pick = list(range(0, 720, 7))
    dirs = ["1" if k % 2 else "-1" for k in range(len(pick))]
    data = tmp_path / "data.csv"
    _write_data(data, [angles[i] for i in pick], dirs)
    out = runner.invoke(app, ["simulate", str(MCH50), "--at", str(data)])
    assert out.exit_code == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[:2] == ["# test rig 3", "# operator: X"]
    rows = list(csv.reader(io.StringIO("\n".join(lines[2:]))))
    assert rows[0] == ["angle_deg", "direction", "note", "simulated_error_arcsec"]
    for k, (row, i) in enumerate(zip(rows[1:], pick)):
        assert row[:3] == [angles[i], dirs[k], f"row {k}, ok"]
        want = dense[i, 1] if dirs[k] == "1" else dense[i, 2]
        assert float(row[3]) == pytest.approx(want, rel=1e-9, abs=1e-9)
    assert len(rows) == len(pick) + 1


def test_at_uses_each_rows_load_and_temperature(runner, tmp_path):
    drive = tmp_path / "warm.toml"
    drive.write_text(MCH50.read_text() + "\n[effects.thermal_drift]\narcsec_per_K = 2.0\n"
                     "[effects.torsional_compliance]\nstiffness_Nm_per_arcsec = 10.0\n")
    data = tmp_path / "data.csv"
    _write_data(data, ["10", "10", "20"], ["1", "1", "1"],
                extra={"temperature_C": [20, 25, 20], "load_Nm": [0, 30, 0]})
    res = runner.invoke(app, ["simulate", str(drive), "--at", str(data), "-f", "json"])
    assert res.exit_code == 0, res.stderr
    sim = json.loads(res.stdout)["simulated_error"]
    # 5 K * 2 arcsec/K + 30 N m / 10 N m/arcsec plus the teeth's own wind-up under 30 N m
    teeth = compliance(load_spec(drive)).per_Nm * 30.0 / AS
    assert sim[1] - sim[0] == pytest.approx(10.0 + 3.0 + teeth, rel=1e-9)
    # the same conditions on a dense scan agree
    res2 = runner.invoke(app, ["simulate", str(drive), "--points", "36", "--temperature-C", "25", "--load-Nm",
                               "30", "-f", "json"])
    assert json.loads(res2.stdout)["curve"]["forward"][1] == pytest.approx(sim[1], rel=1e-9)


def test_effect_option_adds_to_the_curve(runner):
    _, base, _ = _dense(runner, "--points", "36")
    _, more, _ = _dense(runner, "--points", "36", "--effect", "bearing_clearance:clearance_arcsec=12")
    np.testing.assert_allclose(more[:, 4] - base[:, 4], 12.0, rtol=1e-9)
    np.testing.assert_allclose(more[:, 3], base[:, 3], atol=1e-9)


def test_at_without_error_column_and_resimulating_replaces_the_column(runner, tmp_path):
    data = tmp_path / "data.csv"
    _write_data(data, ["0", "90", "180"], ["1", "1", "-1"], comments=())
    first = tmp_path / "first.csv"
    assert runner.invoke(app, ["simulate", str(MCH50), "--at", str(data), "-o", str(first)]).exit_code == 0
    second = runner.invoke(app, ["simulate", str(MCH50), "--at", str(first)])
    assert second.exit_code == 0
    assert second.stdout == first.read_text()


def test_at_bad_csv_names_the_line(runner, tmp_path):
    data = tmp_path / "bad.csv"
    data.write_text("# c\nangle_deg,direction\n0,1\n10,1\nabc,1\n")
    res = runner.invoke(app, ["simulate", str(MCH50), "--at", str(data)])
    assert res.exit_code == 2
    assert res.stderr.startswith(f"error: {data}:5: column angle_deg")
    assert "Traceback" not in res.stderr + res.stdout


def test_at_missing_angle_column(runner, tmp_path):
    data = tmp_path / "bad.csv"
    data.write_text("angle,direction\n0,1\n10,1\n")
    res = runner.invoke(app, ["simulate", str(MCH50), "--at", str(data)])
    assert res.exit_code == 2
    assert f"error: {data}:1: missing required column angle_deg" in res.stderr


def test_never_overwrites_the_input(runner, tmp_path):
    data = tmp_path / "data.csv"
    _write_data(data, ["0", "90"], ["1", "-1"])
    before = data.read_bytes()
    res = runner.invoke(app, ["simulate", str(MCH50), "--at", str(data), "-o", str(data)])
    assert res.exit_code == 2
    assert "refusing to overwrite the input file" in res.stderr
    assert data.read_bytes() == before
    drive = tmp_path / "d.toml"
    drive.write_text(MCH50.read_text())
    res = runner.invoke(app, ["simulate", str(drive), "-o", str(drive)])
    assert res.exit_code == 2 and drive.read_text() == MCH50.read_text()


@pytest.mark.parametrize("args, message", [
    (["--revs", "0"], "error: --revs: expected a number in (0, 1000], got 0"),
    (["--temperature-C", "1000"], "error: --temperature-C: expected a number in [-100, 300] [degC], got 1000"),
    (["--effect", "bearing_clearence"], "error: --effect: unknown effect 'bearing_clearence' "
                                        "(did you mean bearing_clearance?)"),
    (["--effect", "thermal_drift:arcsec_per_K=x"], "error: --effect: thermal_drift.arcsec_per_K: expected a "
                                                   "number, got 'x'"),
    (["--plot", "curve.txt"], "error: curve.txt: --plot expects a file ending in .png, .svg, .pdf"),
])
def test_bad_options_exit_2(runner, args, message):
    res = runner.invoke(app, ["simulate", str(MCH50), *args])
    assert res.exit_code == 2
    assert res.stderr.strip() == message


def test_typer_range_checks_exit_2(runner):
    res = runner.invoke(app, ["simulate", str(MCH50), "--points", "1"])
    assert res.exit_code == 2 and "--points" in res.stderr
    res = runner.invoke(app, ["simulate", str(MCH50), "--phases", "sideways"])
    assert res.exit_code == 2 and "--phases" in res.stderr


def test_missing_drive_exit_2(runner, tmp_path):
    res = runner.invoke(app, ["simulate", str(tmp_path / "none.toml")])
    assert res.exit_code == 2
    assert res.stderr.strip() == f"error: {tmp_path / 'none.toml'}: file not found"


def test_plot_without_matplotlib(runner, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    out = tmp_path / "curve.csv"
    res = runner.invoke(app, ["simulate", str(MCH50), "--points", "10", "--plot", str(tmp_path / "c.png"),
                              "-o", str(out)])
    assert res.exit_code == 2
    assert res.stderr.strip() == "error: plotting needs matplotlib: pip install matplotlib"
    assert not out.exists()


def test_plot_is_written(runner, tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "c.png"
    res = runner.invoke(app, ["simulate", str(MCH50), "--points", "200", "--plot", str(png), "-o",
                              str(tmp_path / "c.csv")])
    assert res.exit_code == 0, res.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_help_has_example(runner):
    res = runner.invoke(app, ["simulate", "--help"])
    assert res.exit_code == 0 and "Example: wormgear simulate" in res.stdout

