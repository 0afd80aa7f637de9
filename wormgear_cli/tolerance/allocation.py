"""Tolerance allocation: which tolerance to tighten for the most yield.

Each varied quantity is tightened in turn, alone, by one step and the run is
repeated with the same seed (common random numbers: the same uniforms, so the
difference between two runs is the effect of the step, not noise); the
quantities are ranked by the joint yield gained (all limits met).

The step: one ISO 1328 accuracy grade finer where a grade drives the
quantity (:attr:`Quantity.grade_driven`) and the spec says which grade it is
(:data:`finer_grade`); otherwise the tolerance times :data:`TIGHTEN_FACTOR`
(70 %).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from wormgear_cli.tolerance import engine
from wormgear_cli.tolerance.statistics import Yield

#: tolerance factor of one step when no grade drives the quantity
TIGHTEN_FACTOR = 0.7

#: Hook for the ISO 1328 grades: ``finer_grade(spec, path) -> (tolerance_mm, grade, finer) | None``,
#: the tolerance [mm] of quantity ``path`` one grade finer than the spec's and the two grade
#: numbers, or None when the spec gives no grade for it.  None here: no grade known, 70 % steps.
finer_grade: Callable | None = None


@dataclass(frozen=True)
class Step:
    """One tightening: ``path``, tolerance ``from_mm`` -> ``to_mm`` (per element of an
    array key the same factor), ``how`` ("grade 6 -> 5" or "70 %"), and the joint
    yield before and after."""

    path: str
    from_mm: tuple
    to_mm: tuple
    how: str
    before: Yield
    after: Yield

    @property
    def gain(self) -> float:
        return self.after.value - self.before.value

    def to_dict(self) -> dict:
        one = lambda t: t[0] if len(t) == 1 else list(t)  # noqa: E731
        return {"key": self.path, "from_mm": one(self.from_mm), "to_mm": one(self.to_mm), "step": self.how,
                "yield": {"value": self.after.value, "low": self.after.low, "high": self.after.high},
                "gain": self.gain}


def tightened(spec, varied) -> tuple[tuple, str]:
    """The tolerance after one step and how the step was made (module doc)."""
    if varied.quantity.grade_driven and finer_grade is not None:
        found = finer_grade(spec, varied.path)
        if found is not None:
            tol, grade, finer = found
            return (float(tol),), f"grade {grade} -> {finer}"
    return tuple(TIGHTEN_FACTOR * t for t in varied.tolerance), f"{round(100 * TIGHTEN_FACTOR)} %"


def allocate(spec, options: engine.Options, target: float, progress: Callable[[int], None] | None = None) -> dict:
    """Rank the varied quantities by the joint yield one step of tightening gains.

    ``options``: the run's options (its seed and samples; only the metrics that
    carry limits are computed); ``target``: the yield aimed at (0 < target < 1).
    Returns the JSON-ready allocation: target, base yield, and the steps best
    first (ties: registry order).  Raises UsageError when the spec has no limit.
    """
    from dataclasses import replace

    from wormgear_cli.errors import UsageError

    metric_set = engine.metrics_for_limits(spec)
    if metric_set is None:
        raise UsageError("allocation needs a limit in [requirements] (max_transmission_error_arcsec or "
                         "max_backlash_arcsec) to count the yield against")
    opts = replace(options, metrics=metric_set, shard=None)
    base_setup = engine.setup(spec, opts)
    base = engine.joint_yield(base_setup)
    if progress is not None:
        progress(1)
    steps = []
    for i, v in enumerate(base_setup.varied):
        if not any(t > 0 for t in v.tolerance):
            continue
        new_tol, how = tightened(spec, v)
        varied = tuple(w.with_tolerance(new_tol) if j == i else w for j, w in enumerate(base_setup.varied))
        after = engine.joint_yield(engine.setup(spec, opts, varied))
        steps.append(Step(v.path, v.tolerance, new_tol, how, base, after))
        if progress is not None:
            progress(1)
    steps.sort(key=lambda st: -st.gain)  # stable: ties keep registry order
    reached = [st.path for st in steps if st.after.low >= target]
    return {"target": target, "yield": {"value": base.value, "low": base.low, "high": base.high},
            "steps": [st.to_dict() for st in steps], "reaching_target": reached}
