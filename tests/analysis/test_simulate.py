"""Tests of the simulation core (:mod:`wormgear_cli.analysis.simulate`): error sources, phases, lost motion."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.support.paths import MCH50
from wormgear_cli.analysis.accuracy import analyze
from wormgear_cli.analysis.simulate import aligned_phases, compliance, components, max_reversal, simulate
from wormgear_cli.physics.effects import Signals
from wormgear_cli.spec.loader import load_spec, with_values
from wormgear_cli.units import RAD_PER_UNIT

AS = RAD_PER_UNIT["arcsec"]
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
    from tests.support.independent_model import perfect_spec

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
    from tests.support.independent_model import perfect_spec

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

