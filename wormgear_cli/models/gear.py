"""Spur gear stage (stage 2): transmission error and backlash.

Source: the paper's gear-stage equations ("Transmission Accuracy Analysis of
Worm and Gear Combined Mechanisms", equations for Delta phi_cc and
Delta phi_ch).  Notation: R1 pinion pitch radius, R2 output-gear pitch
radius, l = R1 + R2 centre distance, Delta e the eccentricity, alpha the
pressure angle, phi the pinion rotation angle.

All functions are pure and broadcast over numpy arrays.
Units: lengths [mm], angles [rad].
"""

from __future__ import annotations

import numpy as np

#: samples per revolution used to bracket the maximum before refinement
_BRACKET_SAMPLES = 48
#: golden-section iterations; the bracket shrinks by 0.618**n
_GOLDEN_ITERATIONS = 64


def eccentricity_ratio(centre_distance, eccentricity):
    """A = (R1 + R2 + Delta e) / Delta e  [-]  (paper, definition under Delta phi_cc).

    Parameters
    ----------
    centre_distance : l = R1 + R2 [mm], > 0
    eccentricity : Delta e [mm], > 0 (A is infinite for Delta e = 0)
    """
    return (centre_distance + eccentricity) / eccentricity


def contact_phase_angle(phi, centre_distance, eccentricity):
    """lambda1 = atan[ Delta e sin(phi) / (l + Delta e (1 - cos phi)) ]  [rad].

    The paper's phase angle of the contact point.  Written with ``arctan2``
    so it is defined for every phi and equals exactly 0 when Delta e = 0.

    Parameters
    ----------
    phi : pinion angle [rad], any real
    centre_distance : l = R1 + R2 [mm], > 0
    eccentricity : Delta e [mm], >= 0
    """
    phi = np.asarray(phi, dtype=float)
    return np.arctan2(
        eccentricity * np.sin(phi),
        centre_distance + eccentricity * (1.0 - np.cos(phi)),
    )


def kinematic_bracket(phi, centre_distance, eccentricity, pressure_angle):
    """F(l, phi): the bracket of the paper's Delta phi_cc  [rad].

    F = 2 atan( sqrt((A+1)/(A-1)) tan(phi/2) ) - phi
        + tan(alpha) ln( 1 + 2A (1 - cos phi) / (A-1)^2 )

    Branch-safe form: with u = phi/2 and k = sqrt((A+1)/(A-1)),
    2 atan(k tan u) - 2u = 2 atan2((k-1) sin u cos u, cos^2 u + k sin^2 u),
    which is continuous through phi = pi (where tan(phi/2) is infinite).
    A is eliminated algebraically, so Delta e = 0 gives exactly 0:
    k^2 - 1 = 2 Delta e / l and 2A/(A-1)^2 = 2 Delta e (l + Delta e) / l^2.

    Parameters
    ----------
    phi : pinion angle [rad], any real
    centre_distance : l [mm], > 0
    eccentricity : Delta e [mm], >= 0, small against l
    pressure_angle : alpha [rad], 0 < alpha < pi/4

    Validity: Delta e << l (the paper's small-eccentricity kinematics).
    """
    phi = np.asarray(phi, dtype=float)
    l = np.asarray(centre_distance, dtype=float)
    de = np.asarray(eccentricity, dtype=float)
    k2m1 = 2.0 * de / l
    k = np.sqrt(1.0 + k2m1)
    km1 = k2m1 / (k + 1.0)
    u = 0.5 * phi
    su, cu = np.sin(u), np.cos(u)
    wrap = 2.0 * np.arctan2(km1 * su * cu, cu * cu + k * su * su)
    g = 2.0 * de * (l + de) / (l * l)
    log_term = np.tan(pressure_angle) * np.log1p(g * 2.0 * su * su)
    return wrap + log_term


def gear_kinematic_te(phi, pinion_radius, gear_radius, eccentricity, pressure_angle):
    """Kinematic part of Delta phi_cc: (R1 + R2)/(2 R2) * F(l, phi)  [rad].

    Parameters
    ----------
    phi : pinion angle [rad]
    pinion_radius : R1 [mm], > 0
    gear_radius : R2 [mm], > 0
    eccentricity : Delta e [mm], >= 0
    pressure_angle : alpha [rad]

    Source: the paper's Delta phi_cc, first term.  Note (R1+R2)/(2R2) =
    (1 + 1/i)/2 with i = R2/R1, the form used in the paper's design study.
    """
    l = pinion_radius + gear_radius
    return l / (2.0 * gear_radius) * kinematic_bracket(phi, l, eccentricity, pressure_angle)


def gear_deformation_te(phi, pinion_radius, gear_radius, eccentricity, pressure_angle, deflection):
    """Load part of Delta phi_cc: delta1 sin(alpha + lambda1) / R2  [rad].

    Parameters
    ----------
    phi : pinion angle [rad]
    pinion_radius, gear_radius : R1, R2 [mm]
    eccentricity : Delta e [mm], >= 0
    pressure_angle : alpha [rad]
    deflection : delta1, tooth-pair deflection along the line of action [mm], >= 0

    Source: the paper's Delta phi_cc, second term.
    """
    lam1 = contact_phase_angle(phi, pinion_radius + gear_radius, eccentricity)
    return deflection * np.sin(pressure_angle + lam1) / gear_radius


def gear_te(phi, pinion_radius, gear_radius, eccentricity, pressure_angle, deflection):
    """Delta phi_cc(phi) = kinematic part + load part  [rad] (the paper's equation)."""
    return gear_kinematic_te(phi, pinion_radius, gear_radius, eccentricity, pressure_angle) + gear_deformation_te(
        phi, pinion_radius, gear_radius, eccentricity, pressure_angle, deflection
    )


def gear_te_max(pinion_radius, gear_radius, eccentricity, pressure_angle, deflection):
    """Maximum over phi of Delta phi_cc, and where it occurs.

    Returns ``(max_value [rad], phi_at_max [rad] in [0, 2 pi))``.

    Method: the curve is sampled at 48 points per revolution to bracket the
    global maximum, then a golden-section search (64 iterations, bracket
    shrinks to ~1e-13 of its width) refines it.  Because the curve is
    smooth and has one maximum per revolution for Delta e << l, the result
    agrees with a bounded optimiser to ~1e-12 relative.  Broadcasts over
    array inputs (one maximum per element).
    """
    args = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (pinion_radius, gear_radius, eccentricity, pressure_angle, deflection))
    )
    shape = args[0].shape
    r1, r2, de, alpha, d1 = (a.reshape(-1, 1) for a in args)

    def f(phi):
        return gear_te(phi, r1, r2, de, alpha, d1)

    step = 2.0 * np.pi / _BRACKET_SAMPLES
    grid = np.arange(_BRACKET_SAMPLES) * step
    values = f(grid[None, :])
    best = np.argmax(values, axis=1)
    lo = (grid[best] - step)[:, None]
    hi = (grid[best] + step)[:, None]
    ratio = (np.sqrt(5.0) - 1.0) / 2.0
    x1 = hi - ratio * (hi - lo)
    x2 = lo + ratio * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(_GOLDEN_ITERATIONS):
        left = f1 >= f2
        hi = np.where(left, x2, hi)
        lo = np.where(left, lo, x1)
        new_x1 = hi - ratio * (hi - lo)
        new_x2 = lo + ratio * (hi - lo)
        # reuse the surviving interior point, evaluate only the new one
        x_new = np.where(left, new_x1, new_x2)
        f_new = f(x_new)
        x1, x2, f1, f2 = (
            np.where(left, x_new, x2),
            np.where(left, x1, x_new),
            np.where(left, f_new, f2),
            np.where(left, f1, f_new),
        )
    phi_star = 0.5 * (lo + hi)
    value = np.maximum(f(phi_star), np.maximum(f1, f2))
    # a zero curve (no eccentricity, no load) has its "maximum" at 0
    phi_star = np.where(value > 0.0, np.mod(phi_star, 2.0 * np.pi), 0.0)
    value = np.maximum(value, 0.0)
    return value.reshape(shape), phi_star.reshape(shape)


def gear_backlash(phi, module, output_teeth, eccentricity, pressure_angle, deflection):
    """Delta phi_ch(phi) = 2 Delta C1 / (m1 z1)  [rad], the paper's gear backlash.

    Delta C1 = 2 Delta e tan(alpha) |sin phi| + 2 delta1   [mm]

    The paper writes 6.875 * Delta C1[um] / (m1 z1) in arcminutes; 6.875 =
    2 * (180*60/pi) / 1000 is exactly "arc length on the pitch circle of
    diameter m1 z1, as an angle", which is what this function returns in
    radians.  The eccentric term is taken in magnitude (|sin phi|): a
    clearance cannot be negative.

    Parameters
    ----------
    phi : pinion angle [rad]
    module : m1 [mm], > 0
    output_teeth : z1, teeth of the output gear, > 0
    eccentricity : Delta e [mm], >= 0
    pressure_angle : alpha [rad]
    deflection : delta1 [mm], >= 0
    """
    clearance = 2.0 * eccentricity * np.tan(pressure_angle) * np.abs(np.sin(phi)) + 2.0 * deflection
    return pitch_arc_to_angle(clearance, module, output_teeth)


def gear_backlash_max(module, output_teeth, eccentricity, pressure_angle, deflection):
    """max over phi of :func:`gear_backlash` (at |sin phi| = 1)  [rad]."""
    return gear_backlash(0.5 * np.pi, module, output_teeth, eccentricity, pressure_angle, deflection)


def pitch_arc_to_angle(arc, module, teeth):
    """Angle subtended by an arc on the pitch circle: 2 * arc / (m z)  [rad].

    Parameters
    ----------
    arc : arc length (or a deviation measured on the pitch circle) [mm]
    module : m [mm]
    teeth : z [-]

    This is the paper's "6.875 / (m z)" factor: 6.875 arcmin per um of
    arc on a pitch diameter of 1 mm * (m z).
    """
    return 2.0 * arc / (module * teeth)
