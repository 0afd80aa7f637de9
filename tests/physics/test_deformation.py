"""ISO 6336-1 single stiffness below a line load of 100 N/mm (clause 9, method B):
c' = c'_th C_M C_R C_B cos(beta) ((F_t K_A / b) / 100)^0.25."""

from __future__ import annotations

import math

import pytest

from tests.support.specs import deflections, line_loads
from wormgear_cli.physics import deformation
from wormgear_cli.spec.loader import with_values


@pytest.mark.parametrize("w, factor", [(12.5, 0.5946), (2.0, 0.3761), (100.0, 1.0), (250.0, 1.0), (0.0, 0.0)])
def test_low_load_factor(w, factor):
    # hand: 0.125^0.25 = 0.5946, 0.02^0.25 = 0.3761
    assert float(deformation.iso6336_low_load_factor(w)) == pytest.approx(factor, abs=1e-4)


def test_mch50_line_loads_and_delta1_by_hand(mch50_spec):
    # hand: F_t = 666 cos 20 = 625.8 N on b = 50 mm -> 12.52 N/mm; worm 85 cos 20 cos 3.178 = 79.75 N / 37.5 mm
    w_gear, w_worm = line_loads(mch50_spec)
    assert w_gear == pytest.approx(12.52, abs=0.01) and w_worm == pytest.approx(2.127, abs=0.005)
    # hand: q' = 0.04723 + 0.15551/18 + 0.25791/144 = 0.057660 -> c'_th = 17.343; c' = 17.343 x 0.8 x 0.975
    # = 13.528; x 0.12517^0.25 = 0.5948 -> 8.046 N/(mm um); delta1 = 625.8 / (50 x 8.046) = 1.556 um
    assert deflections(mch50_spec).gear * 1e3 == pytest.approx(1.556, abs=0.002)


def test_below_100_N_per_mm_the_deflection_grows_as_force_to_the_0_75(mch50_spec):
    one = deflections(mch50_spec, gear_force=100.0, worm_force=100.0)
    two = deflections(mch50_spec, gear_force=200.0, worm_force=200.0)
    assert two.gear / one.gear == pytest.approx(2 ** 0.75, rel=1e-12)
    assert two.worm / one.worm == pytest.approx(2 ** 0.75, rel=1e-12)


def test_application_factor_enters_the_line_load(mch50_spec):
    # K_A = 8 lifts 12.5 N/mm to 100 N/mm: c' unreduced, delta1 = 625.8 / (50 x 13.528) = 0.925 um (hand)
    s = with_values(mch50_spec, {"stiffness.iso_ka": 8.0})
    assert deflections(s).gear * 1e3 == pytest.approx(0.925, abs=0.002)


def test_linearised_compliance_holds_c_prime_at_the_spec_load(mch50_spec):
    lin1 = deflections(mch50_spec, gear_force=1.0, worm_force=1.0, linear_at_spec_load=True)
    spec = deflections(mch50_spec)
    # the secant through the operating point: 666 N x (mm per N) = delta1 at 666 N
    assert lin1.gear * 666.0 == pytest.approx(spec.gear, rel=1e-12)
    assert math.isfinite(lin1.worm) and lin1.worm > 0


def test_the_legacy_two_stage_helpers_warn_and_give_the_trains_values(mch50_spec):
    """The helpers of analysis.accuracy that read a worm + spur drive by its legacy sections are deprecated:
    each warns, naming its replacement, and gives what the train's own definition gives."""
    from wormgear_cli.analysis import accuracy
    from wormgear_cli.drive.worm import paper

    worm, gear = mch50_spec.stages
    with pytest.warns(DeprecationWarning, match=r"drive\.stiffness\.deflection"):
        old = accuracy.deflections(mch50_spec)
    new = deflections(mch50_spec)
    assert (old.gear, old.worm) == (new.gear, new.worm)
    with pytest.warns(DeprecationWarning, match=r"drive\.stiffness\.line_load"):
        assert accuracy.line_loads(mch50_spec) == line_loads(mch50_spec)
    with pytest.warns(DeprecationWarning, match="model_eccentricity"):
        assert accuracy.gear_eccentricity(mch50_spec) == gear.model_eccentricity == 0.030
    with pytest.warns(DeprecationWarning, match=r"drive\.worm\.paper"):
        assert accuracy.worm_stage(mch50_spec, 0.001) == paper(worm, 0.001)
