"""Statistics of the Monte Carlo samples: percentiles, yield intervals, sensitivity indices.

Pure numpy; scipy (binomial interval) imported lazily.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: percentile keys of the report, in order ("max" is the largest sample)
PERCENTILES = ("50", "90", "95", "99", "99.73", "max")
#: equal-width bins per varied column for the sensitivity indices
SENSITIVITY_BINS = 50


def describe(values: np.ndarray) -> dict:
    """``mean``, ``std`` (sample, n - 1; None for one sample) and ``percentiles`` of ``values``.

    Percentiles by linear interpolation between order statistics (numpy's
    default, Hyndman & Fan type 7).  Shape (n,) in, plain floats out.
    """
    v = np.asarray(values, dtype=float)
    q = np.percentile(v, [float(p) for p in PERCENTILES[:-1]])
    return {
        "mean": float(np.mean(v)),
        "std": float(np.std(v, ddof=1)) if v.size > 1 else None,
        "percentiles": {**{p: float(x) for p, x in zip(PERCENTILES[:-1], q)}, "max": float(np.max(v))},
    }


@dataclass(frozen=True)
class Yield:
    """Fraction ``value`` of ``n`` samples passing (``k`` of them) and its two-sided
    binomial ``level`` interval [``low``, ``high``] (Clopper-Pearson, exact)."""

    k: int
    n: int
    value: float
    low: float
    high: float
    level: float = 0.95

    def verdict(self, target: float) -> str:
        """"pass" (low >= target), "fail" (high < target) or "undecided" (the interval straddles it)."""
        if self.low >= target:
            return "pass"
        if self.high < target:
            return "fail"
        return "undecided"


def binomial_yield(k: int, n: int, level: float = 0.95) -> Yield:
    """Yield k/n with its Clopper-Pearson interval (``scipy.stats.binomtest``)."""
    from scipy.stats import binomtest

    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=level, method="exact")
    return Yield(int(k), int(n), k / n, float(ci.low), float(ci.high), level)


def bin_index(values: np.ndarray, low: float, high: float, bins: int = SENSITIVITY_BINS) -> np.ndarray:
    """Equal-width bin (0 .. bins-1) of each value on [low, high] (uint8)."""
    v = np.asarray(values, dtype=float)
    if not high > low:
        return np.zeros(v.shape, np.uint8)
    idx = np.floor((v - low) * (bins / (high - low)))
    return np.clip(idx, 0, bins - 1).astype(np.uint8)


def first_order_indices(bins: dict[str, np.ndarray], y: np.ndarray,
                        nbins: int = SENSITIVITY_BINS) -> tuple[dict[str, float], float] | None:
    """First-order sensitivity indices S_k = Var(E[Y | X_k]) / Var(Y) from samples.

    ``bins``: column -> bin index of each sample (:func:`bin_index`); ``y``: the
    metric per sample.  Estimator: one-way analysis of variance per column,
    the between-bin sum of squares corrected for its expected noise
    (omega-squared form; Saltelli et al., Global Sensitivity Analysis, 2008,
    section 1.2.10 on S_i as the variance of the conditional mean):

        S_k = max(0, (SSB_k - (B_k - 1) MSW_k) / SST),  MSW_k = (SST - SSB_k) / (n - B_k)

    with B_k the occupied bins.  For independent inputs the true indices sum
    to at most 1; estimates summing above 1 are scaled down to sum to 1.
    Returns (column -> S_k, remainder 1 - sum) or None when Y does not vary.
    """
    y = np.asarray(y, dtype=float)
    n = y.size
    mean = float(np.mean(y))
    dev = y - mean
    sst = float(np.dot(dev, dev))
    if n < 3 or not sst > 0.0:
        return None
    out = {}
    for name, idx in bins.items():
        cnt = np.bincount(idx, minlength=nbins).astype(float)
        sums = np.bincount(idx, weights=dev, minlength=nbins)
        occ = cnt > 0
        b = int(np.count_nonzero(occ))
        ssb = float(np.sum(sums[occ] ** 2 / cnt[occ]))
        if b < 2 or n <= b:
            out[name] = 0.0
            continue
        msw = max(sst - ssb, 0.0) / (n - b)
        out[name] = max(0.0, (ssb - (b - 1) * msw) / sst)
    total = math.fsum(out.values())
    if total > 1.0:
        out = {k: v / total for k, v in out.items()}
        total = 1.0
    return out, max(0.0, 1.0 - total)
