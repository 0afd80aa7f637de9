"""The uncertainty of an order fit, two ways: against statsmodels (an independent least-squares code)
with the amplitude's and phase's delta method written out here, and by simulated coverage over seeds.

Covers ``fit_orders`` (``amplitude_stderr``, ``phase_stderr``, ``sigma`` and the residual degrees of
freedom n - rank) and ``analyse_orders`` (measure's joint common + differential fit, ordinary
standard errors: ``serial=False``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from wormgear_cli.measurement.harmonics import fit_orders
from wormgear_cli.measurement.orders import OrdersOptions, analyse_orders

#: statsmodels' least squares (its regression module only: the whole statsmodels.api costs 0.13 s more to import)
sm = pytest.importorskip("statsmodels.regression.linear_model")

ORDERS = (1.0, 2.0, 5.0)
TRUE_A = np.array([3.0, -1.5, 0.8])   # cos coefficients
TRUE_B = np.array([2.0, 2.5, -0.6])   # sin coefficients
OFFSET = 0.7


def _design(theta, orders):
    cols = [np.ones_like(theta)]
    for k in orders:
        cols += [np.cos(k * theta), np.sin(k * theta)]
    return np.column_stack(cols)


def _sample(rng, n=90, noise=0.5, uneven=True):
    theta = np.sort(rng.uniform(0, 2 * np.pi, n)) if uneven else np.linspace(0, 2 * np.pi, n, endpoint=False)
    y = OFFSET + sum(a * np.cos(k * theta) + b * np.sin(k * theta) for k, a, b in zip(ORDERS, TRUE_A, TRUE_B))
    return theta, y + rng.normal(0, noise, n)


def _delta(a, b, cov):
    """Amplitude A = hypot(a, b) and phase phi = atan2(a, b) (y ~ A sin(k t + phi)) with their standard
    errors by the delta method, the gradients taken numerically (central differences), not from the
    closed forms the package uses."""
    def amp(v):
        return math.hypot(v[0], v[1])

    def phase(v):
        return math.atan2(v[0], v[1])

    out = []
    for f in (amp, phase):
        h = 1e-6
        g = np.array([(f((a + h, b)) - f((a - h, b))) / (2 * h), (f((a, b + h)) - f((a, b - h))) / (2 * h)])
        out.append(math.sqrt(g @ cov @ g))
    return out


@pytest.mark.parametrize("weighted", [False, True])
def test_fit_orders_standard_errors_and_dof_match_statsmodels(weighted):
    rng = np.random.default_rng(11)
    theta, y = _sample(rng)
    w = rng.uniform(0.5, 2.0, theta.size) if weighted else None
    fit = fit_orders(theta, y, ORDERS, weights=w)
    x = _design(theta, ORDERS)
    ref = (sm.WLS(y, x, weights=w) if weighted else sm.OLS(y, x)).fit()
    # residual degrees of freedom and the residual standard error
    assert theta.size - fit.rank == ref.df_resid == theta.size - 7
    assert fit.sigma == pytest.approx(math.sqrt(ref.scale), rel=1e-9)
    np.testing.assert_allclose(fit.cos, ref.params[1::2], rtol=1e-9)
    np.testing.assert_allclose(fit.sin, ref.params[2::2], rtol=1e-9)
    cov = ref.cov_params()
    for i in range(len(ORDERS)):
        j = 1 + 2 * i
        se_amp, se_phase = _delta(ref.params[j], ref.params[j + 1], cov[j:j + 2, j:j + 2])
        assert fit.amplitude_stderr[i] == pytest.approx(se_amp, rel=1e-6)
        assert fit.phase_stderr[i] == pytest.approx(se_phase, rel=1e-6)
        assert fit.phase[i] == pytest.approx(math.atan2(ref.params[j], ref.params[j + 1]), abs=1e-12)


def test_fit_orders_dof_with_extra_columns_and_a_repeated_order():
    """A repeated order and an extra column: rank (not the column count) sets the residual df."""
    rng = np.random.default_rng(5)
    theta, y = _sample(rng, n=40)
    extra = rng.normal(size=theta.size)
    fit = fit_orders(theta, y, (1.0, 2.0, 2.0), design_extra=extra)
    x = np.column_stack([_design(theta, (1.0, 2.0)), extra])
    ref = sm.OLS(y, x).fit()
    assert fit.rank == 6 and fit.columns == 8 and fit.rank_deficient
    assert theta.size - fit.rank == ref.df_resid == 34
    assert fit.sigma == pytest.approx(math.sqrt(ref.scale), rel=1e-9)
    # the repeated order is not identifiable: no standard errors for it
    assert np.isnan(fit.phase_stderr[1:]).all() and np.isfinite(fit.phase_stderr[0])


def test_phase_stderr_is_in_radians_and_scales_as_noise_over_amplitude():
    """Hand derivation: n evenly spaced samples, white noise sigma, one order with amplitude A: var(a) =
    var(b) = 2 sigma^2 / n, so se(phi) = sqrt(2/n) sigma / A [rad] and se(A) = sqrt(2/n) sigma."""
    n, amp, sigma = 360, 4.0, 0.3
    theta = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rng = np.random.default_rng(2)
    noise = rng.normal(0, sigma, n)
    noise -= _design(theta, (3.0,)) @ np.linalg.lstsq(_design(theta, (3.0,)), noise, rcond=None)[0]
    noise *= sigma / math.sqrt(noise @ noise / (n - 3))   # residual standard error exactly sigma
    y = amp * np.sin(3 * theta + 0.4) + noise
    fit = fit_orders(theta, y, (3.0,))
    assert fit.sigma == pytest.approx(sigma, rel=1e-12)
    assert fit.amplitude[0] == pytest.approx(amp, rel=1e-12)
    assert fit.phase[0] == pytest.approx(0.4, abs=1e-12)
    assert fit.amplitude_stderr[0] == pytest.approx(math.sqrt(2 / n) * sigma, rel=1e-9)
    assert fit.phase_stderr[0] == pytest.approx(math.sqrt(2 / n) * sigma / amp, rel=1e-9)


def test_analyse_orders_joint_fit_matches_statsmodels():
    """measure's joint fit: common mode + direction x differential mode, ordinary standard errors."""
    rng = np.random.default_rng(3)
    n = 120
    theta = np.tile(np.linspace(0, 2 * np.pi, n // 2, endpoint=False), 2)
    d = np.repeat([1.0, -1.0], n // 2)
    y = 0.2 + 0.1 * d + 2.0 * np.sin(theta + 0.3) + 0.4 * d * np.cos(2 * theta) + rng.normal(0, 0.2, n)
    res = analyse_orders(theta, y, d, (1.0, 2.0), OrdersOptions(serial=False))
    base = _design(theta, (1.0, 2.0))
    x = np.column_stack([base, d[:, None] * base])
    ref = sm.OLS(y, x).fit()
    assert res.sigma == pytest.approx(math.sqrt(ref.scale), rel=1e-9)   # df = n - 10
    assert ref.df_resid == n - 10
    cov = ref.cov_params()
    for i, item in enumerate(res.items):
        for mode, start in (("common", 0), ("differential", 5)):
            j = start + 1 + 2 * i
            amp, se, phase = getattr(item, mode)
            se_amp, _ = _delta(ref.params[j], ref.params[j + 1], cov[j:j + 2, j:j + 2])
            assert amp == pytest.approx(math.hypot(ref.params[j], ref.params[j + 1]), rel=1e-9)
            assert se == pytest.approx(se_amp, rel=1e-6)
            assert phase == pytest.approx(math.atan2(ref.params[j], ref.params[j + 1]), abs=1e-9)


def _coverage(seeds, n=60, noise=0.5):
    """Fraction of seeds whose 95 % t interval (df = n - 7) holds the true amplitude and phase of each
    order."""
    q = stats.t.ppf(0.975, n - 7)
    true_amp = np.hypot(TRUE_A, TRUE_B)
    true_phase = np.arctan2(TRUE_A, TRUE_B)
    hit_amp = np.zeros(len(ORDERS))
    hit_phase = np.zeros(len(ORDERS))
    for seed in seeds:
        theta, y = _sample(np.random.default_rng(seed), n=n, noise=noise)
        fit = fit_orders(theta, y, ORDERS)
        hit_amp += np.abs(fit.amplitude - true_amp) <= q * fit.amplitude_stderr
        dphi = np.angle(np.exp(1j * (fit.phase - true_phase)))
        hit_phase += np.abs(dphi) <= q * fit.phase_stderr
    return hit_amp / len(seeds), hit_phase / len(seeds)


@pytest.mark.slow
def test_order_amplitude_and_phase_intervals_cover_the_truth_95_percent():
    """2000 data sets (amplitude/noise >= 2 per order, where the delta method is good): each 95 %
    interval holds the truth 93-97 % of the time (binomial sd of the fraction ~0.5 %)."""
    amp, phase = _coverage(range(2000))
    assert np.all((amp > 0.93) & (amp < 0.97)), amp
    assert np.all((phase > 0.93) & (phase < 0.97)), phase


def test_order_phase_interval_coverage_quick():
    """A cheap version of the coverage check (300 seeds): catches a standard error off by a factor
    (e.g. degrees for radians, a missing sigma, A for A^2), not a few per cent."""
    amp, phase = _coverage(range(300))
    assert np.all((amp > 0.89) & (amp < 0.99)), amp
    assert np.all((phase > 0.89) & (phase < 0.99)), phase
