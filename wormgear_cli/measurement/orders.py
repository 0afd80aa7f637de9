"""A measurement's orders: coverage, aliasing, resolution and the joint fit, with reasons.

:func:`analyse_orders` decides for every requested order whether it can be fitted on these
samples (beyond the covered span, aliased by the target spacing, folded, too few distinct angles,
not determined apart from the others) and fits the rest jointly in common and differential mode.
The normal equations are accumulated once over the distinct angles (:class:`_AngleSums`), so a
table of many runs reduces to its targets and a dense scan is streamed in blocks.  Pure numpy,
no I/O.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from wormgear_cli.measurement.coverage import Coverage, coverage, trend_columns, unwrap_passes
from wormgear_cli.measurement.coverage import as_1d as _as_1d
from wormgear_cli.measurement.drift import SlowModel, SlowPart, drift_size, pass_keys, slow_model
from wormgear_cli.measurement.harmonics import (
    ALIAS_TOL,
    BLOCK_ROWS,
    ModeFit,
    OrderFit,
    _folded,
    _groups,
    _order_values,
    fit_modes,
    select_orders,
)
from wormgear_cli.measurement.separation import SEPARATION_CORR, canonical_correlations, separation_groups
from wormgear_cli.measurement.serial import SerialBlocks, block_covariance, point_noise, serial_blocks

#: statuses of an order in :class:`OrderReport`
STATUSES = ("fitted", "ambiguous", "aliased", "folded", "unresolved", "beyond span")


@dataclass(frozen=True)
class OrdersOptions:
    """Options of :func:`analyse_orders`.

    ``labels``: a label (shaft or mesh, or None) per requested order;
    ``priority``: orders in the order that breaks ties between orders the
    samples cannot tell apart at all (default: as requested); ``tol``: alias
    tolerance (:func:`~wormgear_cli.measurement.harmonics.alias_groups`);
    ``passes`` (N,) int: run or pass of each row (per-pass span, unwrapping,
    repeated traversals, blocks of the standard errors); ``direction``
    splits them further; ``time`` (N,) [s]: time of each row (the drift in
    time and the time order of the rows; default the row order);
    ``unique``: ``np.unique(theta, return_inverse=True)`` when already
    computed; ``separation``: the canonical correlation above which orders
    closer than 360 deg / span apart are one group
    (:data:`~wormgear_cli.measurement.separation.SEPARATION_CORR`);
    ``serial``: standard errors that hold for serially correlated rows
    (:func:`~wormgear_cli.measurement.serial.serial_blocks`; False: ordinary
    least squares); ``drift_per_run``: each run (``passes``) has an offset and a
    drift in time of its own (the sessions of a guide log;
    :func:`~wormgear_cli.measurement.drift.slow_model`)."""

    labels: tuple | None = None
    priority: tuple | None = None
    tol: float = ALIAS_TOL
    passes: object = None
    time: object = None
    unique: object = None
    separation: float = SEPARATION_CORR
    serial: bool = True
    drift_per_run: bool = False


@dataclass(frozen=True)
class OrderReport:
    """One requested order after :func:`analyse_orders`.

    ``order`` [cycles/rev]; ``label`` (shaft or mesh, or None); ``status``
    (one of :data:`STATUSES`): "fitted"; "ambiguous" (one of a group of
    orders closer than 360 deg / span apart whose columns correlate: the
    group is fitted as one order, its *carrier*, which holds the group's
    amplitude; the others have none); "aliased" (not fitted: the samples
    cannot tell it from the offset or from another requested order, which
    then carries its content); "folded" (its cos and sin are collinear on
    the samples: one phase component only, not fitted); "unresolved" (not
    fitted: too few distinct angles, or not determined apart from the other
    orders); "beyond span" (too slow for the covered arc: no amplitude; the
    slow part is modelled as a trend or drift); ``fitted`` = it has an
    amplitude (status "fitted", or the carrier of an ambiguous group);
    ``aliased_with``: the other requested orders (0.0 = the offset) the
    samples cannot tell it from; ``common`` / ``differential``: (amplitude,
    amplitude_stderr, phase [rad]) of the mean of the directions and of
    half the reversal, NaN where not fitted; ``reason``: why it was not
    fitted, or the group it carries (None when fitted alone); ``group``: the
    members of its separation group (empty when it has none).
    """

    order: float
    label: str | None
    status: str
    aliased_with: tuple[float, ...]
    common: tuple[float, float, float]
    differential: tuple[float, float, float]
    reason: str | None = None
    group: tuple[float, ...] = ()

    @property
    def fitted(self) -> bool:
        return self.status == "fitted" or (self.status == "ambiguous" and math.isfinite(self.common[0]))


@dataclass(frozen=True)
class OrdersAnalysis:
    """Result of :func:`analyse_orders`: ``items`` per distinct requested
    order (in request order), the joint fit's ``residual_rms`` and
    ``sigma``, ``common_offset`` and ``differential_offset`` (half the mean
    reversal; NaN with one direction), ``alias_tol``, ``both_directions``,
    ``distinct_angles`` (number of distinct sampled angles), ``coverage``
    (:class:`Coverage`), ``trend_degree`` (degree of the polynomial that
    stands for the slow part over a partial span; 0 for none), ``unwrapped``
    (angles made continuous for non-integer orders), ``groups`` (the
    :class:`~wormgear_cli.measurement.separation.SeparationGroup` of orders
    fitted as one), ``serial`` (:class:`~wormgear_cli.measurement.serial.SerialBlocks`:
    how the standard errors treat serially correlated rows), ``slow``
    (:class:`~wormgear_cli.measurement.drift.SlowPart`: the trend or drift
    and its size), ``point_noise`` (the point-to-point noise of the residual
    within passes, :func:`~wormgear_cli.measurement.serial.point_noise`)."""

    items: tuple[OrderReport, ...]
    residual_rms: float
    sigma: float
    common_offset: float
    differential_offset: float
    alias_tol: float
    both_directions: bool
    distinct_angles: int
    coverage: Coverage | None = None
    trend_degree: int = 0
    unwrapped: bool = False
    groups: tuple = ()
    serial: SerialBlocks | None = None
    slow: SlowPart | None = None
    point_noise: float = math.nan


@dataclass(frozen=True)
class _Request:
    """The requested orders without repeats, their labels and the tie-break rank."""

    ords: list
    labs: list
    rank: dict

    @classmethod
    def make(cls, orders, opt: OrdersOptions) -> _Request:
        ords: list[float] = []
        labs: list[str | None] = []
        for i, k in enumerate(np.atleast_1d(np.asarray(orders, dtype=float))):
            if float(k) not in ords:
                ords.append(float(k))
                labs.append(None if opt.labels is None else opt.labels[i])
        rank = {k: len(ords) for k in ords}
        for i, k in enumerate([] if opt.priority is None else [float(v) for v in opt.priority]):
            if k in rank and rank[k] == len(ords):
                rank[k] = i
        return cls(ords, labs, rank)

    def key(self, k: float):
        return (self.rank[k], self.ords.index(k))

    @property
    def by_priority(self) -> list[float]:
        return sorted(self.ords, key=self.key)


def analyse_orders(theta, y, direction, orders: Sequence[float],
                   options: OrdersOptions | None = None) -> OrdersAnalysis:
    """Amplitudes at exact orders of a measurement, coverage, aliasing, separation and resolution handled.

    Parameters
    ----------
    theta : array_like [rad], shape (n,)
    y : array_like [any unit], shape (n,)
        Errors.
    direction : array_like, shape (n,)
        +1 / -1 per row.
    orders : sequence of float [cycles/rev]
        Repeats dropped, first kept.
    options : OrdersOptions, optional

    Steps
    -----
    1. Coverage (:func:`coverage`, the largest gap judged against the
       periods asked for) and the slow part (:func:`slow_model`): over a
       partial arc traversed once, a polynomial in the angle along the arc
       (orders whose period is longer than the span are "beyond span");
       traversed repeatedly, a polynomial in time (angle-fixed content, a
       runout too, is fitted as orders).
    2. With non-integer orders the angles are made continuous per pass
       (:func:`unwrap_passes`) so wrapped and unwrapped files agree.
    3. Alias groups on the sampled angles (:func:`alias_groups`): an order
       grouped with the offset is not fitted; in any other group only the
       member first in ``priority`` is fitted and carries the group.
    4. Folded orders (:func:`folded_orders`) are not fitted.
    5. Separation groups (:func:`separation_groups`): orders closer than 360
       deg / span apart whose columns correlate are fitted as one, at the
       member that explains most; the others are "ambiguous".
    6. The rest are kept by how well each is determined (:func:`select_orders`).
    7. One joint least-squares fit on all rows: common mode + direction x
       differential mode at the kept orders (and the slow part).
    8. Standard errors from blocks of consecutive rows when the residual is
       serially correlated (:func:`serial_blocks`), else ordinary.
    """
    opt = options or OrdersOptions()
    req = _Request.make(orders, opt)
    theta = _as_1d("theta", theta)
    n = theta.shape[0]
    d = _as_1d("direction", direction, n)
    y = _as_1d("y", y, n)
    unwrapped = any(k != round(k) for k in req.ords)
    th = unwrap_passes(theta, opt.passes) if unwrapped else theta
    sums = _AngleSums.build(th, y, d, None if unwrapped else opt.unique)
    cov = coverage(theta, opt.passes, unique=sums.ut, orders=req.ords)
    slow = slow_model(theta, cov, opt.passes, d, opt.time, per_run=opt.drift_per_run)
    if slow.kind == "time":
        sums = _AngleSums.build_rows(th, y, d).with_trend(slow.columns)
    elif slow.degree:
        sums = sums.with_trend(trend_columns(sums.ut, cov, slow.degree))
    state = _Decisions(req, {}, {}, {})
    _too_slow(state, cov, slow)
    design = _Design.make(sums, [k for k in req.ords if k not in state.status])
    candidates = _alias_and_fold(state, design, opt.tol, cov)
    candidates = _separate(state, design, candidates, cov, opt.separation)
    design = design.restricted(candidates)
    res = select_orders(th[:0], candidates, gram=design.g0, distinct=sums.ut.shape[0])
    for k in candidates:
        if k in res.kept:
            state.status.setdefault(k, "fitted")
        else:
            state.status[k] = "unresolved"
            state.reason[k] = res.reason.get(k, "not determined on these angles")
    fitted = [k for k in req.ords if k in res.kept]
    solved = _solve_sums(sums, design, fitted)
    if solved is None:  # ill-conditioned: the row-wise solve (minimum-norm, identifiability per column)
        rows_trend = slow.columns if slow.kind == "time" else (trend_columns(th, cov, slow.degree) if slow.degree
                                                               else None)
        fit = fit_modes(th, y, d, fitted, trend=rows_trend)
        serial, drift = SerialBlocks("independent rows", math.nan, 1, n), math.nan
        noise = point_noise(fit.residual, _pass_keys(opt.passes, d), opt.time)
    else:
        fit, serial, drift, noise = _finish(solved, sums, design, fitted, opt)
    return OrdersAnalysis(tuple(_items(req, state, fit, fitted)), fit.rms, fit.sigma, fit.common.offset,
                          fit.differential.offset if sums.both else math.nan, opt.tol, sums.both, cov.distinct, cov,
                          slow.degree, unwrapped, tuple(state.groups.values()), serial, slow.part(drift), noise)


@dataclass
class _Decisions:
    """What :func:`analyse_orders` decided so far: status and reason per order, the separation group of
    each ambiguous order (carrier -> group) and the alias group of each order."""

    req: _Request
    status: dict
    reason: dict
    groups: dict
    group_of: dict = field(default_factory=dict)


def _too_slow(state: _Decisions, cov: Coverage, slow: SlowModel) -> None:
    """Orders with too few distinct angles, or too slow for the covered arc."""
    span_deg = math.degrees(cov.span)
    for k in state.req.ords:
        if cov.distinct < 3:
            state.status[k] = "unresolved"
            state.reason[k] = f"too few distinct angles ({cov.distinct}): an order needs at least 3 (offset, cos, sin)"
        elif slow.beyond(cov, k):
            state.status[k] = "beyond span"
            if slow.run_span > 0:
                state.reason[k] = (f"beyond span: one period is longer than the longest run "
                                   f"({math.degrees(slow.run_span):.4g} deg), so it cannot be told from the runs' own "
                                   "offsets and drifts (no amplitude)")
            elif slow.kind == "angle":
                state.reason[k] = (f"beyond span: one period is longer than the {span_deg:.4g} deg the data cover, so "
                                   "it cannot be told from a trend (no amplitude)")
            else:
                state.reason[k] = (f"beyond span: less than an eighth of one period over the {span_deg:.4g} deg the "
                                   "data cover, so it cannot be told from the offset (no amplitude)")


@dataclass(frozen=True)
class _Design:
    """The normal equations of [1, trend, cos/sin per order] for the orders ``rest`` (g0, g1, r0, r1 of
    :meth:`_AngleSums.grams`) and the number of fixed columns (offset and trend)."""

    rest: list
    g0: np.ndarray
    g1: np.ndarray
    r0: np.ndarray
    r1: np.ndarray
    fixed: int
    n: float

    @classmethod
    def make(cls, sums: _AngleSums, rest: list) -> _Design:
        g0, g1, r0, r1 = sums.grams(np.asarray(rest, dtype=float))
        return cls(list(rest), g0, g1, r0, r1, 1 + sums.trend_count, float(sums.n))

    def columns(self, ks) -> list[int]:
        cols = list(range(self.fixed))
        for k in ks:
            i = self.rest.index(k)
            cols += [self.fixed + 2 * i, self.fixed + 2 * i + 1]
        return cols

    def restricted(self, ks: list) -> _Design:
        cols = self.columns(ks)
        sub = np.ix_(cols, cols)
        return _Design(list(ks), self.g0[sub], self.g1[sub], self.r0[cols], self.r1[cols], self.fixed, self.n)


def _alias_and_fold(state: _Decisions, design: _Design, tol: float, cov: Coverage) -> list[float]:
    """Aliased and folded orders decided; the candidates left, by priority.  Orders that look alike only
    because the arc is short (closer than 360 deg / span apart) are left to the separation rule: it is
    the span, not the spacing of the samples, that cannot tell them apart."""
    req, rest = state.req, design.rest
    if rest:
        arr = np.asarray(rest)
        cm, cp, cz = _correlations_from_gram(design.g0, design.fixed, len(rest), design.n)
        arc = 2.0 * math.pi if cov.full_turn else cov.span
        groups = [g for g in _groups(arr, cm, cp, cz, tol)
                  if 0.0 in g or (max(g) - min(g)) * arc >= 2.0 * math.pi * (1.0 - 1e-9)]
        folded = set(_folded(arr, cp, tol))
    else:
        groups, folded = [], set()
    for grp in groups:
        for k in grp:
            state.group_of[k] = grp
    candidates = []
    for k in req.by_priority:
        if k in state.status:
            continue
        g = state.group_of.get(k)
        if g is not None and (0.0 in g or k != min((v for v in g if v in req.rank), key=req.key)):
            state.status[k] = "aliased"
            state.reason[k] = "the target spacing makes it indistinguishable from " + (
                "a constant" if 0.0 in g else "order " + ", ".join(f"{v:g}" for v in g if v != k))
        elif k in folded:
            state.status[k] = "folded"
            state.reason[k] = "only one phase component is seen on these angles (cos and sin collinear)"
        else:
            candidates.append(k)
    return candidates


def _separate(state: _Decisions, design: _Design, candidates: list, cov: Coverage, threshold: float) -> list[float]:
    """Orders the span cannot separate, fitted as one group each at the member whose columns explain most of
    the data (common mode, with the offset and trend); the other members are "ambiguous"."""
    if len(candidates) < 2:
        return candidates
    sub = design.restricted(candidates)
    corr = canonical_correlations(sub.g0, sub.fixed, len(candidates))
    groups = separation_groups(candidates, corr, cov.span, cov.full_turn, threshold)
    if not groups:
        return candidates
    span_deg = math.degrees(cov.span) if not cov.full_turn else 360.0
    out = list(candidates)
    for grp in groups:
        carrier = max(grp.orders, key=lambda k: (_explained(sub, k), -state.req.rank[k]))
        text = grp.describe(span_deg)
        state.groups[carrier] = grp
        for k in grp.orders:
            state.status[k] = "ambiguous"
            state.reason[k] = text + (f"; fitted as one order at {carrier:g}, which carries the group's amplitude"
                                      if k == carrier else f"; its content is shown at order {carrier:g}")
            if k != carrier:
                out.remove(k)
    return out


def _explained(design: _Design, k: float) -> float:
    """Sum of squares of the data (common-mode normal equations) explained by order ``k`` beyond the fixed columns."""
    fixed = list(range(design.fixed))
    cols = design.columns([k])
    g, r = design.g0[np.ix_(cols, cols)], design.r0[cols]
    gf, rf = design.g0[np.ix_(fixed, fixed)], design.r0[fixed]
    full = float(r @ np.linalg.lstsq(g, r, rcond=1e-12)[0])
    base = float(rf @ np.linalg.lstsq(gf, rf, rcond=1e-12)[0])
    return full - base


def _items(req: _Request, state: _Decisions, fit: ModeFit, fitted: list) -> list[OrderReport]:
    pos = {k: i for i, k in enumerate(fitted)}
    nan3 = (math.nan, math.nan, math.nan)

    def triple(f, i):
        if not f.identifiable[i] or not np.isfinite(f.amplitude[i]):
            return nan3
        return (float(f.amplitude[i]), float(f.amplitude_stderr[i]), float(f.phase[i]))

    member_of = {m: g for g in state.groups.values() for m in g.orders}
    items = []
    for k, lab in zip(req.ords, req.labs):
        others = [v for v in state.group_of.get(k, (k,)) if v != k]
        group = member_of[k].orders if k in member_of else ()
        status = state.status[k]
        if k in pos:
            i = pos[k]
            reason = state.reason.get(k) if status == "ambiguous" else None
            items.append(OrderReport(k, lab, status, tuple(others), triple(fit.common, i),
                                     triple(fit.differential, i), reason, group))
        else:
            items.append(OrderReport(k, lab, status, tuple(others), nan3, nan3, state.reason.get(k), group))
    return items


# --- the joint fit from sums over distinct angles --------------------------------------------------------------


@dataclass(frozen=True)
class _AngleSums:
    """Per distinct angle: count, sum of d, sum of y, sum of d y (d = direction); and sum of y^2.

    The normal equations of the joint common/differential fit only need
    these (d^2 = 1): with B the rows of [1, trend, cos/sin] at the distinct
    angles, X^T X = [[B^T C B, B^T D B], [B^T D B, B^T C B]] and X^T y =
    [B^T Sy, B^T Sdy] with C = diag(count), D = diag(sum d).  A table of
    many runs over few targets is reduced to its targets; a dense scan is
    streamed in blocks."""

    ut: np.ndarray
    count: np.ndarray
    sum_d: np.ndarray
    sum_y: np.ndarray
    sum_dy: np.ndarray
    yy: float
    n: int
    both: bool
    trend: np.ndarray  # (distinct x t)
    inverse: np.ndarray  # (n,) the unit of each row
    d: np.ndarray  # (n,) direction of each row
    y_rows: np.ndarray  # (n,) the data of each row

    @property
    def trend_count(self) -> int:
        return self.trend.shape[1]

    def with_trend(self, trend: np.ndarray) -> _AngleSums:
        """The same sums with trend columns (distinct x t) at the distinct angles."""
        return dataclasses.replace(self, trend=trend)

    @classmethod
    def build(cls, theta, y, d, unique=None) -> _AngleSums:
        ut, inverse = np.unique(theta, return_inverse=True) if unique is None else unique
        inverse = inverse.ravel()
        m = ut.shape[0]
        count = np.bincount(inverse, minlength=m).astype(float)
        sum_d = np.bincount(inverse, weights=d, minlength=m)
        sum_y = np.bincount(inverse, weights=y, minlength=m)
        sum_dy = np.bincount(inverse, weights=d * y, minlength=m)
        both = bool(np.any(d > 0) and np.any(d < 0))
        return cls(ut, count, sum_d, sum_y, sum_dy, float(y @ y), int(theta.shape[0]), both, np.zeros((m, 0)),
                   inverse, d, y)

    @classmethod
    def build_rows(cls, theta, y, d) -> _AngleSums:
        """One unit per row (no reduction): for columns that vary from row to row, such as a drift in time."""
        n = theta.shape[0]
        both = bool(np.any(d > 0) and np.any(d < 0))
        return cls(np.asarray(theta, dtype=float), np.ones(n), np.asarray(d, dtype=float), np.asarray(y, dtype=float),
                   d * y, float(y @ y), n, both, np.zeros((n, 0)), np.arange(n), d, y)

    def basis(self, ords: np.ndarray, units: np.ndarray) -> np.ndarray:
        """Rows [1, trend, cos/sin per order] at the units ``units`` (indices)."""
        blk = np.empty((units.shape[0], 1 + self.trend_count + 2 * ords.shape[0]))
        blk[:, 0] = 1.0
        blk[:, 1:1 + self.trend_count] = self.trend[units]
        _fill_harmonics(blk, 1 + self.trend_count, self.ut[units], ords)
        return blk

    def grams(self, ords: np.ndarray):
        """(B^T C B, B^T D B, B^T Sy, B^T Sdy) for the columns [1, trend, cos/sin per order]."""
        p = 1 + self.trend_count + 2 * ords.shape[0]
        g0 = np.zeros((p, p))
        g1 = np.zeros((p, p))
        r0 = np.zeros(p)
        r1 = np.zeros(p)
        m = self.ut.shape[0]
        for a in range(0, m, BLOCK_ROWS):
            b = min(a + BLOCK_ROWS, m)
            blk = np.empty((b - a, p))
            blk[:, 0] = 1.0
            blk[:, 1:1 + self.trend_count] = self.trend[a:b]
            _fill_harmonics(blk, 1 + self.trend_count, self.ut[a:b], ords)
            weighted = np.concatenate([blk * self.count[a:b, None], blk * self.sum_d[a:b, None]], axis=1) \
                if self.both else blk * self.count[a:b, None]
            g = weighted.T @ blk
            g0 += g[:p]
            if self.both:
                g1 += g[p:]
            r = blk.T @ np.column_stack([self.sum_y[a:b], self.sum_dy[a:b]])
            r0 += r[:, 0]
            r1 += r[:, 1]
        return g0, g1, r0, r1


#: integer orders up to this are evaluated as powers of exp(i theta) (products, not trig calls)
MAX_POWER_ORDER = 1 << 16


def _fill_harmonics(blk: np.ndarray, first: int, theta: np.ndarray, ords: np.ndarray) -> None:
    """Write cos(k theta), sin(k theta) per order into ``blk[:, first::2]`` and ``blk[:, first + 1::2]``.

    Integer orders (up to :data:`MAX_POWER_ORDER`) are the real and imaginary
    parts of z^k, z = exp(i theta), by binary powering (a few complex
    products per order instead of two trig calls; relative error ~k eps,
    about 1e-13 at order 1000); other orders by cos and sin."""
    m = ords.shape[0]
    if m == 0:
        return
    integer = (ords == np.round(ords)) & (ords >= 1) & (ords <= MAX_POWER_ORDER)
    if np.all(integer) and m > 2:
        z = np.exp(1j * theta)
        squares = {1: z}
        top = int(ords.max())
        p = 1
        while p * 2 <= top:
            squares[p * 2] = squares[p] * squares[p]
            p *= 2
        for j, k in enumerate(ords.astype(np.int64)):
            r = None
            bit = 1
            while bit <= k:
                if k & bit:
                    r = squares[bit] if r is None else r * squares[bit]
                bit *= 2
            assert r is not None  # (every order here is an integer >= 1)
            blk[:, first + 2 * j] = r.real
            blk[:, first + 2 * j + 1] = r.imag
        return
    arg = np.multiply.outer(theta, ords)
    blk[:, first:first + 2 * m:2] = np.cos(arg)
    blk[:, first + 1:first + 2 * m:2] = np.sin(arg)


def _correlations_from_gram(gram: np.ndarray, first: int, m: int, total: float):
    """(C_minus, C_plus, C_zero) of :func:`order_correlations` / :func:`offset_correlations` from the
    row-weighted Gram matrix of [1, ..., cos/sin per order] (harmonic columns from index ``first``):
    sum exp(i (k_i -/+ k_j) theta) expands into sums of cos/sin products."""
    c = first + 2 * np.arange(m)
    s_ = c + 1
    cc = gram[np.ix_(c, c)]
    ss = gram[np.ix_(s_, s_)]
    cs = gram[np.ix_(c, s_)]  # sum cos_i sin_j
    c_minus = np.hypot(cc + ss, cs.T - cs) / total
    c_plus = np.hypot(cc - ss, cs.T + cs) / total
    c_zero = np.hypot(gram[0, c], gram[0, s_]) / total
    return c_minus, c_plus, c_zero


@dataclass(frozen=True)
class _Solved:
    """The joint fit's normal-equation solution: coefficients [common columns, differential columns],
    their (unscaled) inverse Gram matrix, rss, sigma, rms and the columns per mode."""

    coef: np.ndarray
    gram_inv: np.ndarray
    rss: float
    sigma: float
    rms: float
    p: int


def _solve_sums(sums: _AngleSums, design: _Design, fitted: list) -> _Solved | None:
    """The joint fit at the ``fitted`` orders from the accumulated sums; None when the normal equations
    are ill-conditioned (the caller then solves row-wise)."""
    b = np.asarray(design.columns(fitted), dtype=int)
    p = b.shape[0]
    if sums.both:
        gram = np.block([[design.g0[np.ix_(b, b)], design.g1[np.ix_(b, b)]],
                         [design.g1[np.ix_(b, b)], design.g0[np.ix_(b, b)]]])
        rhs = np.concatenate([design.r0[b], design.r1[b]])
    else:
        gram = design.g0[np.ix_(b, b)]
        rhs = design.r0[b]
    if sums.n < gram.shape[0]:
        return None
    lam, vec = np.linalg.eigh(gram)
    if not lam[0] > 1e-8 * lam[-1] > 0:
        return None
    cov = (vec / lam) @ vec.T
    coef = cov @ rhs
    rss = max(sums.yy - 2.0 * float(coef @ rhs) + float(coef @ gram @ coef), 0.0)
    dof = sums.n - gram.shape[0]
    sigma = math.sqrt(rss / dof) if dof > 0 else math.nan
    return _Solved(coef, cov, rss, sigma, math.sqrt(rss / sums.n), p)


def _finish(solved: _Solved, sums: _AngleSums, design: _Design, fitted: list,
            opt: OrdersOptions) -> tuple[ModeFit, SerialBlocks, float, float]:
    """(the :class:`ModeFit` with standard errors that hold for the rows' serial correlation, how, the
    peak-to-peak of the fitted slow part, the point-to-point noise of the residual)."""
    ords = np.asarray(fitted, dtype=float)
    resid = _row_residual(sums, ords, solved)
    n = sums.n
    serial = SerialBlocks("independent rows", math.nan, 1, n)
    keys = _pass_keys(opt.passes, sums.d)
    if opt.serial and n > solved.coef.shape[0] + 2:
        serial = serial_blocks(resid, keys, opt.time)
    if serial.independent:
        cov, scale = solved.gram_inv, solved.sigma
    else:
        scores = _score_sums(sums, ords, serial.whiten(resid), serial)
        cov, scale = block_covariance(solved.gram_inv, scores, n) * serial.recolour, 1.0
    fit = _mode_fits(solved, ords, cov, scale, sums.both, design.fixed)
    t = sums.trend_count
    drift = drift_size(sums.trend[sums.inverse], solved.coef[1:1 + t]) if t else 0.0
    return fit, serial, drift, point_noise(resid, keys, opt.time)


def _pass_keys(passes, d: np.ndarray) -> np.ndarray:
    """A pass id per row: the run (or pass) split by direction."""
    return pass_keys(passes, d)


def _row_residual(sums: _AngleSums, ords: np.ndarray, solved: _Solved) -> np.ndarray:
    """y - fit per row, the fit evaluated once per unit (distinct angle) and spread to the rows."""
    p = solved.p
    m = sums.ut.shape[0]
    fc = np.empty(m)
    fd = np.zeros(m)
    for a in range(0, m, BLOCK_ROWS):
        blk = sums.basis(ords, np.arange(a, min(a + BLOCK_ROWS, m)))
        fc[a:a + blk.shape[0]] = blk @ solved.coef[:p]
        if sums.both:
            fd[a:a + blk.shape[0]] = blk @ solved.coef[p:]
    inv = sums.inverse
    return sums.y_rows - (fc[inv] + sums.d * fd[inv])


def _score_sums(sums: _AngleSums, ords: np.ndarray, resid: np.ndarray, serial: SerialBlocks) -> np.ndarray:
    """Per block, the sum over its rows of x_t e_t (x_t: the row's design [B, d B], e_t its residual),
    accumulated over the distinct (block, unit) pairs."""
    u = sums.ut.shape[0]
    assert serial.block_id is not None  # (called for serial blocks only)
    key = serial.block_id.astype(np.int64) * u + sums.inverse
    pairs, pinv = np.unique(key, return_inverse=True)
    pinv = pinv.reshape(-1)
    w_c = np.bincount(pinv, weights=resid, minlength=pairs.shape[0])
    w_d = np.bincount(pinv, weights=sums.d * resid, minlength=pairs.shape[0])
    unit, block = pairs % u, pairs // u
    p = 1 + sums.trend_count + 2 * ords.shape[0]
    width = 2 * p if sums.both else p
    out = np.zeros((serial.blocks, width))
    for a in range(0, pairs.shape[0], BLOCK_ROWS):
        b = min(a + BLOCK_ROWS, pairs.shape[0])
        blk = sums.basis(ords, unit[a:b])
        for j in range(p):
            out[:, j] += np.bincount(block[a:b], weights=blk[:, j] * w_c[a:b], minlength=serial.blocks)
            if sums.both:
                out[:, p + j] += np.bincount(block[a:b], weights=blk[:, j] * w_d[a:b], minlength=serial.blocks)
    return out


def _mode_fits(solved: _Solved, ords: np.ndarray, cov: np.ndarray, scale: float, both: bool, fixed: int) -> ModeFit:
    """Common and differential :class:`OrderFit` from the solution; amplitude standard errors from ``cov``
    times ``scale`` squared (sigma for the ordinary covariance, 1 for a sandwich)."""
    m, p = ords.shape[0], solved.p
    rms, sigma, rank = solved.rms, solved.sigma, solved.coef.shape[0]
    fits = []
    for start in (0, p):
        if start == p and not both:
            nan = np.full(m, np.nan)
            fits.append(OrderFit(ords, nan, nan, nan, nan, nan, nan, np.zeros(m, dtype=bool), math.nan,
                                 np.zeros(0), np.zeros(0), rms, sigma, rank, rank, False))
            continue
        c = solved.coef[start:start + p]
        cv = cov[start:start + p, start:start + p]
        ia = fixed + 2 * np.arange(m)
        a_, b_ = c[ia], c[ia + 1]
        cov_ab = np.empty((m, 2, 2))
        cov_ab[:, 0, 0] = cv[ia, ia]
        cov_ab[:, 1, 1] = cv[ia + 1, ia + 1]
        cov_ab[:, 0, 1] = cov_ab[:, 1, 0] = cv[ia, ia + 1]
        ident = np.ones(m, dtype=bool)
        amp, phase, amp_se, phase_se = _order_values(a_, b_, cov_ab, ident, scale)
        fits.append(OrderFit(ords, amp, phase, a_, b_, amp_se, phase_se, ident, float(c[0]), np.zeros(0),
                             np.zeros(0), rms, sigma, rank, rank, False))
    return ModeFit(fits[0], fits[1], np.zeros(0), rms, sigma, rank, rank, False)
