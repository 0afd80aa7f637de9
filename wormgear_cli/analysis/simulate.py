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
  - the full budget's pitch deviations (only when the spec gives them a size;
    docs/budget.md): cumulative pitch F_p of the output gear (order 1), of the
    pinion and of the wheel (order i_c), each a sinusoid of amplitude F_p/(2r) at
    its shaft reduced by the ratios; single pitch f_p of either spur gear at the
    mesh order z1.  With ``gear_pair.kinematics = "involute"`` the gear
    eccentricity is the sinusoid e/r_b1 sin(i_c theta + psi) instead of the
    paper's curve, and e is only an eccentricity the spec states.
* lost motion (reversal), never negative (each part is clipped at 0):
  - gear: Delta e tan(alpha) (1 + sin phi) / R2, between 0 and the paper's
    eccentric Delta phi_ch part;
  - worm: (Delta j_central + h_j sin(i_c theta + psi_Fi)) / r_wheel / i_c, the
    paper's Delta j +/- its half-width, varying with the wheel's runout;
  - tooth deflection under the spec's (process) loads, which resist motion:
    2 delta1 / R2 + 2 delta2 / (cos(lambda) r_wheel i_c), the paper's
    deformation parts of both backlash equations.
* an external torque T_ext on the output (measured ``load_Nm``) winds the
  teeth up through the same tooth stiffness (C_teeth [rad/(N m)]).

Relation to ``analyze`` (tested in tests/analysis/test_simulate.py):

* The paper combines the worm-stage sources by root-sum-square,
  h = 1/2 sqrt(sum x_k^2), and quotes h as the +/- half-width.  The
  simulated worm-stage common mode is sum_k (x_k / 2) sin(o_k theta + psi_k)
  / (r_wheel i_c).  Over a whole number of output turns its mean square is
  h^2 / 2 / (r_wheel i_c)^2 plus a cross term
  sum_{j<k, o_j = o_k} (x_j x_k / 4) cos(psi_j - psi_k) / (r_wheel i_c)^2
  for every pair of sources on the same shaft (same order).  So its RMS is
  exactly h / sqrt(2) / (r_wheel i_c) when the sources on one shaft are in
  quadrature (or alone on their shaft), and h / sqrt(2) on average over
  independent, uniformly random phases: the root-sum-square is the
  statistical size, not a bound.
* With all phases aligned (:func:`aligned_phases`: every worm-stage source
  peaks at theta = 0) the worm-stage common-mode peak is the linear sum
  1/2 sum_k x_k / (r_wheel i_c) >= h / (r_wheel i_c).
* The common mode excludes tooth deflection: the paper's deformation parts
  of both TE equations (delta1 sin(alpha + lambda1)/R2 and delta2/r_wheel)
  appear here as the direction-dependent lag (key ``deformation``), i.e. in
  the reversal, not as a common-mode offset.
* The simulated reversal (reverse - forward) never exceeds analyze's total
  backlash and equals it when the gear eccentricity's lost-motion peak
  (phi = 90 deg) and the wheel-order backlash variation peak together,
  i.e. when ``gear_eccentricity_phase_deg`` = ``radial_composite_phase_deg``
  (true for the default phases 0).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from wormgear_cli.analysis.accuracy import deflections, gear_eccentricity, geometry
from wormgear_cli.physics import spur as gear_model
from wormgear_cli.physics import worm as worm_model
from wormgear_cli.physics.geometry import DriveGeometry

if TYPE_CHECKING:
    from wormgear_cli.physics.effects import Signals


# an immutable named record built as a NamedTuple, not a frozen dataclass: it is created when
# ``analyze`` starts (0.1 ms against 0.6 ms; docs/development.md, "Start-up")
class Source(NamedTuple):
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
    #: ``"gear"`` or ``"worm"``: the stage the source belongs to
    stage: str = "gear"
    #: ``"shaft"`` (once per turn of a shaft) or ``"mesh"`` (tooth-mesh order)
    kind: str = "shaft"
    #: spec keys its size comes from (for the budget's origin: spec / grade / default)
    size_paths: tuple = ()
    #: largest value of ``curve`` over a turn [rad] (the amplitude for a sinusoid)
    peak: float | None = None


def _sine(amplitude, order):
    def curve(theta, phase):
        return amplitude * np.sin(order * theta + phase)

    curve.sine = (amplitude, order)  # a pure sinusoid: the budget's peak adds these as phasors
    return curve


#: the full budget's sources beyond the paper's five (docs/budget.md)
BUDGET_SOURCES = ("output_gear_cumulative_pitch", "pinion_cumulative_pitch", "wheel_cumulative_pitch",
                  "output_gear_single_pitch", "pinion_single_pitch")


def periodic_sources(spec, all_budget_sources: bool = False) -> list[Source]:
    """The spec's periodic sources, in a fixed order.

    The paper's five sources are always listed (zero-amplitude ones included); the
    budget's pitch-deviation sources (:data:`BUDGET_SOURCES`) only when the spec gives
    them a size, or always with ``all_budget_sources`` (the budget lists every line).
    So a spec without pitch deviations simulates, synthesises and diagnoses exactly
    as before they existed."""
    g = geometry(spec)
    gp, wp, asm = spec.gear_pair, spec.worm_pair, spec.assembly
    z1, z2 = gp.output_gear.teeth, gp.pinion.teeth
    r1, r2 = gp.module * z2 / 2.0, gp.module * z1 / 2.0  # pinion R1, gear R2 (paper's notation)
    de, alpha, i_c = gear_eccentricity(spec), gp.pressure_angle, g.gear_ratio
    to_out = 1.0 / (g.wheel_pitch_radius * i_c)  # mm of arc on the wheel pitch circle -> rad at the output
    ecc_paths = ("assembly.gear_eccentricity_mm", "assembly.gear_centre_distance_error_mm")

    if gp.kinematics == "paper":
        def gear_curve(theta, phase):
            return gear_model.gear_kinematic_te(i_c * theta + phase, r1, r2, de, alpha)

        def gear_lost(theta, phase):
            return de * math.tan(alpha) * (1.0 + np.sin(i_c * theta + phase)) / r2

        gear_amp = _first_harmonic(lambda phi: gear_model.gear_kinematic_te(phi, r1, r2, de, alpha))
        gear_peak = float(gear_model.gear_te_max_fast(r1, r2, de, alpha, 0.0)[0])
    else:
        # involute: e/r_b at the pinion's order, i.e. e/r_b1 at the output (models.gear.involute_stage);
        # the static part of the lost motion (centre distance, thickness allowances) is constant
        gear_amp = gear_peak = de / g.output_base_radius
        gear_curve = _sine(gear_amp, i_c)
        static = (2.0 * asm.gear_centre_distance_error * math.tan(alpha)
                  + gp.output_gear.thickness_deviation + gp.pinion.thickness_deviation)
        ecc_paths = ("assembly.gear_eccentricity_mm",)

        def gear_lost(theta, phase):
            return (static + de * math.tan(alpha) * (1.0 + np.sin(i_c * theta + phase))) / r2

    worm_ecc = math.hypot(asm.worm_eccentricity, asm.worm_bearing_clearance) / math.cos(wp.lead_angle)
    wheel_ecc = math.hypot(asm.wheel_eccentricity, asm.wheel_bearing_clearance) / math.cos(
        wp.transverse_pressure_angle)
    og, pn, wh = gp.output_gear, gp.pinion, wp.wheel

    def sine_source(name, phase_path, order, amplitude, phase, stage, kind, paths, lost=None):
        return Source(name, phase_path, order, amplitude, phase, _sine(amplitude, order), lost, stage, kind,
                      paths, amplitude)

    out = [
        Source("gear_eccentricity", "assembly.gear_eccentricity_phase_deg", i_c, gear_amp,
               asm.gear_eccentricity_phase, gear_curve, gear_lost, "gear", "shaft", ecc_paths, gear_peak),
        sine_source("worm_lead_error", "worm_pair.lead_error_phase_deg", g.worm_order,
                    wp.lead_error / 2.0 * to_out, wp.lead_error_phase, "worm", "shaft",
                    ("worm_pair.lead_error_mm",)),
        sine_source("worm_eccentricity", "assembly.worm_eccentricity_phase_deg", g.worm_order,
                    worm_ecc / 2.0 * to_out, asm.worm_eccentricity_phase, "worm", "shaft",
                    ("assembly.worm_eccentricity_mm", "assembly.worm_bearing_clearance_mm")),
        sine_source("wheel_radial_composite", "worm_pair.wheel.radial_composite_phase_deg", i_c,
                    wh.radial_composite_error / 2.0 * to_out, wh.radial_composite_phase, "worm", "shaft",
                    ("worm_pair.wheel.radial_composite_error_mm",), _worm_lost_motion(spec, g)),
        sine_source("wheel_eccentricity", "assembly.wheel_eccentricity_phase_deg", i_c, wheel_ecc / 2.0 * to_out,
                    asm.wheel_eccentricity_phase, "worm", "shaft",
                    ("assembly.wheel_eccentricity_mm", "assembly.wheel_bearing_clearance_mm")),
        # --- the full budget's sources (docs/budget.md): pitch deviations, each F_p a once-per-turn
        # TE of peak-to-peak F_p / r (amplitude F_p / (2 r)) at its shaft, reduced by the ratios
        sine_source("output_gear_cumulative_pitch", "gear_pair.output_gear.cumulative_pitch_phase_deg", 1.0,
                    og.cumulative_pitch_deviation / (2.0 * r2), og.cumulative_pitch_phase, "gear", "shaft",
                    ("gear_pair.output_gear.cumulative_pitch_deviation_mm",)),
        sine_source("pinion_cumulative_pitch", "gear_pair.pinion.cumulative_pitch_phase_deg", i_c,
                    pn.cumulative_pitch_deviation / (2.0 * r1) / i_c, pn.cumulative_pitch_phase, "gear", "shaft",
                    ("gear_pair.pinion.cumulative_pitch_deviation_mm",)),
        sine_source("wheel_cumulative_pitch", "worm_pair.wheel.cumulative_pitch_phase_deg", i_c,
                    wh.cumulative_pitch_deviation / (2.0 * g.wheel_pitch_radius) / i_c, wh.cumulative_pitch_phase,
                    "worm", "shaft", ("worm_pair.wheel.cumulative_pitch_deviation_mm",)),
        # single pitch deviation f_p: a tooth-to-tooth TE of peak-to-peak f_p on that gear's pitch circle,
        # at the mesh order z1 (both gears: z2 i_c = z1); f_p / (2 r2) = f_p,pinion / (2 R1 i_c) at the output
        sine_source("output_gear_single_pitch", "gear_pair.output_gear.single_pitch_phase_deg", float(z1),
                    og.single_pitch_deviation / (2.0 * r2), og.single_pitch_phase, "gear", "mesh",
                    ("gear_pair.output_gear.single_pitch_deviation_mm",)),
        sine_source("pinion_single_pitch", "gear_pair.pinion.single_pitch_phase_deg", float(z1),
                    pn.single_pitch_deviation / (2.0 * r1) / i_c, pn.single_pitch_phase, "gear", "mesh",
                    ("gear_pair.pinion.single_pitch_deviation_mm",)),
    ]
    return [src for src in out if all_budget_sources or src.name not in BUDGET_SOURCES or src.amplitude != 0.0]


def _first_harmonic(curve, samples: int = 256) -> float:
    """Size of the once-per-turn Fourier component of a 2 pi-periodic ``curve(phi)``.

    Exact for the gear curve (which is smooth, so 256 samples resolve its
    harmonics far beyond the first).  For small Delta e it approaches
    Delta e sqrt(1 + 4 tan^2 alpha) / (2 R2), with mean Delta e tan(alpha) / R2.
    """
    phi = np.arange(samples) * (2.0 * np.pi / samples)
    c = 2.0 / samples * np.sum(curve(phi) * np.exp(-1j * phi))
    return float(abs(c))


def _worm_lost_motion(spec, g: DriveGeometry):
    """max(Delta j_central(no load) + h_j sin(i_c theta + psi), 0) / r_wheel / i_c  [rad].

    Clipped at zero: a clearance cannot be negative (only matters for
    specs whose envelope half-width exceeds the central backlash)."""
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
    return lambda theta, phase: np.maximum(central + h_j * np.sin(g.gear_ratio * theta + phase), 0.0) * to_out


def aligned_phases(spec, quantity: str = "error") -> dict[str, float]:
    """Source phases [rad] that make the sources peak together at theta = 0.

    (The budget's pitch-deviation sources are sinusoids: phase 90 deg.)

    ``quantity="error"``: every sinusoidal source at phase 90 deg and the
    gear eccentricity at the pinion angle of its kinematic maximum, so the
    common mode reaches the linear sum of the peaks at theta = 0.
    ``quantity="reversal"``: the gear eccentricity and the radial composite
    error (the two sources with lost motion) at 90 deg, so the reversal
    reaches analyze's total backlash at theta = 0 (the other sources at
    90 deg too).
    """
    if quantity not in ("error", "reversal"):
        raise ValueError(f"quantity must be 'error' or 'reversal', got {quantity!r}")
    out = {src.name: 0.5 * math.pi for src in periodic_sources(spec)}
    if quantity == "error":
        gp = spec.gear_pair
        r1, r2 = gp.module * gp.pinion.teeth / 2.0, gp.module * gp.output_gear.teeth / 2.0
        if gp.kinematics == "paper":
            _, phi_star = gear_model.gear_te_max_fast(r1, r2, gear_eccentricity(spec), gp.pressure_angle, 0.0)
            out["gear_eccentricity"] = float(phi_star)
    return out


# an immutable named record built as a NamedTuple, not a frozen dataclass: it is created when
# ``analyze`` starts (0.1 ms against 0.6 ms; docs/development.md, "Start-up")
class Compliance(NamedTuple):
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
    # mm per N about the operating point (ISO 6336-1's c' held at the spec's line load)
    unit_defl = deflections(spec, gear_force=1.0, worm_force=1.0, linear_at_spec_load=True)
    # paper: 2 delta1 on the pitch arc (its Delta phi_ch); involute: along the line of action, 1/r_b1
    gear_angle_per_mm = 1.0 / r2 if gp.kinematics == "paper" else 1.0 / g.output_base_radius
    worm_angle_per_mm = 1.0 / (math.cos(wp.lead_angle) * r_w * i_c)
    lag = spec_defl.gear * gear_angle_per_mm + spec_defl.worm * worm_angle_per_mm
    # external torque T [N m] on the output: gear normal force T/r_b1, worm normal force from the wheel torque
    t_mm = 1000.0  # N m -> N mm
    f_gear = t_mm / g.output_base_radius
    f_worm = t_mm / i_c / (r_w * math.cos(wp.normal_pressure_angle) * math.cos(wp.lead_angle))
    per_nm = unit_defl.gear * f_gear * gear_angle_per_mm + unit_defl.worm * f_worm * worm_angle_per_mm
    return Compliance(float(lag), float(per_nm))


def components(spec, signals: Signals, phases: dict | None = None,
               effects: dict | None = None) -> dict[str, np.ndarray]:
    """Every contribution to the simulated error [rad], keyed by name.

    Keys: each periodic source's name (common mode), ``lost_motion``
    (the -d L/2 term), ``deformation`` (process-load lag and external
    wind-up), and ``effect:NAME`` for every enabled effect.  ``phases``
    overrides source phases by source name [rad].  ``effects`` (name ->
    internal parameters) replaces the spec's ``[effects.*]`` when given.
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
    from wormgear_cli.physics.effects import EFFECTS  # the catalogue: not needed by ``analyze``

    for name, params in (spec.effects if effects is None else effects).items():
        out[f"effect:{name}"] = EFFECTS[name].function(signals, g, **params)
    return out


def simulate(spec, signals: Signals, phases: dict | None = None, offset: float = 0.0,
             effects: dict | None = None) -> np.ndarray:
    """The simulated error [rad] at each sample: the sum of :func:`components` plus ``offset``."""
    total = np.full(signals.theta.shape, float(offset))
    for v in components(spec, signals, phases, effects).values():
        total = total + v
    return total


def max_reversal(spec, revolutions: int = 1, points: int = 20000) -> float:
    """Largest simulated lost motion over the given turns [rad] (for tests and docs)."""
    from wormgear_cli.physics.effects import Signals

    theta = np.linspace(0.0, 2.0 * np.pi * revolutions, points, endpoint=False)
    fwd = simulate(spec, Signals.make(theta, 1.0))
    rev = simulate(spec, Signals.make(theta, -1.0))
    return float(np.max(rev - fwd))
