"""``wormgear synth`` and the synthesis core: reproducibility, the plan's layout, the
programmes, the noise, the truth kept apart, option errors."""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest

from wormgear_cli.cli import app
from wormgear_cli.errors import UsageError
from wormgear_cli.measurement import read_measurement
from wormgear_cli.spec import load_spec
from wormgear_cli.synth import (
    COLUMNS,
    Noise,
    Plan,
    format_csv,
    parse_effect,
    parse_load,
    parse_temperature,
    synthesize,
)

ROOT = Path(__file__).resolve().parent.parent
MCH50 = ROOT / "configs" / "mch50.toml"


@pytest.fixture(scope="module")
def spec():
    return load_spec(MCH50)


def _rows(text: str):
    lines = [ln for ln in text.splitlines() if not ln.startswith("#")]
    rows = list(csv.reader(io.StringIO("\n".join(lines))))
    return rows[0], {c: np.array([float(r[j]) for r in rows[1:]]) for j, c in enumerate(rows[0])}


def _synth(runner, tmp_path, *args, name="d.csv"):
    out = tmp_path / name
    res = runner.invoke(app, ["synth", str(MCH50), "-o", str(out), *args])
    assert res.exit_code == 0, res.stderr
    return out


# --- reproducibility ------------------------------------------------------------------


def test_same_seed_same_bytes_other_seed_differs(runner, tmp_path):
    args = ["--noise-arcsec", "0.5", "--run-noise-arcsec", "1", "--temperature", "warmup:20:30:900"]
    a = _synth(runner, tmp_path, "--seed", "7", "--truth", str(tmp_path / "ta.json"), *args, name="a.csv")
    b = _synth(runner, tmp_path, "--seed", "7", "--truth", str(tmp_path / "tb.json"), *args, name="b.csv")
    c = _synth(runner, tmp_path, "--seed", "8", *args, name="c.csv")
    assert a.read_bytes() == b.read_bytes()
    assert (tmp_path / "ta.json").read_bytes() == (tmp_path / "tb.json").read_bytes()
    assert a.read_bytes() != c.read_bytes()
    _, ca = _rows(a.read_text())
    _, cc = _rows(c.read_text())
    assert not np.array_equal(ca["angle_deg"], cc["angle_deg"])  # other targets
    assert not np.array_equal(ca["error_arcsec"], cc["error_arcsec"])


def test_stdout_when_no_output(runner, tmp_path):
    res = runner.invoke(app, ["synth", str(MCH50), "--targets", "5", "--runs", "1"])
    assert res.exit_code == 0
    header, cols = _rows(res.stdout)
    assert tuple(header) == COLUMNS and len(cols["angle_deg"]) == 10


# --- the plan -------------------------------------------------------------------------


def test_iso_plan_layout(spec):
    n, runs = 12, 4
    cols, truth = synthesize(spec, plan=Plan(kind="iso", targets=n, runs=runs, dwell_s=6.0), seed=3)
    assert len(cols["angle_deg"]) == 2 * n * runs
    targets = np.array(truth["plan"]["target_angles_deg"])
    spacing = np.diff(targets)
    assert np.ptp(spacing) > 1.0  # irregular
    p = 360.0 / n
    assert np.all(np.abs(targets - np.arange(n) * p) <= 0.25 * p + 1e-3)
    assert targets[0] == 0.0 and np.all(targets < 360.0)
    for r in range(1, runs + 1):
        fwd = (cols["run"] == r) & (cols["direction"] == 1)
        rev = (cols["run"] == r) & (cols["direction"] == -1)
        assert fwd.sum() == n and rev.sum() == n  # every target once per direction per run
        np.testing.assert_array_equal(cols["angle_deg"][fwd], targets)
        np.testing.assert_array_equal(cols["angle_deg"][rev], targets[::-1])
        assert np.flatnonzero(fwd).max() < np.flatnonzero(rev).min()  # forward, then reverse
    np.testing.assert_allclose(np.diff(cols["time_s"]), 6.0)


def test_irregular_spacing_differs_between_seeds(spec):
    _, t1 = synthesize(spec, plan=Plan(targets=10, runs=1), seed=1)
    _, t2 = synthesize(spec, plan=Plan(targets=10, runs=1), seed=2)
    assert t1["plan"]["target_angles_deg"] != t2["plan"]["target_angles_deg"]


def test_dense_plan_is_even(spec):
    cols, truth = synthesize(spec, plan=Plan(kind="dense", points=720, runs=2, revolutions=2.0))
    fwd = cols["angle_deg"][(cols["run"] == 1) & (cols["direction"] == 1)]
    np.testing.assert_allclose(np.diff(fwd), 1.0)
    assert truth["plan"]["dwell_s"] == 0.5 and "targets" not in truth["plan"]


def test_written_file_reads_as_a_measurement(runner, tmp_path):
    out = _synth(runner, tmp_path, "--targets", "8", "--runs", "3", "--load", "steps:0:40")
    m = read_measurement(out)
    assert len(m) == 48
    assert m.present == {"direction", "run", "load_Nm", "temperature_C", "time_s"}
    assert set(m.run.tolist()) == {1, 2, 3}
    np.testing.assert_array_equal(np.unique(m.load[m.run == 2]), [40.0])


# --- programmes -----------------------------------------------------------------------


def test_warmup_follows_the_exponential(spec):
    cols, _ = synthesize(spec, plan=Plan(targets=10, runs=3), temperature=parse_temperature("warmup:18:33:400"))
    t = cols["time_s"]
    want = 18.0 + 15.0 * (1.0 - np.exp(-t / 400.0))
    np.testing.assert_allclose(cols["temperature_C"], want, atol=5e-4)


def test_cycle_heats_then_cools(spec):
    cols, _ = synthesize(spec, plan=Plan(targets=10, runs=4),
                         temperature=parse_temperature("cycle:20:40:300:400"))
    t, temp = cols["time_s"], cols["temperature_C"]
    peak = 20.0 + 20.0 * (1.0 - math.exp(-400.0 / 300.0))
    assert temp[t == 400.0][0] == pytest.approx(peak, abs=5e-4)
    later = t > 400.0
    want = 20.0 + (peak - 20.0) * np.exp(-(t[later] - 400.0) / 300.0)
    np.testing.assert_allclose(temp[later], want, atol=5e-4)
    assert np.all(np.diff(temp[~later]) > 0) and np.all(np.diff(temp[later]) < 0)


def test_cycle_switches_at_half_time_by_default(spec):
    cols, _ = synthesize(spec, plan=Plan(targets=10, runs=2, dwell_s=10.0),
                         temperature=parse_temperature("cycle:20:40:300"))
    temp = cols["temperature_C"]
    assert cols["time_s"][np.argmax(temp)] == pytest.approx(cols["time_s"][-1] / 2, abs=10.0)


def test_thermal_drift_effect_adds_k_times_temperature_rise(spec):
    plan = Plan(targets=9, runs=2)
    prog = parse_temperature("warmup:20:35:600")
    with_drift, _ = synthesize(spec, plan=plan, temperature=prog, effects={"thermal_drift": {"arcsec_per_K": 1.5}},
                               seed=4)
    without, _ = synthesize(spec, plan=plan, temperature=prog, seed=4)
    diff = with_drift["error_arcsec"] - without["error_arcsec"]
    np.testing.assert_allclose(diff, 1.5 * (with_drift["temperature_C"] - 20.0), atol=2e-4)


def test_load_steps_wind_up_the_table(spec):
    plan = Plan(targets=6, runs=3)
    cols, _ = synthesize(spec, plan=plan, load=parse_load("steps:0:100:-100"),
                         effects={"torsional_compliance": {"stiffness_Nm_per_arcsec": 20.0}})
    assert [cols["load_Nm"][cols["run"] == r][0] for r in (1, 2, 3)] == [0.0, 100.0, -100.0]
    e = cols["error_arcsec"]
    fwd1 = e[(cols["run"] == 1) & (cols["direction"] == 1)]
    fwd2 = e[(cols["run"] == 2) & (cols["direction"] == 1)]
    fwd3 = e[(cols["run"] == 3) & (cols["direction"] == 1)]
    assert np.all(fwd2 - fwd1 > 100.0 / 20.0 - 1e-3)  # at least the catalogue term, plus the teeth
    np.testing.assert_allclose(fwd2 - fwd1, fwd1 - fwd3, atol=2e-4)


# --- noise --------------------------------------------------------------------------


def test_white_noise_size(spec):
    plan = Plan(kind="dense", points=2000, runs=2)
    clean, _ = synthesize(spec, plan=plan, seed=11)
    noisy, _ = synthesize(spec, plan=plan, seed=11, noise=Noise(white_arcsec=0.8))
    np.testing.assert_array_equal(clean["angle_deg"], noisy["angle_deg"])
    n = noisy["error_arcsec"] - clean["error_arcsec"]
    assert np.std(n) == pytest.approx(0.8, rel=0.05)
    assert abs(np.mean(n)) < 0.05


def test_run_offset_is_shared_by_a_run(spec):
    plan = Plan(targets=8, runs=6)
    clean, _ = synthesize(spec, plan=plan, seed=2)
    noisy, truth = synthesize(spec, plan=plan, seed=2, noise=Noise(run_arcsec=2.0))
    d = noisy["error_arcsec"] - clean["error_arcsec"]
    for r, value in enumerate(truth["noise"]["run_values_arcsec"], start=1):
        np.testing.assert_allclose(d[noisy["run"] == r], value, atol=2e-4)
    assert np.ptp(truth["noise"]["run_values_arcsec"]) > 0


def test_run_drift_grows_within_each_run(spec):
    plan = Plan(targets=8, runs=3)
    clean, _ = synthesize(spec, plan=plan, seed=2)
    noisy, truth = synthesize(spec, plan=plan, seed=2, noise=Noise(run_arcsec=2.0, run_kind="drift"))
    d = noisy["error_arcsec"] - clean["error_arcsec"]
    for r, end in enumerate(truth["noise"]["run_values_arcsec"], start=1):
        dr = d[noisy["run"] == r]
        assert dr[0] == pytest.approx(0.0, abs=2e-4)
        assert dr[-1] == pytest.approx(end, abs=2e-4)
        np.testing.assert_allclose(np.diff(dr), end / 15.0, atol=3e-4)


# --- the truth is kept apart ---------------------------------------------------------


def test_truth_file_and_clean_data(runner, tmp_path):
    truth = tmp_path / "truth.json"
    out = _synth(runner, tmp_path, "--seed", "123", "--truth", str(truth), "--noise-arcsec", "0.37",
                 "--effect", "bearing_clearance:clearance_arcsec=6.5", "--effect", "thermal_backlash",
                 "--random-phases", "--temperature", "warmup:20:28:500")
    doc = json.loads(truth.read_text())
    assert doc["seed"] == 123 and doc["noise"]["white_arcsec"] == 0.37
    assert doc["effects"]["bearing_clearance"] == {"clearance_arcsec": 6.5}
    # thermal_backlash without a coefficient takes the physics prediction (steel/bronze/cast iron)
    spec = load_spec(MCH50)
    d_m1 = 2.5 / math.tan(spec.worm_pair.lead_angle)
    r1, r2 = d_m1 / 2, 2.5 * 30 / 2
    mat = spec.materials
    k_um = ((r1 + r2) * mat.housing_expansion - r1 * mat.worm_expansion - r2 * mat.wheel_expansion) * 1000
    assert doc["effects"]["thermal_backlash"]["centre_distance_um_per_K"] == pytest.approx(k_um)
    assert doc["random_phases"] is True
    phases = [v["phase_deg"] for v in doc["phases"].values()]
    assert len(set(phases)) == 5 and all(0 <= p < 360 for p in phases)
    text = out.read_text()
    comments = [ln for ln in text.splitlines() if ln.startswith("#")]
    assert comments and all(s not in "\n".join(comments) for s in ("123", "0.37", "6.5", "bearing", "thermal"))
    assert text.splitlines()[len(comments)] == ",".join(COLUMNS)


def test_truth_phases_are_the_specs_by_default(spec):
    _, truth = synthesize(spec, plan=Plan(targets=4, runs=1))
    assert truth["phases"]["gear_eccentricity"]["key"] == "assembly.gear_eccentricity_phase_deg"
    assert truth["phases"]["gear_eccentricity"]["phase_deg"] == pytest.approx(
        math.degrees(spec.assembly.gear_eccentricity_phase))


def test_format_csv_round_trip(spec):
    result = synthesize(spec, plan=Plan(targets=5, runs=2), noise=Noise(0.3), seed=9)
    header, cols = _rows(format_csv(result))
    assert tuple(header) == COLUMNS
    for c in COLUMNS:
        np.testing.assert_array_equal(cols[c], np.asarray(result.columns[c], dtype=float))


# --- parsing and option errors -------------------------------------------------------


def test_parse_effect():
    assert parse_effect("worm_runout:amplitude_um=3, phase_deg=45") == (
        "worm_runout", {"amplitude_um": 3.0, "phase_deg": 45.0})
    with pytest.raises(UsageError, match="unknown key 'amp'"):
        parse_effect("worm_runout:amp=3")


@pytest.mark.parametrize("args, message", [
    (["--temperature", "warmup:20:30"], "error: --temperature: expected constant:T, warmup:START:END:TAU_s, "
                                        "cycle:START:PEAK:TAU_s[:SWITCH_s] or "
                                        "mesh-warmup:START:END:TAU_s:HOUSING_SHARE:HOUSING_LAG_s, got 'warmup:20:30'"),
    (["--temperature", "warmup:20:30:0"], "error: --temperature: TAU_s must be > 0, got 0 in 'warmup:20:30:0'"),
    (["--temperature", "warmup:20:x:5"], "error: --temperature: expected a number, got 'x' in 'warmup:20:x:5'"),
    (["--load", "steps"], "error: --load: expected constant:L or steps:L1:L2:... [N m], got 'steps'"),
    (["--effect", "nope"], "error: --effect: unknown effect 'nope' (known: output_gear_runout, "
                           "intermediate_shaft_runout, worm_runout, gear_mesh_error, thermal_backlash, "
                           "thermal_drift, torsional_compliance, bearing_clearance)"),
    (["--effect", "worm_runout"], "error: --effect worm_runout: missing amplitude_um (a number in [0, 500] um)"),
    (["--effect", "bearing_clearance:clearance_arcsec=-3"],
     "error: --effect bearing_clearance: clearance_arcsec = -3 outside its range [0, 3600] arcsec"),
    (["--revs", "0"], "error: --revs: expected a number in (0, 1000], got 0"),
    (["--jitter", "0.5"], "error: --jitter: expected a number in [0, 0.5), got 0.5"),
])
def test_bad_options_exit_2(runner, tmp_path, args, message):
    out = tmp_path / "d.csv"
    res = runner.invoke(app, ["synth", str(MCH50), "-o", str(out), *args])
    assert res.exit_code == 2
    assert res.stderr.strip() == message
    assert not out.exists()


def test_typer_checks_exit_2(runner):
    for args in (["--runs", "0"], ["--plan", "random"], ["--targets", "1"], ["--run-noise", "walk"]):
        res = runner.invoke(app, ["synth", str(MCH50), *args])
        assert res.exit_code == 2, args


def test_output_files_must_differ_and_not_be_the_drive(runner, tmp_path):
    drive = tmp_path / "d.toml"
    drive.write_text(MCH50.read_text())
    res = runner.invoke(app, ["synth", str(drive), "-o", str(drive)])
    assert res.exit_code == 2 and drive.read_text() == MCH50.read_text()
    assert "refusing to overwrite the input file" in res.stderr
    same = tmp_path / "x.csv"
    res = runner.invoke(app, ["synth", str(drive), "-o", str(same), "--truth", str(same)])
    assert res.exit_code == 2
    assert res.stderr.strip() == "error: -o, --truth and --plot must name different files"
    assert not same.exists()


def test_help_has_example(runner):
    res = runner.invoke(app, ["synth", "--help"])
    assert res.exit_code == 0 and "Example: wormgear synth" in res.stdout


def test_effect_key_given_twice_is_refused():
    from wormgear_cli.errors import UsageError
    from wormgear_cli.synth import parse_effect

    with pytest.raises(UsageError, match=r"bearing_clearance.clearance_arcsec is given twice"):
        parse_effect("bearing_clearance:clearance_arcsec=1,clearance_arcsec=2")


def test_shipped_demo_is_exactly_what_its_documented_command_makes(runner, tmp_path):
    """configs/mch50-warm.csv is reproducible from the command kept in its truth file."""
    import json
    import shlex

    from tests.conftest import CONFIGS, ROOT

    truth = json.loads((CONFIGS / "mch50-warm.truth.json").read_text())
    args = shlex.split(truth["command"])[1:]
    args[args.index("-o") + 1] = str(tmp_path / "warm.csv")
    args[args.index("--truth") + 1] = str(tmp_path / "warm.json")
    args[args.index("configs/mch50.toml")] = str(ROOT / "configs" / "mch50.toml")
    r = runner.invoke(app, args)
    assert r.exit_code == 0, r.stderr
    assert (tmp_path / "warm.csv").read_bytes() == (CONFIGS / "mch50-warm.csv").read_bytes()
    made = json.loads((tmp_path / "warm.json").read_text())
    assert made.pop("spec").endswith("configs/mch50.toml")
    assert made == {k: v for k, v in truth.items() if k not in ("command", "spec")}
