"""Coverage of the turn: the angular span a measurement covers, a trend over it, continuous angles.

A measurement may span part of a turn (a telescope tracking 15 degrees, a 90 degree scan).  An
order whose period is longer than the covered span cannot be told from a slow trend over it;
:func:`coverage` finds the span (overall and per pass) independently of how the angles are
written, :func:`trend_columns` gives the low-order polynomial that stands for the slow part, and
:func:`unwrap_passes` makes angles continuous so that non-integer orders do not depend on
wrapping.  Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wormgear_cli.measurement.arrays import RANK_BLOCK as BLOCK
from wormgear_cli.measurement.arrays import non_decreasing, unwrap
from wormgear_cli.measurement.arrays import unique as lean_unique

#: degree of the polynomial trend that stands for the orders longer than a partial span
TREND_DEGREE = 3
#: a circular gap counts as a sampling gap (not an uncovered arc) up to this many times the median other gap
GAP_RATIO = 2.0
#: ... or while it is at most this share of the period of the slowest order asked for (order 1 unless a slower
#: one is asked): a hole of a tenth of a period (36 deg of phase) leaves that order seen all round the turn
GAP_PERIOD_SHARE = 0.1
#: passes whose span is computed one by one at most (beyond: overall span only)
MAX_PASS_SPANS = 1000


def as_1d(name: str, value, n: int | None = None) -> np.ndarray:
    """``value`` as a 1-D float array of ``n`` entries (ValueError naming ``name`` otherwise)."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional")
    if n is not None and arr.shape[0] != n:
        raise ValueError(f"{name} has {arr.shape[0]} entries, expected {n}")
    return arr


@dataclass(frozen=True)
class Coverage:
    """The angular span a measurement covers (:func:`coverage`).

    ``span`` [rad]: the arc covered (2 pi for a full turn); ``start`` [rad,
    in [0, 2 pi)]: where the covered arc begins (after the largest gap);
    ``full_turn``: the samples go all round: the angles run over a whole
    turn, or the largest gap between neighbouring angles is no more than
    :data:`GAP_RATIO` times the median of the others (a table of targets),
    or it is at most :data:`GAP_PERIOD_SHARE` of the period of the slowest
    order asked for (irregular or random angles: 4000 random angles over a
    turn leave a largest gap of about 1 deg, a full turn for order 1);
    ``distinct``: number of distinct angles; ``pass_spans`` [rad]: the span
    of each pass (empty when there are more than :data:`MAX_PASS_SPANS`
    passes); ``largest_gap`` [rad]: the largest gap between neighbouring
    angles on the circle (0 when the angles run over a whole turn).
    """

    span: float
    start: float
    full_turn: bool
    distinct: int
    pass_spans: tuple[float, ...] = ()
    largest_gap: float = 0.0

    def beyond(self, order: float) -> bool:
        """Whether one period of ``order`` [cycles/rev] (2 pi / order) is longer than the covered span."""
        return (not self.full_turn) and order * self.span < 2.0 * math.pi * (1.0 - 1e-9)


def _arc(theta: np.ndarray, unique: np.ndarray | None = None,
         slowest: float = 1.0) -> tuple[float, float, bool, int, float]:
    """(span, start, full turn, distinct, largest gap) of one set of angles [rad]; ``unique``: the
    sorted distinct angles when known and all within [0, 2 pi); ``slowest``: the slowest order
    asked for [cycles/rev] (:data:`GAP_PERIOD_SHARE`)."""
    two_pi = 2.0 * math.pi
    if theta.size and float(np.ptp(theta)) >= two_pi:
        return two_pi, 0.0, True, int(np.unique(theta).size if unique is None else unique.size), 0.0
    t = np.unique(np.mod(theta, two_pi)) if unique is None else unique
    if t.size < 2:
        return 0.0, float(t[0]) if t.size else 0.0, False, int(t.size), two_pi
    gaps = np.empty(t.size)
    gaps[:-1] = np.diff(t)
    gaps[-1] = t[0] + two_pi - t[-1]
    i = int(np.argmax(gaps))
    largest = float(gaps[i])
    others = np.delete(gaps, i)
    if largest <= GAP_RATIO * float(np.median(others)) or largest * slowest <= GAP_PERIOD_SHARE * two_pi:
        return two_pi, 0.0, True, int(t.size), largest
    return float(two_pi - largest), float(t[(i + 1) % t.size]), False, int(t.size), largest


def coverage(theta, passes=None, unique=None, orders=None) -> Coverage:
    """The angular span covered by the samples, overall and per pass.

    Parameters
    ----------
    theta : array_like [rad], shape (n,)
        Sample angles, wrapped (0..2 pi) or not.
    passes : array_like of int, shape (n,), optional
        Pass (run) index of each sample.
    unique : ndarray, optional
        The sorted distinct angles when already known (all within [0, 2 pi)).
    orders : sequence of float [cycles/rev], optional
        The orders asked for: the largest gap is judged against the period
        of the slowest of them (and of order 1).

    Returns
    -------
    Coverage
        The covered arc is the turn minus the largest gap between
        neighbouring angles on the circle, so it does not depend on how the
        angles are written.  The largest gap is an uncovered arc only when
        it stands out (more than :data:`GAP_RATIO` times the median of the
        other gaps) and is more than :data:`GAP_PERIOD_SHARE` of the period
        of the slowest order asked for; otherwise the samples cover the
        whole turn.
    """
    theta = as_1d("theta", theta)
    if unique is not None and not (unique.size and unique[0] >= 0.0 and unique[-1] < 2.0 * math.pi):
        unique = None
    positive = [float(k) for k in (orders if orders is not None else ()) if float(k) > 0]
    slowest = min([1.0, *positive])
    span, start, full, distinct, gap = _arc(theta, unique, slowest)
    spans: tuple[float, ...] = ()
    if passes is not None:
        pid = np.asarray(passes)
        ids, inverse = lean_unique(pid)
        if ids.size == 1:
            spans = (span,)
        elif ids.size <= MAX_PASS_SPANS:
            # the rows of each pass together (as they are when the passes follow one another)
            order = None if non_decreasing(inverse) else np.argsort(inverse, kind="stable")
            bounds = np.searchsorted(inverse if order is None else inverse[order], np.arange(ids.size + 1))
            spans = tuple(_arc(theta[bounds[k]:bounds[k + 1]] if order is None else
                               theta[order[bounds[k]:bounds[k + 1]]], slowest=slowest)[0] for k in range(ids.size))
    return Coverage(span, start, full, distinct, spans, gap)


def trend_columns(theta, cov: Coverage, degree: int = TREND_DEGREE) -> np.ndarray:
    """Chebyshev polynomials T_1..T_degree of the angle along the covered arc (n x degree).

    The angle is measured from ``cov.start`` along the arc and mapped onto
    [-1, 1] over ``cov.span``, so the trend does not depend on how the
    angles are written.  Empty (n x 0) for a full turn or degree 0."""
    theta = as_1d("theta", theta)
    if cov.full_turn or degree <= 0 or cov.span <= 0:
        return np.zeros((theta.shape[0], 0))
    u = np.mod(theta - cov.start, 2.0 * math.pi)
    x = 2.0 * u / cov.span - 1.0
    return np.polynomial.chebyshev.chebvander(x, degree)[:, 1:]


def unwrap_passes(theta, passes=None) -> np.ndarray:
    """Angles made continuous in row order within each pass, each pass starting in [0, 2 pi).

    A step of more than pi between consecutive rows is taken as a wrap
    (359.9 deg -> 0.1 deg is +0.2 deg), so wrapped and unwrapped writings of
    one recording give the same angles [rad]; non-integer orders depend on
    them."""
    theta = as_1d("theta", theta)
    if theta.size == 0:
        return theta
    u = unwrap(theta)
    n = theta.shape[0]
    pid = np.zeros(1, dtype=np.int64) if passes is None else np.asarray(passes).reshape(-1)
    first = np.ones(n if passes is not None else 1, dtype=bool)
    first[1:] = pid[1:] != pid[:-1]
    turns = np.floor(u[:first.shape[0]][first] / (2.0 * math.pi))
    shift = 2.0 * math.pi * turns  # per pass
    if passes is None:
        u -= shift[0]
        return u
    carry = -1
    for a in range(0, n, BLOCK):  # u -= shift of each row's pass, the pass numbers counted a block at a time
        block = np.cumsum(first[a:a + BLOCK])
        block += carry
        carry = int(block[-1])
        u[a:a + BLOCK] -= shift[block]
    return u
