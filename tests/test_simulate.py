"""``wormgear simulate``: the curve's relation to analyze's envelope, --at against the dense
scan, effects and loads, CLI options, errors and file safety."""

from __future__ import annotations

import csv
import io
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wormgear_cli.analysis import analyze
from wormgear_cli.cli import app
from wormgear_cli.models.effects import Signals
from wormgear_cli.simulation import aligned_phases, components, compliance, max_reversal, simulate
from wormgear_cli.spec import load_spec, with_values

ROOT = Path(__file__).resolve().parent.parent
MCH50 = ROOT / "configs" / "mch50.toml"
AS = math.pi / 648000.0
WORM_STAGE = ("worm_lead_error", "worm_eccentricity", "wheel_radial_composite", "wheel_eccentricity")


@pytest.fixture(scope="module")
def spec():
    return load_spec(MCH50)


def _hand_worm_terms(spec):
    """The paper's four worm-stage terms x_k [mm] and the output scale 1/(r_wheel i_c), by hand."""
    wp, asm = spec.worm_pair, spec.assembly
    lam = wp.lead_angle
    a2 = math.atan(math.tan(wp.normal_pressure_angle) / math.cos(lam))
    x = {
        "worm_lead_error": wp.lead_error,
        "worm_eccentricity": math.sqrt(asm.worm_eccentricity**2 + asm.worm_bearing_clearance**2) / math.cos(lam),
        "wheel_radial_composite": wp.wheel.radial_composite_error,
        "wheel_eccentricity": math.sqrt(asm.wheel_eccentricity**2 + asm.wheel_bearing_clearance**2) / math.cos(a2),
    }
    i_c = spec.gear_pair.output_gear.teeth / spec.gear_pair.pinion.teeth
    r_wheel = wp.module * wp.wheel.teeth / 2.0
    return x, 1.0 / (r_wheel * i_c)


def _turn(n=4800):
    return np.arange(n) * (2.0 * math.pi / n)


def _worm_common(spec, phases, theta):
    c = components(spec, Signals.make(theta, 1.0), phases)
    return sum(c[k] for k in WORM_STAGE)


# --- relation to analyze's envelope --------------------------------------------------


def test_worm_common_mode_rms_is_h_over_sqrt2_in_quadrature(spec):
    a = analyze(spec)
    i_c = a.info["gear_ratio"]
    h_out = a.angles["worm_te_envelope"] / i_c  # the paper's h, as an angle at the output
    phases = {"worm_lead_error": 0.3, "worm_eccentricity": 0.3 + math.pi / 2,
              "wheel_radial_composite": 1.1, "wheel_eccentricity": 1.1 - math.pi / 2}
    w = _worm_common(spec, phases, _turn())
    assert math.sqrt(np.mean(w * w)) == pytest.approx(h_out / math.sqrt(2.0), rel=1e-9)


@settings(max_examples=20, deadline=None)
@given(ph=st.lists(st.floats(0.0, 2 * math.pi), min_size=4, max_size=4))
def test_worm_common_mode_mean_square_with_any_phases(spec, ph):
    x, to_out = _hand_worm_terms(spec)
    phases = dict(zip(WORM_STAGE, ph))
    w = _worm_common(spec, phases, _turn())
    h = 0.5 * math.sqrt(sum(v * v for v in x.values()))
    # sources on one shaft add as phasors: h^2/2 plus their cross terms
    cross = (x["worm_lead_error"] * x["worm_eccentricity"] / 4 * math.cos(ph[0] - ph[1])
             + x["wheel_radial_composite"] * x["wheel_eccentricity"] / 4 * math.cos(ph[2] - ph[3]))
    want = (h * h / 2 + cross) * to_out**2
    assert np.mean(w * w) == pytest.approx(want, rel=1e-9)


def test_random_phases_average_to_the_root_sum_square(spec):
    x, to_out = _hand_worm_terms(spec)
    h = 0.5 * math.sqrt(sum(v * v for v in x.values())) * to_out
    rng = np.random.default_rng(5)
    theta = _turn(2400)
    ms = [np.mean(_worm_common(spec, dict(zip(WORM_STAGE, rng.uniform(0, 2 * math.pi, 4))), theta) ** 2)
          for _ in range(400)]
    assert np.mean(ms) == pytest.approx(h * h / 2, rel=0.05)


def test_aligned_peak_is_the_linear_sum(spec):
    x, to_out = _hand_worm_terms(spec)
    theta = _turn()
    w = _worm_common(spec, aligned_phases(spec, "error"), theta)
    linear = 0.5 * sum(x.values()) * to_out
    assert w[0] == pytest.approx(linear, rel=1e-12)  # every source peaks at theta = 0
    assert w.max() == pytest.approx(linear, rel=1e-12)
    assert linear >= analyze(spec).angles["worm_te_envelope"] / analyze(spec).info["gear_ratio"]


def test_gear_common_mode_peak_matches_analyze_kinematic_part(spec):
    a = analyze(spec)
    theta = np.linspace(0, 2 * math.pi, 200_001)
    g = components(spec, Signals.make(theta, 1.0), aligned_phases(spec, "error"))["gear_eccentricity"]
    assert g[0] == pytest.approx(g.max(), rel=1e-9)
    assert g.max() == pytest.approx(a.angles["gear_te_eccentricity"], rel=1e-3)


def test_gear_reversal_by_hand():
    """Only a gear eccentricity (0.02 mm), no loads: the simulated lost motion is
    de tan(alpha) (1 + sin phi) / R2, largest 2 de tan(alpha) / R2 = 0.04 * 0.36397023 / 180
    = 8.088227e-5 rad at the aligned phase -- the paper's 2 Delta C1 / (m z1) with
    Delta C1 = 2 de tan(alpha) (R2 = m z1 / 2 = 180 mm).  An explicit drive, not the MCH50."""
    from tests.diagnosis.independent_model import perfect_spec

    s = with_values(perfect_spec(), {"assembly.gear_eccentricity_mm": 0.02})
    theta = _turn(3200)
    phases = aligned_phases(s, "reversal")
    rev = simulate(s, Signals.make(theta, -1.0), phases) - simulate(s, Signals.make(theta, 1.0), phases)
    assert rev.max() == pytest.approx(8.088227e-5, rel=1e-6)
    assert rev.min() >= -1e-18


def test_worm_reversal_by_hand():
    """Only tooth thickness deviations T_s1 30, T_s2 60 um (lambda 3.178 deg, cos = 0.99846212):
    central (T_s1 + T_s2)/(2 cos lambda) = 0.04506931 mm, half-width
    sqrt((T_s1^2 + T_s2^2)/(36 cos^2 lambda))/2 = 0.00559878 mm, so the lost motion peaks at
    (0.04506931 + 0.00559878) / (r_wheel i_c = 37.5 * 8) = 1.688936e-4 rad."""
    from tests.diagnosis.independent_model import perfect_spec

    s = with_values(perfect_spec(), {"worm_pair.worm.thickness_deviation_mm": 0.03,
                                     "worm_pair.wheel.thickness_deviation_mm": 0.06})
    assert max_reversal(s, points=3200) == pytest.approx(1.688936e-4, rel=1e-6)


def test_consistency_max_reversal_equals_total_backlash_when_aligned(spec):
    """A consistency check between two paths that share the stage functions (simulate's aligned
    reversal and analyze's total backlash), not a check of either: the hand-worked checks are
    test_gear_reversal_by_hand and test_worm_reversal_by_hand above."""
    total = analyze(spec).angles["total_backlash"]
    theta = _turn(3200)
    phases = aligned_phases(spec, "reversal")
    rev = simulate(spec, Signals.make(theta, -1.0), phases) - simulate(spec, Signals.make(theta, 1.0), phases)
    assert rev[0] == pytest.approx(total, rel=1e-12)
    assert rev.max() == pytest.approx(total, rel=1e-12)


def test_default_phases_are_aligned_for_the_reversal(spec):
    # MCH50 gives no phases: gear eccentricity and radial composite error both at 0 deg
    assert max_reversal(spec, points=3200) == pytest.approx(analyze(spec).angles["total_backlash"], rel=1e-9)


def test_max_reversal_below_total_backlash_otherwise(spec):
    total = analyze(spec).angles["total_backlash"]
    shifted = with_values(spec, {"worm_pair.wheel.radial_composite_phase_deg": 90.0})
    assert max_reversal(shifted, points=3200) < total - 1.0 * AS


@settings(max_examples=15, deadline=None)
@given(pe=st.floats(-360, 360), pf=st.floats(-360, 360))
def test_reversal_never_exceeds_total_backlash(spec, pe, pf):
    total = analyze(spec).angles["total_backlash"]
    s = with_values(spec, {"assembly.gear_eccentricity_phase_deg": pe,
                           "worm_pair.wheel.radial_composite_phase_deg": pf})
    assert max_reversal(s, points=1600) <= total * (1 + 1e-12)


def test_deformation_parts_of_the_reversal(spec):
    a = analyze(spec)
    i_c = a.info["gear_ratio"]
    c = compliance(spec)
    want = a.angles["gear_backlash_deformation"] + a.angles["worm_backlash_deformation"] / i_c
    assert 2.0 * c.process_lag == pytest.approx(want, rel=1e-12)


def test_forward_lags_reverse_everywhere(spec):
    theta = _turn(2000)
    fwd = simulate(spec, Signals.make(theta, 1.0))
    rev = simulate(spec, Signals.make(theta, -1.0))
    assert np.all(fwd - rev < 0)  # ISO 230-2 reversal B = forward - reverse is negative


def test_external_torque_winds_up_linearly(spec):
    theta = _turn(50)
    base = simulate(spec, Signals.make(theta, 1.0, 0.0))
    plus = simulate(spec, Signals.make(theta, 1.0, 100.0))
    minus = simulate(spec, Signals.make(theta, 1.0, -50.0))
    assert np.all(plus - base > 0)  # positive torque pushes the table forward
    np.testing.assert_allclose(minus - base, -(plus - base) / 2, rtol=1e-9)


# --- CLI ----------------------------------------------------------------------------


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
    assert res.stderr.strip() == "error: plotting needs matplotlib: pip install 'wormgear-cli[plot]'"
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
