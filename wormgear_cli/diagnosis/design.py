"""Column spaces of design matrices: orthonormal bases, projections, how much one block explains another."""

from __future__ import annotations

import math

import numpy as np


def orthonormal(x: np.ndarray, rtol: float = 1e-7, own: bool = False):
    """An orthonormal basis (scaled to unit RMS) of the column space of ``x`` and its rank.

    ``own``: ``x`` is a temporary the caller gives up (e.g. a fresh ``np.hstack``): its
    columns are scaled in place instead of in a copy (the same numbers, one N x k array
    less at the peak of long measurements)."""
    if x.shape[1] == 0:
        return x, 0
    n = x.shape[0]
    norms = np.sqrt(np.sum(x * x, axis=0))
    ok = norms > 0
    if np.all(ok):
        xs = np.divide(x, norms, out=x if own and x.flags.writeable else None)
    else:
        xs = x[:, ok] / norms[ok]
    del x  # (the caller's temporary is released before the SVD)
    u, sv, _ = np.linalg.svd(xs, full_matrices=False)
    del xs
    keep = sv > rtol * sv[0] if sv.size else np.zeros(0, bool)
    # (a copy in the column order the selection gives, whose layout the products downstream follow)
    basis = u[:, keep] * math.sqrt(n)
    return basis, int(np.count_nonzero(keep))


def residualise(basis, cols):
    """cols minus their least-squares projection on an orthonormal (unit-RMS) basis."""
    if basis.shape[1] == 0:
        return cols
    n = basis.shape[0]
    return cols - basis @ (basis.T @ cols) / n


def tolerance(basis, cols):
    """Smallest share of a unit direction in span(cols) that survives projection on the basis."""
    norms = np.sqrt(np.sum(cols * cols, axis=0))
    if np.any(norms == 0):
        return 0.0
    cn = cols / norms
    res = residualise(basis, cn)
    g0 = cn.T @ cn
    g1 = res.T @ res
    # generalised eigenproblem g1 v = lam g0 v: the worst direction inside the column space
    lam0, v0 = np.linalg.eigh(g0)
    if lam0[0] <= 1e-12 * lam0[-1]:
        return 0.0
    w = v0 / np.sqrt(lam0)
    return float(max(np.linalg.eigvalsh(w.T @ g1 @ w)[0], 0.0))


def canonical(a, b):
    """Largest canonical correlation between the column spaces of a and b."""
    return canonical_q(np.linalg.qr(a)[0], np.linalg.qr(b)[0])


def canonical_q(qa, qb):
    """:func:`canonical` from the Q factors of a and b (``np.linalg.qr(a)[0]``), when one block
    is compared with several others."""
    return float(np.linalg.svd(qa.T @ qb, compute_uv=False)[0])


def r2(block, cols):
    """Share of the columns' sum of squares explained by the block (least squares)."""
    if block.shape[1] == 0:
        return 0.0
    coef, *_ = np.linalg.lstsq(block, cols, rcond=None)
    fit = block @ coef
    tot = float(np.sum(cols * cols))
    return float(np.sum(fit * fit) / tot) if tot > 0 else 0.0
