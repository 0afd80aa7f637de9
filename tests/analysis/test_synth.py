"""Tests of the synthesis core (:mod:`wormgear_cli.analysis.synth`): plans, programmes, noise, effects."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.paths import MCH50
from tests.support.synth import csv_rows
from wormgear_cli.analysis.synth import (
    COLUMNS,
    Noise,
    Plan,
    format_csv,
    parse_effect,
    parse_load,
    parse_temperature,
    synthesize,
)
from wormgear_cli.errors import UsageError
from wormgear_cli.spec.loader import load_spec


@pytest.fixture(scope="module")
def spec():
    return load_spec(MCH50)




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


def test_truth_phases_are_the_specs_by_default(spec):
    _, truth = synthesize(spec, plan=Plan(targets=4, runs=1))
    assert truth["phases"]["gear_eccentricity"]["key"] == "assembly.gear_eccentricity_phase_deg"
    assert truth["phases"]["gear_eccentricity"]["phase_deg"] == pytest.approx(
        math.degrees(spec.assembly.gear_eccentricity_phase))


def test_format_csv_round_trip(spec):
    result = synthesize(spec, plan=Plan(targets=5, runs=2), noise=Noise(0.3), seed=9)
    header, cols = csv_rows(format_csv(result))
    assert tuple(header) == COLUMNS
    for c in COLUMNS:
        np.testing.assert_array_equal(cols[c], np.asarray(result.columns[c], dtype=float))


def test_parse_effect():
    assert parse_effect("worm_runout:amplitude_um=3, phase_deg=45") == (
        "worm_runout", {"amplitude_um": 3.0, "phase_deg": 45.0})
    with pytest.raises(UsageError, match="unknown key 'amp'"):
        parse_effect("worm_runout:amp=3")


def test_effect_key_given_twice_is_refused():
    from wormgear_cli.analysis.synth import parse_effect
    from wormgear_cli.errors import UsageError

    with pytest.raises(UsageError, match=r"bearing_clearance.clearance_arcsec is given twice"):
        parse_effect("bearing_clearance:clearance_arcsec=1,clearance_arcsec=2")

