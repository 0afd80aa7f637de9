"""Angles along the arc a measurement covers, for the x axis of a plot.

A partial turn that passes through 0 deg (targets 330 .. 359 and 0 .. 30 deg) is one arc of 60
deg, not two ends of a 360 deg axis with a line drawn across the empty 300 deg: its angles are
made continuous (-30 .. 30 deg).  Lines are broken where the samples leave a gap much wider than
their spacing, so no line crosses an arc that was not measured.  Pure numpy (no matplotlib here).
"""

from __future__ import annotations

import math

import numpy as np

from wormgear_cli.measurement.coverage import coverage

#: a gap between neighbouring plotted angles wider than this many median spacings breaks the line
GAP_BREAK = 4.0


def arc_degrees(theta, of=None) -> tuple[np.ndarray, bool]:
    """(angles [deg] along the covered arc, whether they were moved to make it continuous).

    ``theta`` [rad], shape (n,); ``of`` [rad]: the angles whose coverage decides (default
    ``theta``; e.g. the targets, when ``theta`` are all the rows).  A full turn, or an arc that does
    not pass through 0 deg, keeps its angles as written; an arc through 0 deg gets angles from its
    start (after the largest gap) onward, the part before 0 negative."""
    deg = np.degrees(np.asarray(theta, dtype=float))
    ref = np.asarray(theta if of is None else of, dtype=float)
    if ref.size < 2:
        return deg, False
    cov = coverage(ref)
    if cov.full_turn:
        return deg, False
    ref_deg = np.degrees(ref)
    start = math.degrees(cov.start)
    through_zero = start + math.degrees(cov.span) > 360.0 + 1e-9
    if not through_zero and float(ref_deg.min()) >= 0.0 and float(ref_deg.max()) < 360.0:
        return deg, False  # a plain arc, written as the arc runs: as written
    along = start + np.mod(deg - start, 360.0)
    if through_zero and start > 180.0:
        along = along - 360.0
    return along, not np.allclose(along, deg)


def gap_breaks(x, *ys) -> tuple[np.ndarray, ...]:
    """``x`` (sorted) and ``ys`` with a NaN inserted wherever ``x`` jumps by more than
    :data:`GAP_BREAK` median spacings, so a line drawn through them stops at the gap."""
    x = np.asarray(x, dtype=float)
    if x.size < 3:
        return (x, *(np.asarray(y, dtype=float) for y in ys))
    step = np.diff(x)
    typical = float(np.median(step[step > 0])) if np.any(step > 0) else 0.0
    cut = np.flatnonzero(step > GAP_BREAK * typical) + 1 if typical > 0 else np.empty(0, dtype=int)
    if cut.size == 0:
        return (x, *(np.asarray(y, dtype=float) for y in ys))
    return tuple(np.insert(np.asarray(a, dtype=float), cut, np.nan) for a in (x, *ys))
