"""The error of a rotary axis as a correction table needs it: fitted orders per direction, and
per-target means where the orders do not explain the data.

The model of the error at output angle theta moving in direction d (+1 forward, -1 reverse) is
the one ``measure`` fits (common mode plus direction times differential mode, at exact orders,
with a polynomial trend over a partial span)::

    e(theta, d) = c + sum_k [a_k cos k theta + b_k sin k theta] + T(theta)
                  + d (c' + sum_k [a'_k cos k theta + b'_k sin k theta] + T'(theta))

so it can be evaluated anywhere, between the measured targets too.  Where the orders leave a
residual at the targets that stands above the noise (:class:`TargetTest`: a chi-square test of
the residual cell means against the scatter between runs), the residual means per target and
direction are added, interpolated between the targets by a cubic spline (periodic round a full
turn): the table then follows the measured means at the targets and the model's shape, smoothly
bent, between them.  A spline rather than straight lines: a kink at every target would be
sampled again by the table's own straight lines and leave an error at the targets themselves.

Over a partial span the model is held at the ends of the covered arc outside it (a trend must
not be extrapolated).  Pure numpy; scipy for the test's tail probability and the spline.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from wormgear_cli.compensation.noise import noise_components
from wormgear_cli.measurement.coverage import Coverage, trend_columns, unwrap_passes
from wormgear_cli.measurement.harmonics import BLOCK_ROWS, harmonic_columns
from wormgear_cli.measurement.iso230 import group_targets
from wormgear_cli.measurement.orders import OrdersOptions, analyse_orders

#: significance of the residual at the targets above which per-target means are added
TARGET_ALPHA = 0.01
#: a target is named in the test's report when its residual mean exceeds this many standard errors
WORST_SE = 3.0
#: fewest targets a spline is drawn through (fewer: straight lines between them)
SPLINE_TARGETS = 4


@dataclass(frozen=True)
class ModelPlan:
    """What a correction model is made of, fixed once for the data and reused for every refit.

    ``orders`` [cycles/rev]: the orders fitted; ``unwrapped``: angles made
    continuous per pass (non-integer orders); ``coverage``: the span the
    data cover; ``trend_degree``: degree of the trend over a partial span
    (0: none); ``per_target``: per-target residual means are added;
    ``both``: both directions were measured (else the differential mode is
    zero and the reverse error equals the forward one).
    """

    orders: tuple[float, ...]
    unwrapped: bool
    coverage: Coverage
    trend_degree: int
    per_target: bool
    both: bool


@dataclass(frozen=True)
class CorrectionModel:
    """A fitted :class:`ModelPlan`; angles in rad.

    ``orders`` (m,); ``common`` and ``differential`` (m, 2): (a, b) of
    a cos k theta + b sin k theta; ``offset``, ``differential_offset``;
    ``trend_common``, ``trend_differential`` (t,): coefficients of the
    Chebyshev trend columns; ``targets`` (sorted target angles) and
    ``residual_forward``, ``residual_reverse`` (per-target residual means,
    NaN where a direction was not measured; empty without per-target means).
    """

    plan: ModelPlan
    orders: np.ndarray
    common: np.ndarray
    differential: np.ndarray
    offset: float
    differential_offset: float
    trend_common: np.ndarray
    trend_differential: np.ndarray
    targets: np.ndarray
    residual_forward: np.ndarray
    residual_reverse: np.ndarray

    def without(self, orders: Sequence[float]) -> CorrectionModel:
        """The same model with the given orders left out (their terms set to zero)."""
        drop = np.isin(self.orders, np.asarray(list(orders), dtype=float))
        common, diff = self.common.copy(), self.differential.copy()
        common[drop] = 0.0
        diff[drop] = 0.0
        return dataclasses.replace(self, common=common, differential=diff)

    def _held(self, theta: np.ndarray) -> np.ndarray:
        """Angles outside a partial span moved to the nearer end of the covered arc."""
        cov = self.plan.coverage
        if cov.full_turn:
            return theta
        two_pi = 2.0 * math.pi
        u = np.mod(theta - cov.start, two_pi)
        outside = u > cov.span
        u = np.where(outside & (u - cov.span < two_pi - u), cov.span, np.where(outside, 0.0, u))
        return cov.start + u

    def error(self, theta, direction) -> np.ndarray:
        """The modelled error [rad] at angles ``theta`` [rad] moving in ``direction`` (+1/-1), (n,)."""
        theta = self._held(np.asarray(theta, dtype=float))
        d = np.broadcast_to(np.asarray(direction, dtype=float), theta.shape)
        common = np.full(theta.shape, self.offset)
        diff = np.full(theta.shape, self.differential_offset)
        for k, (a, b), (ad, bd) in zip(self.orders, self.common, self.differential):
            c, s = np.cos(k * theta), np.sin(k * theta)
            common += a * c + b * s
            diff += ad * c + bd * s
        if self.plan.trend_degree:
            t = trend_columns(theta, self.plan.coverage, self.plan.trend_degree)
            common += t @ self.trend_common
            diff += t @ self.trend_differential
        out = common + d * diff
        if self.targets.size:
            out += np.where(d > 0, self._residual(theta, self.residual_forward),
                            self._residual(theta, self.residual_reverse))
        return out

    def _residual(self, theta: np.ndarray, values: np.ndarray) -> np.ndarray:
        """The per-target residual means between the targets: a cubic spline through them
        (periodic round a full turn), linear with fewer than :data:`SPLINE_TARGETS` targets."""
        ok = np.isfinite(values)
        if not np.any(ok):
            return np.zeros(theta.shape)
        two_pi = 2.0 * math.pi
        cov = self.plan.coverage
        start = 0.0 if cov.full_turn else cov.start
        x = np.mod(self.targets[ok] - start, two_pi)
        order = np.argsort(x)
        x, f = x[order], values[ok][order]
        u = np.mod(theta - start, two_pi)
        if cov.full_turn:
            if x.size < SPLINE_TARGETS:
                return np.interp(u, x, f, period=two_pi)
            from scipy.interpolate import CubicSpline  # the spline through the targets

            return CubicSpline(np.append(x, x[0] + two_pi), np.append(f, f[0]), bc_type="periodic")(u)
        if x.size < SPLINE_TARGETS:
            return np.interp(u, x, f)
        from scipy.interpolate import CubicSpline  # the spline through the targets

        return CubicSpline(x, f, bc_type="natural")(np.clip(u, x[0], x[-1]))

def parameters(plan: ModelPlan, theta, direction) -> int:
    """Values a table of ``plan`` is fitted with on these rows: the model's columns, or with
    per-target means the cells (target and direction) they are taken over."""
    if plan.per_target:
        index = group_targets(np.asarray(theta, dtype=float))[0]
        return int(np.unique(2 * index + (np.asarray(direction) < 0)).size)
    return (1 + 2 * len(plan.orders) + plan.trend_degree) * (2 if plan.both else 1)


def _design_block(theta: np.ndarray, d: np.ndarray, plan: ModelPlan, a: int, b: int) -> np.ndarray:
    ords = np.asarray(plan.orders, dtype=float)
    parts = [np.ones((b - a, 1)), harmonic_columns(theta[a:b], ords)]
    if plan.trend_degree:
        parts.append(trend_columns(theta[a:b], plan.coverage, plan.trend_degree))
    base = np.hstack(parts)
    return np.hstack([base, base * d[a:b, None]]) if plan.both else base


def fit_plan(plan: ModelPlan, theta, y, direction, run=None) -> CorrectionModel:
    """Least squares of the plan's model on the rows (angles [rad], errors [rad], +1/-1).

    The normal equations are accumulated in blocks of rows (memory stays
    proportional to the rows, not rows x columns) and solved by a
    pseudo-inverse, so orders the rows cannot tell apart share their content
    instead of failing.  With ``plan.per_target`` the residual means per
    target and direction are kept (:class:`CorrectionModel`).
    """
    theta = np.asarray(theta, dtype=float)
    y = np.asarray(y, dtype=float)
    d = np.asarray(direction, dtype=float)
    th = unwrap_passes(theta, run) if plan.unwrapped else theta
    n = th.shape[0]
    m = len(plan.orders)
    p = 1 + 2 * m + plan.trend_degree
    cols = 2 * p if plan.both else p
    gram = np.zeros((cols, cols))
    rhs = np.zeros(cols)
    for a in range(0, n, BLOCK_ROWS):
        b = min(a + BLOCK_ROWS, n)
        x = _design_block(th, d, plan, a, b)
        gram += x.T @ x
        rhs += x.T @ y[a:b]
    scale = np.sqrt(np.maximum(np.diag(gram), 1e-300))
    coef = np.linalg.pinv(gram / np.outer(scale, scale), rcond=1e-10, hermitian=True) @ (rhs / scale) / scale
    zeros_p = np.zeros(p)
    cc, dc = coef[:p], (coef[p:] if plan.both else zeros_p)
    model = CorrectionModel(
        plan=plan, orders=np.asarray(plan.orders, dtype=float),
        common=np.column_stack([cc[1:1 + 2 * m:2], cc[2:2 + 2 * m:2]]).reshape(m, 2),
        differential=np.column_stack([dc[1:1 + 2 * m:2], dc[2:2 + 2 * m:2]]).reshape(m, 2),
        offset=float(cc[0]), differential_offset=float(dc[0]),
        trend_common=cc[1 + 2 * m:], trend_differential=dc[1 + 2 * m:],
        targets=np.zeros(0), residual_forward=np.zeros(0), residual_reverse=np.zeros(0))
    if not plan.per_target:
        return model

    index, targets = group_targets(theta)
    resid = y - model.error(th, d)
    nt = targets.shape[0]
    means = []
    # one direction measured: its means serve both columns (the reverse repeats the forward, as said)
    for rows in ((d > 0, d < 0) if plan.both else (np.ones(d.shape, dtype=bool),) * 2):
        count = np.bincount(index[rows], minlength=nt)
        with np.errstate(invalid="ignore", divide="ignore"):
            means.append(np.bincount(index[rows], weights=resid[rows], minlength=nt) / count)
    return dataclasses.replace(model, targets=targets, residual_forward=means[0], residual_reverse=means[1])


@dataclass(frozen=True)
class TargetTest:
    """Whether the model's residual at the targets stands above the noise (:func:`check_targets`).

    ``testable``: the cells were measured in several runs; ``rms``: RMS of
    the residual means per target and direction [rad]; ``expected_rms``: the
    RMS the scatter between runs alone would give them [rad]; ``p_value``
    and ``dof`` of the chi-square test; ``significant``: p < alpha;
    ``worst``: (target [rad], direction, residual mean [rad]) of the cells
    beyond :data:`WORST_SE` standard errors, largest first (at most five);
    ``reason``: a sentence.
    """

    testable: bool
    rms: float
    expected_rms: float
    p_value: float
    dof: int
    significant: bool
    worst: tuple
    reason: str


def check_targets(model: CorrectionModel, theta, y, direction, run, alpha: float = TARGET_ALPHA) -> TargetTest:
    """The chi-square test of the residual cell means of ``model`` against the within-run noise.

    chi2 = sum_c n_c rbar_c^2 / s_within^2 over the cells c (target and
    direction) with n_c rows and residual mean rbar_c; degrees of freedom:
    cells minus the model's columns.  s_within^2 from
    :func:`~wormgear_cli.compensation.noise.noise_components` (run offsets
    removed, so an offset per run neither hides nor fakes a pattern).
    """
    theta = np.asarray(theta, dtype=float)
    y = np.asarray(y, dtype=float)
    d = np.asarray(direction, dtype=float)
    th = unwrap_passes(theta, run) if model.plan.unwrapped else theta
    index, targets = group_targets(theta)
    cell = 2 * index + (d < 0)
    noise = noise_components(cell, np.zeros(1, dtype=int) if run is None else run, y)
    resid = y - model.error(th, d)
    _, ci, counts = np.unique(cell, return_inverse=True, return_counts=True)
    ci = ci.ravel()
    rbar = np.bincount(ci, weights=resid) / counts
    rms = float(np.sqrt(np.mean(rbar**2)))
    plan = model.plan
    params = (1 + 2 * len(plan.orders) + plan.trend_degree) * (2 if plan.both else 1)
    dof = counts.shape[0] - params
    scale = float(np.sqrt(np.mean(y * y))) if y.size else 0.0
    if not noise.replicated:
        why = "each target was measured once per direction: the residual at the targets cannot be told from noise"
    elif dof <= 0:
        why = "too few targets for the model's columns: the residual at the targets cannot be judged"
    elif not (math.isfinite(noise.within) and noise.within > (1e-9 * scale) ** 2):
        why = "the runs repeat each other exactly: there is no scatter to judge the residual at the targets against"
    else:
        why = ""
    if why:
        return TargetTest(False, rms, math.nan, math.nan, max(dof, 0), False, (), why)
    from scipy.special import chdtrc  # tail probability of the test

    chi2 = float(np.sum(counts * rbar**2)) / noise.within
    p = float(chdtrc(dof, chi2))
    expected = math.sqrt(noise.within * float(np.mean(1.0 / counts)) * dof / counts.shape[0])
    z = np.abs(rbar) * np.sqrt(counts / noise.within)
    first = np.unique(cell, return_index=True)[1]
    big = np.argsort(-z)
    worst = tuple((float(targets[index[first[c]]]), -1 if d[first[c]] < 0 else 1, float(rbar[c]))
                  for c in big[:5] if z[c] > WORST_SE)
    significant = p < alpha
    reason = (f"the residual at the targets stands above the scatter between runs (p = {p:.2g})" if significant
              else f"the residual at the targets is within the scatter between runs (p = {p:.2g})")
    return TargetTest(True, rms, expected, p, dof, significant, worst, reason)


def plan_model(theta, y, direction, orders: Sequence[float], labels=None, priority=None, run=None,
               alpha: float = TARGET_ALPHA):
    """Decide the model for the data: which orders can be fitted, the trend, per-target means.

    Returns (:class:`ModelPlan`, :class:`~wormgear_cli.measurement.orders.OrdersAnalysis`,
    :class:`TargetTest`, :class:`CorrectionModel`).  The orders that the
    samples can fit follow ``measure``'s rules
    (:func:`~wormgear_cli.measurement.orders.analyse_orders`: beyond span,
    aliased, folded and unresolved orders are left out, with reasons).
    """
    theta = np.asarray(theta, dtype=float)
    d = np.asarray(direction, dtype=float)
    options = OrdersOptions(labels=None if labels is None else tuple(labels),
                            priority=None if priority is None else tuple(priority), passes=run)
    analysis = analyse_orders(theta, y, d, list(orders), options)
    fitted = tuple(it.order for it in analysis.items if it.fitted)
    assert analysis.coverage is not None  # (analyse_orders always measures the coverage)
    plan = ModelPlan(fitted, analysis.unwrapped, analysis.coverage, analysis.trend_degree, False,
                     analysis.both_directions)
    model = fit_plan(plan, theta, y, d, run)
    test = check_targets(model, theta, y, d, run, alpha)
    if test.significant:
        plan = dataclasses.replace(plan, per_target=True)
        model = fit_plan(plan, theta, y, d, run)
    return plan, analysis, test, model
