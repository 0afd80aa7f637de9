"""Scatter within and between runs, on data with known variances (over seeds)."""

from __future__ import annotations

import numpy as np
import pytest

from wormgear_cli.compensation.noise import noise_components


def _data(seed, cells=40, runs=6, within=0.5, between=0.8):
    rng = np.random.default_rng(seed)
    cell = np.tile(np.arange(cells), runs)
    run = np.repeat(np.arange(runs), cells)
    y = rng.normal(0, 10, cells)[cell] + rng.normal(0, between, runs)[run] + rng.normal(0, within, cell.size)
    return cell, run, y


def test_recovers_the_within_and_between_run_variances_on_average():
    est = [noise_components(*_data(seed)) for seed in range(200)]
    assert np.mean([n.within for n in est]) == pytest.approx(0.25, rel=0.03)
    assert np.mean([n.between_runs for n in est]) == pytest.approx(0.64, rel=0.15)
    n = est[0]
    assert (n.runs, n.cells, n.dof, n.replicated) == (6, 40, 240 - 40 - 5, True)


def test_without_repeats_the_within_variance_is_undefined():
    n = noise_components(np.arange(10), np.zeros(10, dtype=int), np.arange(10.0))
    assert not n.replicated and np.isnan(n.within) and n.between_runs == 0.0


def test_two_cells_two_runs_by_hand():
    # cells 0, 1; runs 0, 1: y = 1, 3 | 2, 6.  Cell means 2, 4; deviations -1, 1 | -2, 2;
    # run offsets (-1 - 2) / 2 = -1.5 and 1.5; left 0.5, -0.5 | -0.5, 0.5: sum of squares 1 over
    # 4 - 2 - 1 = 1 dof; between: var(-1.5, 1.5) = 4.5, less 1 / 2 rows per run = 4.0
    n = noise_components([0, 0, 1, 1], [0, 1, 0, 1], [1.0, 3.0, 2.0, 6.0])
    assert (n.within, n.between_runs, n.dof, n.runs, n.cells, n.replicated) == (1.0, 4.0, 1, 2, 2, True)
