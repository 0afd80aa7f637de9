"""Which orders a measurement holds, when nobody says: single-order scans and a forward selection.

Until the measurement layer has its dominant-order scan, ``compensate`` takes its orders from
``--orders`` or ``--drive`` and, without either, from :func:`strongest_orders` here: a plain
forward selection over a list of candidate orders, each step adding the candidate that
removes most of the remaining sum of squares, while that removal is significant.  It is
meant to be replaced by one call to the scan when it lands; :func:`order_amplitudes` also
names the largest orders left in a residual.

Every candidate k brings the columns cos k theta, sin k theta (common mode) and, with both
directions, d cos k theta, d sin k theta (differential mode, d = +/-1), fitted together with
the base columns (offset, differential offset, already chosen orders, any trend).  Pure
numpy; scipy (the chi-square and F tail probabilities) only inside :func:`strongest_orders`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

#: rows x candidates x columns held at once by :func:`order_amplitudes`
BLOCK_CELLS = 4_000_000
#: most orders :func:`strongest_orders` picks
MAX_ORDERS = 8
#: significance of one selection step (Bonferroni over the candidates tried)
ALPHA = 0.01
#: refinements of the strongest order, each on a grid ten times finer
REFINEMENTS = 3
#: a candidate is scanned only when its columns keep at least this share of the norm a sampled
#: sinusoid has (the smallest eigenvalue of their Gram block once the base is projected out, over
#: half the sum of the weights); below it the samples cannot tell the candidate from the base or from
#: an order already chosen, or see one phase of it only (order 12 on 24 even targets)
MIN_DETERMINACY = 1e-3


@dataclass(frozen=True)
class OrderScan:
    """Result of :func:`order_amplitudes`, one entry per candidate order.

    ``orders`` [cycles/rev]; ``common`` and ``differential``: amplitude of
    each mode [unit of y] (differential NaN with one direction; both NaN for
    a candidate the samples cannot tell from the base, see
    :data:`MIN_DETERMINACY`); ``reduction``: weighted sum of squares the
    candidate removes from the base fit [unit of y squared] (0 for such a
    candidate); ``rss``: weighted residual sum of squares
    of the base fit; ``dof``: rows minus base columns; ``columns``: columns
    per candidate (2 or 4).
    """

    orders: np.ndarray
    common: np.ndarray
    differential: np.ndarray
    reduction: np.ndarray
    rss: float
    dof: int
    columns: int


def harmonic_block(theta: np.ndarray, orders: np.ndarray, direction: np.ndarray | None) -> np.ndarray:
    """(n, K, q) columns of each order: cos, sin (q = 2) and with ``direction`` also d cos, d sin (q = 4)."""
    arg = np.multiply.outer(theta, orders)
    c, s = np.cos(arg), np.sin(arg)
    if direction is None:
        return np.stack([c, s], axis=2)
    d = direction[:, None]
    return np.stack([c, s, d * c, d * s], axis=2)


def _base_q(base: np.ndarray, sw: np.ndarray) -> np.ndarray:
    """Orthonormal basis of the weighted base columns (rank-revealing: collinear columns dropped)."""
    bw = base * sw[:, None]
    u, sv, _ = np.linalg.svd(bw, full_matrices=False)
    keep = sv > 1e-10 * (sv[0] if sv.size else 1.0)
    return u[:, keep]


def order_amplitudes(theta, y, direction, candidates: Sequence[float], base=None, weights=None) -> OrderScan:
    """Each candidate order fitted alone on top of the base columns.

    Parameters
    ----------
    theta : array_like [rad], shape (n,)
    y : array_like [any unit], shape (n,)
    direction : array_like of +1/-1, shape (n,)
        With one direction only, the differential columns are left out.
    candidates : sequence of float [cycles/rev]
    base : array_like, shape (n, b), optional
        Columns always fitted (default: an offset, and d with both
        directions); pass them to add chosen orders or a trend.
    weights : array_like, shape (n,), optional
        Row weights (e.g. the run count of a cell mean).

    Returns
    -------
    OrderScan
    """
    theta = np.asarray(theta, dtype=float)
    y = np.asarray(y, dtype=float)
    d = np.asarray(direction, dtype=float)
    n = theta.shape[0]
    both = bool(np.any(d > 0) and np.any(d < 0))
    if base is None:
        base = np.column_stack([np.ones(n), d]) if both else np.ones((n, 1))
    base = np.asarray(base, dtype=float).reshape(n, -1)
    sw = np.ones(n) if weights is None else np.sqrt(np.asarray(weights, dtype=float))
    q_base = _base_q(base, sw)
    yw = y * sw
    yr = yw - q_base @ (q_base.T @ yw)
    total = max(float(sw @ sw), 1e-300)
    rss = float(yr @ yr)
    ords = np.atleast_1d(np.asarray(candidates, dtype=float))
    q = 4 if both else 2
    common = np.empty(ords.size)
    diff = np.full(ords.size, np.nan)
    red = np.empty(ords.size)
    step = max(1, BLOCK_CELLS // max(n * q, 1))
    for a in range(0, ords.size, step):
        k = ords[a:a + step]
        x = harmonic_block(theta, k, d if both else None) * sw[:, None, None]
        x = x - np.einsum("nb,bkq->nkq", q_base, np.einsum("nb,nkq->bkq", q_base, x))
        gram = np.einsum("nkq,nkr->kqr", x, x)
        rhs = np.einsum("nkq,n->kq", x, yr)
        determinacy = np.linalg.eigvalsh(gram)[:, 0] / (0.5 * total)
        gram = gram + 1e-12 * np.trace(gram, axis1=1, axis2=2)[:, None, None] * np.eye(q) + 1e-300 * np.eye(q)
        beta = np.linalg.solve(gram, rhs[:, :, None])[:, :, 0]
        poor = determinacy < MIN_DETERMINACY
        common[a:a + step] = np.where(poor, np.nan, np.hypot(beta[:, 0], beta[:, 1]))
        if both:
            diff[a:a + step] = np.where(poor, np.nan, np.hypot(beta[:, 2], beta[:, 3]))
        red[a:a + step] = np.where(poor, 0.0, np.maximum(np.einsum("kq,kq->k", beta, rhs), 0.0))
    return OrderScan(ords, common, diff, red, rss, n - q_base.shape[1], q)


@dataclass(frozen=True)
class Selection:
    """Result of :func:`strongest_orders`: ``orders`` chosen (in the order chosen) with the
    ``p_values`` of their steps (Bonferroni-adjusted), ``candidates`` tried, and ``reason``
    the selection stopped (a sentence)."""

    orders: tuple[float, ...]
    p_values: tuple[float, ...]
    candidates: tuple[float, ...]
    reason: str


def strongest_orders(theta, y, direction, candidates: Sequence[float], noise_var: float | None = None,
                     weights=None, alpha: float = ALPHA, max_orders: int = MAX_ORDERS, base=None) -> Selection:
    """Forward selection of the orders that stand out of the noise.

    Each step fits every remaining candidate on top of the orders already
    chosen (:func:`order_amplitudes`) and takes the one removing the largest
    sum of squares, if that removal is significant: a chi-square test with
    ``q`` degrees of freedom against ``noise_var`` (the variance of one row
    at weight 1, e.g. of a single run when the rows are cell means weighted
    by their run counts), or without it an F-test against the residual
    variance; the p-value is multiplied by the number of candidates tried
    (Bonferroni).  Stops at ``max_orders`` or at the first step that is not
    significant at ``alpha``.

    Parameters as in :func:`order_amplitudes`; ``noise_var`` [unit of y squared].
    """
    from scipy.special import chdtrc, fdtrc  # tail probabilities; scipy only when orders are searched

    theta = np.asarray(theta, dtype=float)
    d = np.asarray(direction, dtype=float)
    n = theta.shape[0]
    both = bool(np.any(d > 0) and np.any(d < 0))
    cols = [np.asarray(base, dtype=float).reshape(n, -1)] if base is not None else \
        [np.column_stack([np.ones(n), d]) if both else np.ones((n, 1))]
    remaining = [float(k) for k in candidates]
    chosen: list[float] = []
    pvals: list[float] = []
    reason = f"no candidate left ({len(remaining)} tried)"
    while remaining:
        if len(chosen) >= max_orders:
            reason = f"{max_orders} orders chosen (the most this selection takes)"
            break
        base_now = np.hstack(cols)
        scan = order_amplitudes(theta, y, d, remaining, base_now, weights)
        i = int(np.argmax(scan.reduction))
        red = float(scan.reduction[i])
        if red <= 0.0:
            reason = "no further candidate can be told apart from the orders chosen on these angles"
            break
        if noise_var is not None and noise_var > 0:
            p = float(chdtrc(scan.columns, red / noise_var))
        else:
            dof = scan.dof - scan.columns
            rest = scan.rss - red
            if dof <= 0 or rest <= 0:
                reason = "no degrees of freedom left to judge a further order"
                break
            p = float(fdtrc(scan.columns, dof, (red / scan.columns) / (rest / dof)))
        p_adj = min(1.0, p * len(remaining))
        if not p_adj < alpha:
            reason = (f"the strongest further order ({remaining[i]:g}) is not significant "
                      f"(adjusted p = {p_adj:.2g} >= {alpha:g})")
            break
        k = remaining.pop(i)
        chosen.append(k)
        pvals.append(p_adj)
        cols.append(harmonic_block(theta, np.array([k]), d if both else None)[:, 0, :])
    return Selection(tuple(chosen), tuple(pvals), tuple(float(k) for k in candidates), reason)


def strongest_order(theta, y, direction, lowest: float, highest: float, base=None, weights=None,
                    step: float | None = None) -> tuple[float, float]:
    """The single order in [``lowest``, ``highest``] (not necessarily whole) that explains the
    largest sum of squares (the peak of a least-squares periodogram), and its common-mode
    amplitude.  (The fitted amplitude itself peaks away from the true order on a short arc.)

    A grid of step ``step`` (default: a quarter of the resolution 2 pi / span
    of the angles) is scanned, then the best point is refined :data:`REFINEMENTS`
    times on a grid ten times finer around it.  Meant for a mount's worm period from a
    tracking record (a partial turn): pass the drift as ``base`` columns.
    """
    theta = np.asarray(theta, dtype=float)
    span = float(np.ptp(theta)) if theta.size else 0.0
    resolution = 2.0 * math.pi / span if span > 0 else 1.0
    step = step or resolution / 4.0
    grid = np.arange(lowest, highest + 0.5 * step, step)
    if grid.size == 0:
        grid = np.array([lowest])
    scan = order_amplitudes(theta, y, direction, grid, base, weights)
    best = float(grid[int(np.argmax(scan.reduction))])
    for _ in range(REFINEMENTS):  # each pass a grid ten times finer around the best point so far
        fine = np.clip(np.linspace(best - step, best + step, 21), lowest, highest)
        scan = order_amplitudes(theta, y, direction, fine, base, weights)
        i = int(np.argmax(scan.reduction))
        best = float(fine[i])
        step /= 10.0
    return best, float(scan.common[i])
