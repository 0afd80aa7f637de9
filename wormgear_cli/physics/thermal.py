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

Which temperatures (the decision behind the warm-up demo): the catalogue
coefficient is per kelvin of the recorded temperature.  Here that is the
temperature of the worm and the wheel (a sensor at the mesh, in its oil),
and the housing rises by a ratio q of it, so k = a alpha_H q - (r_1 alpha_1
+ r_2 alpha_2) (:func:`predicted_centre_distance_um_per_K`; q = 1, the
default, is a uniform warm-up).  A running worm drive heats at the mesh, so
in a warm-up the housing lags and rises less (:func:`mesh_housing_warmup`);
the lag bends the relation, and ``wormgear synth``'s ``mesh-warmup``
reports by how much.
"""

from __future__ import annotations

import math

import numpy as np

from wormgear_cli.units import ARCSEC


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


def axial_growth(length, expansion, dt):
    """dL = L alpha dT  [mm]: the free thermal growth of a shaft of length ``length`` [mm] with expansion
    ``expansion`` [1/K] warmed by ``dt`` [K].  A worm located axially by one (thrust) bearing grows away
    from it: the mesh, ``length`` from that bearing, moves axially by dL, which turns the wheel by the
    arc dL on its pitch circle (the worm's axial section is a rack).  MCH50 numbers (steel worm, 100 mm,
    10 K): 11.5 um, i.e. 11.5 um / 37.5 mm / 8 = 3.83e-5 rad = 7.9 arcsec at the output.  Broadcasts."""
    return length * expansion * dt


def worm_stage(spec):
    """The drive's worm stage (the last one from the motor), or None; a spec-like record without
    stages gives its ``worm_pair`` (the same attribute names)."""
    stages = getattr(spec, "stages", None)
    if not stages:
        return getattr(spec, "worm_pair", None)
    return next((s for s in reversed(stages) if s.kind == "worm"), None)


def worm_pair_radii(spec) -> tuple[float, float, float]:
    """(a, r_1, r_2) of the worm pair [mm]: d_m1 = z_worm m_x / tan(lambda),
    r_1 = d_m1 / 2, r_2 = m_x z3 / 2, a = r_1 + r_2 (no profile shift).  The drive's worm stage
    (:func:`worm_stage`); ValueError for a drive without one."""
    wp = worm_stage(spec)
    if wp is None:
        raise ValueError("the drive has no worm stage")
    worm_radius = wp.worm.starts * wp.module / math.tan(wp.lead_angle) / 2.0
    wheel_radius = wp.module * wp.wheel.teeth / 2.0
    return worm_radius + wheel_radius, worm_radius, wheel_radius


def centre_distance_change_mm(spec, mesh_dt, housing_dt):
    """Delta a [mm] of the worm pair when worm and wheel warm by ``mesh_dt`` and
    the housing by ``housing_dt`` [K] (arrays broadcast).

    Delta a = a alpha_H dT_H - (r_1 alpha_1 + r_2 alpha_2) dT_mesh, i.e.
    :func:`centre_distance_growth` with dT_1 = dT_2 = dT_mesh (worm and wheel
    at the temperature of the mesh and its oil); geometry from
    :func:`worm_pair_radii`, coefficients from the spec's ``[materials]``.
    """
    mat = spec.materials
    a, r1, r2 = worm_pair_radii(spec)
    return centre_distance_growth(a, r1, r2, mat.housing_expansion, mat.worm_expansion, mat.wheel_expansion,
                                  housing_dt=housing_dt, worm_dt=mesh_dt, wheel_dt=mesh_dt)


def mesh_housing_warmup(t, rise, tau_s, housing_share, housing_lag_s):
    """Temperature rises of the worm mesh and of the housing during a warm-up [K].

    The mesh (worm, wheel rim and their oil; where the sensor is) warms as a
    first-order system, dT_m(t) = D (1 - exp(-t / tau)).  The housing is
    heated by the oil and follows it through a first-order lag towards a
    smaller rise: tau_L d(dT_H)/dt = s dT_m - dT_H, dT_H(0) = 0, whose
    solution is

        dT_H(t) = s D [1 - (tau e^(-t/tau) - tau_L e^(-t/tau_L)) / (tau - tau_L)]

    (tau_L = tau: s D [1 - (1 + t/tau) e^(-t/tau)]; tau_L = 0: s dT_m).

    Parameters
    ----------
    t : times since the start of the warm-up [s], array, >= 0
    rise : D, final rise of the mesh above its start [K]
    tau_s : tau, time constant of the mesh [s], > 0
    housing_share : s, final housing rise / final mesh rise [-], 0..1
    housing_lag_s : tau_L, lag of the housing behind the mesh [s], >= 0

    Returns (dT_mesh, dT_housing) [K], arrays shaped like ``t``.
    Source: the lumped (one node per body) heat balance of a gear unit, as
    used in worm-gear thermal rating (ISO/TR 14521): the mesh loss heats the
    oil, the oil the housing, the housing sheds it to the air.
    """
    t = np.asarray(t, dtype=float)
    mesh = rise * -np.expm1(-t / tau_s)
    if housing_lag_s <= 0.0:
        return mesh, housing_share * mesh
    if math.isclose(housing_lag_s, tau_s, rel_tol=1e-9):
        lagged = 1.0 - (1.0 + t / tau_s) * np.exp(-t / tau_s)
    else:
        lagged = 1.0 - (tau_s * np.exp(-t / tau_s) - housing_lag_s * np.exp(-t / housing_lag_s)) / (
            tau_s - housing_lag_s)
    return mesh, housing_share * rise * lagged


def predicted_centre_distance_um_per_K(spec, housing_rise_ratio: float = 1.0) -> float | None:
    """Predicted ``centre_distance_um_per_K`` of ``thermal_backlash`` for a drive [um/K].

    The coefficient is per kelvin of the recorded temperature, taken as the
    temperature of the worm and the wheel (a sensor at the mesh / in its
    oil); the housing rises by ``housing_rise_ratio`` kelvin per kelvin of
    it (dT_1 = dT_2 = dT, dT_H = q dT):

        k = a alpha_H q - (r_1 alpha_1 + r_2 alpha_2)

    ``housing_rise_ratio`` q = 1 (the default) is one uniform temperature
    change of the whole drive.  A running worm drive heats at the mesh, so
    in a warm-up the housing rises less (q < 1) and k is more negative.
    Geometry from :func:`worm_pair_radii`; expansion coefficients from the
    spec's ``[materials]`` (defaults: steel worm 11.5, bronze wheel 18.5,
    cast-iron housing 10.5 ppm/K).  For the MCH50 this gives about
    -0.32 um/K with q = 1 and -0.70 um/K with q = 0.4: warming closes the
    backlash.  A q that drifts during a warm-up (the housing lagging) makes
    the relation non-linear: see :func:`mesh_housing_warmup`.  None for a drive without a worm
    stage.
    """
    if worm_stage(spec) is None:
        return None
    return float(centre_distance_change_mm(spec, 1.0, housing_rise_ratio) * 1000.0)


def predicted_drift_arcsec_per_K(spec) -> float | None:
    """Predicted ``arcsec_per_K`` of ``thermal_drift`` from the worm's axial growth [arcsec/K]:
    L alpha_worm / (r_w A) per kelvin of the worm shaft (:func:`axial_growth`), L the worm stage's
    ``worm.thrust_bearing_distance_mm``, r_w the wheel's pitch radius, A the product of the ratios
    after the stage.  The sign depends on which side of the mesh the thrust bearing sits; the
    magnitude is given.  None without a worm stage or without a thrust-bearing distance."""
    wp = worm_stage(spec)
    length = getattr(getattr(wp, "worm", None), "thrust_bearing_distance", 0.0) if wp is not None else 0.0
    if not length:
        return None
    after = 1.0
    for s in spec.stages[wp.index:]:
        after *= s.ratio
    return float(axial_growth(length, spec.materials.worm_expansion, 1.0) / (wp.module * wp.wheel.teeth / 2.0)
                 / after / ARCSEC)
