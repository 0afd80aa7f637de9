"""Requirement checks (the ``[requirements]`` table) against an analysis."""

from __future__ import annotations

from dataclasses import dataclass

from wormgear_cli.units import to_unit

#: requirement attribute -> analysis metric it limits
REQUIREMENT_METRICS = {
    "max_transmission_error": "total_transmission_error",
    "max_backlash": "total_backlash",
    "max_gear_transmission_error": "gear_transmission_error",
    "max_gear_backlash": "gear_backlash",
    "max_worm_transmission_error": "worm_transmission_error",
    "max_worm_backlash": "worm_backlash",
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
    """Every requirement present in ``spec`` with its verdict (in TOML order of the schema)."""
    out = []
    full = None
    for attr, metric in REQUIREMENT_METRICS.items():
        limit = getattr(spec.requirements, attr)
        if limit is None:
            continue
        key = f"{attr}_arcsec"
        written = spec.raw.get("requirements", {}).get(key)  # echo the limit exactly as the user wrote it
        limit_arcsec = float(written) if written is not None else float(to_unit(limit, "arcsec"))
        if metric.startswith("budget:"):
            if full is None:
                from wormgear_cli.analysis.budget import budget

                full = budget(spec, analysis)
            value = full.total(metric.split(":", 1)[1])
        else:
            value = analysis.angles[metric]
        out.append(Verdict(f"requirements.{key}", limit_arcsec, float(to_unit(value, "arcsec"))))
    return out
