"""The slow part of a measurement over a partial arc: a trend over the arc, or a drift in time.

Over a partial arc, content slower than the arc (an order whose period is longer than the span, a
thermal drift, a telescope's tracking wander) cannot be told apart as harmonics: it is modelled
as a low-degree polynomial and reported with its size, never as a string of harmonics.  Which
variable the polynomial is in depends on the measurement's design:

* one pass over the arc (a scan, a guide log): angle and time move together, so the slow part is
  a polynomial in the angle along the arc (:func:`~wormgear_cli.measurement.coverage.trend_columns`);
  orders whose period is longer than the arc are "beyond span";
* runs whose errors each have an offset and a drift of their own (the sessions of a telescope's
  guide log: the reconstruction starts from an unknown offset in every session, and the drift from
  polar misalignment and refraction changes over the night): an offset and a polynomial in time per
  run (:func:`drift_columns`); orders whose period is longer than the longest run are "beyond span";
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
from wormgear_cli.measurement.coverage import TREND_DEGREE, Coverage, as_1d, trend_columns

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
    #: with an offset and a drift per run: the longest run's span [rad] (else 0)
    run_span: float = 0.0

    def beyond(self, cov: Coverage, order: float) -> bool:
        """Whether ``order`` [cycles/rev] is too slow for the arc: with a trend over the arc, one period
        longer than the span; with a drift per run, one period longer than the longest run; with a drift
        in time, less than :data:`MIN_PERIOD_SHARE` of a period over the arc."""
        if self.run_span > 0:
            return order * self.run_span < 2.0 * math.pi * (1.0 - 1e-9)
        if self.kind == "none" or cov.full_turn:
            return False
        if self.kind == "angle":
            return cov.beyond(order)
        return order * cov.span < MIN_PERIOD_SHARE * 2.0 * math.pi * (1.0 - 1e-9)

    def part(self, size: float) -> SlowPart:
        """The model as fitted, with the peak-to-peak ``size`` of the fitted polynomial."""
        return SlowPart(self.kind, self.degree, self.signal, self.traversals, float(size), self.run_span > 0)


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


def slow_model(theta, cov: Coverage, passes=None, direction=None, time=None, degree: int = TREND_DEGREE,
               per_run: bool = False) -> SlowModel:
    """The slow part's columns for a measurement at angles ``theta`` [rad] (N,) with coverage ``cov``.

    ``passes`` (N,) run or pass of each row, ``direction`` (N,) +1/-1, ``time`` (N,) [s] or None
    (the row order stands for time).  ``per_run``: each run has an offset and a drift in time of its
    own (:func:`drift_columns`, the row order standing for time without ``time``), whatever the
    coverage.  Otherwise a full turn needs none; one traversal of a partial arc gets a polynomial in
    the angle along the arc; two or more traversals a polynomial in time.  The degree is ``degree``
    (fewer with few distinct angles or times)."""
    th = np.asarray(theta, dtype=float)
    n = th.shape[0]
    if per_run:
        t = np.arange(n, dtype=float) if time is None else np.asarray(time, dtype=float)
        cols = drift_columns(t, passes, degree)
        keys = np.zeros(n, dtype=np.int64) if passes is None else np.unique(
            np.asarray(passes), return_inverse=True)[1].reshape(-1)
        lo = np.full(int(keys.max()) + 1 if n else 0, np.inf)
        hi = np.full(lo.shape, -np.inf)
        np.minimum.at(lo, keys, th)
        np.maximum.at(hi, keys, th)
        span = float(np.max(hi - lo)) if n else 0.0
        return SlowModel("time", degree, f"{'time_s' if time is not None else 'row order'} of each run, with its "
                         "offset", traversals(th, cov, passes, direction), cols, max(span, 1e-300))
    if cov.full_turn or cov.distinct < 2:
        return SlowModel("none", 0, "", 0, np.zeros((n, 0)))
    count = traversals(th, cov, passes, direction)
    if count >= 2:
        t = np.arange(n, dtype=float) if time is None else np.asarray(time, dtype=float)
        deg = max(0, min(degree, int(np.unique(t).size) - 2))
        t_lo, t_hi = float(np.min(t)), float(np.max(t))
        x = 2.0 * (t - t_lo) / (t_hi - t_lo) - 1.0 if t_hi > t_lo else np.zeros(n)
        cols = np.polynomial.chebyshev.chebvander(x, deg)[:, 1:]
        return SlowModel("time", deg, "row order" if time is None else "time_s", count, cols)
    deg = max(0, min(degree, cov.distinct - 2))
    return SlowModel("angle", deg, "angle along the arc", count, trend_columns(th, cov, deg))


def drift_columns(time, run=None, degree: int = TREND_DEGREE) -> np.ndarray:
    """Design columns of a drift per run (n x p), beside an intercept fitted elsewhere.

    For each run (in order of first appearance): Chebyshev polynomials T_1..T_d of its time mapped
    onto [-1, 1] over the run's span (zero on the other runs' rows), d = min(``degree``, samples
    of the run - 1), none for a run of one instant; and, for every run after the first, its
    offset (1 on its rows).  ``time`` (n,) [any unit, e.g. s or rad]; ``run`` (n,) labels or None
    (one run)."""
    t = as_1d("time", time)
    n = t.shape[0]
    labels = np.zeros(n, dtype=np.int64) if run is None else np.asarray(run)
    if labels.shape != (n,):
        raise ValueError(f"run has shape {labels.shape}, expected ({n},)")
    _, first, inverse = np.unique(labels, return_index=True, return_inverse=True)
    order = np.argsort(first)
    cols = []
    for rank, r in enumerate(order):
        rows = inverse.reshape(-1) == r
        tr = t[rows]
        if rank > 0:
            cols.append(rows.astype(float))
        lo, hi = float(tr.min()), float(tr.max())
        d = min(degree, int(rows.sum()) - 1)
        if d <= 0 or hi <= lo:
            continue
        x = 2.0 * (tr - lo) / (hi - lo) - 1.0
        block = np.zeros((n, d))
        block[rows] = np.polynomial.chebyshev.chebvander(x, d)[:, 1:]
        cols.extend(block.T)
    return np.column_stack(cols) if cols else np.zeros((n, 0))


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
    the data] (NaN when not determined); ``per_run``: an offset and a drift per run."""

    kind: str
    degree: int
    signal: str
    traversals: int
    size: float
    #: an offset and a drift per run (:func:`slow_model` with ``per_run``)
    per_run: bool = False

    def describe(self) -> str:
        """What the slow part is, e.g. 'a drift in time_s (a cubic)'."""
        name = {1: "a straight line", 2: "a parabola", 3: "a cubic"}.get(self.degree, f"degree {self.degree}")
        if self.kind == "angle":
            return f"a trend over the arc ({name} in the angle along it)"
        return f"a drift in time ({name} in {self.signal})"
