"""The drive's error as a curve over the output angle (the model behind ``simulate``).

Conventions: output angle theta [rad], direction d = +1 forward / -1
reverse, error = actual - target at the output [rad].  The intermediate
shaft (pinion + wheel) turns i_c = z1/z2 times per output turn, the worm
n_w = i_c z3 / z_worm times.

The simulated error is

    e(theta, d) = common(theta) - d * lost_motion(theta) / 2
                  + C_teeth * T_ext + sum of enabled [effects.*]

* common mode, from the spec's periodic sources, each at its shaft's order
  and its ``*_phase_deg``:
  - gear eccentricity Delta e: the paper's kinematic Delta phi_cc curve
    evaluated at the pinion angle phi = i_c theta + psi_e (order i_c);
  - worm lead error f_hL and worm eccentricity/clearance sqrt(S1^2+C1^2)/cos(lambda)
    at the worm order n_w; wheel radial composite F_i and wheel
    eccentricity/clearance sqrt(S2^2+C2^2)/cos(alpha_2) at the wheel order
    i_c.  Each is a sinusoid of amplitude (value / 2) on the wheel pitch
    circle, i.e. the paper's +/- 1/2 envelope term by term, reduced by i_c.
* lost motion (reversal), never negative:
  - gear: Delta e tan(alpha) (1 + sin phi) / R2, between 0 and the paper's
    eccentric Delta phi_ch part;
  - worm: (Delta j_central + h_j sin(i_c theta + psi_Fi)) / r_wheel / i_c, the
    paper's Delta j +/- its half-width, varying with the wheel's runout;
  - tooth deflection under the spec's (process) loads, which resist motion:
    2 delta1 / R2 + 2 delta2 / (cos(lambda) r_wheel i_c), the paper's
    deformation parts of both backlash equations.
* an external torque T_ext on the output (measured ``load_Nm``) winds the
  teeth up through the same tooth stiffness (C_teeth [rad/(N m)]).

Relation to ``analyze``: the paper combines the worm-stage sources by
root-sum-square, h = 1/2 sqrt(sum x_k^2).  On a whole number of turns the
simulated worm-stage common mode has RMS exactly h / sqrt(2) / (r_wheel i_c)
(independent of the phases), and with all phases aligned its peak is the
linear sum 1/2 sum x_k / (r_wheel i_c) >= h.  The simulated reversal never
exceeds analyze's total backlash and reaches it when the gear eccentricity
(phi = 90 deg) and the wheel-order backlash variation peak together.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from wormgear_cli.analysis import deflections, geometry
from wormgear_cli.models import gear as gear_model
from wormgear_cli.models import worm as worm_model
from wormgear_cli.models.effects import EFFECTS, DriveGeometry, Signals


@dataclass(frozen=True)
class Source:
    """A periodic error source of the spec.

    ``name``: identifier; ``phase_path``: TOML path of its phase key;
    ``order``: cycles per output revolution; ``amplitude`` [rad at the
    output] (for the non-sinusoidal gear curve: its first-harmonic size);
    ``phase`` [rad] as specified; ``curve(theta, phase)`` -> [rad], the
    common-mode contribution; ``lost_motion(theta, phase)`` -> [rad] or None.
    """

    name: str
    phase_path: str
    order: float
    amplitude: float
    phase: float
    curve: Callable
    lost_motion: Callable | None = None


def _sine(amplitude, order):
    return lambda theta, phase: amplitude * np.sin(order * theta + phase)


def periodic_sources(spec) -> list[Source]:
    """The spec's periodic sources, in a fixed order (zero-amplitude ones included)."""
    g = geometry(spec)
    gp, wp, asm = spec.gear_pair, spec.worm_pair, spec.assembly
    z1, z2 = gp.output_gear.teeth, gp.pinion.teeth
    r1, r2 = gp.module * z2 / 2.0, gp.module * z1 / 2.0  # pinion R1, gear R2 (paper's notation)
    de, alpha, i_c = asm.gear_eccentricity, gp.pressure_angle, g.gear_ratio
    to_out = 1.0 / (g.wheel_pitch_radius * i_c)  # mm of arc on the wheel pitch circle -> rad at the output

    def gear_curve(theta, phase):
        return gear_model.gear_kinematic_te(i_c * theta + phase, r1, r2, de, alpha)

    def gear_lost(theta, phase):
        return de * math.tan(alpha) * (1.0 + np.sin(i_c * theta + phase)) / r2

    # first-harmonic size of the kinematic curve ~ (l / 2R2) * sqrt(1 + tan^2 alpha) * de / l
    gear_amp = (r1 + r2) / (2.0 * r2) * math.hypot(1.0, math.tan(alpha)) * de / (r1 + r2 + de)

    worm_ecc = math.hypot(asm.worm_eccentricity, asm.worm_bearing_clearance) / math.cos(wp.lead_angle)
    wheel_ecc = math.hypot(asm.wheel_eccentricity, asm.wheel_bearing_clearance) / math.cos(
        wp.transverse_pressure_angle)
    return [
        Source("gear_eccentricity", "assembly.gear_eccentricity_phase_deg", i_c, gear_amp,
               asm.gear_eccentricity_phase, gear_curve, gear_lost),
        Source("worm_lead_error", "worm_pair.lead_error_phase_deg", g.worm_order, wp.lead_error / 2.0 * to_out,
               wp.lead_error_phase, _sine(wp.lead_error / 2.0 * to_out, g.worm_order)),
        Source("worm_eccentricity", "assembly.worm_eccentricity_phase_deg", g.worm_order, worm_ecc / 2.0 * to_out,
               asm.worm_eccentricity_phase, _sine(worm_ecc / 2.0 * to_out, g.worm_order)),
        Source("wheel_radial_composite", "worm_pair.wheel.radial_composite_phase_deg", i_c,
               wp.wheel.radial_composite_error / 2.0 * to_out, wp.wheel.radial_composite_phase,
               _sine(wp.wheel.radial_composite_error / 2.0 * to_out, i_c), _worm_lost_motion(spec, g)),
        Source("wheel_eccentricity", "assembly.wheel_eccentricity_phase_deg", i_c, wheel_ecc / 2.0 * to_out,
               asm.wheel_eccentricity_phase, _sine(wheel_ecc / 2.0 * to_out, i_c)),
    ]


def _worm_lost_motion(spec, g: DriveGeometry):
    """(Delta j_central(no load) + h_j sin(i_c theta + psi)) / r_wheel / i_c  [rad]."""
    wp, asm = spec.worm_pair, spec.assembly
    _, prof, thk = worm_model.worm_backlash_central(0.0, wp.worm.profile_error, wp.wheel.profile_error,
                                                    wp.worm.thickness_deviation, wp.wheel.thickness_deviation,
                                                    wp.lead_angle)
    h_j = worm_model.worm_backlash_halfwidth(wp.worm.profile_error, wp.wheel.profile_error,
                                             wp.worm.thickness_deviation, wp.wheel.thickness_deviation,
                                             sum(e * e for e in asm.worm_pair_errors), wp.lead_error,
                                             asm.worm_centre_distance_error, wp.wheel.radial_composite_error,
                                             wp.lead_angle, wp.transverse_pressure_angle)
    to_out = 1.0 / (g.wheel_pitch_radius * g.gear_ratio)
    central = float(prof + thk)
    return lambda theta, phase: (central + h_j * np.sin(g.gear_ratio * theta + phase)) * to_out


@dataclass(frozen=True)
class Compliance:
    """Tooth-stiffness terms [rad]: ``process_lag`` per direction under the
    spec's loads, ``per_Nm`` output wind-up per N m of external torque."""

    process_lag: float
    per_Nm: float


def compliance(spec) -> Compliance:
    g = geometry(spec)
    gp, wp = spec.gear_pair, spec.worm_pair
    r2 = gp.module * gp.output_gear.teeth / 2.0
    i_c, r_w = g.gear_ratio, g.wheel_pitch_radius
    spec_defl = deflections(spec)
    unit_defl = deflections(spec, gear_force=1.0, worm_force=1.0)  # mm per N (both models are linear)
    gear_angle_per_mm = 1.0 / r2
    worm_angle_per_mm = 1.0 / (math.cos(wp.lead_angle) * r_w * i_c)
    lag = spec_defl.gear * gear_angle_per_mm + spec_defl.worm * worm_angle_per_mm
    # external torque T [N m] on the output: gear normal force T/r_b1, worm normal force from the wheel torque
    t_mm = 1000.0  # N m -> N mm
    f_gear = t_mm / g.output_base_radius
    f_worm = t_mm / i_c / (r_w * math.cos(wp.normal_pressure_angle) * math.cos(wp.lead_angle))
    per_nm = unit_defl.gear * f_gear * gear_angle_per_mm + unit_defl.worm * f_worm * worm_angle_per_mm
    return Compliance(float(lag), float(per_nm))


def components(spec, signals: Signals, phases: dict | None = None) -> dict[str, np.ndarray]:
    """Every contribution to the simulated error [rad], keyed by name.

    Keys: each periodic source's name (common mode), ``lost_motion``
    (the -d L/2 term), ``deformation`` (process-load lag and external
    wind-up), and ``effect:NAME`` for every enabled effect.  ``phases``
    overrides source phases by source name [rad].
    """
    phases = phases or {}
    out: dict[str, np.ndarray] = {}
    d = signals.direction
    lost = np.zeros_like(signals.theta)
    for src in periodic_sources(spec):
        ph = phases.get(src.name, src.phase)
        out[src.name] = src.curve(signals.theta, ph)
        if src.lost_motion is not None:
            lost = lost + src.lost_motion(signals.theta, ph)
    comp = compliance(spec)
    out["lost_motion"] = -d * lost / 2.0
    out["deformation"] = -d * comp.process_lag + comp.per_Nm * signals.load
    g = geometry(spec)
    for name, params in spec.effects.items():
        out[f"effect:{name}"] = EFFECTS[name].function(signals, g, **params)
    return out


def simulate(spec, signals: Signals, phases: dict | None = None, offset: float = 0.0) -> np.ndarray:
    """The simulated error [rad] at each sample: the sum of :func:`components` plus ``offset``."""
    total = np.full(signals.theta.shape, float(offset))
    for v in components(spec, signals, phases).values():
        total = total + v
    return total


def max_reversal(spec, revolutions: int = 1, points: int = 20000) -> float:
    """Largest simulated lost motion over the given turns [rad] (for tests and docs)."""
    theta = np.linspace(0.0, 2.0 * np.pi * revolutions, points, endpoint=False)
    fwd = simulate(spec, Signals.make(theta, 1.0))
    rev = simulate(spec, Signals.make(theta, -1.0))
    return float(np.max(rev - fwd))
