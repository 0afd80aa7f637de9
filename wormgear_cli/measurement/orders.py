"""A measurement's orders: coverage, aliasing, resolution and the joint fit, with reasons.

:func:`analyse_orders` decides for every requested order whether it can be fitted on these
samples (beyond the covered span, aliased by the target spacing, folded, too few distinct angles,
not determined apart from the others) and fits the rest jointly in common and differential mode.
The normal equations are accumulated once over the distinct angles (:class:`_AngleSums`), so a
table of many runs reduces to its targets and a dense scan is streamed in blocks.  Pure numpy,
no I/O.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from wormgear_cli.measurement.coverage import TREND_DEGREE, Coverage, coverage, trend_columns, unwrap_passes
from wormgear_cli.measurement.coverage import as_1d as _as_1d
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

#: statuses of an order in :class:`OrderReport`
STATUSES = ("fitted", "aliased", "folded", "unresolved", "beyond span")


@dataclass(frozen=True)
class OrderReport:
    """One requested order after :func:`analyse_orders`.

    ``order`` [cycles/rev]; ``label`` (shaft or mesh, or None); ``status``
    (one of :data:`STATUSES`): "fitted"; "aliased" (not fitted: the samples
    cannot tell it from the offset or from another requested order, which
    then carries its content); "folded" (its cos and sin are collinear on
    the samples: one phase component only, not fitted); "unresolved" (not
    fitted: too few distinct angles, or not determined apart from the other
    orders); "beyond span" (its period is longer than the covered span: it
    cannot be told from a trend, no amplitude is given; the slow part is
    modelled as a trend); ``fitted`` = status is "fitted";
    ``aliased_with``: the other requested orders (0.0 = the offset) the
    samples cannot tell it from; ``common`` / ``differential``: (amplitude,
    amplitude_stderr, phase [rad]) of the mean of the directions and of
    half the reversal, NaN where not fitted; ``reason``: why it was not
    fitted (None when fitted).
    """

    order: float
    label: str | None
    status: str
    aliased_with: tuple[float, ...]
    common: tuple[float, float, float]
    differential: tuple[float, float, float]
    reason: str | None = None

    @property
    def fitted(self) -> bool:
        return self.status == "fitted"


@dataclass(frozen=True)
class OrdersAnalysis:
    """Result of :func:`analyse_orders`: ``items`` per distinct requested
    order (in request order), the joint fit's ``residual_rms`` and
    ``sigma``, ``common_offset`` and ``differential_offset`` (half the mean
    reversal; NaN with one direction), ``alias_tol``, ``both_directions``,
    ``distinct_angles`` (number of distinct sampled angles), ``coverage``
    (:class:`Coverage`), ``trend_degree`` (degree of the polynomial trend
    fitted over a partial span; 0 for none), ``unwrapped`` (angles made
    continuous for non-integer orders)."""

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


def analyse_orders(theta, y, direction, orders: Sequence[float], labels: Sequence[str | None] | None = None,
                   priority: Sequence[float] | None = None, tol: float = ALIAS_TOL, passes=None,
                   unique=None) -> OrdersAnalysis:
    """Amplitudes at exact orders of a measurement, coverage, aliasing and resolution handled.

    Parameters
    ----------
    theta : array_like [rad], shape (n,)
    y : array_like [any unit], shape (n,)
        Errors.
    direction : array_like, shape (n,)
        +1 / -1 per row.
    orders : sequence of float [cycles/rev]
        Repeats dropped, first kept.
    labels : sequence of str or None, optional
    priority : sequence of float, optional
        Tie-break between orders the samples cannot tell apart at all
        (default: ``orders`` as given).
    tol : float
        Alias tolerance (:func:`alias_groups`).
    passes : array_like of int, shape (n,), optional
        Pass of each row (for the per-pass span and the unwrapping).
    unique : (ndarray, ndarray), optional
        ``np.unique(theta, return_inverse=True)`` when already computed.

    Steps
    -----
    1. Coverage (:func:`coverage`): on a partial span, orders whose period
       is longer than the span are "beyond span" (not fitted) and a
       polynomial trend of degree :data:`TREND_DEGREE` in the angle along
       the arc (fewer with few distinct angles) stands for the slow part.
    2. With non-integer orders the angles are made continuous per pass
       (:func:`unwrap_passes`) so wrapped and unwrapped files agree.
    3. Alias groups on the sampled angles (:func:`alias_groups`): an order
       grouped with the offset is not fitted; in any other group only the
       member first in ``priority`` is fitted and carries the group.
    4. Folded orders (:func:`folded_orders`) are not fitted.
    5. The rest are kept by how well each is determined
       (:func:`select_orders`).
    6. One joint least-squares fit on all rows (:func:`fit_modes`): common
       mode + direction x differential mode at the kept orders (and the
       trend).
    """
    theta = _as_1d("theta", theta)
    d = _as_1d("direction", direction, theta.shape[0])
    ords: list[float] = []
    labs: list[str | None] = []
    for i, k in enumerate(np.atleast_1d(np.asarray(orders, dtype=float))):
        if float(k) not in ords:
            ords.append(float(k))
            labs.append(None if labels is None else labels[i])
    rank = {k: len(ords) for k in ords}
    for i, k in enumerate([] if priority is None else [float(v) for v in priority]):
        if k in rank and rank[k] == len(ords):
            rank[k] = i
    by_priority = sorted(ords, key=lambda k: (rank[k], ords.index(k)))
    unwrapped = any(k != round(k) for k in ords)
    th = unwrap_passes(theta, passes) if unwrapped else theta
    y = _as_1d("y", y, theta.shape[0])
    sums = _AngleSums.build(th, y, d, None if unwrapped else unique)
    cov = coverage(theta, passes, unique=sums.ut)
    degree = 0 if cov.full_turn else max(0, min(TREND_DEGREE, cov.distinct - 2))
    if degree:
        sums = sums.with_trend(trend_columns(sums.ut, cov, degree))
    status: dict[float, str] = {}
    reason: dict[float, str] = {}
    span_deg = math.degrees(cov.span)
    for k in ords:
        if cov.distinct < 3:
            status[k] = "unresolved"
            reason[k] = (f"too few distinct angles ({cov.distinct}): an order needs at least 3 (offset, cos, sin)")
        elif cov.beyond(k):
            status[k] = "beyond span"
            reason[k] = (f"beyond span: one period is longer than the {span_deg:.4g} deg the data cover, so it "
                         "cannot be told from a trend (no amplitude)")
    rest = [k for k in ords if k not in status]
    # one pass over the distinct angles: the Gram matrices of [1, trend, cos/sin of every remaining order]
    g0, g1, r0, r1 = sums.grams(np.asarray(rest, dtype=float))
    t_cols = sums.trend_count
    if rest:
        arr = np.asarray(rest)
        cm, cp, cz = _correlations_from_gram(g0, 1 + t_cols, len(rest), float(sums.n))
        groups = _groups(arr, cm, cp, cz, tol)
        folded = set(_folded(arr, cp, tol))
    else:
        groups, folded = [], set()
    group_of: dict[float, tuple[float, ...]] = {}
    for g in groups:
        for k in g:
            group_of[k] = g
    candidates = []
    for k in by_priority:
        if k in status:
            continue
        g = group_of.get(k)
        if g is not None and (0.0 in g or k != min((v for v in g if v in rank),
                                                     key=lambda v: (rank[v], ords.index(v)))):
            status[k] = "aliased"
            reason[k] = "the target spacing makes it indistinguishable from " + (
                "a constant" if 0.0 in g else "order " + ", ".join(f"{v:g}" for v in g if v != k))
        elif k in folded:
            status[k] = "folded"
            reason[k] = "only one phase component is seen on these angles (cos and sin collinear)"
        else:
            candidates.append(k)
    cols = list(range(1 + t_cols))
    for k in candidates:
        i = rest.index(k)
        cols += [1 + t_cols + 2 * i, 2 + t_cols + 2 * i]
    sub = np.ix_(cols, cols)
    g0, g1, r0, r1 = g0[sub], g1[sub], r0[cols], r1[cols]
    res = select_orders(th[:0], candidates, gram=g0, distinct=sums.ut.shape[0])
    for k in candidates:
        if k in res.kept:
            status[k] = "fitted"
        else:
            status[k] = "unresolved"
            reason[k] = res.reason.get(k, "not determined on these angles")
    fitted = [k for k in ords if status[k] == "fitted"]
    fit = _fit_from_sums(sums, candidates, fitted, g0, g1, r0, r1)
    if fit is None:  # ill-conditioned: the row-wise solve (minimum-norm, identifiability per column)
        fit = fit_modes(th, y, d, fitted, trend=trend_columns(th, cov, degree) if degree else None)
    pos = {k: i for i, k in enumerate(fitted)}
    nan3 = (math.nan, math.nan, math.nan)

    def triple(f, i):
        if not f.identifiable[i] or not np.isfinite(f.amplitude[i]):
            return nan3
        return (float(f.amplitude[i]), float(f.amplitude_stderr[i]), float(f.phase[i]))

    items = []
    for k, lab in zip(ords, labs):
        others = [v for v in group_of.get(k, (k,)) if v != k]
        if k in pos:
            i = pos[k]
            items.append(OrderReport(k, lab, "fitted", tuple(others), triple(fit.common, i),
                                     triple(fit.differential, i)))
        else:
            items.append(OrderReport(k, lab, status[k], tuple(others), nan3, nan3, reason.get(k)))
    both = bool(np.any(d > 0) and np.any(d < 0))
    return OrdersAnalysis(tuple(items), fit.rms, fit.sigma, fit.common.offset,
                          fit.differential.offset if both else math.nan, tol, both, cov.distinct, cov, degree,
                          unwrapped)


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

    @property
    def trend_count(self) -> int:
        return self.trend.shape[1]

    def with_trend(self, trend: np.ndarray) -> _AngleSums:
        """The same sums with trend columns (distinct x t) at the distinct angles."""
        import dataclasses

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
        return cls(ut, count, sum_d, sum_y, sum_dy, float(y @ y), int(theta.shape[0]), both, np.zeros((m, 0)))

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


def _fit_from_sums(sums: _AngleSums, candidates, fitted, g0, g1, r0, r1):
    """The joint fit at the ``fitted`` orders from the accumulated sums, as a :class:`ModeFit`
    (residual left empty); None when the normal equations are ill-conditioned (the caller then
    solves row-wise)."""
    t = sums.trend_count
    base = list(range(1 + t))
    for k in fitted:
        i = candidates.index(k)
        base += [1 + t + 2 * i, 2 + t + 2 * i]
    b = np.asarray(base, dtype=int)
    p = b.shape[0]
    if sums.both:
        gram = np.block([[g0[np.ix_(b, b)], g1[np.ix_(b, b)]], [g1[np.ix_(b, b)], g0[np.ix_(b, b)]]])
        rhs = np.concatenate([r0[b], r1[b]])
    else:
        gram = g0[np.ix_(b, b)]
        rhs = r0[b]
    if sums.n < gram.shape[0]:
        return None
    lam, vec = np.linalg.eigh(gram)
    if not lam[0] > 1e-8 * lam[-1] > 0:
        return None
    cov = (vec / lam) @ vec.T
    coef = cov @ rhs
    rss = max(sums.yy - 2.0 * float(coef @ rhs) + float(coef @ gram @ coef), 0.0)
    rank = gram.shape[0]
    dof = sums.n - rank
    sigma = math.sqrt(rss / dof) if dof > 0 else math.nan
    rms = math.sqrt(rss / sums.n)
    m = len(fitted)
    ords = np.asarray(fitted, dtype=float)
    fits = []
    for start in (0, p):
        if start == p and not sums.both:
            nan = np.full(m, np.nan)
            fits.append(OrderFit(ords, nan, nan, nan, nan, nan, nan, np.zeros(m, dtype=bool), math.nan,
                                 np.zeros(0), np.zeros(0), rms, sigma, rank, rank, False))
            continue
        c = coef[start:start + p]
        cv = cov[start:start + p, start:start + p]
        ia = 1 + t + 2 * np.arange(m)
        a_, b_ = c[ia], c[ia + 1]
        cov_ab = np.empty((m, 2, 2))
        cov_ab[:, 0, 0] = cv[ia, ia]
        cov_ab[:, 1, 1] = cv[ia + 1, ia + 1]
        cov_ab[:, 0, 1] = cov_ab[:, 1, 0] = cv[ia, ia + 1]
        ident = np.ones(m, dtype=bool)
        amp, phase, amp_se, phase_se = _order_values(a_, b_, cov_ab, ident, sigma)
        fits.append(OrderFit(ords, amp, phase, a_, b_, amp_se, phase_se, ident, float(c[0]), np.zeros(0),
                             np.zeros(0), rms, sigma, rank, rank, False))
    return ModeFit(fits[0], fits[1], np.zeros(0), rms, sigma, rank, rank, False)
