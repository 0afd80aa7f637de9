"""The stage models checked against numbers worked by hand, with explicit arguments.

Every expected value below is written out step by step in the comments (a pocket
calculator reproduces each line); none is taken from the code's output and none
re-types the implementation.  Inputs are chosen so that each term is non-zero and
distinct (swapping two arguments, dropping a term or squaring where the source does not
changes the result), and so the arithmetic stays short: tan(lambda) = 0.1 gives
cos^2(lambda) = 1/1.01, tan(alpha_2) = 0.4 gives cos^2(alpha_2) = 1/1.16.
Tolerances: 1e-9 relative where the hand value is exact to that many digits, otherwise
the digits written.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from wormgear_cli.physics import deformation, thermal, worm
from wormgear_cli.physics import spur as gear

LAM = math.atan(0.1)  # lead angle: cos^2 = 1/1.01, 1/cos = sqrt(1.01) = 1.004987562
ALPHA2 = math.atan(0.4)  # wheel transverse pressure angle: cos^2 = 1/1.16


# --- worm stage: the paper's Delta phi_wc and Delta phi_wh with every input non-zero ------------


def test_worm_te_halfwidth_every_term_by_hand():
    """f_hL 10, S1 8, C1 6, F_i 20, S2 12, C2 5 um:
    f_hL^2                      = 1.00e-4
    (S1^2 + C1^2)/cos^2(lam)    = (6.4e-5 + 3.6e-5) * 1.01 = 1.0100e-4
    F_i^2                       = 4.00e-4
    (S2^2 + C2^2)/cos^2(alpha2) = (1.44e-4 + 2.5e-5) * 1.16 = 1.9604e-4
    sum = 7.9704e-4 mm^2, h = sqrt(sum)/2 = 0.028231897/2 = 0.0141159484 mm."""
    h = worm.worm_te_halfwidth(0.010, 0.008, 0.006, 0.020, 0.012, 0.005, LAM, ALPHA2)
    assert h == pytest.approx(0.01411594843, rel=1e-9)


@pytest.mark.parametrize("position, contribution", [
    (0, 1.00e-4),            # f_hL alone
    (1, 6.4e-5 * 1.01),      # S1 / cos(lambda)
    (2, 3.6e-5 * 1.01),      # C1 / cos(lambda)
    (3, 4.00e-4),            # F_i alone
    (4, 1.44e-4 * 1.16),     # S2 / cos(alpha_2)
    (5, 2.5e-5 * 1.16),      # C2 / cos(alpha_2)
])
def test_worm_te_halfwidth_each_source_alone(position, contribution):
    """One source at a time: h = sqrt(its squared contribution)/2 (the angle each is divided by pinned)."""
    values = [0.0] * 6
    values[position] = (0.010, 0.008, 0.006, 0.020, 0.012, 0.005)[position]
    h = worm.worm_te_halfwidth(*values, LAM, ALPHA2)
    assert h == pytest.approx(0.5 * math.sqrt(contribution), rel=1e-9)


def test_worm_te_bound_by_hand():
    """Delta phi_wc = 2 (delta2 + h)/(m z3) = 2 (0.003 + 0.01411598)/(2.5 * 30) = 4.564253e-4 rad;
    in the paper's form 6.875/(m z3) * (3 + 14.11598) um = 1.5691 arcmin."""
    h = worm.worm_te_halfwidth(0.010, 0.008, 0.006, 0.020, 0.012, 0.005, LAM, ALPHA2)
    value = worm.worm_te(0.003, h, 2.5, 30)
    assert value == pytest.approx(4.564253e-4, rel=1e-6)
    assert value / (math.pi / 10800) == pytest.approx(6.875 / 75 * 17.11598, rel=1e-4)


def test_worm_backlash_halfwidth_every_term_by_hand():
    """f_t1 4, f_t2 6, T_s1 30, T_s2 60 um, sum e_i^2 2e-6 mm^2, f_hL 10, f_a 15, F_i 20 um:
    0.126 (f_t1^2 + f_t2^2)              = 0.126 * 5.2e-5            = 6.552e-6
    (T_s1^2 + T_s2^2)/(36 cos^2 lam)      = 4.5e-3 * 1.01 / 36        = 1.2625e-4
    4 (sum e^2 + f_hL^2)                 = 4 * (2e-6 + 1e-4)         = 4.08e-4
    (4 f_a^2 + F_i^2)/(9 tan alpha2)     = (9e-4 + 4e-4) / 3.6       = 3.611111e-4
    sum = 9.019131e-4, h_j = sqrt(sum)/2 = 0.01501593413 mm."""
    h = worm.worm_backlash_halfwidth(0.004, 0.006, 0.030, 0.060, 2e-6, 0.010, 0.015, 0.020, LAM, ALPHA2)
    assert h == pytest.approx(0.01501593413, rel=1e-9)


def test_worm_backlash_last_term_divides_by_9_tan_alpha2_as_printed():
    """Only f_a and F_i: h_j = sqrt((4 f_a^2 + F_i^2) / (9 tan alpha_2))/2.  With tan = 0.4 the
    printed 9 tan(alpha_2) = 3.6 gives sqrt(1.3e-3/3.6)/2 = 9.50146e-3 mm; 9 tan^2 (= 1.44)
    would give 1.50231e-2 and 9/tan (= 22.5) 3.80058e-3."""
    h = worm.worm_backlash_halfwidth(0, 0, 0, 0, 0.0, 0, 0.015, 0.020, LAM, ALPHA2)
    assert h == pytest.approx(9.501462e-3, rel=1e-6)
    # and with another angle: tan = 0.25 -> 9 tan = 2.25 -> sqrt(1.3e-3/2.25)/2 = 1.201850e-2
    h = worm.worm_backlash_halfwidth(0, 0, 0, 0, 0.0, 0, 0.015, 0.020, LAM, math.atan(0.25))
    assert h == pytest.approx(1.2018504e-2, rel=1e-6)


def test_worm_backlash_central_terms_by_hand():
    """delta2 2 um, f_t 4 + 6 um, T_s 30 + 60 um, tan(lam) = 0.1 (1/cos = 1.004987562):
    deformation 2 * 0.002 * 1.004987562 = 4.019950e-3; profile 1.06 * 0.010 = 0.0106;
    thickness 0.090 / 2 * 1.004987562 = 4.522444e-2 mm."""
    d, p, t = worm.worm_backlash_central(0.002, 0.004, 0.006, 0.030, 0.060, LAM)
    assert d == pytest.approx(4.019950e-3, rel=1e-6)
    assert p == pytest.approx(0.0106, rel=1e-12)
    assert t == pytest.approx(4.522444e-2, rel=1e-6)


def test_worm_backlash_bound_by_hand():
    """Delta phi_wh = 2 (central + h_j)/(m z3) = 2 (0.05 + 0.01)/(2 * 40) = 1.5e-3 rad."""
    assert worm.worm_backlash(0.05, 0.01, 2.0, 40) == pytest.approx(1.5e-3, rel=1e-12)


def test_wheel_transverse_pressure_angle_by_hand():
    """alpha_n 20 deg, lambda 5 deg: tan(alpha_x) = 0.3639702 / 0.9961947 = 0.3653605 -> 20.07031 deg
    (DIN 3975 ZN relation); lambda 0 leaves the angle unchanged."""
    from wormgear_cli.spec.stages import wheel_transverse_pressure_angle  # the one the loader derives with

    a = wheel_transverse_pressure_angle(math.radians(20.0), math.radians(5.0))
    assert math.degrees(a) == pytest.approx(20.07031, abs=1e-5)
    assert wheel_transverse_pressure_angle(0.3, 0.0) == pytest.approx(0.3, rel=1e-12)


# --- spur stage -------------------------------------------------------------------------------


def test_pitch_arc_to_angle_by_hand():
    """2 * 0.003 mm / (2 mm * 50) = 6e-5 rad."""
    assert gear.pitch_arc_to_angle(0.003, 2.0, 50) == pytest.approx(6e-5, rel=1e-12)


def test_gear_backlash_by_hand():
    """Delta C1 = 2 de tan(alpha) |sin phi| + 2 delta1: de 20 um, tan 0.4, phi 30 deg, delta1 1 um ->
    2*0.02*0.4*0.5 + 0.002 = 0.010 mm -> 2*0.010/(2*50) = 2e-4 rad; the same at phi = -30 deg
    (|sin|); the maximum (|sin| = 1): (0.016 + 0.002)*2/100 = 3.6e-4 rad."""
    a = math.atan(0.4)
    assert gear.gear_backlash(math.pi / 6, 2.0, 50, 0.02, a, 0.001) == pytest.approx(2e-4, rel=1e-12)
    assert gear.gear_backlash(-math.pi / 6, 2.0, 50, 0.02, a, 0.001) == pytest.approx(2e-4, rel=1e-12)
    assert gear.gear_backlash_max(2.0, 50, 0.02, a, 0.001) == pytest.approx(3.6e-4, rel=1e-12)


def test_eccentricity_ratio_and_contact_phase_by_hand():
    """A = (l + de)/de = 100.5/0.5 = 201; lambda1(pi/2) = atan(0.5/(100 + 0.5)) = 4.975083e-3 rad;
    lambda1(pi) = atan(0/(100 + 1)) = 0; lambda1(-pi/2) = -4.975083e-3."""
    assert gear.eccentricity_ratio(100.0, 0.5) == pytest.approx(201.0, rel=1e-12)
    assert gear.contact_phase_angle(math.pi / 2, 100.0, 0.5) == pytest.approx(4.9750837e-3, rel=1e-7)
    assert gear.contact_phase_angle(-math.pi / 2, 100.0, 0.5) == pytest.approx(-4.9750837e-3, rel=1e-7)
    assert gear.contact_phase_angle(math.pi, 100.0, 0.5) == pytest.approx(0.0, abs=1e-15)


def test_kinematic_bracket_at_quarter_and_half_turn_by_hand():
    """l 100, de 0.5 (A = 201), tan(alpha) 0.4.  The paper's bracket
    F = 2 atan(k tan(phi/2)) - phi + tan(alpha) ln(1 + 2A(1 - cos phi)/(A - 1)^2), k^2 = (A+1)/(A-1) = 1.01:
    phi = pi:   the atan part is 2 * pi/2 - pi = 0, ln(1 + 4*201/40000) = ln(1.0201) = 0.01990131
                -> F = 0.4 * 0.01990131 = 7.960525e-3
    phi = pi/2: 2 atan(1.004987562) - pi/2 = 4.975145e-3,
                ln(1 + 402/40000) = ln(1.01005) = 9.999835e-3 -> F = 4.975145e-3 + 3.999934e-3 = 8.975079e-3."""
    a = math.atan(0.4)
    assert gear.kinematic_bracket(math.pi, 100.0, 0.5, a) == pytest.approx(7.960265e-3, rel=1e-6)
    assert gear.kinematic_bracket(math.pi / 2, 100.0, 0.5, a) == pytest.approx(4.975145e-3 + 3.999934e-3,
                                                                                rel=1e-6)


def test_gear_te_parts_by_hand():
    """R1 20, R2 80 (l = 100), de 0.5, tan(alpha) 0.4, delta1 2 um, phi = pi:
    kinematic: l/(2 R2) F = 100/160 * 7.960265e-3 = 4.975166e-3 rad;
    load: delta1 sin(alpha + lambda1)/R2 with lambda1(pi) = 0: 0.002 * 0.3713907 / 80 = 9.284767e-6 rad."""
    a = math.atan(0.4)
    kin = gear.gear_kinematic_te(math.pi, 20.0, 80.0, 0.5, a)
    load = gear.gear_deformation_te(math.pi, 20.0, 80.0, 0.5, a, 0.002)
    assert kin == pytest.approx(4.975166e-3, rel=1e-6)
    assert load == pytest.approx(9.284767e-6, rel=1e-6)
    assert gear.gear_te(math.pi, 20.0, 80.0, 0.5, a, 0.002) == pytest.approx(4.975166e-3 + 9.284767e-6, rel=1e-6)


def test_no_eccentricity_leaves_the_load_term():
    """de = 0: Delta phi_cc = delta1 sin(alpha)/R2 at every phi; 0.002 * 0.3713907/80 = 9.284767e-6."""
    a = math.atan(0.4)
    value, where = gear.gear_te_max(20.0, 80.0, 0.0, a, 0.002)
    assert value == pytest.approx(9.284767e-6, rel=1e-6)
    fast, _ = gear.gear_te_max_fast(20.0, 80.0, 0.0, a, 0.002)
    assert fast == pytest.approx(9.284767e-6, rel=1e-6)


@pytest.mark.parametrize("r1, r2, de, d1", [
    (20.0, 80.0, 0.05, 0.002), (22.5, 180.0, 0.03, 0.0), (22.5, 180.0, 0.03, 0.004),
    (10.0, 200.0, 0.5, 0.01), (40.0, 60.0, 0.001, 0.05),
])
def test_fast_maximum_agrees_with_dense_sampling(r1, r2, de, d1):
    """A second method: the maximum of Delta phi_cc on 200 001 samples of one turn (the curve is
    smooth, so sampling is within (2 pi / 2e5)^2 * |f''|/8 of the peak) against both maximisers."""
    a = math.radians(20.0)
    phi = np.linspace(0.0, 2 * np.pi, 200_001)
    dense = float(np.max(gear.gear_te(phi, r1, r2, de, a, d1)))
    for fn in (gear.gear_te_max, gear.gear_te_max_fast):
        value, where = fn(r1, r2, de, a, d1)
        assert float(value) == pytest.approx(dense, rel=1e-8)
        assert float(gear.gear_te(where, r1, r2, de, a, d1)) == pytest.approx(dense, rel=1e-8)
        assert 0.0 <= float(where) < 2 * np.pi


def test_kinematic_peak_matches_dense_sampling():
    """The kinematic peak (no load) of F: location and value against 200 001 samples."""
    a = math.radians(20.0)
    phi = np.linspace(0.0, 2 * np.pi, 200_001)
    f = gear.kinematic_bracket(phi, 202.5, 0.03, a)
    peak = gear.kinematic_peak(202.5, 0.03, a)
    assert float(peak.value if hasattr(peak, "value") else peak[1]) == pytest.approx(float(np.max(f)), rel=1e-9)
    assert float(peak[0]) == pytest.approx(float(phi[np.argmax(f)]), abs=1e-4)


def test_bracket_derivatives_match_finite_differences():
    """A second method: central differences of F (h = 1e-5) against the analytic F', F''."""
    a = math.radians(20.0)
    phi = np.linspace(0.1, 6.2, 13)
    h = 1e-5
    f = lambda x: gear.kinematic_bracket(x, 100.0, 0.5, a)  # noqa: E731
    f1, f2 = gear.kinematic_bracket_derivatives(phi, 100.0, 0.5, a)
    np.testing.assert_allclose(f1, (f(phi + h) - f(phi - h)) / (2 * h), rtol=1e-6, atol=1e-10)
    np.testing.assert_allclose(f2, (f(phi + h) - 2 * f(phi) + f(phi - h)) / h**2, rtol=1e-4, atol=1e-6)


def test_load_factor_derivatives_match_finite_differences():
    a = math.radians(20.0)
    phi = np.linspace(0.1, 6.2, 13)
    h = 1e-4
    hf = lambda x: np.sin(a + gear.contact_phase_angle(x, 100.0, 0.5))  # noqa: E731
    h0, h1, h2 = gear.load_factor_derivatives(phi, 100.0, 0.5, a)
    np.testing.assert_allclose(h0, hf(phi), rtol=1e-12)
    np.testing.assert_allclose(h1, (hf(phi + h) - hf(phi - h)) / (2 * h), rtol=1e-5, atol=1e-11)
    np.testing.assert_allclose(h2, (hf(phi + h) - 2 * hf(phi) + hf(phi - h)) / h**2, rtol=1e-3, atol=1e-6)


# --- deflection -------------------------------------------------------------------------------


def _tr6336_30_virtual_teeth():
    """z_n = z / (cos(beta) cos^2(beta_b)), sin(beta_b) = sin(beta) cos(alpha_n): 18.905, 114.543."""
    beta, an = math.radians(15.8), math.radians(20.0)
    beta_b = math.asin(math.sin(beta) * math.cos(an))
    return [z / (math.cos(beta) * math.cos(beta_b) ** 2) for z in (17, 103)]


def test_iso6336_theoretical_stiffness_tr6336_30_to_the_digits_given():
    """ISO/TR 6336-30 example: m_n 8, z 17/103, beta 15.8 deg, x1 0.145, x2 0 -> c'_th = 17.856
    N/(mm um), given to 3 decimals: the tolerance is half a unit of the last digit (5e-4, 2.8e-5
    relative).  A transposed digit in any C_i that moves q' by more than 0.003 % fails here
    (C1 0.04723 -> 0.04732 moves c'_th by 0.16 %)."""
    zn1, zn2 = _tr6336_30_virtual_teeth()
    c_th = deformation.iso6336_theoretical_stiffness(zn1, zn2, x1=0.145, x2=0.0)
    assert c_th == pytest.approx(17.856, abs=5e-4)


def test_iso6336_theoretical_stiffness_every_term_by_hand():
    """ISO 6336-1 q' with both profile shifts non-zero (z_n 20/50, x1 0.2, x2 0.4), term by term:
    C1 0.04723; C2/zn1 0.15551/20 = 0.0077755; C3/zn2 0.25791/50 = 0.0051582;
    C4 x1 = -0.00635*0.2 = -0.00127; C5 x1/zn1 = -0.11654*0.2/20 = -0.0011654;
    C6 x2 = -0.00193*0.4 = -0.000772; C7 x2/zn2 = -0.24188*0.4/50 = -0.00193504;
    C8 x1^2 = 0.00529*0.04 = 0.0002116; C9 x2^2 = 0.00182*0.16 = 0.0002912;
    q' = 0.05552406 -> c'_th = 18.010210.  Without shifts (defaults x = 0): q' = 0.0601637 -> 16.621318."""
    assert deformation.iso6336_theoretical_stiffness(20.0, 50.0, x1=0.2, x2=0.4) == pytest.approx(18.010210,
                                                                                                   rel=1e-7)
    assert deformation.iso6336_theoretical_stiffness(20.0, 50.0) == pytest.approx(16.621318, rel=1e-7)
    # a rack (zn2 = inf) drops the C3 and C7 terms: q' = 0.04723 + 0.0077755 = 0.0550055 -> 18.179999
    assert deformation.iso6336_theoretical_stiffness(20.0, np.inf) == pytest.approx(1 / 0.0550055, rel=1e-9)


def test_iso6336_single_stiffness_tr6336_30_to_the_digits_given():
    """The same example: c' = c'_th C_M C_R C_B cos(beta) = 12.370 with C_M 0.8, C_R 1 and the
    example's basic rack h_fP = 1.4 m_n, so C_B = 1 + 0.5 (1.2 - 1.4) = 0.9 (ISO 6336-1, alpha_n 20 deg).
    Chained from the published c'_th = 17.856 (not from the code's c'_th):
    17.856 * 0.8 * 1 * 0.9 * cos(15.8 deg) = 17.856 * 0.72 * 0.9622180 = 12.3706 (the rounding of the
    published c'_th, +-5e-4, moves this by +-3.5e-4: tolerance 1e-3); from the code's own c'_th the
    published 12.370 to half a unit of the last digit."""
    beta = math.radians(15.8)
    c = deformation.iso6336_single_stiffness(17.856, cm=0.8, cr=1.0, cb=0.9, helix_angle=beta)
    assert c == pytest.approx(12.370, abs=1e-3)
    zn1, zn2 = _tr6336_30_virtual_teeth()
    c_code = deformation.iso6336_single_stiffness(
        deformation.iso6336_theoretical_stiffness(zn1, zn2, x1=0.145), cm=0.8, cr=1.0, cb=0.9, helix_angle=beta)
    assert c_code == pytest.approx(12.370, abs=5e-4)


def test_iso6336_mesh_stiffness_tr6336_30():
    """c_gamma_alpha = c' (0.75 eps_alpha + 0.25) = 17.465 in the example.  The project has no
    c_gamma_alpha function (only c' enters the deflection), so this checks c' against the published
    mesh stiffness through the example's own relation: eps_alpha = (17.465/12.370 - 0.25)/0.75
    = 1.5492 must be the transverse contact ratio of the example's geometry.  Worked by hand from
    ISO 21771 (a_w 500 mm, tip diameters d + 2 m_n (1 + x), no tip shortening): 1.5495, so the
    code's c' times (0.75 * 1.5495 + 0.25) must give 17.465 within the rounding of eps (4e-4 rel)."""
    zn1, zn2 = _tr6336_30_virtual_teeth()
    c = deformation.iso6336_single_stiffness(deformation.iso6336_theoretical_stiffness(zn1, zn2, x1=0.145),
                                              cm=0.8, cr=1.0, cb=0.9, helix_angle=math.radians(15.8))
    assert c * (0.75 * 1.5495 + 0.25) == pytest.approx(17.465, rel=4e-4)


def test_iso6336_single_stiffness_defaults_and_modulus():
    """Defaults C_M 0.8, C_R 1, C_B 0.975, beta 0, E steel: 10 * 0.78 = 7.8; half the modulus (103 000)
    halves it (3.9); C_R 0.9 and beta 60 deg: 10 * 0.8 * 0.9 * 0.975 * 0.5 = 3.51."""
    assert deformation.iso6336_single_stiffness(10.0) == pytest.approx(7.8, rel=1e-12)
    assert deformation.iso6336_single_stiffness(10.0, modulus=103_000.0) == pytest.approx(3.9, rel=1e-12)
    assert deformation.iso6336_single_stiffness(10.0, cr=0.9, helix_angle=math.pi / 3) == pytest.approx(3.51,
                                                                                                        rel=1e-12)
    assert deformation.E_STEEL == 206_000.0


def test_iso6336_deflection_by_hand():
    """delta = F_t/(b c') = 1200 N / (20 mm * 14 N/(mm um)) = 4.285714 um = 4.285714e-3 mm."""
    assert deformation.iso6336_deflection(1200.0, 20.0, 14.0) == pytest.approx(4.2857143e-3, rel=1e-7)


def test_combined_modulus_by_hand():
    """E = 2 E1 E2/(E1 + E2): steel 206 000 with bronze 98 000 -> 4.0376e10/304 000 = 132 815.79 N/mm^2."""
    assert deformation.combined_modulus(206_000.0, 98_000.0) == pytest.approx(132_815.7895, rel=1e-9)
    assert deformation.combined_modulus(206_000.0, 206_000.0) == pytest.approx(206_000.0, rel=1e-12)


def test_empirical_deflection_by_hand():
    """delta = A1 F_N/((eps+1)^B (lambda2+1)^C E b): A1 2, F_N 1000, eps 1.5, lambda2 0.5, B 2, C 3,
    E 2e5, b 10 -> 2000/(2.5^2 * 1.5^3 * 2e6) = 2000/(6.25 * 3.375 * 2e6) = 4.7407407e-5 mm.
    Exponents distinct and neither 1: swapping them gives 2000/(15.625 * 2.25 * 2e6) = 2.8444444e-5,
    a product (eps+1) B instead of the power 2000/(5 * 3.375 * 2e6) = 5.9259259e-5."""
    d = deformation.empirical_deflection(1000.0, 2e5, 10.0, 1.5, 0.5, 2.0, 2.0, 3.0)
    assert d == pytest.approx(4.7407407e-5, rel=1e-7)


def test_spur_contact_ratio_by_hand():
    """ISO 21771 geometry per unit module, z 20/40, alpha 20 deg, h* 1:
    r_a 11, 21; r_b 9.396926, 18.793852; sqrt(121 - 88.302222) = 5.718197,
    sqrt(441 - 353.208889) = 9.369691; a sin(alpha) = 30 * 0.342020 = 10.260604;
    eps = (5.718197 + 9.369691 - 10.260604)/(pi * 0.939693) = 4.827284/2.952131 = 1.635186.
    With h* 0.8: r_a 10.8, 20.8 -> (5.323324 + 8.912413 - 10.260604)/2.952131 = 1.346530."""
    a = math.radians(20.0)
    assert deformation.spur_contact_ratio(20, 40, a) == pytest.approx(1.635186, abs=2e-6)
    assert deformation.spur_contact_ratio(20, 40, a, addendum_coefficient=0.8) == pytest.approx(1.346530, abs=2e-6)


# --- thermal ------------------------------------------------------------------------------------


def test_centre_distance_growth_by_hand():
    """a 100, r1 20, r2 80 mm; alpha_H 11, alpha_1 12, alpha_2 18 ppm/K; dT 10, 20, 30 K:
    100*11e-6*10 - (20*12e-6*20 + 80*18e-6*30) = 0.011 - (0.0048 + 0.0432) = -0.037 mm."""
    d = thermal.centre_distance_growth(100.0, 20.0, 80.0, 11e-6, 12e-6, 18e-6, 10.0, 20.0, 30.0)
    assert d == pytest.approx(-0.037, rel=1e-12)
    # default dT 1 K each: 100*11e-6 - (20*12e-6 + 80*18e-6) = 1.1e-3 - 1.68e-3 = -5.8e-4 mm/K
    assert thermal.centre_distance_growth(100.0, 20.0, 80.0, 11e-6, 12e-6, 18e-6) == pytest.approx(-5.8e-4,
                                                                                                   rel=1e-12)


def test_predicted_centre_distance_coefficient_by_hand():
    """One start, m 2 mm, tan(lambda) 0.05 -> d_m1 = 2/0.05 = 40, r1 20; wheel 60 teeth -> r2 60, a 80;
    iron 10.5, steel 11.5, bronze 18.5 ppm/K: 80*10.5e-6 - (20*11.5e-6 + 60*18.5e-6)
    = 8.4e-4 - 1.34e-3 = -5.0e-4 mm/K = -0.5 um/K."""
    spec = SimpleNamespace(
        worm_pair=SimpleNamespace(worm=SimpleNamespace(starts=1), module=2.0, lead_angle=math.atan(0.05),
                                  wheel=SimpleNamespace(teeth=60)),
        materials=SimpleNamespace(housing_expansion=10.5e-6, worm_expansion=11.5e-6, wheel_expansion=18.5e-6))
    assert thermal.predicted_centre_distance_um_per_K(spec) == pytest.approx(-0.5, rel=1e-9)


def _argmax_reference(f, lo=0.0, hi=2 * np.pi):
    """Location of the maximum by a second method: dense samples, then scipy's bounded optimiser."""
    from scipy.optimize import minimize_scalar

    phi = np.linspace(lo, hi, 20_001)
    k = int(np.argmax(f(phi)))
    res = minimize_scalar(lambda x: -float(f(x)), bounds=(phi[max(k - 1, 0)], phi[min(k + 1, phi.size - 1)]),
                          method="bounded", options={"xatol": 1e-12})
    return float(res.x)


@pytest.mark.parametrize("r1, r2, de, d1", [
    (20.0, 80.0, 0.5, 0.002), (20.0, 80.0, 1.0, 0.0), (22.5, 180.0, 0.03, 0.004), (40.0, 60.0, 0.2, 0.05),
    (10.0, 200.0, 2.0, 0.01),
])
def test_location_of_the_maximum_against_an_optimiser(r1, r2, de, d1):
    """Both maximisers return where the maximum is, not only its value (the value is flat at the
    peak, so a wrong location hides in it): within 1e-6 rad of scipy's bounded optimiser."""
    a = math.radians(20.0)
    want = _argmax_reference(lambda x: gear.gear_te(x, r1, r2, de, a, d1))
    for fn in (gear.gear_te_max, gear.gear_te_max_fast):
        _, where = fn(r1, r2, de, a, d1)
        assert float(where) == pytest.approx(want, abs=1e-6), fn.__name__


@pytest.mark.parametrize("l, de", [(100.0, 1.0), (100.0, 0.2), (202.5, 0.03)])
def test_kinematic_peak_location_against_an_optimiser(l, de):
    a = math.radians(20.0)
    want = _argmax_reference(lambda x: gear.kinematic_bracket(x, l, de, a))
    peak = gear.kinematic_peak(l, de, a)
    assert float(peak.phi0) == pytest.approx(want, abs=1e-6)
    assert float(peak.f0) == pytest.approx(float(gear.kinematic_bracket(want, l, de, a)), rel=1e-12)
    f1, f2 = gear.kinematic_bracket_derivatives(want, l, de, a)
    assert float(peak.f2) == pytest.approx(float(f2), rel=1e-5)


def test_fast_maximum_is_vectorised_like_the_scalar_calls():
    """Arrays of radii, eccentricities and loads give the same as one call per design."""
    a = math.radians(20.0)
    r1 = np.array([20.0, 22.5, 40.0])
    r2 = np.array([80.0, 180.0, 60.0])
    de = np.array([0.5, 0.03, 0.2])
    d1 = np.array([0.002, 0.0, 0.05])
    v, w = gear.gear_te_max_fast(r1, r2, de, a, d1)
    for k in range(3):
        vk, wk = gear.gear_te_max_fast(r1[k], r2[k], de[k], a, d1[k])
        assert v[k] == pytest.approx(float(vk), rel=1e-12) and w[k] == pytest.approx(float(wk), abs=1e-12)
        want = _argmax_reference(lambda x: gear.gear_te(x, r1[k], r2[k], de[k], a, d1[k]))  # noqa: B023
        assert w[k] == pytest.approx(want, abs=1e-6)


# --- mutation-testing round 2 (issue 13): the maximisers' fall-back and edge cases, involute stage --


def test_involute_stage_every_term_by_hand():
    """r1 50 mm, tan(alpha) 0.75 (cos 0.8): r_b1 = 40 mm; e 0.02, Delta a 0.01, delta 0.004, E_sn 0.06 mm:
    TE_e = 0.02/40 = 5e-4; TE_d = 0.004/40 = 1e-4; lost motion 2 * 0.004/40 = 2e-4; thickness 0.06/50 = 1.2e-3;
    backlash = 2 (0.01 + 0.02) 0.75 / 50 + 1.2e-3 + 2e-4 = 9e-4 + 1.4e-3 = 2.3e-3 rad."""
    st = gear.involute_stage(50.0, math.atan(0.75), 0.02, 0.01, 0.004, 0.06)
    assert st.te_eccentricity == pytest.approx(5e-4, rel=1e-12)
    assert st.te_deformation == pytest.approx(1e-4, rel=1e-12)
    assert st.backlash_deformation == pytest.approx(2e-4, rel=1e-12)
    assert st.backlash_thickness == pytest.approx(1.2e-3, rel=1e-12)
    assert st.backlash == pytest.approx(2.3e-3, rel=1e-12)
    assert tuple(st) == (st.te_eccentricity, st.te_deformation, st.backlash, st.backlash_deformation,
                         st.backlash_thickness)


def test_bracketing_maximiser_is_vectorised_like_the_scalar_calls():
    a = math.radians(20.0)
    r1, r2 = np.array([20.0, 22.5, 40.0]), np.array([80.0, 180.0, 60.0])
    de, d1 = np.array([0.5, 0.03, 0.2]), np.array([0.002, 0.0, 0.05])
    v, w = gear.gear_te_max(r1, r2, de, a, d1)
    assert v.shape == (3,) and w.shape == (3,)
    for k in range(3):
        vk, wk = gear.gear_te_max(r1[k], r2[k], de[k], a, d1[k])
        assert v[k] == pytest.approx(float(vk), rel=1e-12) and w[k] == pytest.approx(float(wk), abs=1e-9)


def test_zero_and_flat_curves():
    """No eccentricity and no load: the curve is 0 and its maximum is put at phi = 0 (both maximisers).
    No eccentricity with load: the constant delta1 sin(alpha)/R2 (9.284767e-6, see above); the location
    of a constant is arbitrary but must lie in [0, 2 pi) as documented (the fast form puts it at 0)."""
    a = math.atan(0.4)
    for fn in (gear.gear_te_max, gear.gear_te_max_fast):
        value, where = fn(20.0, 80.0, 0.0, a, 0.0)
        assert (float(value), float(where)) == (0.0, 0.0)
        assert np.asarray(where).dtype == np.float64
        value, where = fn(20.0, 80.0, 0.0, a, 0.002)
        assert float(value) == pytest.approx(9.284767e-6, rel=1e-6)
        assert 0.0 <= float(where) < 2 * np.pi
    assert float(gear.gear_te_max_fast(20.0, 80.0, 0.0, a, 0.002)[1]) == 0.0


@pytest.mark.parametrize("r1, r2, de, d1", [(20.0, 80.0, 5.0, 0.002), (20.0, 80.0, 3.0, 0.0), (40.0, 60.0, 8.0, 0.05)])
def test_fast_maximum_beyond_the_newton_range_against_an_optimiser(r1, r2, de, d1):
    """Delta e / l = 0.03 .. 0.08 > 0.01: the fast form hands these to the bracketing search; value
    and location against dense samples refined by scipy's bounded optimiser."""
    a = math.radians(20.0)
    f = lambda x: gear.gear_te(x, r1, r2, de, a, d1)  # noqa: E731
    want = _argmax_reference(f)
    value, where = gear.gear_te_max_fast(r1, r2, de, a, d1)
    assert float(where) == pytest.approx(want, abs=1e-6)
    assert float(value) == pytest.approx(float(f(want)), rel=1e-10)


def test_fast_maximum_of_mixed_designs_with_array_angles_and_a_given_peak():
    """One call over designs of every kind (Newton, beyond the Newton range, unloaded, no eccentricity),
    with arrays of eccentricities and pressure angles, and again with the kinematic peak given: each
    design against the optimiser (de = 0: the load term delta1 sin(alpha)/R2 at phi = 0)."""
    r1 = np.array([20.0, 20.0, 22.5, 40.0, 10.0])
    r2 = np.array([80.0, 80.0, 180.0, 60.0, 200.0])
    de = np.array([0.5, 5.0, 0.03, 0.0, 2.0])
    alpha = np.radians([20.0, 25.0, 14.5, 20.0, 30.0])
    d1 = np.array([0.002, 0.002, 0.0, 0.05, 0.01])
    peak = gear.kinematic_peak(r1 + r2, de, alpha)
    for kwargs in ({}, {"peak": peak}):
        v, w = gear.gear_te_max_fast(r1, r2, de, alpha, d1, **kwargs)
        for k in range(5):
            if de[k] == 0.0:
                assert v[k] == pytest.approx(d1[k] * math.sin(alpha[k]) / r2[k], rel=1e-12) and w[k] == 0.0
                continue
            f = lambda x: gear.gear_te(x, r1[k], r2[k], de[k], alpha[k], d1[k])  # noqa: B023, E731
            want = _argmax_reference(f)
            assert w[k] == pytest.approx(want, abs=1e-6), k
            assert v[k] == pytest.approx(float(f(want)), rel=1e-10), k


def test_fast_maximum_needs_no_fall_back_within_the_newton_range(monkeypatch):
    """Within Delta e / l <= 0.01 the documented fast path settles by itself: the bracketing search
    is never called (a mutant that switches the fast path off is caught here)."""
    def boom(*args, **kwargs):
        raise AssertionError("fell back to the bracketing search")

    a = np.radians([20.0, 25.0, 14.5])
    r1, r2 = np.array([20.0, 22.5, 40.0]), np.array([80.0, 180.0, 60.0])
    de, d1 = np.array([0.5, 0.03, 0.2]), np.array([0.002, 0.004, 0.05])
    want = [_argmax_reference(lambda x, k=k: gear.gear_te(x, r1[k], r2[k], de[k], a[k], d1[k])) for k in range(3)]
    monkeypatch.setattr(gear, "gear_te_max", boom)
    _, w = gear.gear_te_max_fast(r1, r2, de, a, d1)
    np.testing.assert_allclose(w, want, atol=1e-6)


@pytest.mark.parametrize("l, de, alpha_deg", [(100.0, 1.0, 20.0), (100.0, 1.0, 10.0), (100.0, 1.0, 35.0),
                                              (100.0, 0.2, 20.0), (202.5, 0.03, 14.5)])
def test_kinematic_peak_is_a_stationary_point(l, de, alpha_deg):
    """Newton converged, not one step short: F'(phi0) = 0 to 1e-12 of |F''(phi0)| (phi0 within ~1e-12 rad
    of the peak; one Newton step from the start leaves ~5e-7 rad), F'' < 0, with the analytic derivatives
    (themselves checked against finite differences above)."""
    a = math.radians(alpha_deg)
    peak = gear.kinematic_peak(l, de, a)
    f1, f2 = gear.kinematic_bracket_derivatives(peak.phi0, l, de, a)
    assert float(f2) < 0.0
    assert abs(float(f1)) <= 1e-12 * abs(float(f2))
    _, h1, h2 = gear.load_factor_derivatives(peak.phi0, l, de, a)
    assert (float(peak.h1), float(peak.h2)) == (float(h1), float(h2))


@pytest.mark.parametrize("r1, r2, de, d1", [(20.0, 80.0, 0.5, 0.002), (22.5, 180.0, 0.03, 0.004),
                                            (40.0, 60.0, 0.2, 0.05), (10.0, 200.0, 2.0, 0.01)])
def test_fast_maximum_is_a_stationary_point(r1, r2, de, d1):
    """Newton settled, not stopped after the first step: Delta phi_cc = l/(2 R2) (F + s H), s = 2 delta1 / l
    (the module's G), so at the maximum F' + s H' = 0; checked with the analytic derivatives (themselves
    checked against finite differences above) to 1e-9 of |F'' + s H''| (one Newton step leaves ~1e-7)."""
    a = math.radians(20.0)
    l, s = r1 + r2, 2 * d1 / (r1 + r2)
    _, where = gear.gear_te_max_fast(r1, r2, de, a, d1)
    f1, f2 = gear.kinematic_bracket_derivatives(where, l, de, a)
    _, h1, h2 = gear.load_factor_derivatives(where, l, de, a)
    g1, g2 = float(f1 + s * h1), float(f2 + s * h2)
    assert g2 < 0.0
    assert abs(g1) <= 1e-9 * abs(g2)
