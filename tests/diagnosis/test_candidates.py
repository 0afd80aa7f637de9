"""Catalogue effects as candidate columns."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.diagnosis_data import Plan, make_measurement
from wormgear_cli import diagnosis as dg
from wormgear_cli.diagnosis import diagnose, report


def test_candidate_columns_recognise_the_three_signature_forms(mch50_spec):
    from wormgear_cli.analysis.accuracy import geometry
    from wormgear_cli.physics.effects import Signals

    sig = Signals(np.linspace(0, 6, 50), np.ones(50), np.linspace(-100, 100, 50), np.linspace(20, 30, 50),
                  np.zeros(50))
    g = geometry(mch50_spec)
    assert dg.candidate("gear_mesh_error", sig, g).kind is dg.CandidateKind.PERIODIC
    assert dg.candidate("torsional_compliance", sig, g).kind is dg.CandidateKind.RECIPROCAL
    assert dg.candidate("thermal_drift", sig, g).kind is dg.CandidateKind.LINEAR
    c = dg.candidate("output_gear_runout", sig, g)
    params = dg.candidate_params(c, np.array([0.003, 0.004]))
    assert params["eccentricity"] == pytest.approx(0.005) and params["phase"] == pytest.approx(math.atan2(4, 3))


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
