"""Worker processes for ``--jobs N``: an ordered map over independent tasks.

Every parallel path of the program goes through :func:`ordered_map`: the tasks are the same
blocks the one-process run computes (random-stream blocks of ``tolerance``, grid chunks of
``sweep``, bootstrap resamples of ``diagnose``), each computed by the same function, and the
results come back in task order, so the output is byte-identical whatever N.

* Start method: ``fork`` where the platform has it (Linux: the workers share the parent's
  prepared state without pickling it), otherwise ``spawn`` (the state is pickled once per
  worker).
* At most ``2 N`` tasks are in flight: memory stays bounded however many tasks there are.
* No thread is started: each worker has its own pipe, task i goes to worker i mod N.
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
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from wormgear_cli.errors import UsageError

#: most workers accepted by --jobs (a typo such as 1000000 would try to start that many processes)
MAX_JOBS = 1024


def available_cores() -> int:
    """Cores this process may run on (its CPU affinity; the machine's count elsewhere)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def resolve_jobs(jobs: int) -> int:
    """``--jobs`` as a worker count: 0 = every available core; UsageError outside 0..MAX_JOBS."""
    if isinstance(jobs, bool) or not 0 <= int(jobs) <= MAX_JOBS:
        raise UsageError(f"jobs: expected a whole number from 0 (every core) to {MAX_JOBS}, got {jobs}",
                         parameter="jobs")
    return available_cores() if int(jobs) == 0 else int(jobs)


def _context():
    import multiprocessing  # lazy: keeps multiprocessing off `sweep`'s start-up

    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("fork" if "fork" in methods and sys.platform != "darwin" else "spawn")


def _worker(conn, function: Callable, state: Any) -> None:
    """A worker's life: tasks in, results (or the task's exception) out, until told to stop."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_DFL)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_SETMASK, set())
    while True:
        try:
            task = conn.recv()
        except (EOFError, OSError):
            break
        if task is None:
            break
        try:
            reply = (True, function(state, task))
        except BaseException as exc:  # handed to the parent, raised there
            reply = (False, exc)
        try:
            conn.send(reply)
        except (EOFError, OSError):
            break
        except Exception as exc:  # a result or exception that does not pickle
            conn.send((False, RuntimeError(f"a worker's result could not be sent back: {exc}")))
    os._exit(0)  # no clean-up of what the parent owns (its buffers, its staged files)


def ordered_map(function: Callable[[Any, Any], Any], state: Any, tasks: Iterable, jobs: int = 1) -> Iterator:
    """``function(state, task)`` for every task, in task order.

    ``jobs`` <= 1, or a single task: computed here, one after the other (no process is
    started).  Otherwise in ``jobs`` worker processes (never more than there are tasks); the
    function must be a module-level function and its results picklable.  ``state`` is what
    every task shares (the prepared run), handed to each worker once; a task's exception is
    raised here.
    """
    tasks = list(tasks)
    jobs = min(int(jobs), len(tasks))
    if jobs <= 1:
        for task in tasks:
            yield function(state, task)
        return
    yield from _in_workers(function, state, tasks, jobs)


def _in_workers(function, state, tasks: list, jobs: int) -> Iterator:
    """Task i goes to worker i mod ``jobs`` (tasks are alike in size), at most two queued per
    worker; each worker answers in the order it was asked, so results are read in task order.
    No thread is started in this process: a stop needs no hand-shake with one."""
    ctx = _context()
    sys.stdout.flush()
    sys.stderr.flush()
    workers, pipes = [], []
    try:
        for _ in range(jobs):
            mine, theirs = ctx.Pipe()
            p = ctx.Process(target=_worker, args=(theirs, function, state), daemon=True)
            p.start()
            theirs.close()
            workers.append(p)
            pipes.append(mine)
        sent = 0
        for n in range(len(tasks)):
            while sent < len(tasks) and sent < n + 2 * jobs:
                try:
                    pipes[sent % jobs].send(tasks[sent])
                except OSError:  # that worker is gone: the receive below says which part it had
                    pass
                sent += 1
            try:
                ok, value = pipes[n % jobs].recv()
            except (EOFError, OSError):
                raise RuntimeError(f"a worker process of --jobs {jobs} died (out of memory, or killed) while "
                                   f"computing part {n + 1} of {len(tasks)}; run again with fewer --jobs") from None
            if not ok:
                raise value
            yield value
        for conn in pipes:
            conn.send(None)
        for p in workers:
            p.join()
    finally:
        _stop(workers, pipes)


def _stop(workers: list, pipes: list) -> None:
    """Stop every worker still running (Ctrl-C, SIGTERM, an error, or the consumer stopped
    reading) and close the pipes."""
    for p in workers:
        if p.is_alive():
            p.terminate()
    for p in workers:
        p.join(timeout=2)
        if p.is_alive():
            p.kill()
            p.join()
    for conn in pipes:
        conn.close()
