"""The resolution of the readings: the step below which the data cannot show a difference.

Readings come in steps: an encoder reports whole counts (a 12-bit encoder: 360 deg / 4096 =
316.4 arcsec per count), an instrument writes a fixed number of digits.  Where every reading of a
cell is the same, its scatter is not zero but below that step, and ISO 230-2's s and R must say so
rather than print 0.00.

:func:`reading_resolution` finds the step of the error readings:

* the digits written: the last decimal every reading has (``1265.625`` and ``-949.219``: 0.001 in
  the file's unit), unknown for readings written to full double precision;
* a grid of counts: the readings at one target differ by whole steps of an encoder with 2^n counts
  per turn (n = 8 .. 24; the coarsest grid that at least :data:`ON_GRID` of the differences sit on,
  at least :data:`MIN_EVIDENCE` of them, the step at least :data:`MIN_STEPS` digits, and the
  distinct differences too many to sit on it by chance, :data:`CHANCE`) -- the target itself need
  not be on the grid (error = actual - target);
* otherwise a grid of the differences' greatest common step, on the same conditions, when it is
  coarser than the digits written and the differences are whole steps of at least two sizes (one
  repeated difference is an offset, such as a reversal, not a grid).

Pure numpy, no I/O.  All angles in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wormgear_cli.units import RAD_PER_UNIT

#: fraction of the non-zero within-target differences that must sit on a grid (a reading that is a
#: mean of several samples may fall between counts)
ON_GRID = 0.8
#: non-zero within-target differences needed to call the readings quantised
MIN_EVIDENCE = 3
#: a grid counts as quantisation only when its step is at least this many of the digits written
MIN_STEPS = 5
#: encoder counts per turn tried: 2^8 .. 2^24
ENCODER_BITS = range(8, 25)
#: largest chance that the distinct differences all sit on an encoder grid by accident ((2 tol / step)
#: per distinct difference), over the grids tried
CHANCE = 1e-4
#: readings looked at (a strided sample beyond this)
SAMPLE = 200_000


@dataclass(frozen=True)
class Resolution:
    """``step`` [rad]: one step of the readings; ``quantised``: they sit on a grid coarser than the
    digits written; ``basis``: how the step was found (a sentence fragment)."""

    step: float
    quantised: bool
    basis: str


def _digits(values: np.ndarray) -> int | None:
    """The decimals every value is written with (0 .. 9), None when they carry more."""
    for k in range(10):
        r = values * 10.0**k
        if np.all(np.abs(r - np.round(r)) <= 1e-6 + 1e-13 * np.abs(r)):
            return k
    return None


def _on_grid(diffs: np.ndarray, step: float, tol: float) -> float:
    """Fraction of ``diffs`` that are whole multiples of ``step`` within ``tol``."""
    q = diffs / step
    return float(np.mean(np.abs(q - np.round(q)) * step <= tol))


def _common_step(diffs: np.ndarray, tol: float) -> float:
    """The greatest step of which the differences are whole multiples within ``tol`` (Euclid on the
    sorted distinct magnitudes)."""
    g = 0.0
    for d in np.unique(np.round(np.abs(diffs) / tol) * tol)[::-1]:
        a, b = max(g, float(d)), min(g, float(d))
        while b > tol:
            a, b = b, math.fmod(a, b)
            if a - b < tol:
                b = 0.0
        g = a
    return g


def within_target_differences(values: np.ndarray, target_index: np.ndarray) -> np.ndarray:
    """Each reading minus the first reading of its target (the non-zero ones)."""
    order = np.argsort(target_index, kind="stable")
    t, v = target_index[order], values[order]
    first = np.ones(t.shape[0], dtype=bool)
    first[1:] = t[1:] != t[:-1]
    ref = v[first][np.cumsum(first) - 1]
    d = v - ref
    return d[d != 0]


def reading_resolution(error, unit: str, target_index) -> Resolution | None:
    """The step of the error readings (see the module doc), or None when it cannot be told.

    Parameters
    ----------
    error : ndarray [rad], shape (n,)
        The readings (actual - target).
    unit : str
        The unit they were written in (a key of :data:`~wormgear_cli.units.RAD_PER_UNIT`).
    target_index : ndarray of int, shape (n,)
        The target of each reading.
    """
    error = np.asarray(error, dtype=float)
    target_index = np.asarray(target_index)
    if error.shape[0] > SAMPLE:  # every stride-th reading (the others are not looked at)
        stride = -(-error.shape[0] // SAMPLE)
        ok = np.zeros(error.shape[0], dtype=bool)
        ok[::stride] = np.isfinite(error[::stride])
    else:
        ok = np.isfinite(error)
    scale = RAD_PER_UNIT[unit]
    values, index = error[ok] / scale, target_index[ok]
    if values.size == 0:
        return None
    k = _digits(values)
    written = None if k is None else 10.0**-k
    # a difference of two readings carries the rounding of both: up to one written digit
    tol = (written if written is not None else 1e-9 * max(1.0, float(np.max(np.abs(values))))) + 1e-9
    diffs = within_target_differences(values, index)
    floor = MIN_STEPS * (written or 0.0)
    if diffs.size >= MIN_EVIDENCE:
        turn = 2.0 * math.pi / scale
        distinct = np.unique(np.round(np.abs(diffs) / tol))  # distinct magnitudes, each a test of the grid
        for bits in ENCODER_BITS:
            step = turn / 2**bits
            if step >= floor and step > 2 * tol and _on_grid(diffs, step, tol) >= ON_GRID \
                    and (2 * tol / step) ** distinct.size <= CHANCE:
                return Resolution(step * scale, True, f"whole counts of an encoder with {2**bits} counts per turn")
        step = _common_step(diffs, tol)
        if step >= max(floor, 2 * tol) and _on_grid(diffs, step, tol) >= ON_GRID:
            mult = np.round(diffs / step)
            if np.unique(mult[mult != 0]).size >= 2:  # whole steps of more than one size: a grid, not one offset
                step = float(np.sum(mult * diffs) / np.sum(mult * mult))  # least squares over every difference
                if written is not None:
                    step = round(step / written) * written
                return Resolution(step * scale, True, "the readings of a target differ by whole steps")
    if written is None:
        return None
    return Resolution(written * scale, False, f"the readings are written to {k} decimal{'s' if k != 1 else ''}")
