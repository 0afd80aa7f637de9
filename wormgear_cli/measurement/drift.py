"""The slow part of a measurement over a partial arc: a trend over the arc, or a drift in time.

Over a partial arc, content slower than the arc (an order whose period is longer than the span, a
thermal drift, a telescope's tracking wander) cannot be told apart as harmonics: it is modelled
as a low-degree polynomial and reported with its size, never as a string of harmonics.  Which
variable the polynomial is in depends on the measurement's design:

* one pass over the arc (a scan, a guide log): angle and time move together, so the slow part is
  a polynomial in the angle along the arc (:func:`~wormgear_cli.measurement.coverage.trend_columns`);
  orders whose period is longer than the arc are "beyond span";
* the arc traversed two or more times (repeated bidirectional ISO 230-2 runs over a tilting
  axis' 90 deg): an error fixed to the angle repeats in every pass while a drift goes on with time,
  so the slow part is a polynomial in time (``time_s``, or the row order where there is none) and
  the angle-fixed content, a once-per-turn runout included, is fitted as orders.

Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wormgear_cli.measurement.arrays import unique as lean_unique
from wormgear_cli.measurement.coverage import TREND_DEGREE, Coverage, trend_columns

#: a pass counts as a traversal of the arc when it spans at least this share of it
PASS_SHARE = 0.5
#: with the arc traversed repeatedly, an order needs this much of one period over the arc (an eighth: 45 deg of
#: phase) to be fitted
MIN_PERIOD_SHARE = 0.125


@dataclass(frozen=True)
class SlowModel:
    """The columns that stand for the slow part (:func:`slow_model`).

    ``kind``: "none" (a full turn), "angle" (a polynomial in the angle along
    the arc) or "time" (a polynomial in time: the arc is traversed
    repeatedly); ``degree``; ``signal``: the variable's name ("angle along
    the arc", "time_s" or "row order"); ``traversals``: passes that cover at
    least :data:`PASS_SHARE` of the arc; ``columns``: Chebyshev polynomials
    T_1..T_degree of the variable mapped onto [-1, 1] (N x degree; for
    "angle" they are functions of the angle alone)."""

    kind: str
    degree: int
    signal: str
    traversals: int
    columns: np.ndarray

    def beyond(self, cov: Coverage, order: float) -> bool:
        """Whether ``order`` [cycles/rev] is too slow for the arc: with a trend over the arc, one period
        longer than the span; with a drift in time, less than :data:`MIN_PERIOD_SHARE` of a period over it."""
        if self.kind == "none" or cov.full_turn:
            return False
        if self.kind == "angle":
            return cov.beyond(order)
        return order * cov.span < MIN_PERIOD_SHARE * 2.0 * math.pi * (1.0 - 1e-9)

    def part(self, size: float) -> SlowPart:
        """The model as fitted, with the peak-to-peak ``size`` of the fitted polynomial."""
        return SlowPart(self.kind, self.degree, self.signal, self.traversals, float(size))


def pass_keys(passes, direction) -> np.ndarray:
    """A pass id per row (N,) int: the run (or pass) of each row split by its direction (one pass without
    either)."""
    d = None if direction is None else np.asarray(direction, dtype=float).reshape(-1)
    n = (d.shape[0] if d is not None else np.asarray(passes).reshape(-1).shape[0])
    if passes is None:
        key = np.zeros(n, dtype=np.intp)
    else:
        key = lean_unique(passes)[1]  # the run's rank, a new array: made the key in place
    key *= 2
    if d is not None:
        key += d > 0
    return lean_unique(key)[1]


def traversals(theta, cov: Coverage, passes=None, direction=None) -> int:
    """Passes (runs split by direction) that each span at least :data:`PASS_SHARE` of the covered arc."""
    th = np.asarray(theta, dtype=float)
    if th.shape[0] == 0:
        return 0
    pid = pass_keys(passes, direction if direction is not None else np.ones(th.shape[0]))
    u = np.mod(th - cov.start, 2.0 * math.pi)
    count = int(pid.max()) + 1
    lo = np.full(count, np.inf)
    hi = np.full(count, -np.inf)
    np.minimum.at(lo, pid, u)
    np.maximum.at(hi, pid, u)
    return int(np.count_nonzero(hi - lo >= PASS_SHARE * cov.span))


def slow_model(theta, cov: Coverage, passes=None, direction=None, time=None, degree: int = TREND_DEGREE) -> SlowModel:
    """The slow part's columns for a measurement at angles ``theta`` [rad] (N,) with coverage ``cov``.

    ``passes`` (N,) run or pass of each row, ``direction`` (N,) +1/-1, ``time`` (N,) [s] or None
    (the row order stands for time).  A full turn needs none; one traversal of a partial arc gets a
    polynomial in the angle along the arc; two or more traversals a polynomial in time.  The degree
    is ``degree`` (fewer with few distinct angles or times)."""
    th = np.asarray(theta, dtype=float)
    n = th.shape[0]
    if cov.full_turn or cov.distinct < 2:
        return SlowModel("none", 0, "", 0, np.zeros((n, 0)))
    count = traversals(th, cov, passes, direction)
    if count >= 2:
        t = np.arange(n, dtype=float) if time is None else np.asarray(time, dtype=float)
        deg = max(0, min(degree, int(np.unique(t).size) - 2))
        lo, hi = float(np.min(t)), float(np.max(t))
        x = 2.0 * (t - lo) / (hi - lo) - 1.0 if hi > lo else np.zeros(n)
        cols = np.polynomial.chebyshev.chebvander(x, deg)[:, 1:]
        return SlowModel("time", deg, "row order" if time is None else "time_s", count, cols)
    deg = max(0, min(degree, cov.distinct - 2))
    return SlowModel("angle", deg, "angle along the arc", count, trend_columns(th, cov, deg))


def drift_size(columns: np.ndarray, coef: np.ndarray) -> float:
    """Peak-to-peak of the fitted slow part ``columns @ coef`` over the rows [unit of the data] (0 without columns)."""
    if columns.shape[1] == 0 or columns.shape[0] == 0:
        return 0.0
    values = columns @ np.asarray(coef, dtype=float)
    return float(np.max(values) - np.min(values))


@dataclass(frozen=True)
class SlowPart:
    """The slow part as fitted: :class:`SlowModel`'s ``kind``, ``degree``, ``signal``,
    ``traversals``, and ``size``, the peak-to-peak of the fitted polynomial over the rows [unit of
    the data] (NaN when not determined)."""

    kind: str
    degree: int
    signal: str
    traversals: int
    size: float

    def describe(self) -> str:
        """What the slow part is, e.g. 'a drift in time_s (a cubic)'."""
        name = {1: "a straight line", 2: "a parabola", 3: "a cubic"}.get(self.degree, f"degree {self.degree}")
        if self.kind == "angle":
            return f"a trend over the arc ({name} in the angle along it)"
        return f"a drift in time ({name} in {self.signal})"
