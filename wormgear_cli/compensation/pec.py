"""Periodic error correction (PEC) of a telescope mount: one worm period of the RA axis's error.

A mount tracking at the sidereal rate turns its RA axis once per sidereal day
(:data:`SIDEREAL_DAY_S`), so a worm of order n (cycles per axis turn: the wheel's teeth for a
worm driving the axis) repeats every SIDEREAL_DAY_S / n seconds.  A PEC curve is the error over
one worm period, drift removed, which the mount plays back against the worm's position.

The tracking record (a :class:`~wormgear_cli.measurement.reader.Measurement` whose angle is the
RA axis angle and whose error is the axis's error, actual - ideal, positive ahead) is fitted by
least squares with a drift per run (an offset and a Chebyshev polynomial of degree
:data:`DRIFT_DEGREE` in the angle, i.e. in time, over each run) and sinusoids at the worm order,
its harmonics and any further orders asked for.  The curve carries the worm order and its whole
harmonics; other orders (a motor or a gear with another period) are fitted alongside, so they
do not bias the curve, but no one-period curve can carry them.

What the curve will leave is cross-validated over whole worm cycles: each cycle in turn is left
out, the curve is made from the others and taken off the left-out cycle (less that cycle's own
linear drift); the periodic error left is the peak-to-peak of the worm-harmonic content of
those corrected cycles.  Pure numpy.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from wormgear_cli.compensation.scan import order_amplitudes
from wormgear_cli.measurement.coverage import unwrap_passes
from wormgear_cli.measurement.harmonics import harmonic_columns

#: one sidereal day [s]: the RA axis turns once in it when tracking
SIDEREAL_DAY_S = 86164.0905
#: degree of the drift polynomial per run
DRIFT_DEGREE = 3
#: a worm cycle left out must hold at least this fraction of a cycle (shorter ends join a neighbour)
MIN_FOLD_CYCLES = 0.5
#: points per worm cycle where the peak-to-peak is read
PP_POINTS = 3600
#: worm periods shorter than this [s] are not taken for a mount's worm when found in a record (mounts'
#: worms turn in 2 to 10 minutes; a shorter strongest period is a motor gear, the seeing or a few samples)
MIN_WORM_PERIOD_S = 60.0
#: worm harmonics at least in the PE a curve leaves (twice the curve's, if more): a mount's PE has
#: content up to the 3rd or 4th harmonic whether the curve carries it or not
LEFT_HARMONICS = 4
#: phase bins of the worm cycle per harmonic of the curve that must each hold a row (see :func:`phase_bins_empty`)
BINS_PER_HARMONIC = 4


def period_of(order: float) -> float:
    """Worm period [s] of an order [cycles per RA-axis turn] at the sidereal rate."""
    return SIDEREAL_DAY_S / order


def order_of(period_s: float) -> float:
    """Order [cycles per RA-axis turn] of a period [s] at the sidereal rate."""
    return SIDEREAL_DAY_S / period_s


def continuous(theta, run) -> np.ndarray:
    """Angles [rad] made continuous within each run (a record may cross 0 deg)."""
    return unwrap_passes(np.asarray(theta, dtype=float), run)


def drift_columns(th: np.ndarray, run: np.ndarray, degree: int = DRIFT_DEGREE) -> np.ndarray:
    """(n, R (1 + degree)) columns: per run an indicator and Chebyshev T_1..T_degree of the angle
    mapped onto [-1, 1] over that run's span."""
    ids, ri = np.unique(run, return_inverse=True)
    ri = ri.ravel()
    cols = np.zeros((th.shape[0], ids.size * (1 + degree)))
    for j in range(ids.size):
        rows = ri == j
        t = th[rows]
        lo, hi = float(t.min()), float(t.max())
        x = 2.0 * (t - lo) / (hi - lo) - 1.0 if hi > lo else np.zeros(t.shape)
        cols[rows, j * (1 + degree):(j + 1) * (1 + degree)] = np.polynomial.chebyshev.chebvander(x, degree)
    return cols


@dataclass(frozen=True)
class HarmonicFit:
    """Sinusoids at ``orders`` fitted with a drift: ``cos``, ``sin`` (m,) [rad] of
    a cos k theta + b sin k theta, ``residual`` (n,) [rad] with the drift and every order removed."""

    orders: np.ndarray
    cos: np.ndarray
    sin: np.ndarray
    residual: np.ndarray

    def evaluate(self, theta, orders: Sequence[float] | None = None) -> np.ndarray:
        """Sum of the fitted sinusoids (only ``orders`` when given) at angles ``theta`` [rad]."""
        theta = np.asarray(theta, dtype=float)
        keep = np.ones(self.orders.shape, dtype=bool) if orders is None else np.isin(self.orders, list(orders))
        out = np.zeros(theta.shape)
        for k, a, b in zip(self.orders[keep], self.cos[keep], self.sin[keep]):
            out += a * np.cos(k * theta) + b * np.sin(k * theta)
        return out


def fit_harmonics(th, y, run, orders: Sequence[float], degree: int = DRIFT_DEGREE) -> HarmonicFit:
    """Least squares of ``y`` on a drift per run (:func:`drift_columns`) and cos/sin at ``orders``
    (minimum-norm where the rows cannot tell orders apart)."""
    y = np.asarray(y, dtype=float)
    ords = np.asarray(list(orders), dtype=float)
    x, scale, drifts = _design(th, run, ords, degree)
    coef = np.linalg.lstsq(x / scale, y, rcond=1e-10)[0] / scale
    h = coef[drifts:]
    return HarmonicFit(ords, h[0::2], h[1::2], y - x @ coef)


def _design(th, run, orders: np.ndarray, degree: int) -> tuple[np.ndarray, np.ndarray, int]:
    """The fit's columns [a drift per run, cos/sin at ``orders``], their norms (the scaling the
    least squares uses) and the number of drift columns."""
    th = np.asarray(th, dtype=float)
    drift = drift_columns(th, np.asarray(run), degree)
    x = np.hstack([drift, harmonic_columns(th, orders)])
    return x, np.sqrt(np.maximum(np.einsum("ij,ij->j", x, x), 1e-300)), drift.shape[1]


def determinacy(th, run, orders: Sequence[float], degree: int = DRIFT_DEGREE) -> tuple[int, int, int]:
    """(rows, terms, terms the rows tell apart) of the fit :func:`fit_harmonics` makes: the
    design's size and its numerical rank (scaled columns, relative tolerance 1e-10)."""
    x, scale, _ = _design(th, run, np.asarray(list(orders), dtype=float), degree)
    return x.shape[0], x.shape[1], int(np.linalg.matrix_rank(x / scale, tol=None))


def peak_to_peak(fit: HarmonicFit, worm_order: float, orders: Sequence[float], start: float = 0.0) -> float:
    """Peak-to-peak [rad] over one worm cycle (from axis angle ``start``) of the fitted sinusoids at ``orders``."""
    theta = start + np.linspace(0.0, 2.0 * math.pi / worm_order, PP_POINTS, endpoint=False)
    curve = fit.evaluate(theta, orders)
    return float(np.ptp(curve)) if curve.size else 0.0


@dataclass(frozen=True)
class PecCurve:
    """One worm period of PE, as a mount plays it back (:func:`pec_curve`).

    ``worm_order`` [cycles per axis turn]; ``period_s``: its period at the
    sidereal rate [s]; ``rows``: the period in whole seconds (one row per
    second); ``harmonics``: the orders carried (whole multiples of the worm
    order); ``extra``: orders fitted alongside but not carried; ``reference``
    [rad]: the axis angle of worm phase 0, the first angle at or after the
    record's start where worm_order x angle is a whole number of turns;
    ``pe`` (rows,) [rad]: the error at worm phase t / rows (axis angle
    reference + 2 pi t / (rows worm_order)), t = 0 .. rows - 1, mean
    removed; ``fit``: the :class:`HarmonicFit`; ``cycles``: worm cycles the
    data cover.
    """

    worm_order: float
    period_s: float
    rows: int
    harmonics: tuple[float, ...]
    extra: tuple[float, ...]
    reference: float
    pe: np.ndarray
    fit: HarmonicFit
    cycles: float

    @property
    def peak_to_peak(self) -> float:
        return peak_to_peak(self.fit, self.worm_order, self.harmonics, self.reference)


def harmonics_of(worm_order: float, orders: Sequence[float], rel_tol: float = 1e-6) -> tuple[list[float], list[float]]:
    """(whole multiples of ``worm_order`` among ``orders``, the others)."""
    carried: list[float] = []
    other: list[float] = []
    for k in orders:
        h = k / worm_order
        (carried if round(h) >= 1 and abs(h - round(h)) <= rel_tol * max(h, 1.0) else other).append(float(k))
    return carried, other


def phase_bins_empty(th, worm_order: float, harmonics: int) -> tuple[int, int]:
    """(empty bins, bins): the worm cycle cut into :data:`BINS_PER_HARMONIC` x ``harmonics`` equal
    phase bins, those no row falls in.  A curve of ``harmonics`` harmonics is determined only where
    the rows reach every part of the cycle: a record of short pieces at one phase (a session each
    worm period, clouds) leaves the rest of the curve to the fit's extrapolation."""
    bins = BINS_PER_HARMONIC * max(1, int(harmonics))
    phase = np.mod(np.asarray(th, dtype=float) * worm_order, 2.0 * math.pi)
    held = np.bincount(np.minimum((phase / (2.0 * math.pi) * bins).astype(int), bins - 1), minlength=bins)
    return int(np.count_nonzero(held == 0)), bins


def cycles_covered(th, run, worm_order: float) -> float:
    """Worm cycles the runs cover together (sum of each run's angular span times the order / 2 pi)."""
    total = 0.0
    for r in np.unique(run):
        t = th[run == r]
        total += float(np.ptp(t)) * worm_order / (2.0 * math.pi)
    return total


def pec_curve(theta, y, run, worm_order: float, orders: Sequence[float]) -> PecCurve:
    """The PEC curve of a tracking record.

    Parameters
    ----------
    theta, y : array_like [rad], shape (n,)
        RA-axis angle (advancing with time) and its error.
    run : array_like of int, shape (n,)
        Session of each row (a drift is fitted per run).
    worm_order : float [cycles per axis turn]
    orders : sequence of float
        Every order fitted (the worm order and its harmonics are carried,
        others fitted alongside).
    """
    run = np.asarray(run)
    th = continuous(theta, run)
    carried, other = harmonics_of(worm_order, orders)
    fit = fit_harmonics(th, y, run, carried + other)
    period = period_of(worm_order)
    rows = max(1, int(math.floor(period + 0.5)))
    # worm phase 0 next to the data: with a worm order that is not whole (a period found or given in
    # seconds), the fitted sinusoids hold only near the record, not at axis angle 0
    turn = 2.0 * math.pi / worm_order
    reference = math.ceil(float(th[0]) / turn - 1e-9) * turn
    pe = fit.evaluate(reference + turn * np.arange(rows) / rows, carried)
    return PecCurve(worm_order, period, rows, tuple(carried), tuple(other), reference, pe - float(np.mean(pe)), fit,
                    cycles_covered(th, run, worm_order))


def curve_standard_error(th, run, curve: PecCurve, degree: int = DRIFT_DEGREE) -> float:
    """RMS over one worm cycle [rad] of the pointwise standard error of ``curve`` (the sum of its
    carried harmonics), from the fit :func:`fit_harmonics` made: the harmonic terms' covariance
    s^2 (X'X)^-1 of that design (a drift per run beside them), s^2 the residual mean square.

    Small beside the curve when each run spans worm cycles; large when the runs are short beside
    the worm period, so that a run's drift and a piece of the curve look alike and the fit trades
    one for the other, noise included.  inf when the design cannot be inverted.  White residuals
    are assumed, so on a guide log's correlated seeing it is a lower bound."""
    ords = curve.fit.orders
    x, scale, drifts = _design(th, np.asarray(run), ords, degree)
    n, p = x.shape
    res = curve.fit.residual
    s2 = float(res @ res) / max(n - p, 1)
    xs = x / scale
    try:
        inv = np.linalg.inv(xs.T @ xs)
    except np.linalg.LinAlgError:
        return math.inf
    h = scale[drifts:]
    cov = s2 * inv[drifts:, drifts:] / np.outer(h, h)
    turn = 2.0 * math.pi / curve.worm_order
    grid = curve.reference + turn * np.arange(PP_POINTS) / PP_POINTS
    g = harmonic_columns(grid, ords) * np.repeat(np.isin(ords, curve.harmonics), 2)  # the carried terms only
    var = np.einsum("ij,jk,ik->i", g, cov, g)
    return float(np.sqrt(np.mean(np.maximum(var, 0.0)))) if np.all(np.isfinite(var)) else math.inf


def cycle_folds(th, run, worm_order: float) -> np.ndarray:
    """Fold of each row: its whole worm cycle within its run (counted from the run's first angle);
    a cycle holding less than :data:`MIN_FOLD_CYCLES` of a cycle joins its neighbour."""
    fold = np.zeros(th.shape[0], dtype=np.int64)
    next_id = 0
    for r in np.unique(run):
        rows = np.flatnonzero(run == r)
        c = np.floor((th[rows] - th[rows].min()) * worm_order / (2.0 * math.pi)).astype(np.int64)
        span = float(np.ptp(th[rows])) * worm_order / (2.0 * math.pi)
        last_full = int(math.floor(span))
        if span - last_full < MIN_FOLD_CYCLES and last_full >= 1:
            c = np.minimum(c, last_full - 1)
        fold[rows] = next_id + c
        next_id += int(c.max()) + 1
    return fold


@dataclass(frozen=True)
class PecPrediction:
    """Result of :func:`predict_pec`: ``before`` [rad], the PE peak-to-peak of the curve;
    ``after`` [rad], the peak-to-peak of the worm-harmonic content left in the left-out
    cycles once corrected (NaN with fewer than two cycles); ``folds``: cycles left out in
    turn; ``residual_orders``: ((order, amplitude [rad]), ...) largest in the corrected
    cycles; ``method``: "cross-validated" or "not cross-validated"."""

    before: float
    after: float
    folds: int
    residual_orders: tuple
    method: str


def predict_pec(theta, y, run, curve: PecCurve, most: int = 3) -> PecPrediction:
    """What the PEC curve will leave (module doc); not cross-validated (``after`` NaN) unless
    the record holds two worm cycles and every curve made without one of them a whole cycle."""
    run = np.asarray(run)
    th = continuous(theta, run)
    y = np.asarray(y, dtype=float)
    fold = cycle_folds(th, run, curve.worm_order)
    ids = np.unique(fold)
    orders = list(curve.harmonics) + list(curve.extra)
    # each curve must be made from a whole worm cycle at least
    enough = ids.size >= 2 and all(cycles_covered(th[fold != f], run[fold != f], curve.worm_order) >= 1.0
                                   for f in ids)
    if not enough or not curve.harmonics:
        return PecPrediction(curve.peak_to_peak, math.nan, 0, (), "not cross-validated")
    left = np.empty_like(y)
    for f in ids:
        held = fold == f
        part = fit_harmonics(th[~held], y[~held], run[~held], orders)
        r = y[held] - part.evaluate(th[held], curve.harmonics)
        x = np.column_stack([np.ones(r.shape[0]), th[held] - th[held].mean()])
        left[held] = r - x @ np.linalg.lstsq(x, r, rcond=None)[0]
    top = max(2 * len(curve.harmonics), LEFT_HARMONICS)
    candidates = sorted({curve.worm_order * h for h in range(1, top + 1)} | set(curve.extra))
    # the PE left is the worm-periodic part of what remains: at the curve's harmonics and at those it
    # does not carry (up to twice as many), which the mount still shows after PEC
    worm_harmonics = [curve.worm_order * h for h in range(1, top + 1)]
    resid_fit = fit_harmonics(th, left, fold, worm_harmonics, degree=0)
    after = peak_to_peak(resid_fit, curve.worm_order, worm_harmonics, curve.reference)
    scan = order_amplitudes(th, left, np.ones_like(th), candidates)
    best = np.argsort(-scan.common)[:most]
    tops = tuple((float(scan.orders[i]), float(scan.common[i])) for i in best)
    return PecPrediction(curve.peak_to_peak, after, int(ids.size), tops, "cross-validated")
