"""Standard errors that hold for serially correlated rows: blocks of consecutive rows (batch means).

Rows of a measurement are taken in time order (``time_s``, or the order of the file) within each
pass.  When the residual of a fit is serially correlated (a guide log's seeing and drift, a dense
scan's slow wander, an ISO 230-2 run's offset) the ordinary least-squares standard errors are too
small: with a lag-1 autocorrelation rho the variance of a slowly varying coefficient grows by
about (1 + rho) / (1 - rho).  The remedy used here is a sandwich covariance whose middle is the
batch-means estimate of the long-run variance of the scores, after AR(1) prewhitening
(Andrews & Monahan 1992, Econometrica 60, 953):

    v_t = e_t - rho e_(t-1)  (within a pass; the first row of a pass e_t sqrt(1 - rho^2)),
    V = c (X'X)^-1 [sum_b U_b U_b'] (X'X)^-1 / (1 - rho)^2,   U_b = sum_{t in block b} x_t v_t,
    c = G / (G - 1) (N - 1) / (N - K)

(G blocks of consecutive rows within a pass, N rows, K columns; the small-sample factor c and the
sandwich are those of Stata and of statsmodels' ``cov_type="cluster"``, :func:`block_covariance`).
The recolouring by 1 / (1 - rho)^2 assumes the columns vary slowly over the noise's correlation
length (orders with many rows per cycle), where it is exact for AR(1) noise; prewhitening removes
most of the downward bias of plain batch means at strong correlation (on AR(1) noise of rho 0.9
the standard errors came out 0.77 of the true scatter without it, 0.88 with it; 0.95 at rho 0.5).
The block length follows Andrews' (1991) AR(1) plug-in rule for the Bartlett kernel applied to the
prewhitened residual, b = 1.1447 (alpha N)^(1/3), alpha = 4 rho^2 / ((1 - rho)^2 (1 + rho)^2),
never longer than a pass.  When the lag-1 autocorrelation is within the noise of white rows
(|rho| sqrt(pairs) < :data:`WHITE_Z`), or negative (ordinary errors are then conservative), the
rows are taken as independent and the ordinary standard errors are kept.

Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wormgear_cli.measurement.arrays import RANK_BLOCK as BLOCK
from wormgear_cli.measurement.arrays import unique as lean_unique

#: |lag-1 autocorrelation| x sqrt(pairs) below which the rows are taken as independent (two-sided 1 %)
WHITE_Z = 2.58
#: the autocorrelation used in the block-length rule is clipped to this (the rule diverges at 1)
MAX_RHO = 0.97
#: fewest blocks for the block covariance; with fewer, the blocks are made shorter to reach it
MIN_BLOCKS = 10


@dataclass(frozen=True)
class SerialBlocks:
    """How the standard errors treat the serial correlation of the rows (:func:`serial_blocks`).

    ``method``: "independent rows" or "blocks"; ``lag1``: pooled lag-1
    autocorrelation of the residual within passes (NaN without pairs);
    ``block_rows``: the longest block [rows] (1 for independent rows);
    ``blocks``: number of blocks G; ``block_id`` (N,) int: the block of
    each row (in the caller's row order; None for independent rows);
    ``rho``: the AR(1) coefficient of the prewhitening (0: none);
    ``order`` / ``first``: the rows in time order and whether each of them
    (in that order) starts a pass; ``in_order``: the rows are in time order
    already (``order`` is 0, 1, 2, ...)."""

    method: str
    lag1: float
    block_rows: int
    blocks: int
    block_id: np.ndarray | None = None
    rho: float = 0.0
    order: np.ndarray | None = None
    first: np.ndarray | None = None
    in_order: bool = False

    @property
    def independent(self) -> bool:
        return self.block_id is None

    def whiten(self, resid) -> np.ndarray:
        """The prewhitened residual v (N,), in the caller's row order (:func:`serial_blocks`)."""
        r = np.asarray(resid, dtype=float).reshape(-1)
        if self.rho == 0.0 or self.order is None:
            return r
        ro = r if self.in_order else r[self.order]
        v = np.empty_like(ro)
        v[1:] = ro[1:] - self.rho * ro[:-1]
        v[0] = ro[0]
        v[self.first] = ro[self.first] * math.sqrt(1.0 - self.rho**2)
        if self.in_order:
            return v
        out = np.empty_like(v)
        out[self.order] = v
        return out

    @property
    def recolour(self) -> float:
        """The factor 1 / (1 - rho)^2 that turns the prewhitened covariance into the covariance."""
        return 1.0 / (1.0 - self.rho) ** 2

    def describe(self) -> str:
        """One phrase for reports."""
        rho = "n/a" if not math.isfinite(self.lag1) else f"{self.lag1:.2f}"
        if self.independent:
            return f"ordinary least squares, rows taken as independent (residual lag-1 autocorrelation {rho})"
        return (f"sandwich over {self.blocks} blocks of up to {self.block_rows} consecutive rows within passes "
                f"after AR(1) prewhitening (batch means; residual lag-1 autocorrelation {rho})")


def _time_order(n: int, passes, time) -> tuple[np.ndarray, np.ndarray, bool]:
    """(row order, pass id of each ordered row, whether the order is the rows' own): by pass (first
    appearance), then time, then file order.  Rows already in that order (passes one after the other,
    time going forward in each) are not sorted."""
    if passes is None:
        rank = np.zeros(n, dtype=np.intp)
    else:
        _, first, inverse = lean_unique(passes, return_index=True)
        rank = np.argsort(np.argsort(first))[inverse]  # passes in the order they appear
        del inverse
    t = None if time is None else np.asarray(time, dtype=float).reshape(-1)
    if _in_time_order(rank, t):
        return np.arange(n), rank, True
    keys = [np.arange(n)]
    if t is not None:
        keys.append(t)
    keys.append(rank)
    order = np.lexsort(tuple(keys))
    return order, rank[order], False


def _in_time_order(rank: np.ndarray, time) -> bool:
    """Whether rows with pass ranks ``rank`` and times ``time`` (or None) are sorted by pass, then time."""
    for a in range(0, rank.shape[0] - 1, BLOCK):
        b = min(a + BLOCK, rank.shape[0] - 1)
        r0, r1 = rank[a:b], rank[a + 1:b + 1]
        ok = r1 >= r0 if time is None else (r1 > r0) | ((r1 == r0) & (time[a + 1:b + 1] >= time[a:b]))
        if not np.all(ok):
            return False
    return True


def _starts(pid: np.ndarray) -> np.ndarray:
    """(N,) bool: whether each row (in time order) starts a pass."""
    new = np.empty(pid.shape[0], dtype=bool)
    new[:1] = True
    np.not_equal(pid[1:], pid[:-1], out=new[1:])
    return new


def lag1_autocorrelation(resid, passes=None, time=None) -> tuple[float, int]:
    """(rho, pairs): the pooled lag-1 autocorrelation of ``resid`` (N,) within passes in time order,
    each pass's mean removed; NaN with fewer than 3 pairs.  Computed with a few arrays of the rows'
    size (the same sums as the plain formula, in the same order)."""
    r = np.asarray(resid, dtype=float).reshape(-1)
    order, pid, in_order = _time_order(r.shape[0], passes, time)
    ro = r if in_order else r[order]
    del order
    new = _starts(pid)
    same = ~new[1:]
    starts = np.flatnonzero(new)
    del new, pid
    counts = np.diff(np.r_[starts, ro.shape[0]])
    means = np.add.reduceat(ro, starts) / counts if starts.size else np.zeros(0)
    dev = np.empty_like(ro)
    for a in range(0, ro.shape[0], BLOCK):  # dev = ro - each row's pass mean
        seg = np.searchsorted(starts, np.arange(a, min(a + BLOCK, ro.shape[0])), side="right") - 1
        np.subtract(ro[a:a + BLOCK], means[seg], out=dev[a:a + BLOCK])
    pairs = int(np.count_nonzero(same))
    den = float(dev @ dev)
    if pairs < 3 or den <= 0:
        return math.nan, pairs
    prod = dev[1:] * dev[:-1]
    del dev
    if pairs < prod.shape[0]:  # keep the pairs within a pass, packed in place in their order
        kept = 0
        for a in range(0, prod.shape[0], BLOCK):
            part = prod[a:a + BLOCK][same[a:a + BLOCK]]
            prod[kept:kept + part.shape[0]] = part
            kept += part.shape[0]
    return float(np.sum(prod[:pairs]) / den), pairs


def andrews_block_length(rho: float, n: int) -> int:
    """Rows per block from Andrews' (1991) AR(1) plug-in bandwidth of the Bartlett kernel:
    1.1447 (alpha n)^(1/3), alpha = 4 rho^2 / ((1 - rho)^2 (1 + rho)^2); at least 1."""
    r = min(max(abs(rho), 0.0), MAX_RHO)
    alpha = 4.0 * r * r / ((1.0 - r) ** 2 * (1.0 + r) ** 2)
    return max(1, int(math.ceil(1.1447 * (alpha * n) ** (1.0 / 3.0))))


def serial_blocks(resid, passes=None, time=None, block_rows: int | None = None) -> SerialBlocks:
    """Blocks of consecutive rows for standard errors that hold under serial correlation.

    Parameters
    ----------
    resid : array_like, shape (N,)
        Residual of the fit [any unit].
    passes : array_like of int, shape (N,), optional
        Pass of each row (a block never spans two passes).
    time : array_like [s], shape (N,), optional
        Time of each row (default: the row order).
    block_rows : int, optional
        Rows per block, without prewhitening (default: :func:`andrews_block_length` of the prewhitened
        residual; white rows are then independent).

    Returns
    -------
    SerialBlocks
    """
    r = np.asarray(resid, dtype=float).reshape(-1)
    n = r.shape[0]
    rho, pairs = lag1_autocorrelation(r, passes, time)
    pre = 0.0
    if block_rows is None and (not math.isfinite(rho) or abs(rho) * math.sqrt(max(pairs, 1)) < WHITE_Z or rho <= 0):
        return SerialBlocks("independent rows", rho, 1, n)
    order, pid, in_order = _time_order(n, passes, time)
    new_pass = _starts(pid)
    del pid
    if block_rows is None:
        pre = min(rho, MAX_RHO)
        probe = SerialBlocks("blocks", rho, 1, n, np.zeros(1, dtype=np.int64), pre, order, new_pass, in_order)
        rho_v, _ = lag1_autocorrelation(probe.whiten(r), passes, time)
        block_rows = andrews_block_length(rho_v if math.isfinite(rho_v) else 0.0, n)
        block_rows = max(1, min(block_rows, n // MIN_BLOCKS))
    ordered_id = _block_numbers(new_pass, block_rows)
    if in_order:
        block_id = ordered_id
    else:
        block_id = np.empty(n, dtype=np.int64)
        block_id[order] = ordered_id
    blocks = int(ordered_id[-1]) + 1 if n else 0
    longest = int(np.max(np.bincount(ordered_id))) if n else 0
    return SerialBlocks("blocks", rho, longest, blocks, block_id, pre, order, new_pass, in_order)


def _block_numbers(new_pass: np.ndarray, block_rows: int) -> np.ndarray:
    """(N,) int64: the block of each row in time order: a new block at the start of each pass and every
    ``block_rows`` rows into it (counted a block of rows at a time)."""
    n = new_pass.shape[0]
    out = np.empty(n, dtype=np.int64)
    start, carry = 0, -1
    for a in range(0, n, BLOCK):
        b = min(a + BLOCK, n)
        at = np.arange(a, b)
        pass_start = np.maximum.accumulate(np.where(new_pass[a:b], at, start))
        start = int(pass_start[-1])
        new_block = new_pass[a:b] | ((at - pass_start) % block_rows == 0)
        part = out[a:b]
        np.cumsum(new_block, out=part)
        part += carry
        carry = int(part[-1])
    return out


def block_covariance(gram_inv: np.ndarray, score_sums: np.ndarray, n: int) -> np.ndarray:
    """The cluster (sandwich) covariance c (X'X)^-1 [sum_b U_b U_b'] (X'X)^-1 of least-squares
    coefficients from the inverse Gram matrix (K x K) and the per-block score sums U (G x K),
    c = G / (G - 1) (N - 1) / (N - K).  Equal to statsmodels' ``OLS.fit(cov_type="cluster")``."""
    g, k = score_sums.shape
    meat = score_sums.T @ score_sums
    c = (g / (g - 1.0) if g > 1 else 1.0) * ((n - 1.0) / (n - k) if n > k else 1.0)
    return c * (gram_inv @ meat @ gram_inv)


def point_noise(resid, passes=None, time=None) -> float:
    """Point-to-point noise [unit of ``resid``]: the robust standard deviation (1.4826 x median absolute
    value) of the differences of consecutive rows within a pass (in time order), over sqrt(2).  Offsets
    per pass cancel; structure that changes slowly along a pass adds little.  NaN with fewer than 3 pairs."""
    r = np.asarray(resid, dtype=float).reshape(-1)
    n = r.shape[0]
    pid = np.zeros(n, dtype=np.int64) if passes is None else np.asarray(passes).reshape(-1)
    t = None if time is None else np.asarray(time, dtype=float).reshape(-1)
    if _in_time_order(pid, t):  # the rows in order already: the differences packed in place, no sort
        diff = np.diff(r)
        kept = 0
        for a in range(0, diff.shape[0], BLOCK):
            b = min(a + BLOCK, diff.shape[0])
            part = diff[a:b][pid[a + 1:b + 1] == pid[a:b]]
            diff[kept:kept + part.shape[0]] = part
            kept += part.shape[0]
        diff = diff[:kept]
    else:
        order = np.lexsort((np.arange(n), np.arange(n, dtype=float) if t is None else t, pid))
        p = pid[order]
        diff = np.diff(r[order])[p[1:] == p[:-1]]
    if diff.shape[0] < 3:
        return math.nan
    np.abs(diff, out=diff)
    return float(1.4826 * np.median(diff, overwrite_input=True) / math.sqrt(2.0))
