"""Requirement checks against an analysis: the drive's ``[requirements]`` (totals at the output,
the full budget, the yield) and each stage's limits at its own output shaft (a stage table's
``max_transmission_error_arcsec`` / ``max_backlash_arcsec``; the legacy form's
``requirements.max_gear_*`` / ``max_worm_*``)."""

from __future__ import annotations

from dataclasses import dataclass

from wormgear_cli.units import to_unit

#: drive-level requirement attribute -> analysis metric it limits (the stages' limits come between
#: the totals and the budget, stage by stage from the output back)
REQUIREMENT_METRICS = {
    "max_transmission_error": "total_transmission_error",
    "max_backlash": "total_backlash",
    # the full budget's TE at the output under each combination rule (wormgear_cli.analysis.budget.Rule)
    "max_budget_linear": "budget:linear",
    "max_budget_rss": "budget:rss",
    "max_budget_peak": "budget:peak",
}


@dataclass(frozen=True)
class Verdict:
    """One requirement: TOML key, limit and computed value [arcsec]."""

    key: str
    limit_arcsec: float
    value_arcsec: float

    @property
    def passed(self) -> bool:
        return self.value_arcsec <= self.limit_arcsec


def evaluate(spec, analysis) -> list[Verdict]:
    """Every requirement present in ``spec`` with its verdict: the totals, each stage's limits (from the
    output back to the motor), the budget's."""
    from wormgear_cli.spec.loader import raw_value

    out = []
    full = None
    limits = [(attr, metric, f"requirements.{attr}_arcsec", getattr(spec.requirements, attr))
              for attr, metric in REQUIREMENT_METRICS.items()]
    stage_limits = [(q, f"{st.name}_{q}", st.paths[f"max_{q}_arcsec"], getattr(st, f"max_{q}"))
                    for st in spec.stages[::-1] for q in ("transmission_error", "backlash")]
    for _, metric, key, limit in limits[:2] + stage_limits + limits[2:]:
        if limit is None:
            continue
        written = raw_value(spec.raw, key)  # echo the limit exactly as the user wrote it
        limit_arcsec = float(written) if written is not None else float(to_unit(limit, "arcsec"))
        if metric.startswith("budget:"):
            if full is None:
                from wormgear_cli.analysis.budget import budget

                full = budget(spec, analysis)
            value = full.total(metric.split(":", 1)[1])
        else:
            value = analysis.angles[metric]
        out.append(Verdict(key, limit_arcsec, float(to_unit(value, "arcsec"))))
    return out
