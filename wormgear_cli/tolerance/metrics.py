"""Metrics of each sampled drive, vectorised over samples.

* ``total_transmission_error``, ``total_backlash``: the paper's totals
  exactly as :func:`wormgear_cli.analysis.accuracy.analyze` computes them (same model
  functions, here on arrays of sampled values); phases do not enter them.
* ``iso230_E``, ``iso230_B``, ``iso230_M``, ``iso230_A``: the ISO 230-2:2014
  (clause 2) figures of an acceptance test without measurement noise, on the
  curve :func:`wormgear_cli.analysis.simulate.simulate` gives for the sample's values
  and phases, at the test's targets (one run; with no noise every run is the
  same, s = 0, so A = E):
  E = max_i,dir x_i - min_i,dir x_i;  B = max_i |x_i(up) - x_i(down)|;
  M = max_i x_i(bi) - min_i x_i(bi) with x_i(bi) = (x_i(up) + x_i(down)) / 2;
  A = max(x + 2 s) - min(x - 2 s) with s = 0.

* ``budget_linear``, ``budget_rss``: the full error budget's TE at the output
  (:mod:`wormgear_cli.analysis.budget`, the lines of ``simulation.periodic_sources`` with
  every budget source plus the two static deflection lines) under the linear
  rule (sum of every line's maximum) and the rss rule (static lines + root-sum-
  square of the periodic ones); phases do not enter them.  The peak rule (a
  search over one output turn per sample) is not sampled.

Both gear-stage kinematics are followed (``gear_pair.kinematics``): ``paper``
(the paper's Delta phi_cc curve of Delta e) and ``involute`` (TE e/r_b1 at the
pinion's order, centre-distance error and thickness allowances in the backlash;
:func:`wormgear_cli.physics.spur.involute_stage`).

The simulated error (simulation module doc) written per sample with the
sinusoidal sources of one shaft combined into one term
(a sin(o theta + psi) = a cos(psi) sin(o theta) + a sin(psi) cos(o theta)):

    e(theta, d) = gear(i_c theta + psi_e) + sum_k a_k sin(o_k theta + psi_k)
                  - d/2 [gear_lost(i_c theta + psi_e)
                         + max(c_w + v_w sin(i_c theta + psi_Fi), 0) / (r_w i_c)]
                  + fixed(theta, d)

with gear = the paper's gear_kinematic_te (paper) or e/r_b1 sin (involute, then one
of the sinusoids), gear_lost = Delta e tan(alpha)(1 + sin) / R2 (paper) or
max(2 Delta a tan(alpha) + E_sn1 + E_sn2 + e tan(alpha)(1 + sin), 0) / R2 (involute;
clipped at 0 as a clearance, which matters only for sampled negative deviations),
the sinusoids the worm-stage sources (orders n_w and i_c) and the pitch deviations
(orders 1, i_c, z1), c_w + v_w sin the worm stage's clearance (constant where its causes are,
varying with F_i: :func:`wormgear_cli.drive.worm.lost_motion_terms`) and fixed = tooth-deflection
lag and the spec's effects (not varied).
All angles [rad], lengths [mm].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wormgear_cli.physics import spur as gear_model

PAPER_METRICS = ("total_transmission_error", "total_backlash")
BUDGET_METRICS = ("budget_linear", "budget_rss")
ISO_METRICS = ("iso230_E", "iso230_B", "iso230_M", "iso230_A")
#: metric sets of ``--metrics`` ("paper+budget": the cheapest set for limits on both)
METRIC_SETS = {"paper": PAPER_METRICS, "budget": BUDGET_METRICS, "paper+budget": PAPER_METRICS + BUDGET_METRICS,
               "iso": ISO_METRICS, "all": PAPER_METRICS + ISO_METRICS + BUDGET_METRICS}

#: Chebyshev-Lobatto nodes of the gear-TE interpolant in Delta e, and its accepted relative error
_CHEB_DEGREE = 48
_CHEB_RTOL = 1e-11
#: samples x targets evaluated at once for the ISO figures (bounds the memory of a block)
_ISO_CELLS = 2_097_152


class GearTeMax:
    """max over phi of the paper's Delta phi_cc as a function of Delta e alone (the other
    inputs are fixed by the spec).  Evaluated with a Chebyshev interpolant on [0, T]
    of :func:`wormgear_cli.physics.spur.gear_te_max_fast` (degree 48, checked against
    the exact maximiser between the nodes to 1e-11 relative; the exact maximiser
    is used when the check fails).  Capped at the value at T (the maximum grows
    with Delta e), so no sample exceeds the corner case.  ``part="deformation"``:
    instead the deformation part of that maximum (analyze's ``gear_te_deformation``:
    the maximum less the kinematic curve at its angle), not capped."""

    def __init__(self, spec, tolerance: float, deflection: float, part: str = "max"):
        gp = spec.gear_pair
        self.args = (gp.module * gp.pinion.teeth / 2.0, gp.module * gp.output_gear.teeth / 2.0)
        self.alpha, self.d1, self.t, self.part = gp.pressure_angle, deflection, float(tolerance), part
        self.at_t = float(self.exact(np.array([self.t]))[0])
        self.coef = None
        if self.t > 0:
            from numpy.polynomial import chebyshev

            k = np.arange(_CHEB_DEGREE + 1)
            x = -np.cos(np.pi * k / _CHEB_DEGREE)
            coef = chebyshev.chebfit(x, self.exact(0.5 * self.t * (x + 1.0)), _CHEB_DEGREE)
            mid = -np.cos(np.pi * (k[:-1] + 0.5) / _CHEB_DEGREE)
            ref = self.exact(0.5 * self.t * (mid + 1.0))
            err = np.max(np.abs(chebyshev.chebval(mid, coef) - ref)) / max(self.at_t, 1e-300)
            if err <= _CHEB_RTOL:
                self.coef = coef

    def exact(self, de):
        value, phi = gear_model.gear_te_max_fast(*self.args, de, self.alpha, self.d1)
        if self.part == "deformation":  # analyze's gear_te_deformation: the maximum less its kinematic part
            return value - gear_model.gear_kinematic_te(phi, *self.args, de, self.alpha)
        return value

    def __call__(self, de):
        de = np.asarray(de, dtype=float)
        if self.coef is None:
            value = self.exact(de)
        else:
            from numpy.polynomial import chebyshev

            value = chebyshev.chebval(2.0 * de / self.t - 1.0, self.coef)
        value = np.where(de == self.t, self.at_t, value)
        return np.minimum(value, self.at_t) if self.part == "max" else value


@dataclass(frozen=True)
class Context:
    """Everything the metrics need that the samples do not vary (built once per run)."""

    spec: object
    deflection_gear: float
    deflection_worm: float
    gear_te: GearTeMax
    gear_kin: GearTeMax  # kinematic maximum alone (deflection 0): the budget's gear line
    gear_def: GearTeMax  # deformation part of gear_te (the budget's static gear line)
    theta: np.ndarray  # test targets [rad]
    fixed_up: np.ndarray  # deflection lag + effects, forward [rad]
    fixed_down: np.ndarray
    registry: object = None  # the drive's registry (wormgear_cli.drive.registry), built once per run


def context(spec, gear_eccentricity_tolerance: float, targets_rad: np.ndarray, dwell_s: float = 10.0) -> Context:
    """Build the :class:`Context` of ``spec`` for test targets ``targets_rad`` [rad] (one
    run, forward pass then reverse pass, ``dwell_s`` [s] per point as ``synth``)."""
    from wormgear_cli.analysis.accuracy import deflections
    from wormgear_cli.analysis.simulate import components
    from wormgear_cli.drive.registry import build
    from wormgear_cli.physics.effects import Signals

    d = deflections(spec)  # a [worm, spur] drive (the thin adapter: docs/tolerance.md)
    reg = build(spec)
    theta = np.asarray(targets_rad, dtype=float)
    n = theta.size
    fixed = {}
    for sign, times in ((1.0, np.arange(n) * dwell_s), (-1.0, (2 * n - 1 - np.arange(n)) * dwell_s)):
        parts = components(spec, Signals.make(theta, sign, 0.0, 20.0, times), registry=reg)
        fixed[sign] = sum((v for k, v in parts.items() if k == "deformation" or k.startswith("effect:")),
                          np.zeros(n))
        # the registry's constant clearances (an anti-backlash residual, a thrust bearing's play, a thermal
        # change of the backlash, a friction torque's wind-up): not varied, -d C / 2
        fixed[sign] = fixed[sign] - sign * sum(c.amount for c in reg.clearances) / 2.0
    paper = spec.gear_pair.kinematics == "paper"
    t = gear_eccentricity_tolerance if paper else 0.0  # the involute stage needs no interpolant
    return Context(spec, float(d.gear), float(d.worm), GearTeMax(spec, t, d.gear), GearTeMax(spec, t, 0.0),
                   GearTeMax(spec, t, d.gear, "deformation"), theta, np.broadcast_to(fixed[1.0], (n,)).copy(),
                   np.broadcast_to(fixed[-1.0], (n,)).copy(), reg)


def stage_value(ctx: Context, v: dict, stage):
    """``value(stage key)`` -> the sampled values of a stage's key (arrays), from the sample columns
    ``v`` (keyed by legacy path: the varied quantities of a [worm, spur] drive), else the stage's own
    value: how the registry's vectorised size functions and stage models read a sampled drive."""
    from wormgear_cli.spec.stages import STAGE_TO_LEGACY, record_values

    own = record_values(stage)

    def value(key):
        if key == "alignment_errors_mm":
            return tuple(np.asarray(v.get(f"assembly.worm_pair_errors_mm[{i}]", own[key][i]), dtype=float)
                         for i in range(6))
        path = STAGE_TO_LEGACY.get((stage.kind, key))
        return np.asarray(v[path] if path in v else own[key], dtype=float)

    return value


def _gear_stage(ctx: Context, v: dict):
    """Gear-stage TE and backlash [rad at the output] per sample, as analyze (both kinematics)."""
    gp = ctx.spec.gear_pair
    de = v["assembly.gear_eccentricity_mm"]
    if gp.kinematics == "paper":
        return ctx.gear_te(de), gear_model.gear_backlash_max(gp.module, gp.output_gear.teeth, de, gp.pressure_angle,
                                                             ctx.deflection_gear)
    inv = gear_model.involute_stage(gp.module * gp.output_gear.teeth / 2.0, gp.pressure_angle, de,
                                    v["assembly.gear_centre_distance_error_mm"], ctx.deflection_gear,
                                    v["gear_pair.output_gear.thickness_deviation_mm"]
                                    + v["gear_pair.pinion.thickness_deviation_mm"])
    return inv.te_eccentricity + inv.te_deformation, inv.backlash


def paper_totals(ctx: Context, values: dict) -> dict[str, np.ndarray]:
    """Total TE and total backlash [rad] per sample, as :func:`analyze` computes them.

    ``values``: column -> values [mm] (see :func:`wormgear_cli.tolerance.sampling.draw`).
    Source: the paper's Delta phi_c = Delta phi_cc + Delta phi_wc / i_c and
    Delta phi_h = Delta phi_ch + Delta phi_wh / i_c (module doc of analysis); the gear
    stage by the spec's kinematics (paper or involute).
    """
    spec = ctx.spec
    gp = spec.gear_pair
    z1, z2 = gp.output_gear.teeth, gp.pinion.teeth
    i_c = z1 / z2
    v = values
    te_gear, bl_gear = _gear_stage(ctx, v)
    from wormgear_cli.drive.worm import paper

    worm = ctx.registry.train.stages[0]
    ws = paper(worm, ctx.deflection_worm, stage_value(ctx, v, worm))  # the worm stage's one definition
    wte, wbl = ws.transmission_error, ws.backlash
    return {"total_transmission_error": te_gear + wte / i_c, "total_backlash": bl_gear + wbl / i_c}


def _sinusoids(ctx: Context, v: dict) -> list:
    """The sinusoidal sources per sample: (amplitude [rad at the output], phase path, order, the spec's
    phase [rad]), the
    registry's sources in their order (all of them: the budget's too) with their sizes evaluated on
    the samples (:attr:`wormgear_cli.drive.records.Source.size`); the paper kinematics' gear curve,
    not a sinusoid, is left out (the gear eccentricity is one only under the involute kinematics)."""
    from wormgear_cli.spec.stages import legacy_path

    reg = ctx.registry
    stages = reg.train.stages
    out = []
    for src in reg.periodic(all_budget_sources=True):
        if getattr(src.curve, "sine", None) is None:
            continue
        stage = stages[src.stage_index - 1]
        out.append((src.size(stage_value(ctx, v, stage)), legacy_path(stages, src.phase_path), src.order, src.phase))
    return out


def budget_totals(ctx: Context, values: dict) -> dict[str, np.ndarray]:
    """The full budget's TE [rad] per sample under the linear and the rss rule, as
    :func:`wormgear_cli.analysis.budget.budget` combines its lines (module doc there):
    linear = sum_static a_k + sum_periodic a_k, rss = sum_static a_k + sqrt(sum_periodic a_k^2).

    Lines: the gear eccentricity (paper: the kinematic maximum of Delta phi_cc at no
    load less the curve's mean, its periodic part; involute: e/r_b1), the sinusoids
    (:func:`_sinusoids`), and the static tooth
    deflections (gear: analyze's gear_te_deformation, which under the paper's
    kinematics depends on Delta e; worm: delta2 on the wheel pitch circle / i_c).
    """
    spec = ctx.spec
    gp = spec.gear_pair
    worm_static = next(x.amplitude for x in ctx.registry.statics if x.stage_kind == "worm")  # not sampled
    periodic = [np.asarray(a, dtype=float) for a, *_ in _sinusoids(ctx, values)]
    if gp.kinematics == "paper":
        de = values["assembly.gear_eccentricity_mm"]
        r1, r2 = gp.module * gp.pinion.teeth / 2.0, gp.module * gp.output_gear.teeth / 2.0
        mean = gear_model.gear_kinematic_mean(r1, r2, de, gp.pressure_angle)  # a constant: no budget line's part
        periodic.insert(0, np.asarray(ctx.gear_kin(de), dtype=float) - mean)
        static = ctx.gear_def(de) + worm_static
    else:
        r_b1 = gp.module * gp.output_gear.teeth * math.cos(gp.pressure_angle) / 2.0
        static = ctx.deflection_gear / r_b1 + worm_static
    lin = sum(periodic)
    sq = sum(a * a for a in periodic)
    return {"budget_linear": static + lin, "budget_rss": static + np.sqrt(sq)}


def iso_figures(ctx: Context, values: dict, phases: dict) -> dict[str, np.ndarray]:
    """ISO 230-2 E, B, M, A [rad] per sample on the simulated curve at the targets (module doc).

    ``values``: column -> values [mm]; ``phases``: phase path -> phases [rad].
    Worked in chunks of samples so that memory stays bounded.
    """
    n = len(next(iter(values.values())))
    per = max(1, _ISO_CELLS // max(ctx.theta.size, 1))
    out = {k: np.empty(n) for k in ISO_METRICS}
    for lo in range(0, n, per):
        hi = min(n, lo + per)
        part = _iso_chunk(ctx, {k: a[lo:hi] for k, a in values.items()}, {k: a[lo:hi] for k, a in phases.items()})
        for k in ISO_METRICS:
            out[k][lo:hi] = part[k]
    return out


def _iso_chunk(ctx: Context, v: dict, ph: dict) -> dict:
    from wormgear_cli.analysis.accuracy import geometry

    spec = ctx.spec
    g = geometry(spec)
    gp = spec.gear_pair
    r1, r2 = gp.module * gp.pinion.teeth / 2.0, gp.module * gp.output_gear.teeth / 2.0
    alpha, i_c = gp.pressure_angle, g.gear_ratio
    to_out = 1.0 / (g.wheel_pitch_radius * i_c)
    paper = gp.kinematics == "paper"
    theta = ctx.theta[None, :]
    col = lambda a: np.asarray(a, dtype=float)[:, None]  # noqa: E731

    de, psi_e = col(v["assembly.gear_eccentricity_mm"]), col(ph["assembly.gear_eccentricity_phase_deg"])
    # sources without a size in this chunk (a tolerance of 0: the budget's pitch deviations of most specs)
    # are left out, and with them their orders
    # a source whose phase is not sampled (a key beyond the legacy form's, e.g. the worm's axial runout) keeps
    # the spec's phase
    sines = [(a, ph[k] if k in ph else np.full(np.shape(a), fixed), o)
             for a, k, o, fixed in _sinusoids(ctx, v) if np.any(a)]
    # every sinusoid of one order as p sin(o theta) + q cos(o theta): one matrix product per term
    orders = list(dict.fromkeys([i_c] + [o for _, _, o in sines]))  # i_c always: the lost motion's order
    th = ctx.theta
    basis = np.stack([f(o * th) for o in orders for f in (np.sin, np.cos)] + [np.ones_like(th)])
    where = {o: 2 * k for k, o in enumerate(orders)}
    j_ic = where[i_c]
    coef = np.zeros((de.shape[0], basis.shape[0]))
    for a, psi, o in sines:
        j = where[o]
        amp = np.asarray(a, dtype=float)
        coef[:, j] += amp * np.cos(psi)
        coef[:, j + 1] += amp * np.sin(psi)
    common = coef @ basis
    if paper:
        common += gear_model.gear_kinematic_te(i_c * theta + psi_e, r1, r2, de, alpha)
    # lost motion (never negative): the gear part and the worm stage's (drive.worm.lost_motion_terms: the
    # paper's Delta j without load, constant where its causes are, varying with F_i at the wheel's order)
    from wormgear_cli.drive.worm import lost_motion_terms
    from wormgear_cli.drive.worm import paper as worm_paper

    worm = ctx.registry.train.stages[0]
    wv = stage_value(ctx, v, worm)
    worm_constant, worm_amplitude = lost_motion_terms(worm, worm_paper(worm, 0.0, wv), wv)
    psi_f = np.asarray(ph["worm_pair.wheel.radial_composite_phase_deg"], dtype=float)
    n = de.shape[0]

    def at_ic(amplitude, phase, constant):
        c = np.zeros((n, basis.shape[0]))
        c[:, j_ic], c[:, j_ic + 1], c[:, -1] = amplitude * np.cos(phase), amplitude * np.sin(phase), constant
        return c @ basis

    c_gear = de[:, 0] * (math.tan(alpha) / r2)
    if paper:
        gear_lost = at_ic(c_gear, psi_e[:, 0], c_gear)
    else:  # simulation's involute gear_lost: (static + e tan(alpha) (1 + sin)) / R2, clipped at 0
        static = (2.0 * math.tan(alpha) * np.asarray(v["assembly.gear_centre_distance_error_mm"], dtype=float)
                  + v["gear_pair.output_gear.thickness_deviation_mm"] + v["gear_pair.pinion.thickness_deviation_mm"])
        gear_lost = np.maximum(at_ic(c_gear, psi_e[:, 0], c_gear + np.asarray(static) / r2), 0.0)
    worm_inner = at_ic(worm_amplitude, psi_f, np.broadcast_to(worm_constant, c_gear.shape))
    lost = gear_lost + np.maximum(worm_inner, 0.0) * to_out
    up = common - 0.5 * lost + ctx.fixed_up[None, :]
    down = common + 0.5 * lost + ctx.fixed_down[None, :]
    e = np.maximum(up.max(axis=1), down.max(axis=1)) - np.minimum(up.min(axis=1), down.min(axis=1))
    bi = common + 0.5 * (ctx.fixed_up + ctx.fixed_down)[None, :]  # (x(up) + x(down)) / 2
    # no noise: s = 0, so A = max(x + 2 s) - min(x - 2 s) over both directions is E
    return {"iso230_E": e, "iso230_B": np.abs(up - down).max(axis=1), "iso230_M": bi.max(axis=1) - bi.min(axis=1),
            "iso230_A": e.copy()}


def evaluate(ctx: Context, values: dict, phases: dict, metrics: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The chosen ``metrics`` [rad] per sample (see the module doc)."""
    out = {}
    if any(m in PAPER_METRICS for m in metrics):
        out.update(paper_totals(ctx, values))
    if any(m in BUDGET_METRICS for m in metrics):
        out.update(budget_totals(ctx, values))
    if any(m in ISO_METRICS for m in metrics):
        out.update(iso_figures(ctx, values, phases))
    return {m: out[m] for m in metrics}
