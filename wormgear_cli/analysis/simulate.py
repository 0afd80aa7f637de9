"""The drive's error as a curve over the output angle (the model behind ``simulate``).

Conventions: output angle theta [rad], direction d = +1 forward / -1
reverse, error = actual - target at the output [rad].  Every periodic
source, static term, clearance and compliance comes from the drive's
registry (:mod:`wormgear_cli.drive.registry`, built from its train of
stages): :func:`periodic_sources` is a view of it.  Below, for the paper's
[worm, spur] drive: the intermediate shaft (pinion + wheel) turns i_c = z1/z2
times per output turn, the worm n_w = i_c z3 / z_worm times; every other
train is the same model stage by stage (docs/models.md).

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
* lost motion (reversal), never negative (each part is clipped at 0; a belt's
  tooth clearance and an anti-backlash arrangement's residual are constants):
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

from typing import TYPE_CHECKING, cast

import numpy as np

from wormgear_cli.drive.records import Compliance, Source, sine  # noqa: F401  (re-exported: their old home)
from wormgear_cli.drive.registry import aligned_phases as aligned
from wormgear_cli.drive.registry import build
from wormgear_cli.drive.train import drive_geometry
from wormgear_cli.physics.effects import EFFECTS, Signals

if TYPE_CHECKING:
    from wormgear_cli.drive.train import Train


def periodic_sources(spec, all_budget_sources: bool = False, registry=None) -> list[Source]:
    """The spec's periodic sources, in a fixed order: a view of the drive's registry.

    The model's own sources are always listed (zero-amplitude ones included); the full
    budget's additions (pitch deviations; a belt's sources) only when the spec gives them a
    size, or always with ``all_budget_sources`` (the budget lists every line).  So a spec
    without pitch deviations simulates, synthesises and diagnoses exactly as before they
    existed.  ``registry``: the spec's :func:`wormgear_cli.drive.registry.build`, built when
    omitted."""
    return (registry or build(spec)).periodic(all_budget_sources)


def aligned_phases(spec, quantity: str = "error") -> dict[str, float]:
    """Source phases [rad] that make the sources peak together at theta = 0
    (:func:`wormgear_cli.drive.registry.aligned_phases`).

    ``quantity="error"``: every sinusoidal source at phase 90 deg and the
    gear eccentricity at the pinion angle of its kinematic maximum, so the
    common mode reaches the linear sum of the peaks at theta = 0.
    ``quantity="reversal"``: the gear eccentricity and the radial composite
    error (the two sources with lost motion) at 90 deg, so the reversal
    reaches analyze's total backlash at theta = 0 (the other sources at
    90 deg too).
    """
    return aligned(spec, quantity)


def compliance(spec) -> Compliance:
    """Tooth-stiffness terms [rad] of the drive, referred to the output (the registry's)."""
    return build(spec).compliance


def components(spec, signals: Signals, phases: dict | None = None,
               effects: dict | None = None, registry=None) -> dict[str, np.ndarray]:
    """Every contribution to the simulated error [rad], keyed by name.

    Keys: each periodic source's name (common mode), ``lost_motion``
    (the -d L/2 term), ``deformation`` (process-load lag and external
    wind-up), ``thermal`` (the thermal drift at the spec's operating
    temperatures, when it has one) and ``effect:NAME`` for every enabled effect.  ``phases``
    overrides source phases by source name [rad].  ``effects`` (name ->
    internal parameters) replaces the spec's ``[effects.*]`` when given.
    """
    phases = phases or {}
    reg = registry or build(spec)
    out: dict[str, np.ndarray] = {}
    d = signals.direction
    lost = np.zeros_like(signals.theta)
    for src in reg.periodic():
        ph = phases.get(src.name, src.phase)
        out[src.name] = src.curve(signals.theta, ph)
        if src.lost_motion is not None:
            lost = lost + src.lost_motion(signals.theta, ph)
    for c in reg.clearances:
        lost = lost + c.amount
    comp = reg.compliance
    out["lost_motion"] = -d * np.maximum(lost, 0.0) / 2.0  # a mesh warmed shut binds: no negative clearance
    out["deformation"] = -d * comp.process_lag + comp.per_Nm * signals.load
    drift = sum(x.amplitude for x in reg.statics if x.kind == "thermal")
    if drift:  # the thermal drift at the spec's operating temperatures, both directions alike
        out["thermal"] = np.full(signals.theta.shape, drift)
    g = drive_geometry(spec, cast("Train", reg.train))  # (the registry's record holds its train untyped)
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
    theta = np.linspace(0.0, 2.0 * np.pi * revolutions, points, endpoint=False)
    fwd = simulate(spec, Signals.make(theta, 1.0))
    rev = simulate(spec, Signals.make(theta, -1.0))
    return float(np.max(rev - fwd))
