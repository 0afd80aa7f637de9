"""The stage models: limits, branch safety, accurate maxima, monotonicity, units."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.support.specs import deflections
from wormgear_cli.analysis.accuracy import analyze
from wormgear_cli.physics import deformation, worm
from wormgear_cli.physics import spur as gear
from wormgear_cli.spec.loader import with_values
from wormgear_cli.units import ANGLE_UNITS, PAPER_ARCMIN_CONSTANT, from_unit, to_unit

ALPHA = math.radians(20.0)


def paper_bracket_as_printed(phi, l, de, alpha):
    """The paper's bracket written literally (with atan(tan)); valid only for |phi| < pi."""
    a = (l + de) / de
    return (2 * np.arctan(np.sqrt((a + 1) / (a - 1)) * np.tan(phi / 2))
            - (phi - np.tan(alpha) * np.log(1 + 2 * a * (1 - np.cos(phi)) / (a - 1) ** 2)))


# --- gear stage -----------------------------------------------------------------------------------


def test_bracket_matches_the_printed_formula_away_from_pi():
    phi = np.linspace(-3.0, 3.0, 601)
    for de in (1e-3, 0.03, 0.5):
        ours = gear.kinematic_bracket(phi, 202.5, de, ALPHA)
        printed = paper_bracket_as_printed(phi, 202.5, de, ALPHA)
        np.testing.assert_allclose(ours, printed, rtol=1e-7, atol=1e-15)


def test_bracket_is_continuous_through_pi():
    """atan(tan(phi/2)) jumps by 2 pi at phi = pi; the branch-safe form must not."""
    eps = 1e-9
    left = gear.kinematic_bracket(math.pi - eps, 202.5, 0.03, ALPHA)
    right = gear.kinematic_bracket(math.pi + eps, 202.5, 0.03, ALPHA)
    assert abs(left - right) < 1e-12
    phi = np.linspace(0, 4 * np.pi, 40001)
    f = gear.kinematic_bracket(phi, 202.5, 0.03, ALPHA)
    assert np.max(np.abs(np.diff(f))) < 1e-6  # smooth, small steps everywhere
    # periodic in phi with period 2 pi
    np.testing.assert_allclose(gear.kinematic_bracket(phi + 2 * np.pi, 202.5, 0.03, ALPHA), f, atol=1e-15)


def test_zero_eccentricity_gives_exactly_zero():
    phi = np.linspace(-10, 10, 101)
    f = gear.kinematic_bracket(phi, 202.5, 0.0, ALPHA)
    assert np.all(f == 0.0)
    value, where = gear.gear_te_max(22.5, 180.0, 0.0, ALPHA, 0.0)
    assert value == 0.0 and where == 0.0
    assert not np.isnan(gear.gear_te(phi, 22.5, 180.0, 0.0, ALPHA, 0.0)).any()
    assert gear.contact_phase_angle(1.0, 202.5, 0.0) == 0.0


def test_small_eccentricity_limit_of_the_maximum():
    """For de << l: k - 1 ~ de/l and ln(1 + x) ~ x, so the bracket ~ (de/l)(sin phi + c (1 - cos phi))
    with c = 2 tan(alpha); its maximum is (de/l)(c + sqrt(1 + c^2)) (derived by hand), times (l/2R2)."""
    r1, r2, de = 22.5, 180.0, 1e-5
    l = r1 + r2
    c = 2 * math.tan(ALPHA)
    expected = l / (2 * r2) * de / l * (c + math.sqrt(1 + c**2))
    value, where = gear.gear_te_max(r1, r2, de, ALPHA, 0.0)
    assert value == pytest.approx(expected, rel=1e-4)
    # argmax: cos(phi) + c sin(phi) = 0, i.e. tan(phi) = -1/c in the second quadrant
    assert where == pytest.approx(math.pi - math.atan(1 / c), abs=1e-3)


@settings(max_examples=40, deadline=None)
@given(
    r1=st.floats(5.0, 200.0), ratio=st.floats(1.0, 20.0), de=st.floats(0.0, 0.5),
    alpha_deg=st.floats(10.0, 30.0), d1=st.floats(0.0, 0.02),
)
def test_maximum_agrees_with_a_bounded_optimiser(r1, ratio, de, alpha_deg, d1):
    from scipy.optimize import minimize_scalar

    r2 = r1 * ratio
    alpha = math.radians(alpha_deg)
    phi = np.linspace(0, 2 * np.pi, 3601)
    f = gear.gear_te(phi, r1, r2, de, alpha, d1)
    k = int(np.argmax(f))
    res = minimize_scalar(lambda x: -float(gear.gear_te(x, r1, r2, de, alpha, d1)),
                          bounds=(phi[k] - 0.01, phi[k] + 0.01), method="bounded",
                          options={"xatol": 1e-12})
    reference = max(-res.fun, float(f[k]))
    value, _ = gear.gear_te_max(r1, r2, de, alpha, d1)
    assert value == pytest.approx(reference, rel=1e-9, abs=1e-18)


def test_maximum_is_vectorised():
    r1 = np.array([10.0, 22.5, 40.0])
    v, w = gear.gear_te_max(r1, 180.0, 0.03, ALPHA, 0.0)
    assert v.shape == (3,) and w.shape == (3,)
    for k in range(3):
        assert v[k] == pytest.approx(float(gear.gear_te_max(r1[k], 180.0, 0.03, ALPHA, 0.0)[0]), rel=1e-12)


def test_gear_backlash_max_by_hand():
    """De = 30 um, alpha = 20 deg, delta1 = 4 um, m = 2.5 mm, z = 144, at |sin phi| = 1:
    Delta C = 2 De tan(alpha) + 2 delta1 = 0.060 * 0.3639702 + 0.008 = 0.0298382 mm;
    Delta phi_ch = 2 Delta C / (m z) = 0.0596764 / 360 = 1.657679e-4 rad = 34.1921 arcsec
    (the paper's 6.875 / (m z) arcmin per um of arc: 6.875 * 29.8382 / 360 = 0.56983 arcmin)."""
    value = gear.gear_backlash_max(2.5, 144, 0.030, ALPHA, 0.004)
    assert value == pytest.approx(1.657679e-4, abs=5e-11)
    assert to_unit(value, "arcsec") == pytest.approx(34.1921, abs=5e-5)
    assert to_unit(value, "arcmin") == pytest.approx(0.56983, rel=2e-4)   # 6.875 is 180*60*2/(pi*1000) to 4 digits


# --- worm stage -----------------------------------------------------------------------------------


def test_worm_te_single_source_in_paper_units():
    """Only a lead error f_hL: Delta phi_wc = 6.875/(m z3) * f_hL/2 arcmin (f in um)."""
    h = worm.worm_te_halfwidth(0.030, 0, 0, 0, 0, 0, math.radians(3.178), math.radians(20.03))
    value = worm.worm_te(0.0, h, 2.5, 30)
    assert to_unit(value, "arcmin") == pytest.approx(6.875 / 75 * 15.0, rel=1e-4)


def test_worm_te_is_root_sum_square():
    """f_hL 3, S1 4, F_i 12 um, lambda 5 deg (cos^2 = 0.9924039): 9e-6 + 1.6e-5/0.9924039 + 1.44e-4
    = 1.6912254e-4 mm^2 -> h = sqrt/2 = 6.502355e-3 mm (all six sources: test_hand_worked.py)."""
    lam, a2 = math.radians(5.0), math.radians(20.0)
    h = worm.worm_te_halfwidth(0.003, 0.004, 0.0, 0.012, 0.0, 0.0, lam, a2)
    assert h == pytest.approx(6.502355e-3, rel=1e-6)


def test_paper_constant_6875():
    assert PAPER_ARCMIN_CONSTANT == pytest.approx(6.875, abs=5e-4)
    # 1 um of arc on a pitch diameter of 1 mm is 2e-3 rad = 6.875 arcmin
    assert to_unit(gear.pitch_arc_to_angle(1e-3, 1.0, 1), "arcmin") == pytest.approx(6.8755, abs=1e-4)


# --- deformation ----------------------------------------------------------------------------------


def test_iso6336_theoretical_stiffness_check_value():
    """ISO/TR 6336-30 example (reference-facts.md): m_n 8, z 17/103, beta 15.8 deg, x1 0.145 -> c'_th 17.856."""
    beta, an = math.radians(15.8), math.radians(20.0)
    beta_b = math.asin(math.sin(beta) * math.cos(an))
    zn = [z / (math.cos(beta) * math.cos(beta_b) ** 2) for z in (17, 103)]
    c = deformation.iso6336_theoretical_stiffness(zn[0], zn[1], x1=0.145, x2=0.0)
    assert c == pytest.approx(17.856, abs=5e-4)  # half a unit of the published last digit


def test_deflection_is_linear_in_load(mch50_spec):
    # ISO 6336-1 is linear only at line loads F_t K_A / b >= 100 N/mm (b = 50 / 37.5 mm: F_N >= 5400 N);
    # below, c' scales with (w/100)^0.25 (tests/physics/test_deformation.py)
    for model, f in (("iso6336", 6000.0), ("empirical", 100.0)):
        s = with_values(mch50_spec, {"stiffness.model": model})
        one = deflections(s, gear_force=f, worm_force=f)
        two = deflections(s, gear_force=2 * f, worm_force=2 * f)
        assert two.gear == pytest.approx(2 * one.gear) and two.worm == pytest.approx(2 * one.worm)
        zero = deflections(s, gear_force=0.0, worm_force=0.0)
        assert zero.gear == 0.0 and zero.worm == 0.0


def test_spur_contact_ratio_of_a_standard_pair():
    # 20 deg, z = 20/40, h* = 1: eps_alpha = 1.635186 (hand calculation from ISO 21771 geometry,
    # worked step by step in test_hand_worked.py::test_spur_contact_ratio_by_hand)
    assert deformation.spur_contact_ratio(20, 40, ALPHA) == pytest.approx(1.635186, abs=2e-6)


# --- whole drive: limits and monotonicity ---------------------------------------------------------

ERROR_KEYS = [
    "assembly.gear_centre_distance_error_mm",
    "assembly.worm_centre_distance_error_mm",
    "assembly.worm_eccentricity_mm",
    "assembly.worm_bearing_clearance_mm",
    "assembly.wheel_eccentricity_mm",
    "assembly.wheel_bearing_clearance_mm",
    "worm_pair.lead_error_mm",
    "worm_pair.worm.profile_error_mm",
    "worm_pair.wheel.profile_error_mm",
    "worm_pair.worm.thickness_deviation_mm",
    "worm_pair.wheel.thickness_deviation_mm",
    "worm_pair.wheel.radial_composite_error_mm",
    "loads.gear_normal_force_N",
    "loads.worm_normal_force_N",
]


def zeroed(spec):
    changes = dict.fromkeys(ERROR_KEYS, 0.0)
    changes["assembly.worm_pair_errors_mm"] = [0.0] * 6
    changes["assembly.gear_eccentricity_mm"] = 0.0
    return with_values(spec, changes)


def test_all_errors_zero_gives_zero(mch50_spec):
    a = analyze(zeroed(mch50_spec))
    for name, value in a.angles.items():
        assert value == 0.0, name


def test_zero_loads_remove_only_the_deformation_parts(mch50_spec):
    a = analyze(with_values(mch50_spec, {"loads.gear_normal_force_N": 0.0, "loads.worm_normal_force_N": 0.0}))
    for part in ("gear_te_deformation", "gear_backlash_deformation", "worm_te_deformation",
                 "worm_backlash_deformation"):
        assert a.angles[part] == 0.0
    assert a.angles["gear_transmission_error"] > 0 and a.info["gear_load_share_pct"] == 0.0


@pytest.mark.parametrize("key", ERROR_KEYS + ["assembly.gear_eccentricity_mm"])
def test_each_error_source_is_monotonic(mch50_spec, key):
    values = np.linspace(0.0, 0.08 if key.endswith("_mm") else 2000.0, 6)
    totals = [analyze(with_values(mch50_spec, {key: float(v)})).angles for v in values]
    for metric in ("total_transmission_error", "total_backlash"):
        series = [t[metric] for t in totals]
        assert all(b >= a - 1e-15 for a, b in zip(series, series[1:])), (key, metric, series)
    # every source moves at least one of the totals
    moved = [totals[-1][m] - totals[0][m] for m in ("total_transmission_error", "total_backlash")]
    assert max(moved) > 0, key


def test_totals_aggregate_through_the_ratio(mch50_spec):
    a = analyze(mch50_spec).angles
    i_c = 144 / 18
    assert a["total_transmission_error"] == pytest.approx(a["gear_transmission_error"]
                                                          + a["worm_transmission_error"] / i_c)
    assert a["total_backlash"] == pytest.approx(a["gear_backlash"] + a["worm_backlash"] / i_c)


# --- units ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("unit, rad", [
    ("deg", 0.017453292519943295),      # pi/180
    ("arcmin", 2.908882086657216e-4),   # pi/10800
    ("arcsec", 4.84813681109536e-6),    # pi/648000
    ("urad", 1e-6),
])
def test_each_unit_in_radians(unit, rad):
    """One unit of each kind in radians, written out (not derived from the package's table)."""
    assert from_unit(1.0, unit) == pytest.approx(rad, rel=1e-15)
    assert to_unit(rad * 2.5, unit) == pytest.approx(2.5, rel=1e-15)
    assert unit in ANGLE_UNITS


def test_unit_facts():
    assert to_unit(from_unit(1.0, "arcsec"), "urad") == pytest.approx(4.8481, abs=1e-4)
    assert to_unit(from_unit(1.0, "deg"), "arcsec") == pytest.approx(3600.0)
    assert to_unit(from_unit(1.0, "deg"), "arcmin") == pytest.approx(60.0)
