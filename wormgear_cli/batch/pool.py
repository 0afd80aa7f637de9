"""Worker processes for ``--jobs N``: an ordered map over independent tasks.

Every parallel path of the program goes through :func:`ordered_map`: the tasks are the same
blocks the one-process run computes (random-stream blocks of ``tolerance``, grid chunks of
``sweep``, bootstrap resamples of ``diagnose``), each computed by the same function, and the
results come back in task order, so the output is byte-identical whatever N.

* Start method: ``fork`` where the platform has it (Linux: the workers share the parent's
  prepared state without pickling it), otherwise ``spawn`` (the state is pickled once per
  worker).
* At most ``2 N`` tasks are in flight: memory stays bounded however many tasks there are.
* Signals: a worker ignores SIGINT (Ctrl-C reaches the whole foreground process group; the
  parent alone decides) and dies on SIGTERM.  When the parent stops (Ctrl-C, SIGTERM, an
  error in a task), the workers are terminated at once and the exception goes on in the
  parent, so the command exits as a one-process run would (130 after Ctrl-C, nothing
  written).
* A worker that dies (out of memory, killed) is an error naming the task, never a hang.
"""

from __future__ import annotations

import os
import signal
import sys
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from wormgear_cli.errors import UsageError

#: most workers accepted by --jobs (a typo such as 1000000 would try to start that many processes)
MAX_JOBS = 1024

_STATE: Any = None
_FUNCTION: Callable | None = None


def available_cores() -> int:
    """Cores this process may run on (its CPU affinity; the machine's count elsewhere)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def resolve_jobs(jobs: int) -> int:
    """``--jobs`` as a worker count: 0 = every available core; UsageError outside 0..MAX_JOBS."""
    if isinstance(jobs, bool) or not 0 <= int(jobs) <= MAX_JOBS:
        raise UsageError(f"--jobs: expected a whole number from 0 (every core) to {MAX_JOBS}, got {jobs}")
    return available_cores() if int(jobs) == 0 else int(jobs)


def _context():
    import multiprocessing

    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("fork" if "fork" in methods and sys.platform != "darwin" else "spawn")


def _init(function: Callable, state: Any) -> None:
    global _STATE, _FUNCTION
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_DFL)
    _STATE, _FUNCTION = state, function


def _call(task):
    return _FUNCTION(_STATE, task)


def ordered_map(function: Callable[[Any, Any], Any], state: Any, tasks: Iterable, jobs: int = 1) -> Iterator:
    """``function(state, task)`` for every task, in task order.

    ``jobs`` <= 1, or a single task: computed here, one after the other (no process is
    started).  Otherwise in ``jobs`` worker processes (never more than there are tasks); the
    function must be a module-level function and its results picklable.  ``state`` is what
    every task shares (the prepared run), handed to each worker once.
    """
    tasks = list(tasks)
    jobs = min(int(jobs), len(tasks))
    if jobs <= 1:
        for task in tasks:
            yield function(state, task)
        return
    yield from _in_workers(function, state, tasks, jobs)


def _in_workers(function, state, tasks: list, jobs: int) -> Iterator:
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    pool = ProcessPoolExecutor(jobs, mp_context=_context(), initializer=_init, initargs=(function, state))
    done = False
    try:
        pending: deque = deque()
        queue = iter(enumerate(tasks))
        for n, task in queue:
            pending.append((n, pool.submit(_call, task)))
            if len(pending) >= 2 * jobs:
                break
        while pending:
            n, future = pending.popleft()
            try:
                result = future.result()
            except BrokenProcessPool:
                raise RuntimeError(f"a worker process of --jobs {jobs} died (out of memory, or killed) while "
                                   f"computing part {n + 1} of {len(tasks)}; run again with fewer --jobs") from None
            nxt = next(queue, None)
            if nxt is not None:
                pending.append((nxt[0], pool.submit(_call, nxt[1])))
            yield result
        done = True
    finally:
        if done:
            pool.shutdown(wait=True)
        else:
            _terminate(pool)


def _terminate(pool) -> None:
    """Stop every worker now (Ctrl-C, SIGTERM, an error, or the consumer stopped reading)."""
    processes = list(getattr(pool, "_processes", {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in processes:
        if p.is_alive():
            p.terminate()
    for p in processes:
        p.join(timeout=5)
