"""Run structure of a measurement: passes, runs, cells and what varies.

A pass is one run in one direction; a cell is one (target, direction) pair.
Without a ``run`` column a pass is a block of consecutive rows in one
direction and each pass its own run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from wormgear_cli.measurement.iso230 import group_targets
from wormgear_cli.measurement.reader import time_restarts
from wormgear_cli.physics.signals import SIGNALS


@dataclass(frozen=True)
class Groups:
    """The run structure of a measurement.

    ``pass_id`` (N,) pass of each row; a pass is one run in one direction.
    ``pass_size`` (P,), ``pass_run`` (P,) run index of each pass,
    ``pass_direction`` (P,).  ``runs``: number of runs R.  ``nested``: some
    run holds more than one pass (then run and pass variances are separate
    components).  ``random``: False when the rows carry no usable run
    structure (every row its own pass): noise is then taken as white.
    ``describe``: how the passes were found.
    """

    pass_id: np.ndarray
    pass_size: np.ndarray
    pass_run: np.ndarray
    pass_direction: np.ndarray
    runs: int
    nested: bool
    random: bool
    describe: str
    # derived in __post_init__ (not arguments, not compared): rows sorted by pass, each pass's first sorted
    # row, rows already in pass order, the passes as blocks of consecutive rows (first row, pass) or None,
    # and the (R, P) run-of-pass indicator
    order: np.ndarray = field(init=False, repr=False, compare=False)
    starts: np.ndarray = field(init=False, repr=False, compare=False)
    in_order: bool = field(init=False, repr=False, compare=False)
    blocks: tuple[np.ndarray, np.ndarray] | None = field(init=False, repr=False, compare=False)
    run_indicator: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        order = np.argsort(self.pass_id, kind="stable")
        starts = np.searchsorted(self.pass_id[order], np.arange(self.pass_size.shape[0]))
        object.__setattr__(self, "order", order)
        object.__setattr__(self, "starts", starts)
        # rows already grouped by pass (the usual file): pass sums need no gathered copy
        object.__setattr__(self, "in_order", bool(np.all(order == np.arange(order.shape[0]))))
        # each pass one block of consecutive rows, the blocks in another order (forward and reverse passes
        # alternating): pass sums are the block sums, put in pass order (no gathered copy either)
        blocks: tuple[np.ndarray, np.ndarray] | None = None
        if not self.in_order and self.pass_id.shape[0]:
            first = np.flatnonzero(np.r_[True, self.pass_id[1:] != self.pass_id[:-1]])
            if first.shape[0] == self.pass_size.shape[0]:
                blocks = (first, self.pass_id[first])
        object.__setattr__(self, "blocks", blocks)
        ind = np.zeros((self.runs, self.pass_size.shape[0]))
        ind[self.pass_run, np.arange(self.pass_size.shape[0])] = 1.0
        object.__setattr__(self, "run_indicator", ind)

    @property
    def passes(self) -> int:
        return int(self.pass_size.shape[0])


def _plain_keys(run: np.ndarray, direction: np.ndarray) -> bool:
    """Finite runs without a negative zero and directions of exactly +/-1: keys whose equality and order
    are those of their values, so sorting pairs and sorting each column agree."""
    return bool(np.all(np.isfinite(run)) and not np.any((run == 0) & np.signbit(run))
                and np.all((direction == 1.0) | (direction == -1.0)))


def make_groups(direction: np.ndarray, run: np.ndarray | None, time: np.ndarray | None = None) -> Groups:
    """Passes and runs from the ``direction``, (optional) ``run`` and (optional) ``time`` [s] columns.

    With a run column: a pass is every row of one (run, direction) pair, a
    run every row of one run number.  Without: a pass is a block of
    consecutive rows in one direction, a new one also starting where time
    goes backwards (:func:`time_restarts`), and each pass is its own run."""
    direction = np.asarray(direction, dtype=float)
    n = direction.shape[0]
    if run is not None:
        run = np.asarray(run)
        run_f = run.astype(float)
        if _plain_keys(run_f, direction):
            # the (run, direction) pairs in the same lexicographic order as np.unique(axis=0) gives them, from
            # two one-dimensional uniques (several times faster than sorting rows)
            run_vals, r_idx = np.unique(run_f, return_inverse=True)
            dir_vals, d_idx = np.unique(direction, return_inverse=True)
            key = r_idx.reshape(-1) * dir_vals.shape[0] + d_idx.reshape(-1)
            ukey, pass_id = np.unique(key, return_inverse=True)
            uniq = np.stack([run_vals[ukey // dir_vals.shape[0]], dir_vals[ukey % dir_vals.shape[0]]], axis=1)
        else:
            keys = np.stack([run_f, direction], axis=1)
            uniq, pass_id = np.unique(keys, axis=0, return_inverse=True)
        pass_id = pass_id.reshape(-1)
        run_vals, pass_run = np.unique(uniq[:, 0], return_inverse=True)
        pass_dir = uniq[:, 1]
        runs = int(run_vals.shape[0])
        describe = "run column: one pass per run and direction"
    else:
        change = np.ones(n, dtype=bool)
        change[1:] = direction[1:] != direction[:-1]
        restarts = time_restarts(time)
        if restarts is not None:
            change |= restarts
        pass_id = np.cumsum(change) - 1
        p = int(pass_id[-1]) + 1
        pass_run = np.arange(p)
        pass_dir = direction[change]
        runs = p
        describe = "no run column: a pass is a block of consecutive rows in one direction"
        if restarts is not None and np.any(restarts):
            describe += " (a new one where time_s goes backwards)"
    size = np.bincount(pass_id, minlength=int(pass_id.max()) + 1).astype(float)
    nested = bool(np.bincount(pass_run).max() > 1) if runs > 0 else False
    random = bool(size.shape[0] >= 2 and np.mean(size) >= 3.0)
    if not random:
        describe += "; passes too short to carry run-to-run noise, noise taken as white"
    return Groups(pass_id.astype(int), size, np.asarray(pass_run, dtype=int), np.asarray(pass_dir, dtype=float),
                  runs, nested and random, random, describe)


# ============================================================================ GLS / REML from sufficient statistics


def pass_sums(values: np.ndarray, groups: Groups) -> np.ndarray:
    """Per-pass column sums of a (N,) or (N, k) array."""
    if values.ndim == 1:
        return np.bincount(groups.pass_id, weights=values, minlength=groups.passes)
    if values.shape[1] == 0:
        return np.zeros((groups.passes, 0))
    if groups.in_order:
        return np.add.reduceat(values, groups.starts, axis=0)
    if groups.blocks is not None and values.flags.c_contiguous:
        # the same rows summed in the same order, the same memory layout, as in the gathered copy below
        first, block_pass = groups.blocks
        out = np.empty((groups.passes, values.shape[1]))
        out[block_pass] = np.add.reduceat(values, first, axis=0)
        return out
    return np.add.reduceat(values[groups.order], groups.starts, axis=0)


@dataclass(frozen=True)
class Cells:
    """Cells = (target, direction) pairs: ``cell_id`` (N,), ``count`` (C,) rows per cell.
    ``replicated``: cells hold two or more rows on average (repeated runs)."""

    cell_id: np.ndarray
    count: np.ndarray

    @property
    def cells(self) -> int:
        return int(self.count.shape[0])

    @property
    def replicated(self) -> bool:
        return bool(np.mean(self.count) >= 2.0)

    def means(self, x: np.ndarray) -> np.ndarray:
        x2 = x.reshape(x.shape[0], -1)
        out = np.empty((self.cells, x2.shape[1]))
        for j in range(x2.shape[1]):
            out[:, j] = np.bincount(self.cell_id, weights=x2[:, j], minlength=self.cells) / self.count
        return out if x.ndim > 1 else out[:, 0]


def make_cells(theta: np.ndarray, direction: np.ndarray) -> Cells:
    """Cells of a measurement: rows at the same target (angles within 1e-6 deg) and direction."""
    tgt, _ = group_targets(theta)
    key = tgt.astype(np.int64) * 2 + (np.asarray(direction) < 0)
    _, cell = np.unique(key, return_inverse=True)
    cell = cell.reshape(-1)
    return Cells(cell, np.bincount(cell).astype(float))


def cell_level(cols: np.ndarray, cells: Cells) -> bool:
    """True when the columns depend on the cell only (no variation between the runs of a cell)."""
    cols = cols.reshape(cols.shape[0], -1)
    tot = float(np.sum(cols * cols))
    if tot <= 0:
        return False
    m = cells.means(cols)
    within = tot - float(np.sum(cells.count[:, None] * m * m))
    return within <= 1e-9 * tot


@dataclass(frozen=True)
class DataInfo:
    """What varies in the measurement (decides which effects can be seen)."""

    directions: tuple
    temperature_range: float
    temperature_present: bool
    load_range: float
    load_present: bool
    time_range: float
    temperature_time_corr: float
    passes_per_direction: float


def data_info(meas, groups: Groups) -> DataInfo:
    d = tuple(sorted({int(x) for x in np.unique(meas.direction)}, reverse=True))
    t_rng = float(np.ptp(meas.temperature))
    tt = math.nan
    if t_rng > 0 and np.ptp(meas.time) > 0:
        tt = float(np.corrcoef(meas.temperature, meas.time)[0, 1])
    present = {s for s in SIGNALS if SIGNALS[s].column in meas.present}
    return DataInfo(d, t_rng, "temperature" in present, float(np.ptp(meas.load)), "load" in present,
                    float(np.ptp(meas.time)), tt, groups.passes / max(len(d), 1))
