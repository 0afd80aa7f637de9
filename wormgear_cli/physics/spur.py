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


def gear_kinematic_mean(pinion_radius, gear_radius, eccentricity, pressure_angle, samples: int = 256):
    """Mean over one pinion turn of the kinematic Delta phi_cc curve  [rad] (arrays of Delta e allowed).

    The paper's curve is not centred on zero: for a small Delta e it is Delta e tan(alpha) / R2 plus a
    first harmonic of Delta e sqrt(1 + 4 tan^2 alpha) / (2 R2) (MCH50: a 12.5 arcsec mean under a
    21.3 arcsec first harmonic, peak 33.8 arcsec).  A constant shifts every position alike, so it is
    no positioning error: the budget counts the curve less its mean (docs/budget.md, "Gear-stage
    kinematics").  The curve is smooth and 2 pi-periodic, so the mean of ``samples`` even samples
    (the trapezoidal rule) is exact to rounding.

    Parameters
    ----------
    pinion_radius, gear_radius : R1, R2 [mm], > 0
    eccentricity : Delta e [mm], >= 0, scalar or array
    pressure_angle : alpha [rad]
    """
    phi = np.arange(samples) * (2.0 * np.pi / samples)
    de = np.asarray(eccentricity, dtype=float)
    curve = gear_kinematic_te(phi, pinion_radius, gear_radius, de[..., None], pressure_angle)
    out = np.mean(curve, axis=-1)
    return float(out) if out.ndim == 0 else out


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


# --- fast exact maximiser (Newton on the analytic derivative) ----------------------------
#
# Delta phi_cc(phi) = l/(2 R2) * G(phi) with
#     G(phi) = F(l, phi) + s * H(phi),   s = 2 delta1 / l,   H = sin(alpha + lambda1(phi, l)).
# F and H depend on l, Delta e and alpha only; the ratio enters as the factor l/(2 R2) =
# (1 + 1/i)/2 and through s.  So the kinematic peak phi0(l) (where F' = 0) is found once per
# centre distance, and each design starts from the exact first Newton step of G from phi0,
# phi1 = phi0 - s H'(phi0) / (F''(phi0) + s H''(phi0)), then converges with a few Newton steps
# on the analytic G'/G''.  Below, c = cos phi, sn = sin phi, S = sin^2(phi/2) = (1 - c)/2.

#: largest Delta e / l for which the Newton maximiser is used; beyond it (far outside the
#: paper's small-eccentricity kinematics) :func:`gear_te_max_fast` falls back to the
#: bracketing maximiser :func:`gear_te_max`
NEWTON_MAX_ECCENTRICITY_RATIO = 1e-2
#: Newton stops when every step is below this [rad]: convergence is quadratic, so the phi left
#: after a step d is ~d^2 ~ 1e-14 rad and the value error ~ G'' (1e-14)^2, far below 1e-15 relative
_NEWTON_STEP_TOL = 1e-7
_NEWTON_MAX_ITERATIONS = 30
#: largest Newton step [rad]; keeps an iteration inside the peak's concave region
_NEWTON_MAX_STEP = 0.5


def _bracket_constants(centre_distance, eccentricity):
    """k^2 - 1, k - 1 and g of :func:`kinematic_bracket` (cancellation-free)."""
    k2m1 = 2.0 * eccentricity / centre_distance
    k = np.sqrt(1.0 + k2m1)
    km1 = k2m1 / (k + 1.0)
    g = 2.0 * eccentricity * (centre_distance + eccentricity) / (centre_distance * centre_distance)
    return k2m1, k, km1, g


def kinematic_bracket_derivatives(phi, centre_distance, eccentricity, pressure_angle):
    """dF/dphi and d2F/dphi2 of :func:`kinematic_bracket`  [rad/rad, rad/rad^2].

    With S = sin^2(phi/2), k^2 = (A+1)/(A-1) = 1 + 2 Delta e / l and g = 2A/(A-1)^2:
      F'  = (k - 1 - (k^2-1) S) / (1 + (k^2-1) S) + tan(alpha) g sin(phi) / D,  D = 1 + g (1 - cos phi)
      F'' = -(k^2-1) k sin(phi) / (2 (1 + (k^2-1) S)^2) + tan(alpha) g (cos(phi) D - g sin^2 phi) / D^2
    (the first term of F' is d/dphi [2 atan(k tan(phi/2))] - 1 written without cancellation).

    Parameters as :func:`kinematic_bracket`; broadcasts.  Source: derivative of the paper's bracket.
    """
    phi = np.asarray(phi, dtype=float)
    k2m1, k, km1, g = _bracket_constants(np.asarray(centre_distance, dtype=float),
                                         np.asarray(eccentricity, dtype=float))
    c, sn = np.cos(phi), np.sin(phi)
    big_s = 0.5 * (1.0 - c)
    den = 1.0 + k2m1 * big_s
    d = 1.0 + g * (1.0 - c)
    t = np.tan(pressure_angle)
    f1 = (km1 - k2m1 * big_s) / den + t * g * sn / d
    f2 = -k2m1 * k * sn / (2.0 * den * den) + t * g * (c * d - g * sn * sn) / (d * d)
    return f1, f2


def load_factor_derivatives(phi, centre_distance, eccentricity, pressure_angle):
    """H = sin(alpha + lambda1), H' and H'' with respect to phi  [-, 1/rad, 1/rad^2].

    lambda1 = atan2(y, x), x = l + Delta e (1 - cos phi), y = Delta e sin phi, Q = x^2 + y^2
    = l^2 + 2 Delta e (l + Delta e)(1 - cos phi);  lambda1' = N/Q with
    N = Delta e ((l + Delta e) cos phi - Delta e);  lambda1'' = (N' Q - N Q') / Q^2.
    H' = cos(alpha + lambda1) lambda1';  H'' = -H lambda1'^2 + cos(alpha + lambda1) lambda1''.

    Parameters: phi [rad], centre_distance l [mm] > 0, eccentricity Delta e [mm] >= 0,
    pressure_angle alpha [rad].  Source: derivative of the paper's load term.
    """
    phi = np.asarray(phi, dtype=float)
    l = np.asarray(centre_distance, dtype=float)
    de = np.asarray(eccentricity, dtype=float)
    c, sn = np.cos(phi), np.sin(phi)
    x = l + de * (1.0 - c)
    y = de * sn
    lde = de * (l + de)
    q = l * l + 2.0 * lde * (1.0 - c)
    root = np.sqrt(q)
    sa, ca = np.sin(pressure_angle), np.cos(pressure_angle)
    h = (sa * x + ca * y) / root
    hc = (ca * x - sa * y) / root  # cos(alpha + lambda1)
    n = lde * c - de * de
    lam1 = n / q
    lam2 = (-lde * sn * q - n * 2.0 * lde * sn) / (q * q)
    return h, hc * lam1, -h * lam1 * lam1 + hc * lam2


class KinematicPeak(tuple):
    """Per centre distance: ``(phi0, F0, F2, H1, H2)``, the kinematic argmax phi0 [rad] of
    F(l, phi), F(phi0), F''(phi0), and H'(phi0), H''(phi0) of the load factor."""

    __slots__ = ()

    def __new__(cls, phi0, f0, f2, h1, h2):
        return super().__new__(cls, (phi0, f0, f2, h1, h2))

    phi0 = property(lambda self: self[0])
    f0 = property(lambda self: self[1])
    f2 = property(lambda self: self[2])
    h1 = property(lambda self: self[3])
    h2 = property(lambda self: self[4])


def kinematic_peak(centre_distance, eccentricity, pressure_angle):
    """The maximum of the bracket F(l, phi) over phi, by Newton on F'  (see :class:`KinematicPeak`).

    Start: the small-eccentricity form F ~ (Delta e / l)(sin phi + 2 tan(alpha)(1 - cos phi))
    peaks at phi = pi - atan(1 / (2 tan alpha)); Newton then converges to machine precision.
    Valid for 0 < Delta e / l <= :data:`NEWTON_MAX_ECCENTRICITY_RATIO` (one peak per turn).
    Broadcasts over centre_distance [mm] and eccentricity [mm]; pressure_angle [rad].
    """
    l = np.asarray(centre_distance, dtype=float)
    de = np.asarray(eccentricity, dtype=float)
    l, de = np.broadcast_arrays(l, de)
    phi = np.full(l.shape, np.pi - np.arctan(0.5 / np.tan(pressure_angle)))
    positive = de > 0.0
    for _ in range(_NEWTON_MAX_ITERATIONS):
        f1, f2 = kinematic_bracket_derivatives(phi, l, de, pressure_angle)
        step = np.where(positive & (f2 < 0.0), f1 / np.where(f2 < 0.0, f2, -1.0), 0.0)
        step = np.clip(step, -_NEWTON_MAX_STEP, _NEWTON_MAX_STEP)
        phi = phi - step
        if not np.any(np.abs(step) > 1e-15 * np.maximum(1.0, np.abs(phi))):
            break
    f0 = kinematic_bracket(phi, l, de, pressure_angle)
    _, f2 = kinematic_bracket_derivatives(phi, l, de, pressure_angle)
    _, h1, h2 = load_factor_derivatives(phi, l, de, pressure_angle)
    return KinematicPeak(phi, f0, f2, h1, h2)


def gear_te_max_fast(pinion_radius, gear_radius, eccentricity, pressure_angle, deflection, peak=None):
    """Maximum over phi of Delta phi_cc, and where it occurs: the fast exact form of
    :func:`gear_te_max` (same arguments and return value ``(max [rad], phi_at_max [rad] in [0, 2 pi))``).

    Method: Newton on the analytic derivative of G = F + s H (module comment above), started
    from the exact first Newton step off the kinematic peak.  ``peak``: a
    :class:`KinematicPeak` already broadcast to the designs (the sweep computes it once per
    centre distance and indexes it); computed here when omitted.  Designs whose Newton
    iteration does not settle on a concave peak, or with Delta e / l above
    :data:`NEWTON_MAX_ECCENTRICITY_RATIO`, are handed to :func:`gear_te_max`.  Delta e = 0
    gives the load term alone, delta1 sin(alpha) / R2, at phi = 0.

    Accuracy: agrees with a bounded scalar optimiser on dense samples to ~1e-11 relative
    (the limit of the reference itself).  Units: radii, eccentricity, deflection [mm];
    angles [rad].  Scalar eccentricity and pressure angle are kept scalar (faster).
    """
    r1, r2, d1 = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in
                                       (pinion_radius, gear_radius, deflection)))
    de, alpha = np.asarray(eccentricity, dtype=float), np.asarray(pressure_angle, dtype=float)
    shape = np.broadcast_shapes(r1.shape, de.shape, alpha.shape)
    r1, r2, d1 = (np.broadcast_to(a, shape).ravel() for a in (r1, r2, d1))
    n = r1.size
    de = de if de.ndim == 0 else np.broadcast_to(de, shape).ravel()
    alpha = alpha if alpha.ndim == 0 else np.broadcast_to(alpha, shape).ravel()

    def at(x, idx):
        return x if np.ndim(x) == 0 else x[idx]

    l = r1 + r2
    if peak is None:
        phi0, f0, f2, h1, h2 = (np.broadcast_to(p, (n,)) for p in kinematic_peak(l, de, alpha))
    else:
        phi0, f0, f2, h1, h2 = (np.broadcast_to(np.asarray(p, dtype=float), shape).ravel() for p in peak)
    s = 2.0 * d1 / l
    valid = (de > 0.0) & (de <= NEWTON_MAX_ECCENTRICITY_RATIO * l)
    valid = np.broadcast_to(valid, (n,))
    loaded = valid & (s > 0.0)

    # exact first Newton step of G from the kinematic peak (F'(phi0) = 0)
    g2 = f2 + s * h2
    ok = valid & (g2 < 0.0)
    phi = phi0 - np.clip(s * h1 / np.where(ok, g2, -1.0), -_NEWTON_MAX_STEP, _NEWTON_MAX_STEP)
    active = np.flatnonzero(loaded & ok)
    for _ in range(_NEWTON_MAX_ITERATIONS):
        if active.size == 0:
            break
        p, la, da, aa, sa = phi[active], l[active], at(de, active), at(alpha, active), s[active]
        f1a, f2a = kinematic_bracket_derivatives(p, la, da, aa)
        _, h1a, h2a = load_factor_derivatives(p, la, da, aa)
        gp1, gp2 = f1a + sa * h1a, f2a + sa * h2a
        concave = gp2 < 0.0
        step = np.clip(gp1 / np.where(concave, gp2, -1.0), -_NEWTON_MAX_STEP, _NEWTON_MAX_STEP)
        phi[active] = p - step
        ok[active[~concave]] = False
        active = active[concave & (np.abs(step) > _NEWTON_STEP_TOL)]
    else:
        ok[active] = False

    # value: unloaded designs take the peak value directly, loaded ones the paper's formula
    unloaded = valid & ~loaded
    value = np.where(unloaded, l / (2.0 * r2) * f0, 0.0)
    phi = np.where(unloaded, phi0, phi)
    idx = np.flatnonzero(loaded & ok)
    if idx.size:
        value[idx] = gear_te(phi[idx], r1[idx], r2[idx], at(de, idx), at(alpha, idx), d1[idx])
    flat = np.flatnonzero(np.broadcast_to(de <= 0.0, (n,)))
    if flat.size:
        value[flat] = d1[flat] * np.sin(at(alpha, flat)) / r2[flat]
        phi[flat] = 0.0
    slow = np.flatnonzero(~(valid & (ok | ~loaded)) & np.broadcast_to(de > 0.0, (n,)))
    if slow.size:
        value[slow], phi[slow] = gear_te_max(r1[slow], r2[slow], at(de, slow), at(alpha, slow), d1[slow])
    value = np.maximum(value, 0.0)
    phi = np.mod(phi, 2.0 * np.pi)
    return value.reshape(shape), phi.reshape(shape)


# --- involute reading of the gear stage (``gear_pair.kinematics = "involute"``) -----------------


class InvoluteStage(tuple):
    """``(te_eccentricity, te_deformation, backlash, backlash_deformation, backlash_thickness)``
    [rad at the output] of :func:`involute_stage`."""

    __slots__ = ()

    def __new__(cls, *values):
        return super().__new__(cls, values)

    te_eccentricity = property(lambda self: self[0])
    te_deformation = property(lambda self: self[1])
    backlash = property(lambda self: self[2])
    backlash_deformation = property(lambda self: self[3])
    backlash_thickness = property(lambda self: self[4])


def involute_stage(gear_radius, pressure_angle, eccentricity, centre_distance_error, deflection,
                   thickness_allowances):
    """The spur stage read by involute theory, at the output gear  [rad].

    * An eccentricity e of the pinion moves its base circle by e sin(phi) along the
      line of action: TE e/r_b2 at the pinion's order, i.e. e/(r_b2 i_c) = e/r_b1 at
      the output (r_b = r cos(alpha)); amplitude e/r_b1.
    * A static centre-distance error Delta a leaves the involute action conjugate:
      no TE, a circumferential backlash change j_t = 2 Delta a tan(alpha) at the pitch
      circle; the eccentricity adds up to 2 e tan(alpha) once per pinion turn.
    * Tooth deflection delta along the line of action: TE delta/r_b1 under load and a
      lost motion 2 delta/r_b1 between the two directions.
    * Tooth-thickness allowances E_sn1 + E_sn2 (ISO/TR 10064-2: j_bn = |E_sns1 + E_sns2|
      cos(alpha_n), j_wt = j_bn / cos(alpha_wt) = |E_sns1 + E_sns2| for a standard spur
      pair) add to the circumferential backlash.

    Parameters
    ----------
    gear_radius : r1, output-gear pitch radius [mm], > 0
    pressure_angle : alpha [rad]
    eccentricity : e [mm], >= 0
    centre_distance_error : Delta a [mm], >= 0
    deflection : delta [mm] along the line of action, >= 0
    thickness_allowances : E_sn1 + E_sn2 in magnitude [mm], >= 0

    Returns :class:`InvoluteStage`.  Backlash angles are circumferential arcs on the
    output's pitch circle divided by r1, deflection angles divided by r_b1.
    """
    rb = gear_radius * np.cos(pressure_angle)
    t = np.tan(pressure_angle)
    te_e = eccentricity / rb
    te_d = deflection / rb
    bl_d = 2.0 * deflection / rb
    bl_t = thickness_allowances / gear_radius
    bl = 2.0 * (centre_distance_error + eccentricity) * t / gear_radius + bl_t + bl_d
    return InvoluteStage(te_e, te_d, bl, bl_d, bl_t)  # arrays broadcast (tolerance samples)
