"""The independent data generator of the diagnosis tests agrees with the effect registry."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.diagnosis_data import ARCSEC, CASES, Plan, hidden_error, make_rows


@pytest.mark.parametrize("name", sorted(CASES))
def test_hand_written_formula_matches_the_registry(name, mch50_spec):
    from wormgear_cli.analysis.accuracy import geometry
    from wormgear_cli.physics.effects import EFFECTS, Signals, params_from_keys

    rng = np.random.default_rng(5)
    theta = rng.uniform(0, 2 * np.pi, 500)
    d = np.where(rng.uniform(size=500) < 0.5, 1.0, -1.0)
    load = rng.uniform(-300, 300, 500)
    temp = rng.uniform(15, 40, 500)
    sig = Signals(theta, d, load, temp, np.zeros(500))
    reg = EFFECTS[name].function(sig, geometry(mch50_spec), **params_from_keys(name, CASES[name])) / ARCSEC
    mine = hidden_error(name, CASES[name], theta, d, load, temp)
    assert np.allclose(mine, reg, rtol=1e-9, atol=1e-9)


def test_plan_rows_follow_the_iso_cycle():
    rows = make_rows(Plan(runs=2, warmup=(20, 30, 100), loads=(0, 50)), np.random.default_rng(0))
    assert rows["angle_deg"].shape == (96,)
    # each run: forward ascending then reverse descending over the same targets
    fwd, rev = rows["angle_deg"][:24], rows["angle_deg"][24:48]
    assert np.all(np.diff(fwd) > 0) and np.array_equal(rev, fwd[::-1])
    assert list(np.unique(rows["load_Nm"][rows["run"] == 2])) == [50.0]
    assert rows["temperature_C"][0] == 20.0 and rows["temperature_C"][-1] > 29.0
