"""Thermal growth of the worm centre distance (physics behind ``thermal_backlash``).

The effect catalogue's ``thermal_backlash`` takes the growth of the worm
pair's working centre distance per kelvin, k = d(Delta a)/dT.  This module
predicts k from the spec's ``[materials]`` expansion coefficients, so a
value fitted by ``diagnose`` can be compared with physics.

Model (first order, as in the reference facts): the housing bores move
apart with the housing, while the worm and the wheel grow radially towards
each other,

    Delta a = a alpha_H dT_H - (r_1 alpha_1 dT_1 + r_2 alpha_2 dT_2)

with a the centre distance, r_1 the worm pitch radius (d_m1 / 2), r_2 the
wheel pitch radius, alpha the linear expansion coefficients [1/K] of
housing (H), worm (1) and wheel (2).  A positive Delta a opens the
backlash.  Units: lengths [mm], coefficients [1/K], results [mm/K] or
[um/K].
"""

from __future__ import annotations

import math


def centre_distance_growth(centre_distance, worm_radius, wheel_radius, housing_expansion, worm_expansion,
                           wheel_expansion, housing_dt=1.0, worm_dt=1.0, wheel_dt=1.0):
    """Delta a = a alpha_H dT_H - (r_1 alpha_1 dT_1 + r_2 alpha_2 dT_2)  [mm].

    Parameters
    ----------
    centre_distance : a, worm-pair centre distance [mm], > 0
    worm_radius : r_1, worm pitch (reference) radius d_m1 / 2 [mm], > 0
    wheel_radius : r_2, wheel pitch radius m z3 / 2 [mm], > 0
    housing_expansion, worm_expansion, wheel_expansion : alpha_H, alpha_1,
        alpha_2 [1/K] (steel ~11.5e-6, CuSn12 bronze ~18.5e-6, grey cast
        iron 10.5e-6..11e-6)
    housing_dt, worm_dt, wheel_dt : temperature changes of each part [K]
        (default 1 K each: the result is then the coefficient in [mm/K])

    Validity: small temperature changes (|dT| of some tens of K), free
    expansion, no thermal gradients inside a part; the pitch radii stand
    for the radii at which the flanks meet.  Broadcasts over arrays.
    Source: the usual first-order centre-distance relation (housing growth
    minus the radial growth of both members), see the module docstring.
    """
    return (centre_distance * housing_expansion * housing_dt
            - (worm_radius * worm_expansion * worm_dt + wheel_radius * wheel_expansion * wheel_dt))


def predicted_centre_distance_um_per_K(spec) -> float:
    """Predicted ``centre_distance_um_per_K`` of ``thermal_backlash`` for a drive [um/K].

    Assumptions: one uniform temperature change of the whole drive (housing,
    worm and wheel warm alike, dT_H = dT_1 = dT_2); worm pitch radius from
    the lead angle, d_m1 = z_worm m_x / tan(lambda); wheel pitch radius
    m_x z3 / 2; centre distance a = (d_m1 + d_2) / 2 (no profile shift);
    expansion coefficients from the spec's ``[materials]`` (defaults: steel
    worm 11.5, bronze wheel 18.5, cast-iron housing 10.5 ppm/K).  For the
    MCH50 this gives about -0.32 um/K: warming closes the backlash.
    """
    wp, mat = spec.worm_pair, spec.materials
    worm_radius = wp.worm.starts * wp.module / math.tan(wp.lead_angle) / 2.0
    wheel_radius = wp.module * wp.wheel.teeth / 2.0
    a = worm_radius + wheel_radius
    k_mm = centre_distance_growth(a, worm_radius, wheel_radius, mat.housing_expansion, mat.worm_expansion,
                                  mat.wheel_expansion)
    return float(k_mm * 1000.0)
