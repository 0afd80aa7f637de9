"""Worm stage (stage 1): transmission error and backlash.

Source: the paper's Delta phi_wc and Delta j / Delta phi_wh equations.
Index 1 is the worm, index 2 the wheel.  The +/- envelopes are returned as
separate parts so callers can report the bound and its pieces.
Units: lengths [mm], angles [rad].  All functions broadcast.
"""

from __future__ import annotations

import numpy as np

from wormgear_cli.physics.spur import pitch_arc_to_angle


def worm_te_halfwidth(lead_error, worm_eccentricity, worm_clearance, radial_composite,
                      wheel_eccentricity, wheel_clearance, lead_angle, transverse_pressure_angle):
    """Half-width of the worm-stage TE envelope  [mm of arc at the wheel pitch circle].

    h = 1/2 * sqrt( f_hL^2 + (S1^2 + C1^2)/cos^2(lambda) + F_i^2
                    + (S2^2 + C2^2)/cos^2(alpha_2) )

    S1 and S2 are radial runouts (total indicator readings): an eccentric member of
    centre offset e has S = 2 e, so S2 / (2 cos(alpha_2)) on the pitch circle is
    e / r_b at the wheel, the involute rule (docs/models.md, "Runout and eccentricity").

    Parameters
    ----------
    lead_error : f_hL [mm], >= 0
    worm_eccentricity : S1, radial runout of the worm [mm], >= 0
    worm_clearance : C1, worm bearing clearance [mm], >= 0
    radial_composite : F_i, wheel radial composite error [mm], >= 0
    wheel_eccentricity : S2, radial runout of the wheel [mm], >= 0
    wheel_clearance : C2, wheel bearing clearance [mm], >= 0
    lead_angle : lambda [rad]
    transverse_pressure_angle : alpha_2 [rad]

    Source: the +/- term of the paper's Delta phi_wc.
    """
    total = (
        lead_error**2
        + (worm_eccentricity**2 + worm_clearance**2) / np.cos(lead_angle) ** 2
        + radial_composite**2
        + (wheel_eccentricity**2 + wheel_clearance**2) / np.cos(transverse_pressure_angle) ** 2
    )
    return 0.5 * np.sqrt(total)


def worm_te(deflection, halfwidth, module, wheel_teeth):
    """Delta phi_wc = 2 (delta2 + h) / (m2 z3)  [rad], the upper bound of the envelope.

    The paper: Delta phi_wc = 6.875/(m2 z3) [delta2 +/- h] arcmin with
    lengths in um; the bound quoted (0.0424 deg for the MCH50) is the +
    branch.  ``deflection`` delta2 [mm], ``halfwidth`` h [mm] from
    :func:`worm_te_halfwidth`, ``module`` m2 axial module [mm],
    ``wheel_teeth`` z3.
    """
    return pitch_arc_to_angle(deflection + halfwidth, module, wheel_teeth)


def worm_backlash_central(deflection, worm_profile_error, wheel_profile_error,
                          worm_thickness_deviation, wheel_thickness_deviation, lead_angle):
    """Central (deterministic) part of Delta j, split into its three terms  [mm].

    Returns ``(deformation, profile, thickness)`` with
      deformation = 2 delta2 / cos(lambda)
      profile     = 1.06 (f_t1 + f_t2)
      thickness   = (T_s1 + T_s2) / (2 cos(lambda))

    Parameters
    ----------
    deflection : delta2, worm-mesh deflection [mm], >= 0
    worm_profile_error, wheel_profile_error : f_t1, f_t2 [mm], >= 0
    worm_thickness_deviation, wheel_thickness_deviation : T_s1, T_s2 [mm], >= 0
    lead_angle : lambda [rad]

    Source: the paper's Delta j, first line.
    """
    cos_lam = np.cos(lead_angle)
    deformation = 2.0 * deflection / cos_lam
    profile = 1.06 * (worm_profile_error + wheel_profile_error)
    thickness = (worm_thickness_deviation + wheel_thickness_deviation) / (2.0 * cos_lam)
    return deformation, profile, thickness


def worm_backlash_halfwidth(worm_profile_error, wheel_profile_error, worm_thickness_deviation,
                            wheel_thickness_deviation, alignment_errors_sq, lead_error,
                            centre_distance_error, radial_composite, lead_angle,
                            transverse_pressure_angle):
    """Half-width of the Delta j envelope  [mm].

    h_j = 1/2 sqrt[ 0.126 (f_t1^2 + f_t2^2) + (T_s1^2 + T_s2^2)/(36 cos^2 lambda)
                    + 4 (sum e_i^2 + f_hL^2) + (4 f_a^2 + F_i^2)/(9 tan alpha_2) ]

    Parameters
    ----------
    worm_profile_error, wheel_profile_error : f_t1, f_t2 [mm]
    worm_thickness_deviation, wheel_thickness_deviation : T_s1, T_s2 [mm]
    alignment_errors_sq : sum of the six e_i^2 [mm^2], >= 0
    lead_error : f_hL [mm]
    centre_distance_error : f_a, worm-pair centre-distance error [mm]
    radial_composite : F_i [mm]
    lead_angle : lambda [rad]
    transverse_pressure_angle : alpha_2 [rad]

    Source: the paper's Delta j, the +/- term, as printed (the last term
    divides by 9 tan(alpha_2), not its square).
    """
    total = (
        0.126 * (worm_profile_error**2 + wheel_profile_error**2)
        + (worm_thickness_deviation**2 + wheel_thickness_deviation**2) / (36.0 * np.cos(lead_angle) ** 2)
        + 4.0 * (alignment_errors_sq + lead_error**2)
        + (4.0 * centre_distance_error**2 + radial_composite**2) / (9.0 * np.tan(transverse_pressure_angle))
    )
    return 0.5 * np.sqrt(total)


def worm_backlash(central, halfwidth, module, wheel_teeth):
    """Delta phi_wh = 2 (Delta j_central + h_j) / (m2 z3)  [rad] (upper bound).

    ``central`` and ``halfwidth`` in [mm]; the paper's 6.875/(m2 z3) factor
    in radians.
    """
    return pitch_arc_to_angle(central + halfwidth, module, wheel_teeth)
