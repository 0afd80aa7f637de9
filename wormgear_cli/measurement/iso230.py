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
    """Count per target (T,), and mean and sample standard deviation (n - 1) per target (R, T) of each row of
    ``values`` (R, m) (rows of errors on the same m readings); NaN when undefined.  Each row's sums are
    those of a bincount of that row alone, in the same order (the same numbers)."""
    count = values.shape[0]
    n = np.bincount(index, minlength=ntarget).astype(float)
    cell = (np.arange(count)[:, None] * ntarget + index).ravel()  # (row, target) as one bin
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.bincount(cell, weights=values.ravel(), minlength=count * ntarget).reshape(count, ntarget) / n
        dev = values - mean[:, index]
        ss = np.bincount(cell, weights=(dev * dev).ravel(), minlength=count * ntarget).reshape(count, ntarget)
        s = np.sqrt(ss / (n - 1.0))
    mean[:, n == 0] = np.nan
    s[:, n < 2] = np.nan
    return n.astype(int), mean, s


def _span(*arrays) -> np.ndarray:
    """max - min over the finite entries of each row of the arrays (R, .) joined (NaN for a row of none)."""
    vals = np.concatenate(arrays, axis=1)
    finite = np.isfinite(vals)
    high = np.where(finite, vals, -np.inf).max(axis=1, initial=-np.inf)
    low = np.where(finite, vals, np.inf).min(axis=1, initial=np.inf)
    return np.where(finite.any(axis=1), high - low, np.nan)


def _largest(values: np.ndarray) -> np.ndarray:
    """max over the non-NaN entries of each row (R, T) (-inf for a row of none)."""
    return np.where(np.isnan(values), -np.inf, values).max(axis=1, initial=-np.inf)


def _all_defined(s: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Per row of ``s`` (R, T): some target has readings and every such target's s is defined."""
    present = n > 0
    return bool(np.any(present)) & np.all(np.isfinite(s[:, present]), axis=1)


@dataclass(frozen=True)
class _Cells:
    """Per target (R, T) and axis (R,) figures of R rows of errors on the same readings, with what
    decides which are defined."""

    mean_bi: np.ndarray
    reversal: np.ndarray
    r_up: np.ndarray
    r_dn: np.ndarray
    r_bi: np.ndarray
    axis: dict
    has_up: bool
    has_dn: bool
    both: np.ndarray
    ok_up: np.ndarray
    ok_dn: np.ndarray


def _figures(n_up, mean_up, s_up, n_dn, mean_dn, s_dn) -> _Cells:
    """The per-target and axis figures (module doc) from the cells' counts (T,), means and standard
    deviations (R, T), NaN where undefined."""
    reversal = mean_up - mean_dn
    mean_bi = 0.5 * (mean_up + mean_dn)
    r_up = 4.0 * s_up
    r_dn = 4.0 * s_dn
    r_bi = np.maximum(np.maximum(2.0 * s_up + 2.0 * s_dn + np.abs(reversal), r_up), r_dn)  # NaN propagates
    has_up, has_dn = bool(np.any(n_up > 0)), bool(np.any(n_dn > 0))
    both = (n_up > 0) & (n_dn > 0)
    ok_up = _all_defined(s_up, n_up)
    ok_dn = _all_defined(s_dn, n_dn)

    def acc(means, ss):
        return _span(*(m + 2.0 * s for m, s in zip(means, ss)), *(m - 2.0 * s for m, s in zip(means, ss)))

    nan = np.full(mean_up.shape[0], math.nan)
    fig = {"A_up": np.where(has_up & ok_up, acc([mean_up], [s_up]), nan),
           "A_down": np.where(has_dn & ok_dn, acc([mean_dn], [s_dn]), nan),
           "A": np.where(has_up & has_dn & ok_up & ok_dn, acc([mean_up, mean_dn], [s_up, s_dn]), nan),
           "R_up": np.where(has_up & ok_up, _largest(r_up), nan),
           "R_down": np.where(has_dn & ok_dn, _largest(r_dn), nan),
           "R": np.where(bool(np.any(both)) & ok_up & ok_dn, _largest(r_bi), nan)}
    if np.any(both):
        b = reversal[:, both]
        signed = np.take_along_axis(b, np.argmax(np.abs(b), axis=1)[:, None], axis=1)[:, 0]
        B, B_signed, B_mean = np.abs(signed), signed, np.mean(b, axis=1)
        M = _span(mean_bi[:, both])
    else:
        B = B_signed = B_mean = M = nan
    fig.update(B=B, B_signed=B_signed, B_mean=B_mean, M=M,
               E=_span(mean_up, mean_dn) if has_up and has_dn else nan,
               E_up=_span(mean_up) if has_up else nan,
               E_down=_span(mean_dn) if has_dn else nan)
    if mean_up.shape[1] == 1:  # one target: A, E and M compare targets
        fig.update(dict.fromkeys(("A", "A_up", "A_down", "E", "E_up", "E_down", "M"), nan))
    return _Cells(mean_bi, reversal, r_up, r_dn, r_bi, fig, has_up, has_dn, both, ok_up, ok_dn)


def axis_figures(errors, direction, grouping) -> dict[str, np.ndarray]:
    """The axis figures of :func:`iso230_figures` (name -> (R,) [rad], NaN when undefined) of R rows of
    errors ``errors`` (R, n) [rad] on the same readings: ``direction`` (n,) and ``grouping`` (target index
    per reading, target angles) of :func:`group_targets`.  Row r's figures are, to the bit, those of
    ``iso230_figures`` of ``errors[r]`` (the simulated repeat tests of a correction table evaluate
    hundreds of them at once)."""
    errors = np.asarray(errors, dtype=float)
    up = np.asarray(direction, dtype=float) > 0
    index, target = grouping
    nt = target.shape[0]
    return _figures(*_cell_stats(errors[:, up], index[up], nt), *_cell_stats(errors[:, ~up], index[~up], nt)).axis


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
    n_up, mean_up, s_up = _cell_stats(error[None, up], index[up], nt)
    n_dn, mean_dn, s_dn = _cell_stats(error[None, ~up], index[~up], nt)
    c = _figures(n_up, mean_up, s_up, n_dn, mean_dn, s_dn)
    mean_up, s_up, mean_dn, s_dn = mean_up[0], s_up[0], mean_dn[0], s_dn[0]
    equal_up, equal_dn = (n_up >= 2) & (s_up <= EQUAL), (n_dn >= 2) & (s_dn <= EQUAL)
    table = TargetTable(target, n_up, n_dn, mean_up, mean_dn, s_up, s_dn, c.mean_bi[0], c.reversal[0], c.r_up[0],
                        c.r_dn[0], c.r_bi[0], equal_up, equal_dn)

    notes = []
    has_up, has_dn, both = c.has_up, c.has_dn, c.both
    ok_up, ok_dn = bool(c.ok_up[0]), bool(c.ok_dn[0])
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
    if nt == 1:
        notes.append("one target only (a one-position test): A, E and M compare targets and are not applicable; "
                     "B and R are that target's values")
    fig = {k: float(v[0]) for k, v in c.axis.items()}
    below = tuple(k for k in ("R_up", "R_down", "R") if math.isfinite(fig[k]) and fig[k] <= 4 * EQUAL)
    return Iso230Figures(**fig, targets=table, rows=int(angle.shape[0]), notes=tuple(notes), below=below)


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
