"""Row-sized array operations with few temporaries: a measurement of tens of millions of rows is
analysed in memory bounded by a few arrays of its size.

:func:`unique` gives exactly what ``np.unique(x, return_index=..., return_inverse=True,
return_counts=...)`` gives for a 1-D array (the same sorted values, first indices, inverse and
counts, whatever numpy's version), with about half its peak memory: numpy's keeps a sorted copy,
the permutation, a cumulative sum and its copy and the inverse alive at once (about 41 bytes a row
for float64); this one 25, and 16 for whole numbers in a short range (pass and run numbers), which
are counted instead of sorted.  Pure numpy.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: whole numbers whose range is at most this many times the row count (and at most
#: :data:`COUNTED_MAX`) are counted (np.bincount) rather than sorted
COUNTED_SPAN = 4
COUNTED_MAX = 1 << 24


def unique(x, return_index: bool = False, return_inverse: bool = True, return_counts: bool = False):
    """``np.unique(x, return_index, return_inverse, return_counts)`` of a 1-D array, the same arrays.

    Parameters
    ----------
    x : array_like, shape (n,)
        Values (any shape is flattened, as numpy does).
    return_index, return_inverse, return_counts : bool
        As for :func:`numpy.unique`.

    Returns
    -------
    tuple
        (sorted distinct values, [first index of each], [index of each row's value], [count of each]),
        the optional parts as asked for; the inverse is ``np.intp`` of shape (n,).
    """
    x = np.asarray(x).reshape(-1)
    flags: dict[str, Any] = {"return_index": return_index, "return_inverse": return_inverse,
                             "return_counts": return_counts}  # numpy's overloads want literal flags
    if not (return_index or return_inverse) or x.shape[0] == 0:
        whole = np.unique(x, **flags)
        return whole if isinstance(whole, tuple) else (whole,)
    if x.dtype.kind in "ib" or (x.dtype.kind == "u" and x.dtype.itemsize < 8):
        counted = _counted(x, return_index, return_inverse, return_counts)
        if counted is not None:
            return counted
    perm = x.argsort(kind="mergesort" if return_index else "quicksort")
    aux = x[perm]
    if aux.dtype.kind in "cfmM" and np.isnan(aux[-1]):  # NaNs are one value: numpy's own rule
        del perm, aux
        return np.unique(x, **flags)
    mask = np.empty(aux.shape, dtype=bool)
    mask[:1] = True
    np.not_equal(aux[1:], aux[:-1], out=mask[1:])
    out: tuple = (aux[mask],)
    del aux
    if return_index:
        out += (perm[mask],)
    if return_inverse:
        inverse = np.empty(x.shape[0], dtype=np.intp)
        rank = ranks(mask)
        inverse[perm] = rank
        del rank, perm
        out += (inverse,)
    if return_counts:
        out += (np.diff(np.append(np.flatnonzero(mask), mask.shape[0])),)
    return out


def _counted(x: np.ndarray, return_index: bool, return_inverse: bool, return_counts: bool):
    """:func:`unique` of whole numbers in a short range by counting them, or None when the range is long."""
    lo, hi = int(x.min()), int(x.max())
    if hi - lo > min(COUNTED_SPAN * x.shape[0], COUNTED_MAX):
        return None
    shifted = x if lo == 0 and x.dtype.kind != "b" else x.astype(np.int64) - lo
    count = np.bincount(shifted, minlength=hi - lo + 1)
    present = count > 0
    out: tuple = ((np.flatnonzero(present) + lo).astype(x.dtype),)
    inverse = ranks(present)[shifted] if return_index or return_inverse else None
    if return_index:
        assert inverse is not None
        out += (_first_rows(inverse, int(np.count_nonzero(present))),)
    if return_inverse:
        out += (inverse,)
    if return_counts:
        out += (count[present].astype(np.intp),)
    return out


def _first_rows(inverse: np.ndarray, k: int) -> np.ndarray:
    """The first row of each of the ``k`` values of ``inverse`` (every value occurs), a block at a time."""
    first = np.full(k, -1, dtype=np.intp)
    left = k
    for a in range(0, inverse.shape[0], RANK_BLOCK):
        values, at = np.unique(inverse[a:a + RANK_BLOCK], return_index=True)
        new = first[values] < 0
        first[values[new]] = at[new] + a
        left -= int(np.count_nonzero(new))
        if not left:
            break
    return first


#: elements of a bool array summed at a time by :func:`ranks`
RANK_BLOCK = 1 << 16


def ranks(mask: np.ndarray) -> np.ndarray:
    """``np.cumsum(mask) - 1`` as ``np.intp`` (the rank of each True among the Trues), without the
    copy of ``mask`` cast to integers that ``np.cumsum`` makes first: summed a block at a time."""
    out = np.empty(mask.shape[0], dtype=np.intp)
    carry = -1
    for a in range(0, mask.shape[0], RANK_BLOCK):
        part = out[a:a + RANK_BLOCK]
        np.cumsum(mask[a:a + RANK_BLOCK], out=part)
        part += carry
        carry = int(part[-1])
    return out


def non_decreasing(x: np.ndarray) -> bool:
    """Whether ``x`` (N,) never decreases (judged a block at a time, without a copy)."""
    for a in range(0, x.shape[0] - 1, RANK_BLOCK):
        b = min(a + RANK_BLOCK, x.shape[0] - 1)
        if not np.all(x[a + 1:b + 1] >= x[a:b]):
            return False
    return True


def unwrap(p) -> np.ndarray:
    """``np.unwrap(p)`` of a 1-D float array (period 2 pi), the same numbers, computed a block at a
    time: a jump of more than pi between neighbours is taken as a wrap (numpy's rules, including its
    treatment of a jump of exactly pi), and the corrections summed in row order."""
    p = np.asarray(p, dtype=float).reshape(-1)
    period = 2.0 * math.pi
    high = period / 2
    low = -high
    up = np.array(p, copy=True)
    carry = None
    for a in range(1, p.shape[0], RANK_BLOCK):
        b = min(a + RANK_BLOCK, p.shape[0])
        dd = p[a:b] - p[a - 1:b - 1]
        ddmod = np.mod(dd - low, period) + low
        np.copyto(ddmod, high, where=(ddmod == low) & (dd > 0))
        ph = ddmod - dd
        np.copyto(ph, 0, where=abs(dd) < high)
        if carry is not None:  # the running sum of the corrections goes on from the previous block
            ph[0] += carry
        np.cumsum(ph, out=ph)
        carry = ph[-1]
        up[a:b] = p[a:b] + ph
    return up
