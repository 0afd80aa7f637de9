"""Which orders the data can tell apart: a separation rule from the design (span, spacing, correlation).

Two orders k1, k2 sampled over an arc of span S [rad] can be told apart only when their sampled
columns differ: over one continuous arc the correlation of exp(i k1 theta) and exp(i k2 theta) is
about |sinc((k1 - k2) S / 2)|, which vanishes at |k1 - k2| S = 2 pi (the Rayleigh limit: orders
closer than 360 deg / span apart are not separated; a 39 deg arc cannot tell 224 from 225).  The
rule used here is measured on the design itself, so that the spacing of the samples, gaps and the
columns held in the fit (offset, trend) count: two orders are *inseparable* when the largest
canonical correlation of their (cos, sin) pairs, after the held columns are projected out, is at
least :data:`SEPARATION_CORR` (0.9: the standard errors of either inflated by 1 / sqrt(1 - 0.81),
2.3 times, or more) *and* they are closer than 360 deg / span apart (on a full turn: less than one
cycle per turn apart).  Orders far apart whose columns correlate are a matter of the spacing of the
samples (aliasing, :func:`~wormgear_cli.measurement.harmonics.alias_groups`, and the determinacy of
:func:`~wormgear_cli.measurement.harmonics.select_orders`), not of the span.  Inseparable orders form
groups (transitively); a group is fitted as one order and reported with the span that would
separate it (360 deg / the smallest spacing of its orders).

Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: largest canonical correlation of two orders' (cos, sin) columns above which they cannot be told apart
SEPARATION_CORR = 0.9


@dataclass(frozen=True)
class SeparationGroup:
    """Orders the data cannot tell apart (:func:`separation_groups`).

    ``orders``: the members, sorted; ``correlation``: the largest canonical
    correlation between two members; ``span_needed_deg``: the span over
    which their columns become orthogonal, 360 / (smallest spacing of the
    members) [deg]."""

    orders: tuple[float, ...]
    correlation: float
    span_needed_deg: float

    def describe(self, span_deg: float) -> str:
        """A sentence naming the members, their correlation and the span that would separate them."""
        names = ", ".join(f"{k:g}" for k in self.orders)
        need = self.span_needed_deg
        what = ("a full turn" if abs(need - 360.0) < 1e-6 else
                f"{need:.4g} deg (more than a full turn)" if need > 360.0 else f"{need:.4g} deg")
        arc = "a full turn" if span_deg >= 360.0 - 1e-9 else f"this {span_deg:.4g} deg arc"
        return (f"orders {names} cannot be told apart on {arc} (closer than 360 deg / span apart; their columns "
                f"correlate {self.correlation:.2f}); a span of at least {what} would separate them")


def canonical_correlations(gram: np.ndarray, first: int, m: int) -> np.ndarray:
    """(m x m) largest canonical correlation between the (cos, sin) pairs of every two orders.

    ``gram``: the Gram matrix of [fixed columns (``first`` of them: offset, trend ...), cos/sin per
    order (m pairs)]; the fixed columns are projected out first (Schur complement).  The diagonal
    is 1.  A pair whose columns vanish after the projection gets correlation 1 with everything."""
    fixed = gram[:first, :first]
    cross = gram[:first, first:first + 2 * m]
    harm = gram[first:first + 2 * m, first:first + 2 * m]
    if first:
        schur = harm - cross.T @ np.linalg.lstsq(fixed, cross, rcond=1e-12)[0]
    else:
        schur = harm
    blocks = schur.reshape(m, 2, m, 2).transpose(0, 2, 1, 3)  # blocks[i, j] = S_ij (2 x 2)
    diag = blocks[np.arange(m), np.arange(m)]  # (m, 2, 2)
    lam, vec = np.linalg.eigh(diag)
    scale = float(np.max(np.abs(harm))) if harm.size else 1.0
    ok = lam[:, 0] > 1e-12 * max(scale, 1e-300)
    inv_sqrt = np.where(ok[:, None, None],
                        (vec / np.sqrt(np.where(ok[:, None], lam, 1.0))[:, None, :]) @ vec.transpose(0, 2, 1), 0.0)
    # whitened cross blocks W_i S_ij W_j; their largest singular value is the canonical correlation
    whitened = inv_sqrt[:, None] @ blocks @ inv_sqrt[None, :]
    corr = np.linalg.svd(whitened, compute_uv=False)[..., 0]
    corr = np.minimum(corr, 1.0)
    bad = ~ok
    corr[bad, :] = 1.0
    corr[:, bad] = 1.0
    np.fill_diagonal(corr, 1.0)
    return corr


def separation_groups(orders, corr: np.ndarray, span: float, full_turn: bool,
                      threshold: float = SEPARATION_CORR) -> list[SeparationGroup]:
    """Groups (two or more members) of ``orders`` [cycles/rev] that cannot be told apart, joined
    transitively: two orders are linked when their canonical correlation (``corr``, from
    :func:`canonical_correlations`) reaches ``threshold`` and they are closer than 2 pi / span
    apart (``span`` [rad]; a full turn counts as 2 pi)."""
    ords = [float(k) for k in orders]
    m = len(ords)
    arc = 2.0 * math.pi if full_turn else float(span)
    ks = np.asarray(ords, dtype=float)
    close = np.abs(ks[:, None] - ks[None, :]) * arc < 2.0 * math.pi * (1.0 - 1e-9)
    parent = list(range(m))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    linked = np.triu((corr >= threshold) & close, 1)
    for i, j in zip(*np.nonzero(linked)):
        ri, rj = find(int(i)), find(int(j))
        if ri != rj:
            parent[max(ri, rj)] = min(ri, rj)
    members: dict[int, list[int]] = {}
    for i in range(m):
        members.setdefault(find(i), []).append(i)
    out = []
    for idx in members.values():
        if len(idx) < 2:
            continue
        idx = sorted(idx, key=lambda i: ords[i])
        sub = corr[np.ix_(idx, idx)].copy()
        np.fill_diagonal(sub, 0.0)
        members_k = np.asarray([ords[i] for i in idx])
        spacing = float(np.min(np.diff(members_k))) if members_k.size > 1 else 0.0
        need = 360.0 / spacing if spacing > 0 else math.inf
        out.append(SeparationGroup(tuple(float(k) for k in members_k), float(np.max(sub)), need))
    return sorted(out, key=lambda g: g.orders)
