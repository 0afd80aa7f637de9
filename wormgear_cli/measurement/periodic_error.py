"""Periodic error as astronomers quote it: drift removed, the worm cycle folded, peak to peak, harmonics.

A telescope mount's periodic error (PE) is the part of the RA axis's error that repeats with every
turn of the worm.  It is quoted as the peak-to-peak range of the error over one worm cycle, after
the slow drift (polar misalignment, refraction, a tracking rate a little off) is taken out, and
shown as the error curve over one worm period with the samples of every cycle folded onto it.

Given the error ``y`` at the axis angles ``theta`` (a reconstructed guide log, or any measurement),
the worm order k (cycles per axis turn: a worm of period P on an axis turning once per T has
k = T / P, e.g. 180 for a 180-tooth RA wheel and T a sidereal day) and H harmonics, one linear
least-squares fit at exact orders (:func:`~wormgear_cli.measurement.harmonics.fit_orders`) gives

    y_i = c + d_r(t_i) + sum_{h=1..H} [a_h cos(h k theta_i) + b_h sin(h k theta_i)]
              + sum_{e in extra} [a_e cos(e theta_i) + b_e sin(e theta_i)] + r_i,

where d_r is the drift of run r: an offset and a polynomial of degree D in time over the run
(Chebyshev polynomials of the time mapped onto [-1, 1] over the run, so the basis is well
conditioned; a cubic by default), and the extra orders stand for periodic errors of other parts
(a motor gear) that would otherwise leak into the worm's.  Fitting drift and harmonics together
keeps either from taking the other's share.  The smoothed error curve over one worm period is
the fitted worm harmonics, sum_h (a_h cos 2 pi h phi + b_h sin 2 pi h phi) over the worm phase
phi in [0, 1): the least-squares low-pass of the folded data to H harmonics; its range is the
peak-to-peak PE.  The folded samples (drift and extra orders removed, averaged in bins of worm
phase) are given for plots.  Amplitudes are zero-to-peak; ``peak_to_peak`` is a range.

Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from wormgear_cli.measurement.coverage import TREND_DEGREE, as_1d
from wormgear_cli.measurement.drift import drift_columns
from wormgear_cli.measurement.harmonics import fit_orders, harmonic_columns
from wormgear_cli.measurement.serial import block_covariance, serial_blocks
from wormgear_cli.units import SIDEREAL_DAY_S

#: worm harmonics fitted by default (the worm order and its next three multiples)
DEFAULT_HARMONICS = 4
#: degree of the drift polynomial in time per run (a cubic, as the usual PE analyses)
DRIFT_DEGREE = TREND_DEGREE
#: bins of worm phase for the folded samples
FOLD_BINS = 50
#: samples of the smoothed curve over one worm period
CURVE_POINTS = 720


def worm_order(period_s: float, axis_period_s: float = SIDEREAL_DAY_S) -> float:
    """The order [cycles per axis turn] of a period of ``period_s`` [s] on an axis turning once per
    ``axis_period_s`` [s] (a sidereal day by default: an equatorial mount's RA axis).  ValueError
    unless both are positive."""
    if not (period_s > 0 and axis_period_s > 0):
        raise ValueError("periods must be positive")
    return axis_period_s / period_s


def order_period_s(order: float, axis_period_s: float = SIDEREAL_DAY_S) -> float:
    """The period [s] of ``order`` [cycles per axis turn] on an axis turning once per ``axis_period_s`` [s]."""
    if not (order > 0 and axis_period_s > 0):
        raise ValueError("order and axis period must be positive")
    return axis_period_s / order


@dataclass(frozen=True)
class PeriodicError:
    """Result of :func:`periodic_error` (``y``'s unit throughout; phases [rad]).

    ``order`` the worm order [cycles per axis turn], ``period_s`` its period [s] (None without
    ``axis_period_s``); ``orders`` the fitted orders: the ``harmonics`` worm harmonics h * order
    first, then the extra orders; per order ``amplitude`` (zero-to-peak), ``phase`` (y ~ A sin(k
    theta + phase)), ``amplitude_stderr`` and ``identifiable`` (as
    :class:`~wormgear_cli.measurement.harmonics.OrderFit`).  Per sample: ``drift`` (offset and
    trend of each run), ``worm`` (the fitted worm harmonics), ``residual`` (y minus everything
    fitted).  ``curve_phase`` (m,) worm phase in [0, 1) and ``curve`` (m,) the smoothed error curve
    over one worm period (mean zero); ``peak_to_peak`` its range.  ``fold_phase`` (bins,) bin
    centres, ``fold_mean`` (bins,) mean of y - drift - extra orders per bin (NaN where empty) and
    ``fold_count``.  RMS values: ``rms_raw`` y about each run's mean, ``rms_detrended`` y - drift
    (periodic error in), ``rms_without_worm`` y - drift - worm harmonics (what a perfect PEC of the
    worm would leave), ``rms_residual`` y minus everything fitted.  ``cycles``: worm cycles the
    runs cover together.
    """

    order: float
    period_s: float | None
    harmonics: int
    orders: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray
    amplitude_stderr: np.ndarray
    identifiable: np.ndarray
    drift: np.ndarray
    worm: np.ndarray
    residual: np.ndarray
    curve_phase: np.ndarray
    curve: np.ndarray
    peak_to_peak: float
    fold_phase: np.ndarray
    fold_mean: np.ndarray
    fold_count: np.ndarray
    rms_raw: float
    rms_detrended: float
    rms_without_worm: float
    rms_residual: float
    cycles: float
    standard_errors: str = "ordinary least squares, rows taken as independent"


def _run_means_rms(y: np.ndarray, run) -> float:
    if run is None:
        return float(np.sqrt(np.mean((y - y.mean()) ** 2)))
    _, inverse = np.unique(np.asarray(run), return_inverse=True)
    inverse = inverse.reshape(-1)
    means = np.bincount(inverse, weights=y) / np.bincount(inverse)
    return float(np.sqrt(np.mean((y - means[inverse]) ** 2)))


def _cycles(theta: np.ndarray, run, order: float) -> float:
    if run is None:
        return float(np.ptp(theta)) * order / (2.0 * math.pi)
    _, inverse = np.unique(np.asarray(run), return_inverse=True)
    inverse = inverse.reshape(-1)
    spans = np.full(inverse.max() + 1, -np.inf)
    np.maximum.at(spans, inverse, theta)
    lows = np.full(spans.shape, np.inf)
    np.minimum.at(lows, inverse, theta)
    return float(np.sum(spans - lows)) * order / (2.0 * math.pi)


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x * x)))


def _serial_stderr(theta, orders, cols, fit, run, time) -> tuple[np.ndarray, str]:
    """The amplitudes' standard errors and how they were made: the fit's own (rows independent) unless
    the residual is serially correlated within runs; then the sandwich over blocks of consecutive rows
    after AR(1) prewhitening (:func:`~wormgear_cli.measurement.serial.serial_blocks`), amplitudes by
    the delta method."""
    serial = serial_blocks(fit.residual, run, time)
    if serial.independent:
        return fit.amplitude_stderr, serial.describe()
    n = theta.shape[0]
    x = np.hstack([np.ones((n, 1)), harmonic_columns(theta, orders), cols])
    gram_inv = np.linalg.pinv(x.T @ x, hermitian=True)
    scores = np.zeros((serial.blocks, x.shape[1]))
    assert serial.block_id is not None  # (not independent: the rows are in blocks)
    np.add.at(scores, serial.block_id, x * serial.whiten(fit.residual)[:, None])
    cov = block_covariance(gram_inv, scores, n) * serial.recolour
    a, b = fit.cos, fit.sin
    ia = 1 + 2 * np.arange(orders.shape[0])
    with np.errstate(invalid="ignore", divide="ignore"):
        var = (a * a * cov[ia, ia] + b * b * cov[ia + 1, ia + 1] + 2 * a * b * cov[ia, ia + 1]) / (a * a + b * b)
    se = np.sqrt(np.maximum(np.where(np.isfinite(var), var, 0.5 * (cov[ia, ia] + cov[ia + 1, ia + 1])), 0.0))
    return np.where(fit.identifiable, se, np.nan), serial.describe()


def periodic_error(theta, y, order: float, *, time=None, run=None, harmonics: int = DEFAULT_HARMONICS,
                   extra_orders: Sequence[float] = (), drift_degree: int = DRIFT_DEGREE, bins: int = FOLD_BINS,
                   axis_period_s: float | None = None) -> PeriodicError:
    """The periodic error of a worm of order ``order`` in the error ``y`` (see the module doc).

    Parameters
    ----------
    theta : array_like (n,) [rad]
        Axis angle of each sample (continuous within a run: the RA axis's angle of a guide log).
    y : array_like (n,) [any unit, e.g. arcsec]
        Error of the axis.
    order : float [cycles per axis turn]
        The worm order (:func:`worm_order` from a period in seconds).
    time : array_like (n,) [s] or None
        Time of each sample for the drift; None: the drift is a polynomial in ``theta``.
    run : array_like (n,) or None
        Run (session) of each sample: each run has its own offset and drift.
    harmonics : int
        Worm harmonics fitted, H >= 1 (the order and its multiples up to H times).
    extra_orders : sequence of float [cycles per axis turn]
        Other orders fitted alongside (a motor gear's); not part of the worm curve.  Those equal
        to a worm harmonic are left out (the harmonic carries them).
    drift_degree : int
        Degree of each run's drift polynomial (0: an offset only).
    bins : int
        Bins of worm phase for ``fold_mean``.
    axis_period_s : float or None [s]
        The axis's period (e.g. :data:`~wormgear_cli.units.SIDEREAL_DAY_S`), for ``period_s``.

    Raises
    ------
    ValueError
        Arrays of different lengths, fewer than two samples, ``order`` not positive, ``harmonics``
        below 1, ``drift_degree`` negative, ``bins`` below 1.
    """
    theta = as_1d("theta", theta)
    n = theta.shape[0]
    y = as_1d("y", y, n)
    if n < 2:
        raise ValueError("at least two samples are needed")
    if not (order > 0 and math.isfinite(order)) or harmonics < 1 or drift_degree < 0 or bins < 1:
        raise ValueError("order must be positive, harmonics >= 1, drift_degree >= 0 and bins >= 1")
    worm_orders = order * np.arange(1, harmonics + 1)
    extra = [float(e) for e in extra_orders
             if not np.any(np.abs(worm_orders - e) <= 1e-9 * max(abs(e), 1.0))]
    orders = np.concatenate([worm_orders, np.asarray(extra, dtype=float)])
    cols = drift_columns(theta if time is None else as_1d("time", time, n), run, drift_degree)
    fit = fit_orders(theta, y, orders.tolist(), design_extra=cols)
    amp_se, serial = _serial_stderr(theta, orders, cols, fit, run, time)
    coef = np.empty(2 * orders.shape[0])
    coef[0::2], coef[1::2] = fit.cos, fit.sin
    drift = fit.offset + cols @ fit.extra
    worm = harmonic_columns(theta, worm_orders) @ coef[:2 * harmonics]
    rest = harmonic_columns(theta, orders[harmonics:]) @ coef[2 * harmonics:]
    phase_grid = np.arange(CURVE_POINTS) / CURVE_POINTS
    curve = harmonic_columns(2.0 * math.pi * phase_grid, np.arange(1.0, harmonics + 1)) @ coef[:2 * harmonics]
    fine = harmonic_columns(np.linspace(0.0, 2.0 * math.pi, 16 * CURVE_POINTS, endpoint=False),
                            np.arange(1.0, harmonics + 1)) @ coef[:2 * harmonics]
    folded = y - drift - rest
    phi = np.mod(order * theta / (2.0 * math.pi), 1.0)
    which = np.minimum((phi * bins).astype(np.int64), bins - 1)
    count = np.bincount(which, minlength=bins)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.bincount(which, weights=folded, minlength=bins) / count
    return PeriodicError(
        order=float(order), period_s=None if axis_period_s is None else order_period_s(order, axis_period_s),
        harmonics=int(harmonics), orders=orders, amplitude=fit.amplitude, phase=fit.phase,
        amplitude_stderr=amp_se, identifiable=fit.identifiable, drift=drift, worm=worm,
        residual=fit.residual, curve_phase=phase_grid, curve=curve, peak_to_peak=float(np.ptp(fine)),
        fold_phase=(np.arange(bins) + 0.5) / bins, fold_mean=mean, fold_count=count,
        rms_raw=_run_means_rms(y, run), rms_detrended=_rms(y - drift), rms_without_worm=_rms(y - drift - worm),
        rms_residual=_rms(fit.residual), cycles=_cycles(theta, run, order), standard_errors=serial)
