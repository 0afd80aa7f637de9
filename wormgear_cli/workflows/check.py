"""``check`` as a library call: the whole per-file verdict (load, analyse, requirements, yield)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING

from wormgear_cli.analysis.requirements import deprecations, evaluate
from wormgear_cli.errors import WormgearError
from wormgear_cli.units import ARCSEC

if TYPE_CHECKING:
    from wormgear_cli.tolerance.engine import YieldCheck

#: ISO 230-2 requirement attribute -> the tolerance engine's metric that samples it
ISO_YIELD = {"max_iso230_A": "iso230_A", "max_iso230_E": "iso230_E", "max_iso230_B": "iso230_B",
             "max_iso230_M": "iso230_M"}


@dataclass(frozen=True)
class FileCheck:
    """The verdict of ``wormgear check`` on one drive file.

    ``valid``: the spec (and its ``[statistics]``) loaded; ``passed``: valid and within every
    requirement (with ``requirements.min_yield``: the estimated yield reaches it);
    ``problems``: the spec's errors, one line each; ``requirements``: one dict per requirement
    (``key``, ``measure``: amplitude / lost motion / range, ``limit_arcsec``, ``value_arcsec``,
    ``passed``: None when the limit is judged by the yield; an ISO 230-2 limit also ``predicted``:
    the figure and the test plan it was predicted on); ``yield_check``: the Monte Carlo yield
    (:class:`wormgear_cli.tolerance.engine.YieldCheck`) or None; ``findings``: the text lines
    ``check`` prints for this file; ``warnings``: lines for stderr (implausible inputs, deprecated
    keys, results beyond a full turn: :func:`wormgear_cli.analysis.sanity.check_angles`).
    """

    file: str
    valid: bool
    passed: bool
    problems: tuple = ()
    requirements: tuple = ()
    yield_check: YieldCheck | None = None
    findings: tuple = ()
    warnings: tuple = ()

    def to_dict(self) -> dict:
        """The file's entry of ``check --format json``."""
        out = {"file": self.file, "valid": self.valid, "passed": self.passed, "problems": list(self.problems),
               "requirements": [dict(r) for r in self.requirements]}
        if self.yield_check is not None:
            out["yield"] = self.yield_check.to_dict()
        return out


def check_file(path) -> FileCheck:
    """Load ``path``, analyse it and judge its ``[requirements]`` (what ``wormgear check`` does per file).

    A spec error is not raised: it is returned as an invalid :class:`FileCheck` with the
    error's lines as ``problems``.
    """
    # lazy: analysis.accuracy, analysis.sanity, spec.loader pull in numpy, ctypes; this module loads without them
    from wormgear_cli.analysis.accuracy import analyze
    from wormgear_cli.analysis.sanity import check_angles
    from wormgear_cli.spec.loader import load_spec

    name = str(path)
    try:
        spec = load_spec(path)
        result = analyze(spec)
        absurd = check_angles(result.angles, name, strict=True)  # not finite, beyond a full turn: a problem
        verdicts = evaluate(spec, result)
        yc, by_yield = None, set()
        if spec.requirements.min_yield is not None:  # a Monte Carlo estimate: imported only then
            # lazy: keeps tolerance.engine off `check`'s start-up
            from wormgear_cli.tolerance.engine import YIELD_REQUIREMENTS

            yc = check_yield(spec)
            by_yield = {f"requirements.{a}_arcsec" for a in (*YIELD_REQUIREMENTS, *ISO_YIELD)}  # what the yield counts
        elif "statistics" in spec.raw:  # validated even when no yield is required
            # lazy: keeps tolerance.quantities off `check`'s start-up
            from wormgear_cli.tolerance.quantities import statistics_table

            statistics_table(spec)
    except WormgearError as exc:
        return FileCheck(name, False, False, problems=tuple(exc.problems))
    passed, rows, findings = True, [], []
    for v in verdicts:
        row = {"key": v.key, "measure": v.measure, "limit_arcsec": v.limit_arcsec, "value_arcsec": v.value_arcsec,
               "passed": v.passed}
        if v.predicted is not None:
            row["predicted"] = v.predicted
        if not v.passed and v.key in by_yield:  # with min_yield the sampled limits are judged by the yield
            row["passed"] = None
            findings.append(f"{name}: worst case over {v.key}: limit {v.limit_arcsec:g} arcsec, corner value "
                            f"{v.value_arcsec:.2f} arcsec (judged by requirements.min_yield)")
        elif not v.passed:
            passed = False
            findings.append(f"{name}: FAIL {v.key}: limit {v.limit_arcsec:g} arcsec, {_value_words(v)} "
                            f"{v.value_arcsec:.2f} arcsec")
        rows.append(row)
    if yc is not None:
        passed = passed and yc.passed
        findings.append(f"{name}: {yc.line()}")
    elif passed:
        n = len(verdicts)
        findings.append(f"{name}: ok ({n} requirement{'s' if n != 1 else ''} met)" if n else
                        f"{name}: ok (valid; no requirements)")
    warnings = (*spec.warnings, *deprecations(spec), *((absurd,) if absurd else ()))
    return FileCheck(name, True, passed, requirements=tuple(rows), yield_check=yc, findings=tuple(findings),
                     warnings=warnings)


def _value_words(v) -> str:
    """How a failed limit names its value: ``value`` (an amplitude or a lost motion) or ``predicted
    ISO 230-2 E (range)`` for a figure of the acceptance test."""
    if v.predicted is None:
        return "value"
    return f"predicted {v.predicted['figure']} ({v.measure})"


def check_yield(spec, samples: int | None = None, seed: int = 0):
    """The ``min_yield`` requirement of ``spec`` (None when absent): the joint yield of every sampled
    limit, the tolerance engine's (:data:`~wormgear_cli.tolerance.engine.YIELD_REQUIREMENTS`) and the
    ISO 230-2 figures of the acceptance test, sampled on the spec's own ``[test_plan]`` targets (its
    ``reading_scatter_arcsec`` s adds 4 s to each sampled A: the model's runs are alike).  A target
    inside the 95 % interval is undecided (and fails).  Raises SpecError when there is no limit to
    count the yield against."""
    import numpy as np  # lazy: numpy only on this path

    from wormgear_cli.tolerance import engine  # lazy: keeps tolerance.engine off `check`'s start-up

    if not any(getattr(spec.requirements, a) is not None for a in ISO_YIELD):
        return engine.check_yield(spec, samples or engine.CHECK_SAMPLES, seed)
    from wormgear_cli.tolerance import statistics as stats  # lazy: keeps tolerance.statistics off `check`'s start-up

    s = _iso_setup(spec, samples or engine.CHECK_SAMPLES, seed)
    lim = dict(engine.limits(s))
    for attr, metric in ISO_YIELD.items():
        limit = getattr(spec.requirements, attr)
        if limit is not None:
            lim[f"requirements.{attr}_arcsec"] = (metric, limit / ARCSEC)
    shift = {"iso230_A": 4.0 * spec.test_plan.reading_scatter / ARCSEC}
    ok = n = 0
    for block in engine.blocks(s):
        every = np.ones(block.stop - block.start, dtype=bool)
        for metric, limit in lim.values():
            every &= block.metrics[metric] + shift.get(metric, 0.0) <= limit
        ok += int(np.count_nonzero(every))
        n += block.stop - block.start
    target = float(spec.requirements.min_yield)
    est = stats.binomial_yield(ok, n)
    return engine.YieldCheck(target, est, est.verdict(target))


def _iso_setup(spec, samples: int, seed: int):
    """The tolerance engine's run (every metric, arcsec) with its ISO 230-2 test on the spec's plan."""
    import numpy as np  # lazy: numpy only on this path

    # lazy: analysis.acceptance pulls in numpy, ctypes; this module loads without it (the next imports alike)
    from wormgear_cli.analysis.acceptance import DWELL_S, plan_targets
    from wormgear_cli.tolerance import engine
    from wormgear_cli.tolerance import metrics as metrics_mod

    s = engine.setup(spec, engine.Options(samples=samples, seed=seed, metrics="all"))
    targets = plan_targets(spec.test_plan)
    return dataclasses.replace(s, targets_deg=np.degrees(targets),
                               context=metrics_mod.context(spec, s.varied, targets, DWELL_S))
