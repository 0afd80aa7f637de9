"""Periodic error as astronomers quote it (wormgear_cli.measurement.periodic_error).

Checked on data made here with a known truth (tracking at the sidereal rate, a worm curve, a drift,
seeing over seeds), against numpy's least squares as the oracle of the joint fit, and on the three
real guide logs' right answers (tests/data/telescope/README.md).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.paths import DATA
from wormgear_cli.measurement.guidelog import GuideLogOptions, read_guidelog
from wormgear_cli.measurement.periodic_error import (
    drift_columns,
    order_period_s,
    periodic_error,
    worm_order,
)
from wormgear_cli.units import ARCSEC, SIDEREAL_DAY_S

WORM = 180.0
TRUE = ((1, 6.0, 0.4), (2, 1.5, -1.0), (3, 0.8, 2.0))  # harmonic, amplitude ["], phase [rad]


def tracking(seed, runs=((0.0, 1800.0), (3000.0, 1500.0)), dt=2.0, noise=0.5, theta0=-0.7):
    """(theta, y, time, run, true worm curve per sample) of a mount tracking through ``runs``
    (start [s], length [s]): worm harmonics TRUE, a different offset and cubic drift per run, noise."""
    rng = np.random.default_rng(seed)
    t = np.concatenate([np.arange(a, a + n, dt) for a, n in runs])
    run = np.concatenate([np.full(int(round(n / dt)), k + 1) for k, (a, n) in enumerate(runs)])
    theta = theta0 + 2 * math.pi * t / SIDEREAL_DAY_S
    worm = sum(a * np.sin(h * WORM * theta + ph) for h, a, ph in TRUE)
    drift = np.zeros_like(t)
    for k, (a, n) in enumerate(runs):
        rows = run == k + 1
        u = (t[rows] - a) / n
        drift[rows] = rng.normal(0, 20) + rng.normal(0, 5) * u + rng.normal(0, 3) * u ** 2 + rng.normal(0, 2) * u ** 3
    return theta, worm + drift + rng.normal(0, noise, t.size), t, run, worm


def true_peak_to_peak():
    phi = np.linspace(0, 2 * math.pi, 200_001)
    curve = sum(a * np.sin(h * phi + ph) for h, a, ph in TRUE)
    return float(np.ptp(curve))


def test_amplitudes_within_their_standard_errors_over_seeds():
    z = []
    for seed in range(20):
        theta, y, t, run, _ = tracking(seed)
        pe = periodic_error(theta, y, WORM, time=t, run=run, harmonics=3)
        z.append((pe.amplitude - [a for _, a, _ in TRUE]) / pe.amplitude_stderr)
    z = np.array(z)
    assert np.all(np.abs(z) < 4.5)
    assert abs(z.mean()) < 0.8 and 0.6 < z.std() < 1.5


def test_joint_fit_is_numpy_least_squares_with_per_run_polynomials():
    theta, y, t, run, _ = tracking(3)
    pe = periodic_error(theta, y, WORM, time=t, run=run, harmonics=3, extra_orders=(705.0,))
    cols = []
    for k in (1, 2):  # per run: offset, t, t^2, t^3 (plain monomials, not the module's Chebyshev basis)
        rows = (run == k).astype(float)
        tk = (t - t[run == k].mean()) / 1000.0
        cols += [rows, rows * tk, rows * tk ** 2, rows * tk ** 3]
    for k in (180.0, 360.0, 540.0, 705.0):
        cols += [np.cos(k * theta), np.sin(k * theta)]
    coef = np.linalg.lstsq(np.column_stack(cols), y, rcond=None)[0]
    np.testing.assert_allclose(pe.amplitude, np.hypot(coef[8::2], coef[9::2]), rtol=1e-8)
    model = np.column_stack(cols) @ coef
    np.testing.assert_allclose(pe.residual, y - model, atol=1e-8)
    np.testing.assert_allclose(pe.drift, np.column_stack(cols[:8]) @ coef[:8], atol=1e-8)


def test_curve_peak_to_peak_and_rms_against_the_truth():
    theta, y, t, run, worm = tracking(5, noise=0.3)
    pe = periodic_error(theta, y, WORM, time=t, run=run, harmonics=3, axis_period_s=SIDEREAL_DAY_S)
    assert pe.period_s == pytest.approx(SIDEREAL_DAY_S / 180.0)
    assert pe.peak_to_peak == pytest.approx(true_peak_to_peak(), abs=0.1)
    # the smoothed curve is the truth over one worm period (the phase of theta = 0 at phi = 0)
    phi = 2 * math.pi * pe.curve_phase
    truth = sum(a * np.sin(h * phi + ph) for h, a, ph in TRUE)
    assert np.max(np.abs(pe.curve - truth)) < 0.1
    np.testing.assert_allclose(pe.worm, worm, atol=0.1)
    assert pe.rms_residual == pytest.approx(0.3, rel=0.1)
    assert pe.rms_without_worm == pytest.approx(0.3, rel=0.1)
    expected = math.sqrt(0.3 ** 2 + sum(a * a / 2 for _, a, _ in TRUE))
    assert pe.rms_detrended == pytest.approx(expected, rel=0.05)
    assert pe.rms_raw > pe.rms_detrended
    assert pe.cycles == pytest.approx((1800 - 2 + 1500 - 2) / (SIDEREAL_DAY_S / 180), rel=1e-6)
    # the folded samples (50 bins) follow the curve
    fold_truth = np.interp(pe.fold_phase, pe.curve_phase, pe.curve, period=1.0)
    assert np.max(np.abs(pe.fold_mean - fold_truth)) < 0.5


def test_extra_order_kept_out_of_the_worm_curve():
    theta, y, t, run, worm = tracking(8, noise=0.1)
    y = y + 2.0 * np.sin(705.0 * theta)
    pe = periodic_error(theta, y, WORM, time=t, run=run, harmonics=3, extra_orders=(705.0, 360.0))
    assert pe.orders.tolist() == [180.0, 360.0, 540.0, 705.0]  # 360 is the second harmonic already
    assert pe.amplitude[3] == pytest.approx(2.0, abs=0.05)
    np.testing.assert_allclose(pe.worm, worm, atol=0.1)
    assert pe.rms_without_worm == pytest.approx(math.sqrt(0.1 ** 2 + 2.0), rel=0.05)
    assert pe.rms_residual == pytest.approx(0.1, rel=0.15)


def test_drift_in_angle_without_time_and_one_run():
    theta, y, t, run, _ = tracking(2, runs=((0.0, 2400.0),))
    a = periodic_error(theta, y, WORM, harmonics=3)
    b = periodic_error(theta, y, WORM, time=t, harmonics=3)
    np.testing.assert_allclose(a.amplitude, b.amplitude, rtol=1e-9)  # angle and time are proportional here


def test_drift_columns():
    cols = drift_columns([0.0, 1.0, 2.0, 10.0, 11.0, 12.0, 20.0], [5, 5, 5, 2, 2, 2, 9], degree=3)
    # run 5: T1, T2 (3 samples: degree 2); run 2: offset, T1, T2; run 9 (one sample): offset only
    assert cols.shape == (7, 6)
    np.testing.assert_allclose(cols[:3, 0], [-1, 0, 1])
    np.testing.assert_allclose(cols[:3, 1], [1, -1, 1])
    np.testing.assert_allclose(cols[:, 2], [0, 0, 0, 1, 1, 1, 0])
    np.testing.assert_allclose(cols[:, 5], [0, 0, 0, 0, 0, 0, 1])
    assert drift_columns([0.0, 1.0], degree=0).shape == (2, 0)


def test_periods_and_orders():
    assert worm_order(SIDEREAL_DAY_S / 180) == pytest.approx(180.0)
    assert order_period_s(360.0) == pytest.approx(239.345, abs=1e-3)
    assert worm_order(239.345, axis_period_s=86164.2) == pytest.approx(360.0, abs=1e-3)
    for bad in (lambda: worm_order(0.0), lambda: order_period_s(-1.0),
                lambda: periodic_error([0.0, 1.0], [0.0, 1.0], 0.0),
                lambda: periodic_error([0.0, 1.0], [0.0, 1.0], 10.0, harmonics=0),
                lambda: periodic_error([0.0], [0.0], 10.0),
                lambda: periodic_error([0.0, 1.0], [0.0], 10.0)):
        with pytest.raises(ValueError):
            bad()


@pytest.mark.parametrize("name, session, order, harmonics, extra, right, tol", [
    ("cge-pro-180.guidelog.txt", 1, 180, 3, (), (8.28, 0.79, 1.14), 0.02),
    ("losmandy-g11-360.guidelog.txt", 1, 360, 2, (), (4.07, 1.63), 0.02),
    ("losmandy-g11-360.guidelog.txt", 1, 360, 2, (180,), (4.11, 1.64, 0.82), 0.02),
    ("eq6-ppec-19-sessions.guidelog.txt", 3, 180, 2, (705,), (2.34, 0.78, 0.10), 0.02),
])
def test_real_logs_through_the_reader(name, session, order, harmonics, extra, right, tol):
    path = DATA / "telescope" / name
    m = read_guidelog(path.read_text(), name, GuideLogOptions(sessions=(session,)))
    pe = periodic_error(m.angle, m.error / ARCSEC, order, time=m.time, run=m.run, harmonics=harmonics,
                        extra_orders=extra, axis_period_s=SIDEREAL_DAY_S)
    np.testing.assert_allclose(pe.amplitude, right, atol=tol)
    assert pe.peak_to_peak > 2 * pe.amplitude[0] * 0.9
    assert pe.rms_without_worm < pe.rms_detrended


def test_noise_free_curve_peak_to_peak_exact_and_phases():
    """Without noise the fit is exact: the amplitudes, phases and the range of the curve are the truth's
    (the maximum at worm phase 0.5 rad, inside the first radian of the period)."""
    theta, _, t, run, _ = tracking(0, noise=0.0)
    ph = math.pi / 2 - 0.5
    y = 3.0 * np.sin(WORM * theta + ph) + 0.01 * t
    pe = periodic_error(theta, y, WORM, time=t, run=run, harmonics=1, drift_degree=1)
    assert pe.order == 180.0 and pe.harmonics == 1 and pe.period_s is None
    assert pe.amplitude[0] == pytest.approx(3.0, abs=1e-9)
    assert pe.phase[0] == pytest.approx(ph, abs=1e-9)
    assert pe.identifiable.tolist() == [True]
    assert pe.peak_to_peak == pytest.approx(6.0, abs=1e-4)
    assert pe.rms_residual == pytest.approx(0.0, abs=1e-9)
    for h, a, p in TRUE:  # three harmonics: phases as y ~ A sin(k theta + phase)
        y = y + a * np.sin(h * WORM * theta + p) if h > 1 else y
    pe3 = periodic_error(theta, y, WORM, time=t, run=run, harmonics=3, drift_degree=1)
    np.testing.assert_allclose(pe3.phase[1:], [p for _, _, p in TRUE[1:]], atol=1e-9)


def test_drift_follows_time_not_angle():
    """A drift linear in time on an axis that does not turn evenly: fitted exactly with ``time``,
    not with the angle, and a lower degree leaves a quadratic drift in the residual."""
    t = np.linspace(0.0, 3000.0, 1500)
    theta = 2 * math.pi * (t + 400.0 * np.sin(t / 500.0)) / SIDEREAL_DAY_S
    y = 2.0 * np.sin(WORM * theta) + 0.002 * t + 1e-6 * t ** 2
    exact = periodic_error(theta, y, WORM, time=t, harmonics=1, drift_degree=2)
    assert exact.rms_residual == pytest.approx(0.0, abs=1e-8)
    assert periodic_error(theta, y, WORM, harmonics=1, drift_degree=2).rms_residual > 1e-3
    assert periodic_error(theta, y, WORM, time=t, harmonics=1, drift_degree=1).rms_residual > 1e-2


def test_rms_raw_about_each_run_mean_and_cycles_without_runs():
    theta = np.array([0.0, 0.001, 0.002, 0.003])
    y = np.array([1.0, 3.0, 10.0, 14.0])
    pe = periodic_error(theta, y, 10.0, run=[1, 1, 2, 2], harmonics=1, drift_degree=0)
    assert pe.rms_raw == pytest.approx(math.sqrt(2.5))
    one = periodic_error(theta, y, 10.0, harmonics=1, drift_degree=0)
    assert one.rms_raw == pytest.approx(float(np.std(y)))
    assert one.cycles == pytest.approx(0.003 * 10.0 / (2 * math.pi))
    assert periodic_error(theta, y, 10.0, harmonics=1, axis_period_s=86400.0).period_s == pytest.approx(8640.0)


def test_fold_of_part_of_a_cycle_and_with_an_extra_order():
    # under a quarter of a worm cycle: bins 2..6 are empty (NaN) and every array has one entry per
    # bin; the first sample, a hair below 0, folds onto phase 1.0 exactly and counts in the last bin
    theta = np.linspace(-1e-20, 0.24 * 2 * math.pi / WORM, 400)
    y = np.sin(WORM * theta) + 0.5 * np.sin(705.0 * theta)
    pe = periodic_error(theta, y, WORM, harmonics=1, extra_orders=(705.0,), drift_degree=0, bins=8)
    assert pe.fold_count.shape == pe.fold_mean.shape == pe.fold_phase.shape == (8,)
    assert pe.fold_count.sum() == 400 and pe.fold_count[2:7].sum() == 0 and pe.fold_count[7] == 1
    assert np.isnan(pe.fold_mean[2:7]).all()
    # the extra order is taken out of the folded samples: bin means of sin(180 theta) alone
    centres = np.array([np.mean(np.sin(WORM * theta[(np.mod(WORM * theta / (2 * math.pi), 1) * 8).astype(int) == b]))
                        for b in (0, 1)])
    np.testing.assert_allclose(pe.fold_mean[:2], centres, atol=1e-6)
    tail_empty = periodic_error(theta[1:], y[1:], WORM, harmonics=1, extra_orders=(705.0,), drift_degree=0, bins=8)
    assert tail_empty.fold_count.shape == tail_empty.fold_mean.shape == (8,)
    assert tail_empty.fold_count[2:].sum() == 0 and np.isnan(tail_empty.fold_mean[2:]).all()


def test_extra_orders_within_a_billionth_of_a_harmonic_left_out():
    theta, y, t, run, _ = tracking(1)
    pe = periodic_error(theta, y, WORM, time=t, run=run, harmonics=2, extra_orders=(360.0000001, 360.01))
    assert pe.orders.tolist() == [180.0, 360.0, 360.01]


def test_argument_bounds():
    theta, y = [0.0, 0.01], [0.0, 1.0]
    for kwargs in ({"harmonics": 1}, {"drift_degree": 0}, {"bins": 1}):
        periodic_error(theta, y, 0.5, **kwargs)  # the smallest values accepted
    for order, kwargs in ((0.0, {}), (math.inf, {}), (1.0, {"harmonics": 0}), (1.0, {"drift_degree": -1}),
                          (1.0, {"bins": 0})):
        with pytest.raises(ValueError, match="^order must be positive, harmonics >= 1, drift_degree >= 0 and bins >= 1$"):
            periodic_error(theta, y, order, **kwargs)
    with pytest.raises(ValueError, match="^at least two samples are needed$"):
        periodic_error([0.0], [1.0], 1.0)
    with pytest.raises(ValueError, match="y has 1 entries, expected 2"):
        periodic_error(theta, [1.0], 1.0)
    with pytest.raises(ValueError, match="time has 1 entries, expected 2"):
        periodic_error(theta, y, 1.0, time=[0.0])
    assert worm_order(0.5) == pytest.approx(SIDEREAL_DAY_S / 0.5)
    assert order_period_s(0.5) == pytest.approx(SIDEREAL_DAY_S / 0.5)
    for call in (lambda: worm_order(1.0, 0.0), lambda: worm_order(0.0)):
        with pytest.raises(ValueError, match="^periods must be positive$"):
            call()
    for call in (lambda: order_period_s(0.0), lambda: order_period_s(1.0, 0.0)):
        with pytest.raises(ValueError, match="^order and axis period must be positive$"):
            call()
    assert worm_order(2.0, 0.5) == 0.25 and order_period_s(2.0, 0.5) == 0.25
    with pytest.raises(ValueError, match="time must be one-dimensional"):
        drift_columns([[0.0, 1.0]])
    with pytest.raises(ValueError, match=r"run has shape \(3,\), expected \(2,\)"):
        drift_columns([0.0, 1.0], [1, 2, 3])


def test_drift_columns_runs_of_one_instant_and_offsets():
    # a run of one sample first, a run whose samples share one instant, then a run of two samples at t 10..11
    cols = drift_columns([5.0, 7.0, 7.0, 10.0, 11.0], [3, 1, 1, 2, 2], degree=3)
    assert cols.shape == (5, 3)  # run 1: offset; run 2: offset, T1 (2 samples: degree 1); run 3: nothing
    np.testing.assert_allclose(cols[:, 0], [0, 1, 1, 0, 0])
    np.testing.assert_allclose(cols[:, 1], [0, 0, 0, 1, 1])
    np.testing.assert_allclose(cols[:, 2], [0, 0, 0, -1, 1])
    one = drift_columns([2.0, 3.0, 4.0], degree=2)
    np.testing.assert_allclose(one, [[-1, 1], [0, -1], [1, 1]])
