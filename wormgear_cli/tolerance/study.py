"""A whole tolerance study: the run's statistics, the allocation when a target yield is due,
and the report document (what ``wormgear tolerance`` prints and the API returns)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from wormgear_cli.errors import UsageError
from wormgear_cli.tolerance import report
from wormgear_cli.tolerance.allocation import allocate
from wormgear_cli.tolerance.engine import LIMIT_KEYS, Setup, Summary, allocation_runs, metrics_for_limits


def finish(s: Setup, summary: Summary, target_yield: float | None = None, samples: int | None = None,
           shard: str | None = None, progress: Callable[[int], None] | None = None) -> dict:
    """The report of a tolerance run (what ``wormgear tolerance`` prints and the API returns).

    The allocation runs when a target is due: ``target_yield``, else ``[requirements]
    min_yield``; each toleranced key is tightened in turn (one ISO 1328 grade where a grade
    sets it, else to 70 %) on :func:`allocation_runs` samples.

    Parameters
    ----------
    s : Setup
        The run's set-up (:func:`setup`).
    summary : Summary
        Its statistics (:func:`run` or :func:`summarize`).
    target_yield : float, optional
        Target yield in (0, 1).
    samples : int, optional
        Samples the run had (default ``s.options.samples``); the allocation uses at most
        :data:`ALLOCATION_SAMPLES`.
    shard : str, optional
        ``K/N`` label of a sharded run, for the document.
    progress : callable, optional
        Called with 1 after each allocation run.

    Raises
    ------
    UsageError
        ``target_yield`` given but no limit in ``[requirements]`` to count the yield against.
    """
    spec = s.spec
    if target_yield is not None and metrics_for_limits(spec) is None:
        raise UsageError(f"a target yield needs a limit in [requirements] ({LIMIT_KEYS}) to count the yield "
                         "against")
    target = target_yield if target_yield is not None else spec.requirements.min_yield
    plan = allocation_runs(s, target, s.options.samples if samples is None else samples)
    allocation = None
    if plan is not None:
        allocation = allocate(spec, replace(s.options, samples=plan[0]), float(target), progress)
    return report.document(s, summary, allocation, shard)
