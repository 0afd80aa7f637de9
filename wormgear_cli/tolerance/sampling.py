"""Truncated distributions and counter-based random streams for the Monte Carlo samples.

Distributions (:data:`DISTRIBUTIONS`) are data: a name, the quantity kinds
they fit, whether a process capability applies, and the truncated inverse
CDF.  Every draw is an inverse-CDF transform of one uniform number, truncated
to the quantity's interval [L, U] (parts out of tolerance are rejected at
inspection, so no value lies beyond its tolerance):

    x = F^-1( F(L) + u (F(U) - F(L)) ),   u ~ U(0, 1)

* ``normal`` (mean mu, standard deviation sigma) on [L, U] with process
  capabilities cp, cpk (ISO 22514-2):  sigma = (U - L) / (6 cp);  the mean is
  shifted from the middle towards the upper (worse) limit so that
  cpk = (U - mu) / (3 sigma):  mu = (L + U)/2 + (U - L)/2 (1 - cpk/cp).
  Defaults cp = cpk = 1: the tolerance at 3 sigma, centred.  Only cpk given:
  cp = cpk (centred).
* ``rayleigh`` on [0, T] (the magnitude of a two-dimensional normal offset
  with sigma per axis): sigma = T / (3 c), c = cpk, else cp, else 1;
  F(x) = 1 - exp(-x^2 / (2 sigma^2)).
* ``uniform`` on [L, U].

Random streams: sample j belongs to block b = j // :data:`BLOCK`; each block
has its own PCG64 generator keyed by ``SeedSequence(seed, spawn_key=(b,))``
and draws a (rows, BLOCK) matrix of uniforms (row-major, so a longer matrix
starts with the same numbers): one row per phase and per column of the drive's
quantities, in the append-only order of its
:class:`~wormgear_cli.tolerance.quantities.Layout` (for the legacy [worm, spur]
train :data:`~wormgear_cli.tolerance.quantities.STREAM_ROWS`, :data:`STREAM_COLUMNS`
rows).  So sample j is the same whatever the block size used for the computation
or the shard it falls in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wormgear_cli.tolerance import quantities
from wormgear_cli.tolerance.distributions import DISTRIBUTIONS, Distribution  # noqa: F401  (re-exported)
from wormgear_cli.tolerance.quantities import PHASES, STREAM_ROWS, Varied

#: samples per random-stream block (fixed: changing it changes every sample)
BLOCK = 65536
#: uniform rows per block: one per phase and per registry column (array keys one per element)
STREAM_COLUMNS = len(STREAM_ROWS)


def sample_values(varied: Varied, u: np.ndarray, element: int = 0) -> np.ndarray:
    """Values [mm] of element ``element`` of a varied quantity from uniforms ``u`` in [0, 1).

    Truncated to the quantity's interval (see the module doc) when it is inspected (the default); an
    uninspected key follows its law's whole range (a magnitude or an allowance never below zero); a
    zero tolerance gives zeros.  Shape of ``u``.
    """
    low, high = varied.bounds(element)
    if high <= low:
        return np.full(np.shape(u), low)
    law = DISTRIBUTIONS[varied.distribution]
    if not varied.inspected and law.whole is not None:
        x = law.whole(u, low, high, varied.cp, varied.cpk)
        return x if low < 0 else np.maximum(x, 0.0)
    x = law.ppf(u, low, high, varied.cp, varied.cpk)
    return np.clip(x, low, high)


def block_uniforms(seed: int, block: int, rows: int | None = None, lo: int = 0, hi: int = BLOCK) -> np.ndarray:
    """The (``rows``, :data:`BLOCK`) uniforms in [0, 1) of block ``block`` (default
    :data:`STREAM_COLUMNS` rows, the legacy train's), columns ``lo:hi`` of it: the same numbers
    as a slice of the whole matrix (the generator skips the others: each number is one 64-bit
    step of PCG64, which ``advance`` jumps in O(log n), so a draw of a few samples does not
    generate the whole block)."""
    ss = np.random.SeedSequence(int(seed), spawn_key=(int(block),))
    bits = np.random.PCG64(ss)
    gen = np.random.Generator(bits)
    rows = STREAM_COLUMNS if rows is None else rows
    if (lo, hi) == (0, BLOCK):
        return gen.random((rows, BLOCK))
    out = np.empty((rows, hi - lo))
    for r in range(rows):  # row r is numbers r BLOCK .. (r + 1) BLOCK - 1 of the stream
        bits.advance(lo if r == 0 else BLOCK - (hi - lo))
        gen.random(out=out[r])
    return out


@dataclass(frozen=True)
class Draw:
    """Samples [start, stop): ``values`` column -> values [mm] (every registry
    column, array keys as ``path[i]``), ``phases`` phase path -> phase [rad]."""

    start: int
    stop: int
    values: dict
    phases: dict


def draw(varied: tuple[Varied, ...], seed: int, start: int, stop: int, layout=None) -> Draw:
    """Draw samples ``start`` .. ``stop - 1`` (whatever blocks they span).  ``layout``: the drive's
    :class:`~wormgear_cli.tolerance.quantities.Layout` (its rows and phases); None: the legacy
    train's (:data:`~wormgear_cli.tolerance.quantities.STREAM_ROWS`, keyed by legacy paths)."""
    first, last = start // BLOCK, (stop - 1) // BLOCK
    parts = []
    for b in range(first, last + 1):
        lo = max(start - b * BLOCK, 0)
        hi = min(stop - b * BLOCK, BLOCK)
        parts.append(block_uniforms(seed, b, None if layout is None else layout.row_count, lo, hi))
    u = parts[0] if len(parts) == 1 else np.concatenate(parts, axis=1)
    # rows in the append-only order of quantities.STREAM_ROWS: growing the registry adds rows at the
    # end and leaves every existing sample unchanged
    if layout is None:
        row, phase_paths = {name: k for k, name in enumerate(quantities.STREAM_ROWS)}, PHASES
    else:
        row, phase_paths = layout.rows, layout.phases
    phases = {p: 2.0 * math.pi * u[row[p]] for p in phase_paths}
    values = {}
    for v in varied:
        for e, col in enumerate(v.quantity.columns()):
            values[col] = sample_values(v, u[row[col]], e)
    return Draw(start, stop, values, phases)
