"""ISO 230-2:2014 positioning figures of a rotary axis from a measurement.

Definitions (x_ij = actual - target at target i, run j; up = forward,
direction +1; down = reverse, direction -1):

* mean deviation per target and direction: x_i(up) = mean_j x_ij(up), likewise down;
* standard deviation s_i(up) = sqrt(sum_j (x_ij - x_i)^2 / (n - 1)), likewise down;
* reversal B_i = x_i(up) - x_i(down) (negative with lost motion); axis
  reversal B = max_i |B_i|; mean reversal B_mean = mean_i B_i;
* unidirectional repeatability R_i(up) = 4 s_i(up), likewise down;
  bidirectional R_i = max(2 s_i(up) + 2 s_i(down) + |B_i|, R_i(up), R_i(down));
  axis R(up) = max_i R_i(up), R(down), R = max_i R_i;
* systematic deviation E(up) = max_i x_i(up) - min_i x_i(up), likewise down,
  bidirectional E = max over all x_i(up), x_i(down) - min over the same;
* mean bidirectional deviation x_i = (x_i(up) + x_i(down)) / 2, M = max_i x_i - min_i x_i;
* accuracy A(up) = max_i (x_i(up) + 2 s_i(up)) - min_i (x_i(up) - 2 s_i(up)),
  likewise down; bidirectional A = max over both directions of (x + 2 s)
  - min over both directions of (x - 2 s).

Choices where the standard is silent (documented in docs/measure.md):

* Rows belong to the same target when their angles differ by at most
  ``tol`` (default 1e-6 deg) from a neighbour in sorted order; the target
  angle is the mean of its rows.  Angles are not wrapped: 0 deg and 360 deg
  are different targets.
* A target measured in one direction only has NaN for every bidirectional
  figure (B_i, R_i, x_i); it still counts for the unidirectional figures
  and for E and A.  With one direction missing altogether the
  bidirectional A, B, E, M, R are NaN (the unidirectional ones remain).
* s needs two runs: with a single run in a cell s is NaN, and so are the
  figures built on it (R_i, and the axis A and R of every set that
  contains such a cell); E, M and B do not need s and stay defined.
* One target only (a one-position backlash test: many landings from each
  side at one angle): A, E and M compare targets and are NaN (not
  applicable); B and R are that target's reversal and repeatabilities.

All angles in radians.  Pure numpy, no I/O.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

#: default target grouping tolerance [rad] (1e-6 deg)
TARGET_TOL = math.radians(1e-6)
#: a standard deviation at most this [rad] comes from readings that are all equal (1e-12 rad = 2e-7 arcsec)
EQUAL = 1e-12


@dataclass(frozen=True)
class TargetTable:
    """Per-target statistics, arrays of one entry per target (sorted by angle).

    ``target`` [rad]; ``n_up``, ``n_down`` runs per direction; ``mean_up``,
    ``mean_down`` x_i [rad]; ``s_up``, ``s_down`` [rad]; ``mean_bi``
    (x_i(up) + x_i(down)) / 2; ``reversal`` B_i; ``r_up``, ``r_down``, ``r_bi``
    R_i(up), R_i(down), R_i [rad].  NaN where undefined.  ``equal_up``,
    ``equal_down``: the cell has at least two readings and all are equal
    (s = 0 below the resolution of the data).
    """

    target: np.ndarray
    n_up: np.ndarray
    n_down: np.ndarray
    mean_up: np.ndarray
    mean_down: np.ndarray
    s_up: np.ndarray
    s_down: np.ndarray
    mean_bi: np.ndarray
    reversal: np.ndarray
    r_up: np.ndarray
    r_down: np.ndarray
    r_bi: np.ndarray
    equal_up: np.ndarray | None = None
    equal_down: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.target)


@dataclass(frozen=True)
class Iso230Figures:
    """Axis figures [rad] (NaN when undefined, see the module doc).

    ``A``, ``A_up``, ``A_down``: accuracy; ``B``: max |B_i|; ``B_signed``:
    the B_i of largest magnitude with its sign; ``B_mean``: mean B_i
    (signed); ``E``, ``E_up``, ``E_down``: systematic deviation; ``M``: mean
    bidirectional deviation; ``R``, ``R_up``, ``R_down``: repeatability.
    ``targets``: table per target; ``rows``: rows used; ``notes``: plain
    sentences on what was undefined and why; ``below``: names of the axis
    figures (``R_up``, ``R_down``, ``R``) that are zero only because every
    cell they come from has all its readings equal (below the resolution of
    the data, not zero).
    """

    A: float
    A_up: float
    A_down: float
    B: float
    B_signed: float
    B_mean: float
    E: float
    E_up: float
    E_down: float
    M: float
    R: float
    R_up: float
    R_down: float
    targets: TargetTable
    rows: int
    notes: tuple[str, ...]
    below: tuple[str, ...] = ()

    def axis(self) -> dict:
        """Axis figures as name -> value [rad]."""
        return {k: getattr(self, k) for k in ("A", "A_up", "A_down", "B", "B_signed", "B_mean", "E", "E_up",
                                              "E_down", "M", "R", "R_up", "R_down")}


def group_targets(angle: np.ndarray, tol: float = TARGET_TOL, unique=None) -> tuple[np.ndarray, np.ndarray]:
    """Target index per row and the target angles (mean of their rows).

    Rows whose sorted angles are within ``tol`` [rad] of their neighbour
    share a target.  ``unique``: (sorted distinct angles, index of each
    row's angle among them) of ``np.unique(angle, return_inverse=True)``
    when already computed (saves a sort of the rows)."""
    angle = np.asarray(angle, dtype=float)
    if unique is not None:
        ut, inverse = unique
        new = np.empty(ut.shape[0], dtype=bool)
        if ut.shape[0]:
            new[0] = True
            new[1:] = np.diff(ut) > tol
        inverse = np.ravel(inverse)
        # every distinct angle its own target (the usual case): the targets are the distinct angles'
        # indices, so the index is the inverse itself (no second array of the rows' size)
        index = inverse if new.all() else (np.cumsum(new) - 1)[inverse]
        count = np.bincount(index)
        return index, np.bincount(index, weights=angle) / count
    order = np.argsort(angle, kind="stable")
    sorted_angle = angle[order]
    new = np.empty(angle.shape[0], dtype=bool)
    if angle.shape[0]:
        new[0] = True
        new[1:] = np.diff(sorted_angle) > tol
    index_sorted = np.cumsum(new) - 1
    index = np.empty(angle.shape[0], dtype=np.int64)
    index[order] = index_sorted
    count = np.bincount(index)
    target = np.bincount(index, weights=angle) / count
    return index, target


def _cell_stats(values: np.ndarray, index: np.ndarray, ntarget: int):
    """Count, mean and sample standard deviation (n - 1) per target; NaN when undefined."""
    n = np.bincount(index, minlength=ntarget).astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.bincount(index, weights=values, minlength=ntarget) / n
        dev = values - mean[index]
        ss = np.bincount(index, weights=dev * dev, minlength=ntarget)
        s = np.sqrt(ss / (n - 1.0))
    mean[n == 0] = np.nan
    s[n < 2] = np.nan
    return n.astype(int), mean, s


def _span(*arrays) -> float:
    """max - min over the finite entries of the arrays (NaN if none)."""
    vals = np.concatenate([np.ravel(a) for a in arrays])
    vals = vals[np.isfinite(vals)]
    return float(vals.max() - vals.min()) if vals.size else math.nan


def _all_defined(s: np.ndarray, n: np.ndarray) -> bool:
    present = n > 0
    return bool(np.any(present)) and bool(np.all(np.isfinite(s[present])))


def iso230_figures(angle, error, direction, tol: float = TARGET_TOL, grouping=None) -> Iso230Figures:
    """ISO 230-2 figures from rows of ``angle`` [rad], ``error`` [rad]
    (actual - target) and ``direction`` (+1 forward/up, -1 reverse/down).

    See the module doc for the definitions and the choices made where the
    standard is silent.  ``grouping``: (target index per row, target
    angles) of :func:`group_targets` when already computed.  Returns
    :class:`Iso230Figures`."""
    angle = np.asarray(angle, dtype=float)
    error = np.asarray(error, dtype=float)
    direction = np.asarray(direction, dtype=float)
    index, target = group_targets(angle, tol) if grouping is None else grouping
    nt = target.shape[0]
    up = direction > 0
    n_up, mean_up, s_up = _cell_stats(error[up], index[up], nt)
    n_dn, mean_dn, s_dn = _cell_stats(error[~up], index[~up], nt)
    reversal = mean_up - mean_dn
    mean_bi = 0.5 * (mean_up + mean_dn)
    r_up = 4.0 * s_up
    r_dn = 4.0 * s_dn
    r_bi = np.maximum(np.maximum(2.0 * s_up + 2.0 * s_dn + np.abs(reversal), r_up), r_dn)  # NaN propagates
    equal_up, equal_dn = (n_up >= 2) & (s_up <= EQUAL), (n_dn >= 2) & (s_dn <= EQUAL)
    table = TargetTable(target, n_up, n_dn, mean_up, mean_dn, s_up, s_dn, mean_bi, reversal, r_up, r_dn, r_bi,
                        equal_up, equal_dn)

    notes = []
    has_up, has_dn = bool(np.any(n_up > 0)), bool(np.any(n_dn > 0))
    both = (n_up > 0) & (n_dn > 0)
    ok_up = _all_defined(s_up, n_up)
    ok_dn = _all_defined(s_dn, n_dn)
    single = int(np.count_nonzero(n_up == 1) + np.count_nonzero(n_dn == 1))
    if single:
        lacking = [d for d, has, ok in (("forward", has_up, ok_up), ("reverse", has_dn, ok_dn)) if has and not ok]
        notes.append(f"{single} target/direction cell{'s have' if single > 1 else ' has'} a single run: the "
                     "standard deviation is undefined there, so R and A are not given for the "
                     f"{' and '.join(lacking)} direction{'s' if len(lacking) > 1 else ''} nor bidirectionally")
    if not has_dn:
        notes.append("no reverse (direction -1) rows: reversal B, M and the bidirectional figures are undefined")
    elif not has_up:
        notes.append("no forward (direction +1) rows: reversal B, M and the bidirectional figures are undefined")
    elif np.any(both):
        one_way = int(np.count_nonzero(~both))
        if one_way:
            notes.append(f"{one_way} target{'s were' if one_way > 1 else ' was'} measured in one direction only: "
                         "no reversal or bidirectional figures there")
    else:
        notes.append("no target was measured in both directions (different angles per direction?): "
                     "reversal B, M and the bidirectional R are undefined")

    one_target = nt == 1
    if one_target:
        notes.append("one target only (a one-position test): A, E and M compare targets and are not applicable; "
                     "B and R are that target's values")

    def acc(means, ss):
        return _span(*(m + 2.0 * s for m, s in zip(means, ss)), *(m - 2.0 * s for m, s in zip(means, ss)))

    nan = math.nan
    A_up = acc([mean_up], [s_up]) if has_up and ok_up else nan
    A_dn = acc([mean_dn], [s_dn]) if has_dn and ok_dn else nan
    A = acc([mean_up, mean_dn], [s_up, s_dn]) if has_up and has_dn and ok_up and ok_dn else nan
    R_up = float(np.nanmax(r_up)) if has_up and ok_up else nan
    R_dn = float(np.nanmax(r_dn)) if has_dn and ok_dn else nan
    R = float(np.nanmax(r_bi)) if np.any(both) and ok_up and ok_dn else nan
    if np.any(both):
        b = reversal[both]
        k = int(np.argmax(np.abs(b)))
        B, B_signed, B_mean = float(abs(b[k])), float(b[k]), float(np.mean(b))
        M = _span(mean_bi[both])
    else:
        B = B_signed = B_mean = M = nan
    E = _span(mean_up, mean_dn) if has_up and has_dn else nan
    E_up = _span(mean_up) if has_up else nan
    E_dn = _span(mean_dn) if has_dn else nan
    if one_target:
        A = A_up = A_dn = E = E_up = E_dn = M = nan
    below = tuple(k for k, v in (("R_up", R_up), ("R_down", R_dn), ("R", R)) if math.isfinite(v) and v <= 4 * EQUAL)
    return Iso230Figures(
        A=A, A_up=A_up, A_down=A_dn, B=B, B_signed=B_signed, B_mean=B_mean, E=E, E_up=E_up, E_down=E_dn,
        M=M, R=R, R_up=R_up, R_down=R_dn, targets=table, rows=int(angle.shape[0]), notes=tuple(notes), below=below)


def withhold_directional(figures: Iso230Figures, reason: str) -> Iso230Figures:
    """The figures with every one-direction value withheld (NaN), for rows whose directions are mixed.

    Used when the file has no direction column yet a run visits a target
    more than once (an up/down table flattened): the "forward" cells then
    mix both directions, so their s, R, A and E mean nothing.  Axis A, E, R
    (forward, reverse and bidirectional), the per-target s and R are
    withheld; ``reason`` is added to the notes."""
    nan = math.nan
    t = figures.targets
    blank = np.full(len(t), np.nan)
    none = np.zeros(len(t), dtype=bool)
    table = dataclasses.replace(t, s_up=blank, s_down=blank, r_up=blank, r_down=blank, r_bi=blank,
                                mean_up=blank, mean_down=blank, mean_bi=blank, reversal=blank, equal_up=none,
                                equal_down=none)
    return dataclasses.replace(figures, A=nan, A_up=nan, A_down=nan, E=nan, E_up=nan, E_down=nan, R=nan,
                               R_up=nan, R_down=nan, targets=table, notes=figures.notes + (reason,), below=())


def measurement_figures(measurement, tol: float = TARGET_TOL) -> Iso230Figures:
    """:func:`iso230_figures` of a :class:`~wormgear_cli.measurement.reader.Measurement`."""
    return iso230_figures(measurement.angle, measurement.error, measurement.direction, tol)
