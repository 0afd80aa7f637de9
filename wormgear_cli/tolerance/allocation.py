"""Tolerance allocation: which tolerance to tighten for the most yield.

Each varied quantity is tightened in turn, alone, by one step and the run is
repeated with the same seed (common random numbers: the same uniforms, so the
difference between two runs is the effect of the step, not noise); the
quantities are ranked by the joint yield gained (all limits met).

The step: one ISO 1328 accuracy grade finer where a grade drives the
quantity (:attr:`Quantity.grade_driven`) and the spec says which grade it is
(:data:`finer_grade`: the spur gears' pitch deviations that their ISO 1328-1
``accuracy_grade`` sets); otherwise, while the target is not met, the least tightening of
that key alone that reaches the target yield (the lower end of its 95 % interval), found by
bisection on the fraction of the tolerance kept (:data:`BISECTION_STEPS` halvings, the same
seed each run so that the yield is monotone in the fraction), or, when no tightening of that key
alone reaches the target (not even a zero tolerance), the tolerance times
:data:`TIGHTEN_FACTOR` (70 %) to rank it by the yield it gains.  The best step is also given as a
sentence (``answer``), e.g. "tighten the
output gear's cumulative pitch deviation to grade 3 (17 -> 12 um): yield 91.2 % -> 99.1 %".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from wormgear_cli.errors import UsageError
from wormgear_cli.physics.iso1328 import flank_tolerances
from wormgear_cli.spec.loader import value_origin
from wormgear_cli.tolerance import engine
from wormgear_cli.tolerance.statistics import Yield

#: tolerance factor of one step when no grade drives the quantity and the target is out of reach by it
TIGHTEN_FACTOR = 0.7
#: halvings of the bisection on the fraction of a tolerance kept (2^-7: within 1 % of the tolerance)
BISECTION_STEPS = 7

#: ISO 1328-1:2013 tolerance (FlankTolerances attribute) behind each grade-driven spur-gear key
GRADE_TOLERANCE = {"cumulative_pitch_deviation_mm": "F_pT", "single_pitch_deviation_mm": "f_pT"}


def iso1328_finer_grade(spec, path: str) -> tuple[float, int, int] | None:
    """The tolerance [mm] of ``path`` one ISO 1328-1:2013 class finer than the spec's, and the two classes.

    Only for a spur-gear key (of any spur stage) the part's ``accuracy_grade`` sets (the value comes from the
    grade, not written in the spec: :func:`wormgear_cli.spec.loader.value_origin` is "grade"), with
    the standard's formulas (eq. 5 F_pT... eq. 6; rounding 5.2.3) at the gear's module,
    reference diameter m z and face width.  None otherwise (no grade, an explicit value,
    already class 1): the step is then the 70 % factor.
    """
    found = [(s, k) for s in spec.stages for k, p in s.paths.items() if p == path and s.kind == "spur"]
    if not found:
        return None
    stage, stage_key = found[0]
    member, _, key = stage_key.partition(".")
    if key not in GRADE_TOLERANCE or member not in ("gear", "pinion") or value_origin(spec, path) != "grade":
        return None
    part = getattr(stage, member)
    grade = part.accuracy_grade
    if grade is None or grade <= 1:
        return None

    tol = flank_tolerances(grade - 1, stage.module, stage.module * part.teeth, stage.face_width, part.teeth)
    return getattr(tol, GRADE_TOLERANCE[key]) * 1e-3, int(grade), int(grade) - 1


#: Hook for the grades: ``finer_grade(spec, path) -> (tolerance_mm, grade, finer) | None``,
#: the tolerance [mm] of quantity ``path`` one grade finer than the spec's and the two grade
#: numbers, or None when the spec gives no grade for it (then the 70 % step).
finer_grade: Callable | None = iso1328_finer_grade


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

    def advice(self) -> str:
        """The step as a sentence, e.g. "tighten the output gear's cumulative pitch deviation to grade 3
        (17 -> 12 um): yield 91.2 % -> 99.1 %"."""
        # "grade 6 -> 5" -> "to grade 5"; "70 %" -> "to 70 %"
        to = f"to grade {self.how.rsplit(' ', 1)[1]}" if self.how.startswith("grade") else f"to {self.how}"
        um = lambda t: "/".join(f"{1e3 * x:.3g}" for x in t)  # noqa: E731
        return (f"tighten {describe(self.path)} {to} ({um(self.from_mm)} -> {um(self.to_mm)} um): yield "
                f"{100 * self.before.value:.1f} % -> {100 * self.after.value:.1f} %")

    def to_dict(self) -> dict:
        one = lambda t: t[0] if len(t) == 1 else list(t)  # noqa: E731
        return {"key": self.path, "from_mm": one(self.from_mm), "to_mm": one(self.to_mm), "step": self.how,
                "yield": {"value": self.after.value, "low": self.after.low, "high": self.after.high},
                "gain": self.gain, "advice": self.advice()}


#: owners of a key, as a sentence names them (the TOML section's last part)
_OWNERS = {"output_gear": "the output gear's", "pinion": "the pinion's", "worm": "the worm's",
           "wheel": "the wheel's", "worm_pair": "the worm pair's", "gear_pair": "the gear pair's",
           "gear": "the gear's", "driver": "the driving pulley's", "driven": "the driven pulley's"}


def describe(path: str) -> str:
    """A toleranced key in words: worm_pair.wheel.radial_composite_error_mm -> "the wheel's radial
    composite error"; assembly.wheel_eccentricity_mm -> "the wheel eccentricity"; a stage key names its
    stage: stage.2.wheel.runout_mm -> "the wheel's runout (stage 2)"."""
    parts = path.split(".")
    words = parts[-1].removesuffix("_mm").replace("_", " ")
    if len(parts) > 2 and parts[0] == "stage" and parts[1].isdigit():
        owner = _OWNERS.get(parts[2], "the") if len(parts) > 3 else "the"
        return f"{owner} {words} (stage {parts[1]})"
    owner = _OWNERS.get(parts[-2], "the") if len(parts) > 1 else "the"
    return f"{owner} {words}"


def tightened(spec, varied) -> tuple[tuple, str]:
    """The tolerance after one step and how the step was made (module doc)."""
    if varied.quantity.grade_driven and finer_grade is not None:
        found = finer_grade(spec, varied.path)
        if found is not None:
            tol, grade, finer = found
            return (float(tol),), f"grade {grade} -> {finer}"
    return tuple(TIGHTEN_FACTOR * t for t in varied.tolerance), f"{round(100 * TIGHTEN_FACTOR)} %"


def least_tightening(varied, run: Callable, target: float) -> tuple | None:
    """(tolerance, how, yield) of the least tightening of ``varied`` alone whose joint yield reaches
    ``target`` (the lower end of its 95 % interval), by bisection on the fraction f of the tolerance
    kept: f = 0 must reach it (else None: out of reach by this key), f = 1 does not (the base run);
    :data:`BISECTION_STEPS` halvings keep the largest f found to reach it.  ``run(tolerance)`` -> the
    joint :class:`~wormgear_cli.tolerance.statistics.Yield` with that tolerance (the same seed)."""
    scaled = lambda f: tuple(f * t for t in varied.tolerance)  # noqa: E731
    best = run(scaled(0.0))
    if best.low < target:
        return None
    lo, hi = 0.0, 1.0
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        y = run(scaled(mid))
        if y.low >= target:
            lo, best = mid, y
        else:
            hi = mid
    return scaled(lo), f"{100 * lo:.0f} %", best


def _kept(step) -> float:
    """The fraction of the tolerance a step keeps (its first element)."""
    return step.to_mm[0] / step.from_mm[0] if step.from_mm[0] > 0 else 0.0


def allocate(spec, options: engine.Options, target: float, progress: Callable[[int], None] | None = None) -> dict:
    """Rank the varied quantities by the joint yield one step of tightening gains.

    ``options``: the run's options (its seed and samples; only the metrics that
    carry limits are computed); ``target``: the yield aimed at (0 < target < 1).
    Returns the JSON-ready allocation: target, base yield, and the steps best
    first (ties: registry order).  Raises UsageError when the spec has no limit.
    """
    metric_set = engine.metrics_for_limits(spec)
    if metric_set is None:
        raise UsageError(f"allocation needs a limit in [requirements] ({engine.LIMIT_KEYS}) to count the "
                         "yield against")
    opts = replace(options, metrics=metric_set, shard=None)
    base_setup = engine.setup(spec, opts)
    base = engine.joint_yield(base_setup)
    if progress is not None:
        progress(1)
    steps = []
    for i, v in enumerate(base_setup.varied):
        if not any(t > 0 for t in v.tolerance):
            continue

        def run(tol, i=i):
            varied = tuple(w.with_tolerance(tol) if j == i else w for j, w in enumerate(base_setup.varied))
            return engine.joint_yield(engine.setup(spec, opts, varied))

        new_tol, how = tightened(spec, v)
        least = None if how.startswith("grade") or base.low >= target else least_tightening(v, run, target)
        if least is not None:
            new_tol, how, after = least
        else:
            after = run(new_tol)
        steps.append(Step(v.path, v.tolerance, new_tol, how, base, after))
        if progress is not None:
            progress(1)
    # the steps that reach the target first, the least tightening (most tolerance kept) first; then the
    # others by the yield they gain (stable: ties keep registry order)
    steps.sort(key=lambda st: (st.after.low < target, -_kept(st) if st.after.low >= target else -st.gain))
    reached = [st.path for st in steps if st.after.low >= target]
    if base.low >= target:
        best = (f"target met, no tightening needed: yield {100 * base.value:.2f} % (95 % interval from "
                f"{100 * base.low:.2f} %) >= {100 * target:g} %")
    elif steps and steps[0].gain > 0:
        best = steps[0].advice()
    else:
        best = "no single step gains yield: tighten several tolerances together or revise the limits"
    return {"target": target, "yield": {"value": base.value, "low": base.low, "high": base.high},
            "steps": [st.to_dict() for st in steps], "reaching_target": reached, "answer": best}
