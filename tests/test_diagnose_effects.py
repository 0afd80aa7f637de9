"""diagnose on data with hidden effects: named, bounded, gap shrinks; null data; decoys; what cannot be seen."""

from __future__ import annotations

import pytest

from wormgear_cli.diagnosis import diagnose, report
from wormgear_cli.spec import with_values

from tests.test_diagnose_data import NO_ORDER_8, NO_ORDER_240, R_B1, Plan, make_measurement

WARM = (20.0, 35.0, 1200.0)
STEPS = (0.0, 250.0, -250.0)

#: each catalogue effect hidden alone at a realistic size, with the signals it needs varying:
#: name -> (spec changes, plan, parameters in catalogue units, keys to check against the 95 % interval)
HIDDEN = {
    "output_gear_runout": ({}, Plan(), {"eccentricity_um": 8.0, "phase_deg": 40.0}, ("eccentricity_um", "phase_deg")),
    "intermediate_shaft_runout": (NO_ORDER_8, Plan(), {"eccentricity_um": 6.0, "phase_deg": -110.0},
                                  ("eccentricity_um", "phase_deg")),
    "worm_runout": (NO_ORDER_240, Plan(kind="dense", targets=1000, runs=2, dwell_s=1.0),
                    {"amplitude_um": 3.0, "phase_deg": 75.0}, ("amplitude_um", "phase_deg")),
    "gear_mesh_error": ({}, Plan(kind="dense", targets=1000, runs=2, dwell_s=1.0),
                        {"amplitude_um": 2.0, "phase_deg": -20.0}, ("amplitude_um", "phase_deg")),
    "thermal_backlash": ({}, Plan(warmup=WARM), {"centre_distance_um_per_K": -0.8}, ("centre_distance_um_per_K",)),
    "thermal_drift": ({}, Plan(warmup=WARM), {"arcsec_per_K": 0.45}, ("arcsec_per_K",)),
    "torsional_compliance": ({}, Plan(runs=6, loads=STEPS), {"stiffness_Nm_per_arcsec": 30.0},
                             ("stiffness_Nm_per_arcsec",)),
    "bearing_clearance": ({}, Plan(), {"clearance_arcsec": 3.0}, ("clearance_arcsec",)),
}


def _spec(mch50_spec, changes):
    return with_values(mch50_spec, changes) if changes else mch50_spec


@pytest.mark.parametrize("name", sorted(HIDDEN))
def test_each_effect_hidden_alone_is_named_bounded_and_shrinks_the_gap(name, mch50_spec):
    changes, plan, params, check = HIDDEN[name]
    spec = _spec(mch50_spec, changes)
    covered = []
    for seed in (11, 12):
        meas, _ = make_measurement(spec, plan, hidden={name: params}, seed=seed)
        doc = report(diagnose(spec, meas, resamples=30))
        assert [e["name"] for e in doc["effects_found"]] == [name]
        assert doc["gap_before"]["rms_arcsec"] >= 3.0 * doc["gap_after"]["rms_arcsec"]
        found = doc["effects_found"][0]
        covered.append(all(found["interval_95"][k][0] <= params[k] <= found["interval_95"][k][1] for k in check))
    # a 95 % interval misses now and then: both seeds missing has probability ~0.25 %
    assert any(covered), covered


@pytest.mark.slow  # 30 diagnose runs; calibration proper: tests/diagnosis/test_calibration.py
def test_the_95_percent_interval_covers_the_truth_at_its_nominal_rate(mch50_spec):
    import numpy as np

    _, plan, params, _ = HIDDEN["thermal_backlash"]
    inside, estimates, half = [], [], []
    for seed in range(30):
        meas, _ = make_measurement(mch50_spec, plan, hidden={"thermal_backlash": params}, seed=500 + seed)
        found = diagnose(mch50_spec, meas, resamples=0).found
        assert [f.name for f in found] == ["thermal_backlash"]
        lo, hi = found[0].intervals["centre_distance_um_per_K"]
        inside.append(lo <= -0.8 <= hi)
        estimates.append(found[0].params["coefficient"] * 1e3)
        half.append((hi - lo) / 2)
    assert sum(inside) >= 26, sum(inside)  # P(<= 25 of 30 | 95 %) ~ 1.6 %
    # and not by being needlessly wide: the half-width is about 1.96 times the scatter of the estimates
    assert np.mean(half) < 3.0 * np.std(estimates)


@pytest.mark.slow  # many diagnose runs; false-positive rate: tests/diagnosis/test_calibration.py
def test_null_data_name_nothing_in_at_least_95_percent_of_seeds(mch50_spec):
    # every candidate testable: warm-up, load steps, both directions, jittered targets
    plan = Plan(targets=16, runs=4, warmup=(20.0, 30.0, 900.0), loads=(0.0, 200.0, -200.0))
    named = []
    for seed in range(40):
        meas, _ = make_measurement(mch50_spec, plan, seed=1000 + seed)
        diag = diagnose(mch50_spec, meas, resamples=20)
        if diag.found:
            named.append((seed, [f.name for f in diag.found]))
        elif seed < 3:
            assert report(diag)["verdict"].startswith("no missing effect found")
    assert len(named) <= 2, named


def test_two_hidden_effects_are_both_named(mch50_spec):
    hidden = {"thermal_backlash": {"centre_distance_um_per_K": -0.7}, "torsional_compliance":
              {"stiffness_Nm_per_arcsec": 40.0}}
    meas, _ = make_measurement(mch50_spec, Plan(runs=6, warmup=WARM, loads=STEPS), hidden=hidden, seed=3)
    doc = report(diagnose(mch50_spec, meas, resamples=30))
    found = {e["name"]: e for e in doc["effects_found"]}
    assert set(found) == set(hidden)
    lo, hi = found["torsional_compliance"]["interval_95"]["stiffness_Nm_per_arcsec"]
    assert lo <= 40.0 <= hi
    lo, hi = found["thermal_backlash"]["interval_95"]["centre_distance_um_per_K"]
    assert lo <= -0.7 <= hi
    assert sum(e["gap_share_pct"] for e in found.values()) > 80.0


def test_a_decoy_outside_the_catalogue_is_reported_unexplained_not_named(mch50_spec):
    import numpy as np

    def third_order(theta, d):
        return 2.5 * np.sin(3.0 * theta + 0.4)

    meas, _ = make_measurement(mch50_spec, Plan(runs=5, warmup=WARM), seed=5, decoy=third_order)
    doc = report(diagnose(mch50_spec, meas, resamples=30))
    assert doc["effects_found"] == []
    assert doc["verdict"].startswith("no missing effect found")
    orders = [u for u in doc["unexplained"] if u["kind"] == "order" and u["order"] == 3.0 and u["mode"] == "common"]
    assert orders and "the catalogue has no effect at this order" in orders[0]["explanation"]
    assert orders[0]["amplitude_arcsec"] == pytest.approx(2.5, rel=0.15)


def test_same_order_effect_absorbed_by_fitted_phases_is_reported_unobservable(mch50_spec):
    # MCH50's wheel eccentricity is a pure sinusoid at order i_c = 8 of fixed size A (its phase is fitted).
    # Rotating it from 0 to 60 deg adds the chord A (sin(8t + 60) - sin(8t)) = A sin(8t + 120): an
    # intermediate-shaft runout of that size and phase is exactly what a different phase would give.
    import math

    from wormgear_cli.simulation import periodic_sources

    amp = next(s.amplitude for s in periodic_sources(mch50_spec) if s.name == "wheel_eccentricity")  # rad
    e_um = amp * (R_B1 * 1e3)  # chord length 2 A sin(30 deg) = A, as an eccentricity at the base radius
    hidden = {"intermediate_shaft_runout": {"eccentricity_um": e_um, "phase_deg": 120.0}}
    meas, _ = make_measurement(mch50_spec, Plan(), hidden=hidden, seed=8, phases="spec")
    doc = report(diagnose(mch50_spec, meas, resamples=30))
    assert doc["effects_found"] == []
    status = {c["name"]: c for c in doc["candidates"]}["intermediate_shaft_runout"]
    assert status["status"] == "unobservable"
    assert "fitted phases" in status["reason"] and "order-8" in status["reason"]
    assert "--keep-phases" in status["remedy"]
    wheel = {p["source"]: p for p in doc["fit"]["phases"]}["wheel_eccentricity"]
    assert math.isclose(wheel["fitted_deg"], 60.0, abs_tol=3.0)
    # with the phases known (held as specified) the same data name it, bounded, and say what it trades with
    doc = report(diagnose(mch50_spec, meas, fit_phases=False, resamples=30))
    assert [e["name"] for e in doc["effects_found"]] == ["intermediate_shaft_runout"]
    lo, hi = doc["effects_found"][0]["interval_95"]["eccentricity_um"]
    half = (hi - lo) / 2.0
    assert lo - half <= e_um <= hi + half  # about four standard errors; coverage is tested on its own
    assert "wheel_eccentricity" in doc["effects_found"][0]["indistinguishable_from"]


def test_same_order_excess_beyond_the_spec_sources_is_named_with_its_rivals(mch50_spec):
    # 40 um (49 arcsec) is more than the order-8 sources can produce together (about 42 arcsec)
    meas, _ = make_measurement(mch50_spec, Plan(), hidden={"intermediate_shaft_runout":
                                                           {"eccentricity_um": 40.0, "phase_deg": 30.0}}, seed=9)
    doc = report(diagnose(mch50_spec, meas, resamples=30))
    found = {e["name"]: e for e in doc["effects_found"]}
    assert "intermediate_shaft_runout" in found
    rivals = found["intermediate_shaft_runout"]["indistinguishable_from"]
    assert {"gear_eccentricity", "wheel_radial_composite", "wheel_eccentricity"} <= set(rivals)


def test_orders_aliased_by_even_target_spacing_are_unobservable(mch50_spec):
    # 24 evenly spaced targets: orders 144 and 240 fall on a constant (144 x 15 deg = 6 turns)
    meas, _ = make_measurement(mch50_spec, Plan(kind="even"), hidden={"gear_mesh_error":
                                                                      {"amplitude_um": 2.0, "phase_deg": 0.0}}, seed=2)
    doc = report(diagnose(mch50_spec, meas, resamples=30))
    status = {c["name"]: c for c in doc["candidates"]}
    for name in ("gear_mesh_error", "worm_runout"):
        assert status[name]["status"] == "unobservable"
        assert "aliased" in status[name]["reason"]
        assert "dense scan" in status[name]["remedy"] or "irregular" in status[name]["remedy"]
    assert "gear_mesh_error" not in [e["name"] for e in doc["effects_found"]]


def test_signals_that_do_not_vary_make_their_effects_unobservable(mch50_spec):
    # one direction, no temperature column, no load column
    meas, _ = make_measurement(mch50_spec, Plan(directions=(1,), runs=4), seed=4)
    doc = report(diagnose(mch50_spec, meas, resamples=20))
    status = {c["name"]: c for c in doc["candidates"]}
    for name in ("thermal_backlash", "thermal_drift", "torsional_compliance", "bearing_clearance"):
        assert status[name]["status"] == "unobservable", name
    assert "temperature_C" in status["thermal_drift"]["reason"] and "warm-up" in status["thermal_drift"]["remedy"]
    assert "load" in status["torsional_compliance"]["reason"] + status["torsional_compliance"]["remedy"]
    assert "direction" in status["bearing_clearance"]["reason"]


def test_less_lost_motion_than_modelled_is_not_forced_onto_bearing_clearance(mch50_spec):
    meas, _ = make_measurement(mch50_spec, Plan(), hidden={"bearing_clearance": {"clearance_arcsec": -4.0}}, seed=6)
    doc = report(diagnose(mch50_spec, meas, resamples=20))
    assert doc["effects_found"] == []
    status = {c["name"]: c for c in doc["candidates"]}["bearing_clearance"]
    assert status["status"] == "unphysical"
    assert "less lost motion" in status["remedy"]
    assert any(u["kind"] == "reversal" for u in doc["unexplained"])
