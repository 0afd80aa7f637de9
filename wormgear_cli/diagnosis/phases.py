"""Fitting the spec's model: phases of its periodic sources, zero offset and effect columns.

Deterministic starts (as specified, aligned with the measured harmonics),
a grid over each shaft's phases, a Levenberg-Marquardt polish in the GLS
metric and REML variance components, alternated (:func:`fit_model`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from wormgear_cli.diagnosis.design import orthonormal
from wormgear_cli.diagnosis.mixed import Cross, VarFit, gls_quadratic, reml
from wormgear_cli.diagnosis.runs import Groups
from wormgear_cli.measurement.harmonics import fit_orders
from wormgear_cli.physics.effects import EFFECTS, Signals
from wormgear_cli.units import ARCSEC


@dataclass(frozen=True)
class PhaseSource:
    """A periodic term of the spec whose phase is fitted.

    ``name``: source name (as :func:`simulation.periodic_sources`) or
    ``effect:NAME``; ``key``: TOML path of its phase key; ``order``
    [cycles/output rev]; ``amplitude`` [arcsec] (first harmonic, as
    specified); ``phase`` [rad] as specified; ``contrib(signals, psi)`` ->
    its whole contribution [arcsec] (common part and lost-motion part).
    ``pointwise``: the contribution at a row depends on that row's angle
    and direction only (a source of :func:`simulation.periodic_sources`), so
    it may be evaluated once per distinct (angle, direction) pair
    (:meth:`FitContext.values`)."""

    name: str
    key: str
    order: float
    amplitude: float
    phase: float
    contrib: Callable
    pointwise: bool = False


class _SourceContrib:
    """A simulation source's contribution (sig, psi) -> [arcsec]; :meth:`at_pairs` the same at distinct
    pairs whose angles repeat."""

    def __init__(self, src):
        self.src = src

    def __call__(self, sig: Signals, psi):
        src = self.src
        out = src.curve(sig.theta, psi)
        if src.lost_motion is not None:
            out = out - sig.direction * src.lost_motion(sig.theta, psi) / 2.0
        return out / ARCSEC

    def at_pairs(self, d: Distinct, angles: tuple[np.ndarray, np.ndarray], psi):
        # contrib(d.sig, psi) with the curves (functions of the angle only) evaluated once per distinct angle
        src = self.src
        angle, index = angles
        out = np.take(src.curve(angle, psi), index)
        if src.lost_motion is not None:
            out = out - d.sig.direction * np.take(src.lost_motion(angle, psi), index) / 2.0
        return out / ARCSEC


def pair_values(source: PhaseSource, d: Distinct, psi) -> np.ndarray:
    """``source.contrib(d.sig, psi)`` at the distinct pairs ``d`` (the same numbers: every operation is
    elementwise); a simulation source's curves are evaluated once per distinct angle when the pairs
    repeat their angles (forward and reverse passes at the same targets)."""
    if isinstance(source.contrib, _SourceContrib) and d.angles is not None:
        return source.contrib.at_pairs(d, d.angles, psi)
    return source.contrib(d.sig, psi)


def effect_contrib(eff, params, g):
    def contrib(sig, psi):
        return eff.function(sig, g, **{**params, eff.phase: psi}) / ARCSEC
    return contrib


def phase_sources(spec, geometry, signals) -> tuple[list[PhaseSource], list[PhaseSource]]:
    """(fittable, all) periodic terms of the spec.

    All of :func:`simulation.periodic_sources` plus the spec's periodic
    ``[effects.*]`` (those with a phase key).  A term is fittable when its
    contribution at these samples changes with its phase (a source of zero
    size, or one whose lost motion does not depend on the phase, is not)."""
    # lazy: keeps analysis.simulate off `measure`'s start-up
    from wormgear_cli.analysis.simulate import periodic_sources

    out = []
    for src in periodic_sources(spec):
        out.append(PhaseSource(src.name, src.phase_path, float(src.order), float(src.amplitude) / ARCSEC,
                               float(src.phase), _SourceContrib(src), pointwise=True))
    for name, params in spec.effects.items():
        eff = EFFECTS[name]
        if eff.phase is None or eff.order is None:
            continue
        amp = float(np.max(np.abs(eff.function(unit_circle(), geometry, **params)))) / ARCSEC
        key = next(p.key for p in eff.params if p.name == eff.phase)
        out.append(PhaseSource(f"effect:{name}", f"effects.{name}.{key}", float(eff.order(geometry)), amp,
                               float(params[eff.phase]),
                               effect_contrib(eff, dict(params), geometry)))
    probe = probe_signals(signals)
    fittable = []
    for s in out:
        a = s.contrib(probe, 0.3)
        b = s.contrib(probe, 1.9)
        if np.max(np.abs(a - b)) > 1e-9:
            fittable.append(s)
    return fittable, out


def unit_circle(n: int = 720):
    return Signals.make(np.linspace(0.0, 2.0 * np.pi, n, endpoint=False))


def probe_signals(signals, n: int = 2000):
    step = max(1, signals.theta.shape[0] // n)
    sl = slice(None, None, step)
    theta = np.concatenate([signals.theta[sl], np.linspace(0.0, 2.0 * np.pi, 360, endpoint=False)])
    direction = np.concatenate([signals.direction[sl], np.where(np.arange(360) % 2 == 0, 1.0, -1.0)])
    pad = lambda v, fill: np.concatenate([np.asarray(v)[sl], np.full(360, fill)])  # noqa: E731
    return Signals(theta, direction, pad(signals.load, 0.0), pad(signals.temperature, 20.0), pad(signals.time, 0.0))


def subset(sig, idx):
    return Signals(sig.theta[idx], sig.direction[idx], sig.load[idx], sig.temperature[idx], sig.time[idx])


@dataclass(frozen=True)
class FitContext:
    """The fixed inputs of every fit of one measurement.

    ``y`` (N,) measured error [arcsec]; ``sig``: its signals
    (:class:`wormgear_cli.physics.effects.Signals`); ``groups``: run
    structure; ``base`` (N,) the spec's model without the fitted sources
    [arcsec]; ``sources``: the periodic sources whose phases are fitted;
    ``spec_psi`` (m,) their specified (or starting) phases [rad]."""

    y: np.ndarray
    sig: Signals
    groups: Groups
    base: np.ndarray
    sources: tuple
    spec_psi: tuple

    @property
    def n(self) -> int:
        return int(self.y.shape[0])

    def subsample(self, idx: np.ndarray) -> FitContext:
        """The rows ``idx`` as one group (white-noise metric), for cheap multi-start searches."""
        one = Groups(np.zeros(idx.shape[0], dtype=int), np.array([float(idx.shape[0])]), np.zeros(1, int),
                     np.ones(1), 1, False, False, "subsample")
        return FitContext(self.y[idx], subset(self.sig, idx), one, self.base[idx], self.sources, self.spec_psi)

    def replaced(self, **changes) -> FitContext:
        return replace(self, **changes)

    @cached_property
    def distinct(self) -> Distinct | None:
        """The rows' distinct (angle, direction) pairs, when there are at most half as many as rows."""
        return distinct_pairs(self.sig)

    def values(self, source: PhaseSource, psi) -> np.ndarray:
        """``source.contrib(self.sig, psi)`` (N,) [arcsec]: for a pointwise source evaluated once per
        distinct (angle, direction) pair and spread to the rows (the same numbers: every operation is
        elementwise)."""
        d = self.distinct if source.pointwise else None
        if d is None:
            return source.contrib(self.sig, psi)
        return pair_values(source, d, psi)[d.inverse]


@dataclass(frozen=True)
class Distinct:
    """Distinct (angle, direction) pairs of a measurement's rows: ``sig`` one row per pair (the
    signals of its first row), ``inverse`` (N,) the pair of each row; ``angles``: (distinct angles
    (U,), the angle of each pair (P,)) when the pairs repeat their angles (U <= 3/4 P), else None."""

    sig: Signals
    inverse: np.ndarray
    angles: tuple[np.ndarray, np.ndarray] | None = None


def distinct_pairs(sig, max_share: float = 0.5) -> Distinct | None:
    """The distinct (angle, direction) pairs of ``sig``'s rows (bitwise equal values), or None when
    there are more than ``max_share`` times as many as rows (nothing to gain)."""
    n = sig.theta.shape[0]
    if n == 0 or sig.theta.ndim != 1:
        return None
    theta = np.ascontiguousarray(sig.theta, dtype=float)
    direction = np.ascontiguousarray(np.broadcast_to(sig.direction, theta.shape), dtype=float)
    _, t_first, t_idx = np.unique(theta.view(np.int64), return_index=True, return_inverse=True)
    t_idx = t_idx.reshape(-1)
    d_vals, d_idx = np.unique(direction.view(np.int64), return_inverse=True)
    key = t_idx.astype(np.int64) * d_vals.shape[0] + d_idx.reshape(-1)
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    if first.shape[0] > max_share * n:
        return None
    angles = None
    if t_first.shape[0] <= 0.75 * first.shape[0]:
        angles = (theta[t_first], _index(t_idx[first], t_first.shape[0]))
    return Distinct(subset(sig, first), _index(inverse.reshape(-1), first.shape[0]), angles)


def distinct_angles(theta: np.ndarray, max_share: float = 0.5) -> tuple[np.ndarray, np.ndarray] | None:
    """(distinct values (U,), index of each row's value (N,)) of the angles ``theta`` (bitwise
    equal values), or None when there are more than ``max_share`` times as many as rows."""
    theta = np.ascontiguousarray(theta, dtype=float)
    n = theta.shape[0]
    if n == 0:
        return None
    _, first, inverse = np.unique(theta.view(np.int64), return_index=True, return_inverse=True)
    if first.shape[0] > max_share * n:
        return None
    return theta[first], _index(inverse.reshape(-1), first.shape[0])


def _index(inverse: np.ndarray, size: int) -> np.ndarray:
    """Row -> distinct value index (``size`` values), as np.intp: np.take and fancy indexing convert
    any other index type on every call (an int32 index made each take of 1e5 rows ten times slower)."""
    return np.ascontiguousarray(inverse, dtype=np.intp)


@dataclass(frozen=True)
class PhaseFit:
    """A Levenberg-Marquardt polish: phases ``psi`` [rad], linear coefficients ``beta``,
    ``residual`` (N,) [arcsec] and its GLS ``cost`` (residual' V~^-1 residual); ``parts``:
    each source's contribution [arcsec] at ``psi``, per row or per distinct (angle,
    direction) pair (:func:`_evaluator`): a list a following polish of the same rows from
    ``psi`` takes over (see :func:`levenberg_marquardt`)."""

    psi: np.ndarray
    beta: np.ndarray
    residual: np.ndarray
    cost: float
    parts: list = field(default_factory=list)


@dataclass
class ModelFit:
    """The fitted model at the measured rows.

    ``psi`` [rad] fitted phase of each fittable source; ``beta`` linear
    coefficients (offset [arcsec] first, then effect columns); ``fitted``,
    ``residual`` [arcsec]; ``jac`` (N, m) d fitted / d psi [arcsec/rad];
    ``lin`` (N, l) the linear columns; ``var``: the REML fit of the
    linearised model; ``cost``: residual' V~^-1 residual."""

    psi: np.ndarray
    beta: np.ndarray
    fitted: np.ndarray
    residual: np.ndarray
    jac: np.ndarray
    lin: np.ndarray
    var: VarFit
    cost: float

    @property
    def offset(self) -> float:
        return float(self.beta[0])


def sources_total(sources, sig, psi):
    out = np.zeros(sig.theta.shape)
    for s, p in zip(sources, psi):
        out = out + s.contrib(sig, p)
    return out


def _sum_parts(parts, n: int) -> np.ndarray:
    """Sum of the (N,) arrays ``parts``, added in list order: the same numbers as
    ``np.sum(parts, axis=0)`` without its (len(parts), N) stacked copy."""
    if not parts:
        return np.zeros(n)
    out = parts[0].copy()
    for p in parts[1:]:
        out += p
    return out


def _jacobian(sources, sig, psi, h: float = 1e-5, parts=None, out=None, values=None, spread=None):
    """d contribution / d phase [arcsec/rad] per source: central differences, or forward
    differences from the contributions ``parts`` already computed at ``psi``; written into
    ``out`` (N, m) when given (e.g. the first columns of a design).  ``values(source, psi)``:
    how a contribution is evaluated (default ``source.contrib(sig, psi)``); ``spread(a)``:
    from those values to the rows (default: they are the rows; see :func:`_evaluator`)."""
    if values is None:
        values = lambda s, p: s.contrib(sig, p)  # noqa: E731
    cols = np.empty((sig.theta.shape[0], len(sources))) if out is None else out
    for j, (s, p) in enumerate(zip(sources, psi)):
        if parts is None:
            col = (values(s, p + h) - values(s, p - h)) / (2 * h)
        else:
            col = (values(s, p + h) - parts[j]) / h
        if spread is None:
            cols[:, j] = col
        else:
            np.take(col, spread, out=cols[:, j])
    return cols


def _evaluator(ctx: FitContext):
    """(values, spread, size): how :func:`levenberg_marquardt` evaluates the sources of ``ctx``.

    When every source is pointwise and the rows repeat (angle, direction) pairs,
    contributions, their sums and finite differences are kept per distinct pair
    (``size`` of them) and ``spread`` (the row -> pair index) takes them to the rows
    only where a row-sized array is needed: every step is elementwise, so the numbers
    are those of the row-sized arrays, for a fraction of the work and memory.
    Otherwise ``values`` is :meth:`FitContext.values`, ``spread`` None and ``size`` N."""
    d = ctx.distinct
    if d is not None and ctx.sources and all(s.pointwise for s in ctx.sources):
        return (lambda s, p: pair_values(s, d, p)), d.inverse, int(d.sig.theta.shape[0])
    return ctx.values, None, ctx.n


def _to_rows(a, spread):
    return a if spread is None else np.take(a, spread)


def gls_cost(r, groups, gp, gr):
    """r' V~^-1 r [arcsec^2] of a residual r (N,) at variance ratios gp, gr (:func:`mixed.gls_quadratic`)."""
    return gls_quadratic(r, groups, gp, gr)


def levenberg_marquardt(ctx: FitContext, psi, lin, gp, gr, fit_phases=True, iters=40, parts=None) -> PhaseFit:
    """Levenberg-Marquardt on the phases and the linear coefficients in the GLS metric
    (variance ratios ``gp``, ``gr`` held).

    ``parts``: the sources' contributions at ``psi`` on ``ctx``'s rows when
    already known (the ``parts`` of a previous polish on the same rows ending
    at ``psi``): a list the fit takes over and empties, so the caller's copy
    holds no N-sized arrays while the fit runs.

    Not :func:`scipy.optimize.least_squares`, measured: on the 19 white-metric
    polishes of the 1e5-row bench case (2000-row subsamples, the bulk of the
    calls) least_squares(method="lm") reached the same cost (never lower by
    more than 1e-9 relative) in 0.85 s CPU against 0.29 s for this one (its
    finite-difference Jacobian re-evaluates every source for every parameter;
    here each source's column comes from its own contribution only).  The
    full-data polishes work in the GLS metric from per-pass sums, which
    least_squares would need as a whitened residual V~^(-1/2) r at every call."""
    y, sig, groups, base, sources = ctx.y, ctx.sig, ctx.groups, ctx.base, ctx.sources
    m = len(sources) if fit_phases else 0
    psi = np.array(psi, dtype=float)
    n = y.shape[0]
    values, spread, size = _evaluator(ctx)
    if parts:
        given = parts
        parts = list(given)
        given.clear()
    else:
        parts = [values(s, p) for s, p in zip(sources, psi)]
    src = _to_rows(_sum_parts(parts, size), spread)
    # start with the linear coefficients solved exactly
    r0 = y - base - src
    cr = Cross.build(lin, r0, groups)
    A, b, _, _ = cr.weighted([gp], [gr])
    beta = np.linalg.lstsq(A[0], b[0], rcond=None)[0]
    resid = r0 - lin @ beta
    cost = gls_cost(resid, groups, gp, gr)
    mu = 1e-3
    # [Jacobian | linear columns], made once by np.hstack (whose memory layout, C or Fortran, the products
    # downstream follow bit for bit): the Jacobian columns are rewritten in place each iteration
    design = np.hstack([np.empty((n, m)), lin])
    for _ in range(iters):
        if m:
            _jacobian(sources, sig, psi, h=1e-6, parts=parts, out=design[:, :m], values=values, spread=spread)
        cr = Cross.build(design, resid, groups)
        A, b, _, _ = cr.weighted([gp], [gr])
        A, b = A[0], b[0]
        diag = np.diag(A).copy()
        diag = np.where(diag > 0, diag, 1.0)
        improved = False
        for _ in range(12):
            try:
                step = np.linalg.solve(A + mu * np.diag(diag) + 1e-12 * np.max(diag) * np.eye(len(b)), b)
            except np.linalg.LinAlgError:
                mu *= 10.0
                continue
            psi_new = psi + step[:m]
            beta_new = beta + step[m:]
            parts_new = [values(s, p) for s, p in zip(sources, psi_new)] if m else parts
            src_new = _to_rows(_sum_parts(parts_new, size), spread) if m else src
            resid_new = y - base - src_new - lin @ beta_new
            cost_new = gls_cost(resid_new, groups, gp, gr)
            if cost_new <= cost:
                rel = (cost - cost_new) / max(cost, 1e-300)
                psi, beta, src, resid, cost, parts = psi_new, beta_new, src_new, resid_new, cost_new, parts_new
                mu = max(mu / 5.0, 1e-12)
                improved = True
                break
            mu *= 8.0
        if not improved or rel < 1e-10:
            break
    return PhaseFit(psi, beta, resid, cost, parts)


def _harmonic_starts(ctx: FitContext):
    """Deterministic starting phases: as specified; aligned with the measured
    harmonic at each order; and rotated variants for shafts carrying several sources."""
    y, sig, base, sources, spec_psi = ctx.y, ctx.sig, ctx.base, ctx.sources, ctx.spec_psi

    starts = [np.array(spec_psi, dtype=float)]
    if not sources:
        return starts
    orders = sorted({s.order for s in sources})
    with np.errstate(invalid="ignore", divide="ignore"):
        fit = fit_orders(sig.theta, y - base, orders)
    measured = {o: fit.phase[i] for i, o in enumerate(orders)}
    circle = unit_circle(1440)
    intrinsic = []
    for s in sources:
        both = 0.5 * (s.contrib(circle, 0.0)
                      + s.contrib(type(circle)(circle.theta, -circle.direction, circle.load, circle.temperature,
                                                circle.time), 0.0))
        with np.errstate(invalid="ignore", divide="ignore"):
            f0 = fit_orders(circle.theta, both, [s.order])
        intrinsic.append(float(f0.phase[0]) if f0.amplitude[0] > 1e-12 else 0.0)
    rank = {}
    for s in sources:
        rank[s.name] = sum(1 for t in sources if t.order == s.order and sources.index(t) < sources.index(s))
    for spread in (0.0, math.pi):
        starts.append(np.array([measured[s.order] - intrinsic[j] + spread * min(rank[s.name], 1)
                                for j, s in enumerate(sources)]))
    return starts


def _memo(memo: dict, key, make):
    """``memo[key]``, made by ``make()`` the first time: what a phase scan uses that depends
    neither on its start nor on its sweep (the QR factor of the linear columns, each source's
    values on the grid), computed once for the scans of one fit from several starts."""
    if key not in memo:
        memo[key] = make()
    return memo[key]


def _grid_values(source, sig2, phases, d, rows: int) -> np.ndarray:
    """(N, grid) a source's contribution at each grid phase, at the rows (spread from the distinct
    pairs ``d`` when given)."""
    values = np.broadcast_to(source.contrib(sig2, phases[None, :]), (rows, phases.shape[0]))
    return values if d is None else values[d.inverse]


def _group_scan(ctx: FitContext, psi, lin, grid: int = 24, sweeps: int = 4, keep: int = 4, memo: dict | None = None):
    """Candidate phase vectors found shaft by shaft on a grid (white-noise metric, linear
    columns projected out).

    For the sources sharing an order (at most three at a time; larger groups one
    by one), every combination of ``grid`` phases is scored with the others held:
    the cost of (i_1..i_m) is |r - sum_k c_k(i_k)|^2 after the projection,
    expanded with the Gram matrix of the projected columns, so all grid^m
    combinations cost one small matrix product.  Sweeps repeat until nothing
    moves.  Grid points are only a coarse look at the landscape (a large source
    misplaced by half a step costs more than a wrong basin), so besides the best
    vector the ``keep`` lowest local minima of each shaft's grid are returned,
    for the caller to polish and compare.  ``memo``: a dict shared by the scans of one
    ``ctx`` and ``lin`` from several starts (:func:`_memo`)."""
    y, sig, base, sources = ctx.y, ctx.sig, ctx.base, ctx.sources
    psi = np.array(psi, dtype=float)
    if not sources:
        return [psi]
    memo = {} if memo is None else memo
    q = _memo(memo, "q", lambda: np.linalg.qr(lin)[0])
    # pointwise sources on rows that repeat (angle, direction) pairs: evaluated at the pairs and spread
    d = ctx.distinct if all(s.pointwise for s in sources) else None
    at = sig if d is None else d.sig
    sig2 = Signals(at.theta[:, None], at.direction[:, None], at.load[:, None], at.temperature[:, None],
                   at.time[:, None])

    def on_grid(k):
        return _memo(memo, k, lambda: _grid_values(sources[k], sig2, phases, d, at.theta.shape[0]))

    def value(k, p):
        return sources[k].contrib(sig, p) if d is None else ctx.values(sources[k], p)
    phases = np.linspace(0.0, 2.0 * np.pi, grid, endpoint=False)
    by_order: dict = {}
    for k, s in enumerate(sources):
        by_order.setdefault(s.order, []).append(k)
    blocks = []
    for members in by_order.values():
        blocks += [members] if len(members) <= 3 else [[k] for k in members]
    contrib = [value(k, p) for k, p in enumerate(psi)]
    total = np.sum(contrib, axis=0)

    def project(a):
        return a - q @ (q.T @ a)

    def grid_cost(members):
        m = len(members)
        rest = y - base - (total - sum(contrib[k] for k in members))
        cols = [on_grid(k) for k in members]
        z = project(np.hstack([*cols, rest[:, None]]))
        gram = z.T @ z
        cost = np.full((grid,) * m, gram[-1, -1])
        for a in range(m):
            shape = [grid if i == a else 1 for i in range(m)]
            cost = cost - 2.0 * gram[a * grid:(a + 1) * grid, -1].reshape(shape)
            for b in range(m):
                blk = gram[a * grid:(a + 1) * grid, b * grid:(b + 1) * grid]
                if a == b:
                    cost = cost + np.diag(blk).reshape(shape)
                else:
                    # G_ab[i_a, i_b] laid out on axes a and b (rows on the lower axis)
                    pair = blk if a < b else blk.T
                    cost = cost + pair.reshape([grid if i in (a, b) else 1 for i in range(m)])
        now = project(rest - sum(contrib[k] for k in members))
        return cost, float(now @ now)

    def move(members, idx):
        nonlocal total
        for a, k in enumerate(members):
            psi[k] = phases[idx[a]]
            new = value(k, psi[k])
            total = total - contrib[k] + new
            contrib[k] = new

    for _ in range(sweeps):
        changed = False
        for members in blocks:
            cost, now = grid_cost(members)
            best = np.unravel_index(int(np.argmin(cost)), cost.shape)
            if float(cost[best]) < now * (1.0 - 1e-9):
                move(members, best)
                changed = True
        if not changed:
            break
    out = [psi.copy()]
    for members in blocks:
        cost, _ = grid_cost(members)
        # local minima of the periodic grid (no neighbour lower)
        is_min = np.ones(cost.shape, dtype=bool)
        for axis in range(cost.ndim):
            for shift in (-1, 1):
                is_min &= cost <= np.roll(cost, shift, axis=axis)
        flat = np.flatnonzero(is_min.ravel())
        for j in flat[np.argsort(cost.ravel()[flat])][1:keep]:
            alt = psi.copy()
            for a, k in enumerate(members):
                alt[k] = phases[np.unravel_index(int(j), cost.shape)[a]]
            out.append(alt)
    return out


def fit_model(ctx: FitContext, lin, fit_phases=True, extra_starts=(), variance: VarFit | None = None) -> ModelFit:
    """Fit the phases (if ``fit_phases``) and the linear coefficients of ``lin`` (N, l) by
    GLS with REML variance components (alternating, at most three rounds).

    The phases start from several deterministic points (:func:`_harmonic_starts`
    from ``ctx.spec_psi``, plus ``extra_starts``), each refined on a subsample of
    at most 3000 rows with white-noise weights; the best is then refined on every
    row.  With ``variance`` the variance ratios are held at that fit's (no REML)."""
    y, sig, groups, sources = ctx.y, ctx.sig, ctx.groups, ctx.sources
    m = len(sources) if fit_phases else 0
    n = y.shape[0]
    psi = np.array(ctx.spec_psi, dtype=float)
    ev, spread, _ = _evaluator(ctx)
    if m:
        step = max(1, n // 2000)
        idx = np.arange(0, n, step)
        sub = ctx.subsample(idx)
        best: PhaseFit | None = None
        starts = [*_harmonic_starts(sub), *extra_starts]
        inits = [*starts[:1], *extra_starts]
        sub_lin, memo = lin[idx], dict[object, np.ndarray]()
        for start in starts:
            inits += _group_scan(sub, start, sub_lin, keep=3, memo=memo)
        seen = set()
        for init in inits:
            key = tuple(np.round(np.mod(init, 2 * np.pi), 3))
            if key in seen:
                continue
            seen.add(key)
            trial = levenberg_marquardt(sub, init, lin[idx], 0.0, 0.0, True, 25)
            trial.parts.clear()
            if best is None or trial.cost < best.cost - 1e-9 * abs(trial.cost):
                best = trial
        assert best is not None  # (_harmonic_starts gives at least one start)
        psi = best.psi
    if variance is not None:
        held = levenberg_marquardt(ctx, psi, lin, variance.gp, variance.gr, m > 0)
        jac = _jacobian(sources, sig, held.psi, values=ev, spread=spread) if m else np.zeros((n, 0))
        return ModelFit(held.psi, held.beta, y - held.residual, held.residual, jac, lin, variance, held.cost)
    gp = gr = 0.0
    var: VarFit | None = None
    pf: PhaseFit | None = None
    for _ in range(3):
        # each round starts where the last ended: its contributions there are taken over, not recomputed
        pf = levenberg_marquardt(ctx, psi, lin, gp, gr, m > 0, parts=pf.parts if pf is not None else None)
        psi = pf.psi
        jac = _jacobian(sources, sig, psi, values=ev, spread=spread) if m else np.zeros((n, 0))
        cr = Cross.build(orthonormal(np.hstack([lin, jac]), own=True)[0], pf.residual, groups)
        var = reml(cr)
        done = abs(var.gp - gp) <= 0.05 * max(gp, 1e-9) and abs(var.gr - gr) <= 0.05 * max(gr, 1e-9)
        gp, gr = var.gp, var.gr
        if done:
            break
    else:
        assert pf is not None  # (the loop ran)
        pf = levenberg_marquardt(ctx, psi, lin, gp, gr, m > 0, parts=pf.parts)
        psi = pf.psi
        jac = _jacobian(sources, sig, psi, values=ev, spread=spread) if m else np.zeros((n, 0))
    assert pf is not None and var is not None  # (the loop ran)
    return ModelFit(psi, pf.beta, y - pf.residual, pf.residual, jac, lin, var, pf.cost)
