"""The scatter of a measurement about its per-target means: within runs, and between runs.

A test of several runs holds every target and direction (a *cell*) several times.  The
deviations from the cell means split into an offset per run (the table warmed, the
instrument re-zeroed) and the scatter within a run:

    x_cjr = m_c + u_r + e_cjr,    u_r ~ (0, s_run^2),  e ~ (0, s_within^2)

by the method of moments: u_r is the mean deviation of run r's rows from their cell means,
s_within^2 the mean square of what is left (divided by its degrees of freedom, rows - cells -
runs + 1), s_run^2 the variance of the u_r less what the within scatter contributes to them.
An offset common to a run moves every cell mean alike, so it changes none of the ISO 230-2
figures' differences (E, B, M) but does widen the per-cell standard deviations (R, A).
Pure numpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Noise:
    """Result of :func:`noise_components`.

    ``within`` [unit of y squared]: variance of one row about its cell mean
    and run offset (NaN when no cell is repeated); ``between_runs``: variance
    of the run offsets (0 with one run); ``dof``: degrees of freedom of
    ``within``; ``runs``, ``cells``: counts; ``replicated``: some cell holds
    two rows or more.
    """

    within: float
    between_runs: float
    dof: int
    runs: int
    cells: int
    replicated: bool


def noise_components(cell, run, y) -> Noise:
    """The within-run and between-run variances of ``y`` about its cell means.

    Parameters
    ----------
    cell : array_like of int, shape (n,)
        Cell (target and direction) of each row.
    run : array_like of int, shape (n,)
        Run of each row (one value for all rows when runs are not known).
    y : array_like [any unit], shape (n,)
    """
    cell = np.asarray(cell)
    y = np.asarray(y, dtype=float)
    _, ci, counts = np.unique(cell, return_inverse=True, return_counts=True)
    ci = ci.ravel()
    _, ri, run_counts = np.unique(np.asarray(run), return_inverse=True, return_counts=True)
    ri = ri.ravel()
    n, nc, nr = y.shape[0], counts.shape[0], run_counts.shape[0]
    dev = y - (np.bincount(ci, weights=y, minlength=nc) / counts)[ci]
    u = np.bincount(ri, weights=dev, minlength=nr) / run_counts if nr > 1 else np.zeros(1)
    e = dev - u[ri]
    dof = n - nc - (nr - 1)
    within = float(e @ e) / dof if dof > 0 else math.nan
    between = 0.0
    if nr > 1 and math.isfinite(within):
        between = max(0.0, float(np.var(u, ddof=1)) - within / float(np.mean(run_counts)))
    return Noise(within, between, int(dof), int(nr), int(nc), bool(np.any(counts > 1)))
