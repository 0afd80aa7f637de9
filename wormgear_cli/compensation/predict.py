"""What a correction table will leave, said before it is loaded: ISO 230-2 figures of a repeat test.

Cross-validation over runs: each run in turn is left out, a table is made from the other runs
exactly as the final table is made, and applied to the left-out run as the controller applies it
(:func:`~wormgear_cli.compensation.table.apply_table`).  The corrected rows are therefore judged
on data the table was not made from.  Their mean square, less the scatter of the measurement
itself (:func:`~wormgear_cli.compensation.noise.noise_components`), is what the table leaves
systematically at the targets: its own noise and what the model misses.

A single corrected test is one draw of noisy figures (E is a range over the targets, so its
spread between repeat tests is some 10 to 20 %).  The prediction is therefore the distribution of
the figures over simulated repeat tests of the same plan (targets, directions, runs): per cell the
systematic remainder, per run an offset and per row a scatter with the measured variances.  The
remainder repeats on a repeat test: it is the cross-validated rows' mean per cell (target and
direction), so an order the table cannot carry keeps its shape (the same in both directions, a
sinusoid's range over the targets), scaled to the variance the final table leaves (the
cross-validated mean square less the scatter, see :func:`_remainder`).  Drawing it afresh per
cell instead would turn a left-out order into independent errors per direction and overstate B
and E.  The table's own noise (its fitted values' share of the scatter) is drawn afresh per
cell.  The median is the predicted figure, the 5 and 95 % points its range.

With a single run nothing can be left out: the figures of the table applied to its own data are
given instead, said to be in-sample (optimistic).  Pure numpy.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from wormgear_cli.compensation.noise import Noise, noise_components
from wormgear_cli.compensation.scan import harmonic_block, order_amplitudes
from wormgear_cli.compensation.table import apply_table
from wormgear_cli.measurement.coverage import TREND_DEGREE, coverage, trend_columns
from wormgear_cli.measurement.iso230 import axis_figures, group_targets, iso230_figures

#: simulated repeat tests behind a predicted figure (fewer on long files: REPLICATE_ROWS / rows)
REPLICATES = 200
#: rows x replicates simulated at most
REPLICATE_ROWS = 4_000_000
#: fewest replicates
MIN_REPLICATES = 40
#: readings of simulated repeat tests evaluated at once (memory: 8 bytes each, a few arrays of it)
REPLICATE_BATCH_ROWS = 1_000_000
#: seed of the simulated repeat tests (same input, same output)
SEED = 20_230_201
#: the figures predicted (ISO 230-2 names; _up is forward, _down reverse)
FIGURES = ("E", "B", "A", "M", "E_up", "A_up", "E_down", "A_down")
#: orders named as the largest left in the residual
RESIDUAL_ORDERS = 3
#: highest whole order scanned in the residual (beyond the model's own orders)
RESIDUAL_MAX_ORDER = 60


@dataclass(frozen=True)
class Figure:
    """A predicted figure [rad]: ``median`` over simulated repeat tests, ``low`` and ``high``
    their 5 and 95 % points (all equal for an in-sample figure)."""

    median: float
    low: float
    high: float


@dataclass(frozen=True)
class TablePrediction:
    """Result of :func:`predict_table`.

    ``method``: "cross-validated" or "in-sample"; ``folds``: runs left out
    one at a time (0 in-sample); ``before``: the ISO 230-2 figures as
    measured (:class:`~wormgear_cli.measurement.iso230.Iso230Figures`);
    ``after``: figure name -> :class:`Figure`; ``noise``:
    :class:`~wormgear_cli.compensation.noise.Noise` of the measurement;
    ``remainder_rms`` [rad]: RMS of what the table leaves systematically at
    the targets; ``residual_orders``: (order, common amplitude, differential
    amplitude [rad]) of the largest orders in the corrected rows;
    ``replicates``: simulated repeat tests.
    """

    method: str
    folds: int
    before: object
    after: dict
    noise: Noise
    remainder_rms: float
    residual_orders: tuple
    replicates: int


def _cells(theta, d):
    grouping = group_targets(theta)
    return grouping, 2 * grouping[0] + (d < 0)


def corrected_rows(make_table: Callable, theta, y, d, run) -> tuple[np.ndarray, int]:
    """The rows corrected by tables made without them: (corrected errors [rad], folds).

    ``make_table(mask)`` returns the table made from the rows where
    ``mask`` is True.  With a single run the table of all rows is applied
    to them (folds 0)."""
    runs = np.unique(run)
    out = np.empty_like(y)
    if runs.size < 2:
        return y + apply_table(make_table(np.ones(y.shape[0], dtype=bool)), theta, d), 0
    for r in runs:
        held = run == r
        out[held] = y[held] + apply_table(make_table(~held), theta[held], d[held])
    return out, int(runs.size)


def _figures(x, d, grouping) -> dict:
    """The figures of :data:`FIGURES` (name -> (R,) [rad]) of R rows of errors ``x`` (R, n)."""
    f = axis_figures(x, d, grouping)
    return {k: f[k] for k in FIGURES}


def systematic_remainder(cell, centred, remainder_var: float) -> np.ndarray:
    """The remainder a repeat test shows at each row [rad], shape (n,): the mean of the
    cross-validated, run-centred rows ``centred`` per cell (target and direction), scaled so
    that its mean square over the rows is ``remainder_var`` (their noise taken out)."""
    _, ci = np.unique(cell, return_inverse=True)
    ci = ci.ravel()
    means = (np.bincount(ci, weights=centred) / np.bincount(ci))[ci]
    mean_square = float(np.mean(means**2))
    if mean_square <= 0.0 or remainder_var <= 0.0:
        return np.zeros_like(means)
    return means * math.sqrt(remainder_var / mean_square)


def _simulate(theta, d, grouping, cell, run, systematic, own: float, noise) -> dict:
    """Figures over simulated repeat tests -> name -> :class:`Figure`: ``systematic`` [rad]
    per row, the table's own noise per cell (variance ``own``), a run offset and a scatter per
    row drawn with the measured variances."""
    rng = np.random.default_rng(SEED)
    n = theta.shape[0]
    _, ci = np.unique(cell, return_inverse=True)
    _, ri = np.unique(run, return_inverse=True)
    ci, ri = ci.ravel(), ri.ravel()
    count = max(MIN_REPLICATES, min(REPLICATES, REPLICATE_ROWS // max(n, 1)))
    within = noise.within if math.isfinite(noise.within) else 0.0
    draws: dict[str, list[np.ndarray]] = {k: [] for k in FIGURES}
    per_batch = max(1, REPLICATE_BATCH_ROWS // max(n, 1))
    for first in range(0, count, per_batch):  # the tests drawn one after the other, evaluated a batch at once
        x = np.empty((min(per_batch, count - first), n))
        for row in x:
            row[:] = (systematic + rng.normal(0.0, math.sqrt(own), ci.max() + 1)[ci]
                      + rng.normal(0.0, math.sqrt(noise.between_runs), ri.max() + 1)[ri]
                      + rng.normal(0.0, math.sqrt(within), n))
        for k, v in _figures(x, d, grouping).items():
            draws[k].append(v)
    out = {}
    for k, values in draws.items():
        v = np.concatenate(values)
        if not np.all(np.isfinite(v)):
            out[k] = Figure(math.nan, math.nan, math.nan)
            continue
        lo, med, hi = np.quantile(v, [0.05, 0.5, 0.95])
        out[k] = Figure(float(med), float(lo), float(hi))
    return out


def residual_orders(theta, resid, d, extra=(), most: int = RESIDUAL_ORDERS) -> tuple:
    """The ``most`` orders that explain most of ``resid``, chosen one after the other (each on
    top of those already chosen, so an order's aliases on the targets are not named again)
    among whole orders 1 .. min(targets / 2, :data:`RESIDUAL_MAX_ORDER`) and the ``extra``
    orders: ((order, common, differential) [rad], ...), the amplitudes of each order's step.
    Fitted on the means per angle and direction, weighted by their rows (the same fit as on the
    rows, for far fewer rows when runs repeat the angles)."""
    _, first, inverse, counts = np.unique(np.column_stack([theta, d]), axis=0, return_index=True,
                                             return_inverse=True, return_counts=True)
    resid = np.bincount(inverse.ravel(), weights=resid) / counts
    theta, d = theta[first], d[first]
    cov = coverage(theta)
    if cov.distinct < 3:
        return ()
    top = max(1, min(cov.distinct // 2, RESIDUAL_MAX_ORDER))
    candidates = sorted(k for k in set(range(1, top + 1)) | {float(k) for k in extra if k > 0} if not cov.beyond(k))
    both = bool(np.any(d > 0) and np.any(d < 0))
    parts = [np.ones((theta.shape[0], 1))]
    if not cov.full_turn:  # the slow part over a partial span is a trend
        parts.append(trend_columns(theta, cov, max(0, min(TREND_DEGREE, cov.distinct - 2))))
    base = np.hstack(parts)
    if both:
        base = np.hstack([base, base * d[:, None]])
    out = []
    for _ in range(min(most, len(candidates))):
        scan = order_amplitudes(theta, resid, d, candidates, base, counts)
        if not np.any(scan.reduction > 0):
            break
        i = int(np.argmax(scan.reduction))
        k = float(scan.orders[i])
        out.append((k, float(scan.common[i]),
                    float(scan.differential[i]) if math.isfinite(scan.differential[i]) else math.nan))
        base = np.hstack([base, harmonic_block(theta, np.array([k]), d if both else None)[:, 0, :]])
        candidates.remove(k)
    return tuple(out)


def predict_table(make_table: Callable, theta, y, direction, run, orders=(), parameters: int | None = None
                  ) -> TablePrediction:
    """The ISO 230-2 figures a repeat test will show once the table is loaded (module doc).

    Parameters
    ----------
    make_table : callable
        ``make_table(mask)`` -> :class:`~wormgear_cli.compensation.table.CorrectionTable`
        made from the rows where ``mask`` is True, as the final table is made.
    theta, y : array_like [rad], shape (n,)
        Angles and errors (actual - target).
    direction, run : array_like, shape (n,)
    orders : sequence of float
        Orders also scanned in the residual (the model's, and those the table cannot carry).
    parameters : int or None
        Values the table is fitted with (the model's columns, or the cells
        with per-target means): its own noise at the rows is then known, a
        within-run variance times parameters / rows (the mean leverage), and
        only what the model misses is taken from the cross-validation.  None:
        both from the cross-validation, scaled by (R - 1) / R.
    """

    theta = np.asarray(theta, dtype=float)
    y = np.asarray(y, dtype=float)
    d = np.asarray(direction, dtype=float)
    run = np.zeros(y.shape[0], dtype=int) if run is None else np.asarray(run)
    grouping, cell = _cells(theta, d)
    before = _iso(theta, y, d, grouping)
    corrected, folds = corrected_rows(make_table, theta, y, d, run)
    noise = noise_components(cell, run, y)
    _, ri = np.unique(run, return_inverse=True)
    ri = ri.ravel()
    centred = corrected - (np.bincount(ri, weights=corrected) / np.bincount(ri))[ri]
    tops = residual_orders(theta, centred, d, orders)
    if folds and math.isfinite(noise.within):
        missed, own = _remainder(float(np.mean(centred**2)), noise.within, folds, parameters, y.shape[0])
        after = _simulate(theta, d, grouping, cell, run, systematic_remainder(cell, centred, missed), own, noise)
        count = max(MIN_REPLICATES, min(REPLICATES, REPLICATE_ROWS // max(y.shape[0], 1)))
        return TablePrediction("cross-validated", folds, before, after, noise, math.sqrt(missed + own), tops, count)
    figs = {k: float(v[0]) for k, v in _figures(corrected[None], d, grouping).items()}
    after = {k: Figure(v, v, v) for k, v in figs.items()}
    return TablePrediction("in-sample", 0, before, after, noise, float(np.sqrt(np.mean(centred**2))), tops, 0)


def _remainder(mean_square: float, within: float, folds: int, parameters: int | None, rows: int
               ) -> tuple[float, float]:
    """The variances the final table leaves at a row [rad^2]: (what the model misses, m^2, a
    systematic remainder with the shape of the cross-validated rows; the table's own noise,
    independent per cell).

    The cross-validated rows hold the scatter (``within``), m^2 and the noise of a table made
    from (R - 1) of the R runs (within x h x R / (R - 1), h = parameters / rows the mean
    leverage); the final table, made from all runs, leaves m^2 + within x h.  With
    ``parameters`` None the two are not told apart: all of it is taken as systematic, scaled by
    (R - 1) / R."""
    if parameters is None:
        return max(0.0, mean_square - within) * (folds - 1) / folds, 0.0
    h = parameters / rows
    missed = max(0.0, mean_square - within * (1.0 + h * folds / (folds - 1)))
    return missed, within * h


def _iso(theta, y, d, grouping):
    return iso230_figures(theta, y, d, grouping=grouping)
