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


#: most samples whose metric values are kept in memory for the percentiles; beyond it the
#: percentiles come from a second pass over the samples (:class:`OrderStatistics`)
IN_MEMORY_SAMPLES = 4_000_000
#: top bits of the order-preserving float key that index the histogram of the second pass
_KEY_BITS = 20


def _ranks(n: int) -> list[tuple[str, int, int, float]]:
    """(key, lower rank, upper rank, fraction) of each percentile: linear interpolation between
    order statistics at h = (n - 1) q / 100 (Hyndman & Fan type 7, numpy's default)."""
    out = []
    for p in PERCENTILES:
        if p == "max":
            out.append((p, n - 1, n - 1, 0.0))
            continue
        h = (n - 1) * float(p) / 100.0
        lo = math.floor(h)
        out.append((p, lo, min(lo + 1, n - 1), h - lo))
    return out


def _order_key(y: np.ndarray) -> np.ndarray:
    """The histogram bin of each value: the top bits of an order-preserving uint64 image of the float."""
    b = np.ascontiguousarray(y, dtype=np.float64).view(np.uint64)
    neg = (b >> np.uint64(63)).astype(bool)
    key = np.where(neg, ~b, b | np.uint64(1 << 63))
    return (key >> np.uint64(64 - _KEY_BITS)).astype(np.int64)


class OrderStatistics:
    """Exact percentiles of a stream of values with bounded memory.

    Up to :data:`IN_MEMORY_SAMPLES` values are kept; beyond, only a histogram over
    the top bits of an order-preserving image of the floats (2^20 bins, 8 MB), and
    :meth:`percentiles` asks for a second pass (``replay``) that collects only the
    values in the bins holding the needed order statistics.  Both ways give the
    same numbers: the order statistics, then linear interpolation (:func:`_ranks`).
    """

    def __init__(self):
        self.parts: list | None = []
        self.hist: np.ndarray | None = None
        self.n = 0

    def add(self, y: np.ndarray) -> None:
        y = np.ascontiguousarray(y, dtype=float)  # the blocks' arrays are fresh: kept without a copy
        self.n += y.size
        if self.parts is not None:
            self.parts.append(y)
            if self.n > IN_MEMORY_SAMPLES:
                self.hist = np.zeros(1 << _KEY_BITS, np.int64)
                for part in self.parts:
                    self.hist += np.bincount(_order_key(part), minlength=1 << _KEY_BITS)
                self.parts = None
        else:
            assert self.hist is not None  # (the parts went into the histogram)
            self.hist += np.bincount(_order_key(y), minlength=1 << _KEY_BITS)

    @property
    def needs_second_pass(self) -> bool:
        return self.parts is None

    def _wanted(self):
        ranks = _ranks(self.n)
        return ranks, sorted({r for _, lo, hi, _ in ranks for r in (lo, hi)})

    def start_second_pass(self) -> None:
        """Prepare :meth:`collect`: the histogram bins that hold the needed order statistics."""
        _, wanted = self._wanted()
        assert self.hist is not None  # (a second pass is needed: the parts went into the histogram)
        self.cum = np.cumsum(self.hist)
        self.rank_bin = {r: int(np.searchsorted(self.cum, r, side="right")) for r in wanted}
        self.keep = np.array(sorted(set(self.rank_bin.values())), dtype=np.int64)
        self.got: list[np.ndarray] = []

    def collect(self, y: np.ndarray) -> None:
        """Second pass: keep the values that fall in the needed bins (same values, same order as the first)."""
        y = np.asarray(y, dtype=float)
        self.got.append(y[np.isin(_order_key(y), self.keep)])

    def percentiles(self) -> dict:
        """``{"50": .., ..., "max": ..}`` (after the second pass when :attr:`needs_second_pass`)."""
        ranks, wanted = self._wanted()
        if self.parts is not None:
            a = np.concatenate(self.parts) if len(self.parts) != 1 else self.parts[0]
            part = np.partition(a, wanted)
            stat = {r: float(part[r]) for r in wanted}
        else:
            vals = np.sort(np.concatenate(self.got))
            keys = _order_key(vals)
            stat = {}
            for r, b in self.rank_bin.items():
                before = int(self.cum[b - 1]) if b > 0 else 0
                stat[r] = float(vals[np.searchsorted(keys, b, side="left") + (r - before)])
        return {p: (stat[lo] if frac == 0.0 else stat[lo] + frac * (stat[hi] - stat[lo])) for p, lo, hi, frac in ranks}


class Moments:
    """Streaming count, mean, sample standard deviation and maximum; sums taken about a
    reference ``centre`` (any value near the data, e.g. the corner case) against cancellation."""

    def __init__(self, centre: float = 0.0):
        self.c, self.n, self.s1, self.s2 = float(centre), 0, 0.0, 0.0

    def add(self, y: np.ndarray) -> None:
        d = np.asarray(y, dtype=float) - self.c
        self.n += d.size
        self.s1 += float(np.sum(d))
        self.s2 += float(np.dot(d, d))

    @property
    def mean(self) -> float:
        return self.c + self.s1 / self.n

    @property
    def sst(self) -> float:
        """Sum of squared deviations from the mean."""
        return max(self.s2 - self.s1 * self.s1 / self.n, 0.0)

    @property
    def std(self) -> float | None:
        return math.sqrt(self.sst / (self.n - 1)) if self.n > 1 else None


def describe(values: np.ndarray) -> dict:
    """``mean``, ``std`` (sample, n - 1; None for one sample) and ``percentiles`` of ``values``
    (one array; the run uses :class:`Moments` and :class:`OrderStatistics` block by block)."""
    v = np.asarray(values, dtype=float)
    m, o = Moments(float(v[0])), OrderStatistics()
    m.add(v)
    o.add(v)
    return {"mean": m.mean, "std": m.std, "percentiles": o.percentiles()}


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
    # lazy: scipy.stats is slow to import (a large part of a second); only this path needs it
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


class BinSums:
    """Streaming sums for the first-order indices: per varied column, the count of samples in
    each equal-width bin and, per metric, the sum of (y - centre) in each bin."""

    def __init__(self, columns, metrics, nbins: int = SENSITIVITY_BINS):
        self.nbins = nbins
        self.counts = {c: np.zeros(nbins) for c in columns}
        self.sums = {m: {c: np.zeros(nbins) for c in columns} for m in metrics}

    def add(self, bins: dict, deviations: dict) -> None:
        """``bins``: column -> bin index per sample; ``deviations``: metric -> y - centre per sample."""
        for c, idx in bins.items():
            self.counts[c] += np.bincount(idx, minlength=self.nbins)
            for m, d in deviations.items():
                self.sums[m][c] += np.bincount(idx, weights=d, minlength=self.nbins)

    def indices(self, metric: str, moments: Moments) -> tuple[dict[str, float], float] | None:
        """First-order sensitivity indices S_k = Var(E[Y | X_k]) / Var(Y) of ``metric``.

        One-way analysis of variance per column (bins of equal width over the
        column's interval), the between-bin sum of squares corrected for its
        expected noise (omega-squared form; Saltelli et al., Global Sensitivity
        Analysis, 2008, 1.2.10, S_i as the variance of the conditional mean):

            S_k = max(0, (SSB_k - (B_k - 1) MSW_k) / SST),  MSW_k = (SST - SSB_k) / (n - B_k)

        with B_k the occupied bins.  For independent inputs the true indices sum
        to at most 1; estimates summing above 1 are scaled down to sum to 1.
        Returns (column -> S_k, remainder 1 - sum) or None when Y does not vary.
        """
        n, sst = moments.n, moments.sst
        if n < 3 or not sst > 0.0:
            return None
        mean_dev = moments.s1 / n
        out = {}
        for c, cnt in self.counts.items():
            sums = self.sums[metric][c]
            occ = cnt > 0
            b = int(np.count_nonzero(occ))
            if b < 2 or n <= b:
                out[c] = 0.0
                continue
            ssb = max(float(np.sum(sums[occ] ** 2 / cnt[occ])) - n * mean_dev * mean_dev, 0.0)
            msw = max(sst - ssb, 0.0) / (n - b)
            out[c] = max(0.0, (ssb - (b - 1) * msw) / sst)
        total = math.fsum(out.values())
        if total > 1.0:
            out = {k: v / total for k, v in out.items()}
            total = 1.0
        return out, max(0.0, 1.0 - total)


def first_order_indices(bins: dict[str, np.ndarray], y: np.ndarray,
                        nbins: int = SENSITIVITY_BINS) -> tuple[dict[str, float], float] | None:
    """:meth:`BinSums.indices` of one metric ``y`` from its bin indices (all samples at once)."""
    y = np.asarray(y, dtype=float)
    m = Moments(float(np.mean(y)))
    m.add(y)
    sums = BinSums(list(bins), ["y"], nbins)
    sums.add(bins, {"y": y - m.c})
    return sums.indices("y", m)
