"""Requirement checks against an analysis: the drive's ``[requirements]`` (totals at the output,
the full budget, the ISO 230-2 figures of its acceptance test, the yield) and each stage's limits at
its own output shaft (a stage table's ``max_transmission_error_arcsec`` / ``max_backlash_arcsec``;
the legacy form's ``requirements.max_gear_*`` / ``max_worm_*``).

Like with like: every limit is compared with the quantity of its own kind (:data:`MEASURES`):
an **amplitude** (zero to peak: the paper's Delta phi_c, the budget's totals), a **lost motion**
(the whole reversal: the paper's Delta phi_h, ISO 230-2's B) or a **range** (max - min over the
acceptance test's targets: ISO 230-2's A, E, M).  A tolerance quoted as +/- x is an amplitude x or
a range 2 x (docs/budget.md, "Amplitudes and ranges").
"""

from __future__ import annotations

from dataclasses import dataclass, field

from wormgear_cli.units import to_unit

#: drive-level requirement attribute -> the quantity it limits (the stages' limits come between the
#: totals and the budget, stage by stage from the output back); "budget:RULE" a budget total,
#: "iso:FIGURE" a figure of the predicted acceptance test (wormgear_cli.analysis.acceptance)
REQUIREMENT_METRICS = {
    "max_transmission_error": "total_transmission_error",
    "max_backlash": "total_backlash",
    # the full budget's TE amplitude at the output under each rule (wormgear_cli.analysis.budget.Rule)
    "max_budget_linear": "budget:linear",
    "max_budget_statistical": "budget:statistical",
    "max_budget_rss": "budget:statistical",  # deprecated name (DEPRECATED)
    "max_budget_peak": "budget:peak",
    # ISO 230-2 figures of the acceptance test on the spec's [test_plan]
    "max_iso230_A": "iso:A",
    "max_iso230_E": "iso:E",
    "max_iso230_B": "iso:B",
    "max_iso230_M": "iso:M",
}
#: what the ISO 230-2 figures are (every other limit: a backlash is a lost motion, the rest amplitudes)
ISO_MEASURES = {"A": "range", "E": "range", "M": "range", "B": "lost motion"}
#: old requirement attribute -> (its new name, why)
DEPRECATED = {"max_budget_rss": ("max_budget_statistical", "judged against the statistical total (root-sum-square "
                                 "within an order, summed across orders), which the plain root-sum-square "
                                 "under-stated")}


@dataclass(frozen=True)
class Verdict:
    """One requirement: TOML key, limit and computed value [arcsec]; ``measure`` (amplitude, lost
    motion, range); ``predicted``: for an ISO 230-2 limit, the figure and the test it was predicted
    on (else None)."""

    key: str
    limit_arcsec: float
    value_arcsec: float
    measure: str = "amplitude"
    predicted: dict | None = field(default=None, compare=False)

    @property
    def passed(self) -> bool:
        return self.value_arcsec <= self.limit_arcsec


def _measure(metric: str) -> str:
    """What a limit on ``metric`` compares: amplitude, lost motion or range (module docstring)."""
    if metric.startswith("iso:"):
        return ISO_MEASURES[metric[4:]]
    return "lost motion" if metric.endswith("backlash") else "amplitude"


def evaluate(spec, analysis) -> list[Verdict]:
    """Every requirement present in ``spec`` with its verdict: the totals, each stage's limits (from the
    output back to the motor), the budget's, the acceptance test's."""
    # lazy: spec.loader pulls in numpy, ctypes; this module loads without it
    from wormgear_cli.spec.loader import raw_value

    out = []
    cache: dict = {}
    limits = [(metric, f"requirements.{attr}_arcsec", getattr(spec.requirements, attr))
              for attr, metric in REQUIREMENT_METRICS.items()]
    stage_limits = [(f"{st.name}_{q}", st.paths[f"max_{q}_arcsec"], getattr(st, f"max_{q}"))
                    for st in spec.stages[::-1] for q in ("transmission_error", "backlash")]
    for metric, key, limit in limits[:2] + stage_limits + limits[2:]:
        if limit is None:
            continue
        written = raw_value(spec.raw, key)  # echo the limit exactly as the user wrote it
        limit_arcsec = float(written) if written is not None else float(to_unit(limit, "arcsec"))
        value, predicted = _value(spec, analysis, metric, cache)
        out.append(Verdict(key, limit_arcsec, float(to_unit(value, "arcsec")), _measure(metric), predicted))
    return out


def _value(spec, analysis, metric: str, cache: dict) -> tuple[float, dict | None]:
    """The quantity ``metric`` limits [rad], and for an ISO 230-2 figure what it was predicted on."""
    if metric.startswith("budget:"):
        if "budget" not in cache:
            # lazy: analysis.budget pulls in numpy, ctypes; this module loads without it
            from wormgear_cli.analysis.budget import budget

            cache["budget"] = budget(spec, analysis)
        return cache["budget"].total(metric.split(":", 1)[1]), None
    if metric.startswith("iso:"):
        if "test" not in cache:
            # lazy: analysis.acceptance pulls in numpy, ctypes; this module loads without it
            from wormgear_cli.analysis.acceptance import predict

            cache["test"] = predict(spec, analysis.registry)
        test = cache["test"]
        name = metric.split(":", 1)[1]
        return test.figure(name), {"figure": f"ISO 230-2 {name}", **test.describe()}
    return analysis.angles[metric], None


def deprecations(spec) -> list[str]:
    """One line per deprecated requirement key the spec uses: what it is now judged against."""
    out = []
    for attr, (new, why) in DEPRECATED.items():
        if getattr(spec.requirements, attr) is not None:
            out.append(f"{spec.source}: requirements.{attr}_arcsec: a deprecated name, {why}; rename it "
                       f"requirements.{new}_arcsec")
    return out
