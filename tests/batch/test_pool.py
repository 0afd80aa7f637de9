"""The worker pool of --jobs: results in task order, errors raised in the parent, no hang."""

from __future__ import annotations

import os

import numpy as np
import pytest

from wormgear_cli.batch.pool import available_cores, ordered_map, resolve_jobs
from wormgear_cli.errors import UsageError


def _square_block(state, task):
    rng = np.random.default_rng(task)  # the same task gives the same numbers wherever it runs
    return state * rng.random(1000) ** 2, os.getpid()


def _fails(state, task):
    if task == state:
        raise UsageError(["first line of a problem", "second problem"])
    return task


def _dies(state, task):
    if task == state:
        os._exit(3)
    return task


def test_results_come_in_task_order_from_other_processes():
    serial = list(ordered_map(_square_block, 2.0, range(9), jobs=1))
    parallel = list(ordered_map(_square_block, 2.0, range(9), jobs=3))
    assert all(np.array_equal(a[0], b[0]) for a, b in zip(serial, parallel))
    assert {pid for _, pid in serial} == {os.getpid()}
    assert os.getpid() not in {pid for _, pid in parallel} and len({pid for _, pid in parallel}) == 3


def test_a_task_error_is_raised_here_with_its_lines():
    with pytest.raises(UsageError) as exc:
        list(ordered_map(_fails, 4, range(8), jobs=2))
    assert exc.value.problems == ["first line of a problem", "second problem"]


def test_a_dead_worker_is_an_error_not_a_hang():
    with pytest.raises(RuntimeError, match=r"a worker process of --jobs 2 died .* computing part 4 of 6"):
        list(ordered_map(_dies, 3, range(6), jobs=2))


def test_a_consumer_that_stops_early_stops_the_workers():
    gen = ordered_map(_square_block, 1.0, range(50), jobs=2)
    next(gen)
    gen.close()  # no worker left behind (the test would hang at exit otherwise)
    import multiprocessing

    assert not multiprocessing.active_children()


def test_jobs_zero_is_every_core_and_the_bounds_are_checked():
    assert resolve_jobs(0) == available_cores() >= 1
    assert resolve_jobs(3) == 3
    with pytest.raises(UsageError, match="^jobs: expected a whole number from 0"):  # the API's word; CLI: --jobs
        resolve_jobs(-1)
