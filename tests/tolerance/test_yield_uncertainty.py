"""tolerance's yield interval and percentiles, two ways: against an independent computation
(Clopper-Pearson from beta quantiles written here, scipy's binomtest, numpy's percentile) and by
simulated coverage over seeds."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from wormgear_cli.tolerance.statistics import PERCENTILES, OrderStatistics, binomial_yield, describe


def _clopper_pearson(k, n, level):
    """Clopper & Pearson (1934) from the beta distribution: low = B(alpha/2; k, n-k+1),
    high = B(1-alpha/2; k+1, n-k), with 0 and 1 at the ends."""
    alpha = 1 - level
    low = 0.0 if k == 0 else stats.beta.ppf(alpha / 2, k, n - k + 1)
    high = 1.0 if k == n else stats.beta.ppf(1 - alpha / 2, k + 1, n - k)
    return low, high


@pytest.mark.parametrize("k,n", [(0, 7), (1, 20), (37, 40), (990, 1000), (4999, 5000), (123, 456)])
@pytest.mark.parametrize("level", [0.95, 0.99, 0.80])
def test_yield_interval_is_clopper_pearson(k, n, level):
    y = binomial_yield(k, n, level)
    low, high = _clopper_pearson(k, n, level)
    assert y.value == k / n and y.k == k and y.n == n and y.level == level
    assert y.low == pytest.approx(low, abs=1e-9)
    assert y.high == pytest.approx(high, abs=1e-9)
    ci = stats.binomtest(k, n).proportion_ci(confidence_level=level, method="exact")
    assert (y.low, y.high) == pytest.approx((ci.low, ci.high), abs=1e-12)


def test_yield_interval_hand_values():
    """k = 0 and k = n by hand: (alpha/2)^(1/n) is the one-sided bound; 0 of 10 at 95 %:
    high = 1 - 0.025^(1/10) = 0.30850; 10 of 10: low = 0.025^(1/10) = 0.69150."""
    assert binomial_yield(0, 10).high == pytest.approx(0.30850, abs=5e-6)
    assert binomial_yield(10, 10).low == pytest.approx(0.69150, abs=5e-6)


def _yield_coverage(p, n, seeds):
    rng = np.random.default_rng(seeds)
    ks = rng.binomial(n, p, size=4000)
    values, counts = np.unique(ks, return_counts=True)   # one interval per distinct count
    hits = sum(int(c) for k, c in zip(values, counts) if (y := binomial_yield(int(k), n)).low <= p <= y.high)
    return hits / ks.size


def test_yield_interval_covers_the_true_yield_quick():
    """Clopper-Pearson is conservative: coverage >= 95 % (here over 4000 simulated runs, sd 0.35 %),
    and a 90 % interval mistaken for 95 % would fall to ~90 %."""
    assert _yield_coverage(0.97, 200, 1) >= 0.94


@pytest.mark.parametrize("p,n", [(0.5, 30), (0.9, 100), (0.99, 500), (0.999, 2000)])
def test_yield_interval_covers_the_true_yield(p, n):
    cov = _yield_coverage(p, n, 2)
    assert 0.94 <= cov <= 0.995, cov


@pytest.mark.parametrize("n", [1, 2, 3, 10, 101, 1000, 12345])
def test_percentiles_match_numpy_linear(n):
    """Hyndman & Fan type 7 (numpy's default 'linear') at each reported percentile, on values with
    ties and negative numbers."""
    rng = np.random.default_rng(n)
    v = np.round(rng.normal(0, 3, n), 1)
    got = describe(v)["percentiles"]
    for key in PERCENTILES:
        want = v.max() if key == "max" else np.percentile(v, float(key))
        assert got[key] == pytest.approx(want, abs=1e-12), key


def test_percentiles_second_pass_match_numpy(monkeypatch):
    """The bounded-memory path (histogram, then a second pass) gives numpy's values too."""
    import wormgear_cli.tolerance.statistics as st

    monkeypatch.setattr(st, "IN_MEMORY_SAMPLES", 1000)
    rng = np.random.default_rng(8)
    blocks = [rng.gamma(2.0, 1.0, 700) - 1.0 for _ in range(5)]
    o = OrderStatistics()
    for b in blocks:
        o.add(b)
    assert o.needs_second_pass
    o.start_second_pass()
    for b in blocks:
        o.collect(b)
    got = o.percentiles()
    v = np.concatenate(blocks)
    for key in PERCENTILES:
        want = v.max() if key == "max" else np.percentile(v, float(key))
        assert got[key] == pytest.approx(want, abs=1e-12), key
