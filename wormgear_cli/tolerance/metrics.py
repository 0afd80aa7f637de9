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

* ``budget_linear``, ``budget_statistical``, ``budget_rss``: the full error budget's TE amplitude
  at the output (:mod:`wormgear_cli.analysis.budget`, the registry's periodic lines with every
  budget source plus the static lines) under the linear rule (sum of every line's maximum), the
  statistical rule (static lines + root-sum-square within an order, summed across orders:
  :func:`wormgear_cli.analysis.budget.statistical_total`) and the deprecated rss rule (static
  lines + root-sum-square of every periodic one); phases do not enter them.  The peak rule (a
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
lag and the spec's effects (not varied); the registry's constant clearances are added to the
lost motion.
All angles [rad], lengths [mm].
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from wormgear_cli.analysis.budget import statistical_total
from wormgear_cli.analysis.simulate import components
from wormgear_cli.drive import spur
from wormgear_cli.drive.models import MODELS
from wormgear_cli.drive.registry import build
from wormgear_cli.drive.spur import base_radius
from wormgear_cli.physics import spur as gear_model
from wormgear_cli.physics.effects import Signals
from wormgear_cli.spec.stages import record_values
from wormgear_cli.tolerance.quantities import train_quantities

if TYPE_CHECKING:
    from wormgear_cli.drive.registry import Registry

PAPER_METRICS = ("total_transmission_error", "total_backlash")
BUDGET_METRICS = ("budget_linear", "budget_statistical", "budget_rss")
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
    """max over phi of the paper's Delta phi_cc of a spur stage as a function of Delta e alone (the
    other inputs are fixed by the spec).  Evaluated with a Chebyshev interpolant on [0, T]
    of :func:`wormgear_cli.physics.spur.gear_te_max_fast` (degree 48, checked against
    the exact maximiser between the nodes to 1e-11 relative; the exact maximiser
    is used when the check fails).  Capped at the value at T (the maximum grows
    with Delta e), so no inspected sample exceeds the corner case; beyond T (an uninspected
    key's tail) the exact maximiser.  ``part="deformation"``:
    instead the deformation part of that maximum (analyze's ``gear_te_deformation``:
    the maximum less the kinematic curve at its angle), not capped.  ``stage``: the spur
    stage record (a spec of a [worm, spur] drive: its spur stage)."""

    def __init__(self, stage, tolerance: float, deflection: float, part: str = "max"):
        if getattr(stage, "kind", None) != "spur":  # a spec: its (one) spur stage
            stage = [s for s in stage.stages if s.kind == "spur"][-1]
        self.args = (stage.module * stage.pinion.teeth / 2.0, stage.module * stage.gear.teeth / 2.0)
        self.alpha, self.d1, self.t, self.part = stage.pressure_angle, deflection, float(tolerance), part
        self.at_t = float(self.exact(np.array([self.t]))[0])
        self.coef = None
        if self.t > 0:
            from numpy.polynomial import chebyshev  # lazy: numpy.polynomial.chebyshev only on this path

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
            from numpy.polynomial import chebyshev  # lazy: numpy.polynomial.chebyshev only on this path

            value = chebyshev.chebval(2.0 * de / self.t - 1.0, self.coef)
        value = np.where(de == self.t, self.at_t, value)
        if self.part == "max":
            value = np.minimum(value, self.at_t)
        over = de > self.t  # beyond the interpolant: an uninspected key's tail, computed exactly
        if np.any(over):
            value = np.where(over, self.exact(np.where(over, de, self.t)), value)
        return value


class StageContext(NamedTuple):
    """What the metrics need of one stage: its ``stage`` record, tooth ``deflection`` [mm], ``columns``
    (stage key -> the sample column, a tuple of columns for an array key), ``own(key)`` its values
    where no column varies, and for a spur stage of the paper's kinematics the interpolants of
    Delta phi_cc's maximum (``te_max``), of its kinematic maximum (``kin_max``, the budget's line) and
    of the deformation part (``def_part``, the budget's static line)."""

    stage: Any  # a stage record of the spec (wormgear_cli.spec.stages)
    deflection: float
    columns: dict
    own: object
    te_max: object = None
    kin_max: object = None
    def_part: object = None


@dataclass(frozen=True)
class Context:
    """Everything the metrics need that the samples do not vary (built once per run)."""

    spec: object
    stages: tuple  # StageContext per stage, motor -> output
    theta: np.ndarray  # test targets [rad]
    fixed_up: np.ndarray  # deflection lag + effects, forward [rad]
    fixed_down: np.ndarray
    registry: Registry | None = None  # the drive's registry (wormgear_cli.drive.registry), built once per run


def _own_values(stage):
    if stage.kind == "spur":
        return spur.values(stage)

    return record_values(stage).__getitem__


def _stage_context(stage, deflection: float, quantities, tolerance: dict) -> StageContext:
    cols = {q.key: (q.columns() if q.length > 1 else q.path) for q in quantities if q.stage == stage.index}
    own = _own_values(stage)
    if stage.kind != "spur" or stage.kinematics != "paper":
        return StageContext(stage, deflection, cols, own)
    t = tolerance.get(stage.index, 0.0)
    return StageContext(stage, deflection, cols, own, GearTeMax(stage, t, deflection), GearTeMax(stage, t, 0.0),
                        GearTeMax(stage, t, deflection, "deformation"))


def context(spec, tolerances, targets_rad: np.ndarray, dwell_s: float = 10.0) -> Context:
    """Build the :class:`Context` of ``spec`` for test targets ``targets_rad`` [rad] (one
    run, forward pass then reverse pass, ``dwell_s`` [s] per point as ``synth``).
    ``tolerances``: the varied quantities (:func:`~wormgear_cli.tolerance.quantities.varied_quantities`,
    which set each paper-kinematics spur stage's interpolation interval [0, T] of Delta e), or a
    number, the eccentricity tolerance of the drive's spur stage."""
    reg = build(spec)
    if isinstance(tolerances, (int, float)):
        spurs = [s.index for s in spec.stages if s.kind == "spur"]
        tol = {spurs[-1]: float(tolerances)} if spurs else {}
        quantities = train_quantities(spec)
    else:
        tol = {v.quantity.stage: v.tolerance[0] for v in tolerances if v.quantity.key == "eccentricity_mm"}
        quantities = tuple(v.quantity for v in tolerances)
    theta = np.asarray(targets_rad, dtype=float)
    n = theta.size
    fixed = {}
    for sign, times in ((1.0, np.arange(n) * dwell_s), (-1.0, (2 * n - 1 - np.arange(n)) * dwell_s)):
        parts = components(spec, Signals.make(theta, sign, 0.0, 20.0, times), registry=reg)
        fixed[sign] = sum((v for k, v in parts.items() if k == "deformation" or k.startswith("effect:")),
                          np.zeros(n))
    stages = tuple(_stage_context(s, d, quantities, tol) for s, d in zip(spec.stages, reg.deflections))
    return Context(spec, stages, theta, np.broadcast_to(fixed[1.0], (n,)).copy(),
                   np.broadcast_to(fixed[-1.0], (n,)).copy(), reg)


def stage_value(ctx: Context, v: dict, stage):
    """``value(stage key)`` -> the sampled values of a stage's key (arrays), from the sample columns
    ``v`` (keyed by the quantities' paths), else the stage's own value: how the registry's
    vectorised size functions and the stage models read a sampled drive."""
    sc = ctx.stages[stage.index - 1]
    cols, own = sc.columns, sc.own

    def value(key):
        col = cols.get(key)
        if isinstance(col, tuple):
            return tuple(np.asarray(v.get(c, own(key)[i]), dtype=float) for i, c in enumerate(col))
        return np.asarray(v[col] if col in v else own(key), dtype=float)

    return value


def _stage_totals(sc: StageContext, value, spec) -> tuple:
    """(TE, backlash) [rad] at the stage's own output shaft per sample, by its kind's model (a worm
    stage with its additions beyond the paper, which are not sampled)."""
    return MODELS[sc.stage.kind].sampled_totals(sc.stage, sc.deflection, value, spec, sc.te_max)


def paper_totals(ctx: Context, values: dict) -> dict[str, np.ndarray]:
    """Total TE and total backlash [rad] per sample, as :func:`analyze` computes them.

    ``values``: column -> values [mm] (see :func:`wormgear_cli.tolerance.sampling.draw`).
    Source: the paper's Delta phi = sum_h Delta phi_h / O_h (O_h the product of the ratios after
    stage h; for its two stages Delta phi_cc + Delta phi_wc / i_c), each stage by its kind's model
    (:mod:`wormgear_cli.drive`; a spur stage by its kinematics, paper or involute), added from
    the output back as :meth:`~wormgear_cli.drive.registry.Registry.totals`.
    """
    assert ctx.registry is not None  # (context() builds it)
    te = bl = 0.0
    for sc, r in zip(reversed(ctx.stages), reversed(ctx.registry.results)):
        t, b = _stage_totals(sc, stage_value(ctx, values, sc.stage), ctx.spec)
        te = te + t / r.after
        bl = bl + b / r.after
    bl = bl + sum(ctx.registry.backlash_additions().values())  # a friction torque's wind-up (not sampled)
    return {"total_transmission_error": te, "total_backlash": bl}


def _sinusoids(ctx: Context, v: dict) -> list:
    """The sinusoidal sources per sample: (amplitude [rad at the output], phase path, order, the spec's
    phase [rad]: kept where the layout samples no phase, e.g. the worm's axial runout in a legacy file), the
    registry's sources in their order (all of them: the budget's too) with their sizes evaluated on
    the samples (:attr:`wormgear_cli.drive.records.Source.size`); a source that is not a sinusoid
    (the paper kinematics' spur curve) is left out."""
    reg = ctx.registry
    assert reg is not None  # (context() builds it)
    train: Any = reg.train  # (the registry's train is typed object in drive.registry)
    stages = train.stages
    out = []
    for src in reg.periodic(all_budget_sources=True):
        if getattr(src.curve, "sine", None) is None:
            continue
        assert src.size is not None  # (a sinusoid's size is a function of the stage's values)
        out.append((src.size(stage_value(ctx, v, stages[src.stage_index - 1])), src.phase_path, src.order,
                    src.phase))
    return out


def _static(ctx: Context, x, value):
    """A static line [rad at the output] per sample: a paper-kinematics spur stage's deformation part
    (it depends on Delta e), an involute spur stage's delta / r_b2, else the registry's constant."""
    sc = ctx.stages[x.stage_index - 1]
    st = sc.stage
    if st.kind == "spur":
        part = sc.def_part(value("eccentricity_mm")) if sc.def_part is not None else \
            sc.deflection / base_radius(st)
        assert ctx.registry is not None  # (context() builds it)
        train: Any = ctx.registry.train  # (the registry's train is typed object in drive.registry)
        return part / train.after(st)
    return x.amplitude


def budget_totals(ctx: Context, values: dict) -> dict[str, np.ndarray]:
    """The full budget's TE [rad] per sample under the linear and the rss rule, as
    :func:`wormgear_cli.analysis.budget.budget` combines its lines (module doc there):
    linear = sum_static a_k + sum_periodic a_k, rss = sum_static a_k + sqrt(sum_periodic a_k^2).

    Lines: the registry's periodic sources with their sizes on the samples (a paper-kinematics spur
    stage's eccentricity: the kinematic maximum of Delta phi_cc at no load, by its interpolant, less
    the curve's mean: its periodic part), and its static lines (:func:`_static`).
    """
    reg = ctx.registry
    assert reg is not None  # (context() builds it)
    train: Any = reg.train  # (the registry's train is typed object in drive.registry)
    stages = train.stages
    periodic = []
    for src in reg.periodic(all_budget_sources=True):
        sc = ctx.stages[src.stage_index - 1]
        value = stage_value(ctx, values, stages[src.stage_index - 1])
        if src.curve_at is not None and sc.kin_max is not None:
            st, de = sc.stage, value("eccentricity_mm")
            mean = gear_model.gear_kinematic_mean(st.module * st.pinion.teeth / 2.0, st.module * st.gear.teeth / 2.0,
                                                  de, st.pressure_angle)  # a constant shift: no line's part
            periodic.append(np.asarray((sc.kin_max(de) - mean) / train.after(st), dtype=float))
        else:
            assert src.size is not None  # (a periodic source's size is a function of the stage's values)
            periodic.append(np.asarray(src.size(value), dtype=float))
    static = None
    for x in reg.statics:
        part = _static(ctx, x, stage_value(ctx, values, stages[x.stage_index - 1]))
        static = part if static is None else static + part
    static = 0.0 if static is None else static
    lin = sum(periodic)
    sq = sum(a * a for a in periodic)
    orders = [src.order for src in reg.periodic(all_budget_sources=True)]
    return {"budget_linear": static + lin, "budget_rss": static + np.sqrt(sq),
            "budget_statistical": statistical_total(periodic, orders, static)}


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
    reg = ctx.registry
    assert reg is not None  # (context() builds it)
    train: Any = reg.train  # (the registry's train is typed object in drive.registry)
    stages = train.stages
    sources = reg.periodic(all_budget_sources=True)
    value = {s.index: stage_value(ctx, v, s) for s in stages}
    n = len(next(iter(v.values())))
    # sources without a size in this chunk (a tolerance of 0: the budget's pitch deviations of most specs)
    # are left out, and with them their orders
    # a source whose phase is not sampled (a key beyond the legacy form's, e.g. the worm's axial runout)
    # keeps the spec's phase
    sines = [(a, ph[k] if k in ph else np.full(np.shape(a), fixed), o)
             for a, k, o, fixed in _sinusoids(ctx, v) if np.any(a)]
    losing = [src for src in sources if src.lost_size is not None]
    # every sinusoid of one order as p sin(o theta) + q cos(o theta): one matrix product per term; the
    # lost-motion orders first
    orders = list(dict.fromkeys([src.order for src in losing] + [o for _, _, o in sines]))
    th = ctx.theta
    basis = np.stack([f(o * th) for o in orders for f in (np.sin, np.cos)] + [np.ones_like(th)])
    where = {o: 2 * k for k, o in enumerate(orders)}
    coef = np.zeros((n, basis.shape[0]))
    for a, psi, o in sines:
        j = where[o]
        amp = np.asarray(a, dtype=float)
        coef[:, j] += amp * np.cos(psi)
        coef[:, j + 1] += amp * np.sin(psi)
    common = coef @ basis
    theta = ctx.theta[None, :]
    for src in sources:
        if src.curve_at is not None:  # the paper's spur curve (not a sinusoid), per sample
            col = value[src.stage_index]
            common += src.curve_at(lambda key: np.asarray(col(key))[:, None], theta,  # noqa: B023
                                   np.asarray(ph[src.phase_path], dtype=float)[:, None])

    def at(order, amplitude, phase, constant):
        c = np.zeros((n, basis.shape[0]))
        j = where[order]
        c[:, j], c[:, j + 1], c[:, -1] = amplitude * np.cos(phase), amplitude * np.sin(phase), constant
        return c @ basis

    # lost motion (never negative): each source's (clipped where it can turn negative), then the clearances
    lost = None
    for src in losing:
        assert src.lost_size is not None  # (losing: the sources with a lost motion)
        c, a, scale, clipped = src.lost_size(value[src.stage_index])
        part = at(src.order, a, np.asarray(ph[src.phase_path], dtype=float), np.broadcast_to(c, (n,)))
        part = np.maximum(part, 0.0) * scale if clipped else part * scale
        lost = part if lost is None else lost + part
    for cl in reg.clearances:
        amount = cl.size(value[cl.stage_index])[:, None] if cl.size is not None else cl.amount
        lost = amount if lost is None else lost + amount
    lost = 0.0 if lost is None else lost
    up = common - 0.5 * lost + ctx.fixed_up[None, :]
    down = common + 0.5 * lost + ctx.fixed_down[None, :]
    e = np.maximum(up.max(axis=1), down.max(axis=1)) - np.minimum(up.min(axis=1), down.min(axis=1))
    bi = common + 0.5 * (ctx.fixed_up + ctx.fixed_down)[None, :]  # (x(up) + x(down)) / 2
    # no noise: s = 0, so A = max(x + 2 s) - min(x - 2 s) over both directions is E
    return {"iso230_E": e, "iso230_B": np.abs(up - down).max(axis=1), "iso230_M": bi.max(axis=1) - bi.min(axis=1),
            "iso230_A": e.copy()}


def evaluate(ctx: Context, values: dict, phases: dict, metrics: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The chosen ``metrics`` [rad] per sample (see the module doc); a metric no sample varies (a duplex
    worm's backlash) is repeated per sample."""
    out = _evaluate(ctx, values, phases, metrics)
    n = len(next(iter(values.values())))
    return {m: (v if np.shape(v) == (n,) else np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy())
            for m, v in out.items()}


def _evaluate(ctx: Context, values: dict, phases: dict, metrics: tuple[str, ...]) -> dict[str, np.ndarray]:
    out = {}
    if any(m in PAPER_METRICS for m in metrics):
        out.update(paper_totals(ctx, values))
    if any(m in BUDGET_METRICS for m in metrics):
        out.update(budget_totals(ctx, values))
    if any(m in ISO_METRICS for m in metrics):
        out.update(iso_figures(ctx, values, phases))
    return {m: out[m] for m in metrics}
