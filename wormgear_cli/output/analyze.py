"""Output of ``wormgear analyze``: the JSON document (the table is drawn from it).

Core code, shared by the CLI and the Python API (:func:`wormgear_cli.api.analyze`).
"""

from __future__ import annotations


def document(spec, result, unit: str) -> dict:
    """The JSON document of ``wormgear analyze`` (angles in ``unit``): the paper's stage and
    total values (:meth:`wormgear_cli.analysis.accuracy.Analysis.report`), the full error budget
    (:func:`wormgear_cli.analysis.budget.budget`) and the values used with their origin."""
    from wormgear_cli.analysis.budget import budget

    return {**result.report(unit), **budget(spec, result).report(unit), "values_used": values_used(spec)}


#: spec keys whose value and origin analyze lists (the tolerances the budget and the paper use)
LISTED_KEYS = (
    "gear_pair.output_gear.cumulative_pitch_deviation_mm", "gear_pair.output_gear.single_pitch_deviation_mm",
    "gear_pair.output_gear.profile_error_mm", "gear_pair.output_gear.thickness_deviation_mm",
    "gear_pair.pinion.cumulative_pitch_deviation_mm", "gear_pair.pinion.single_pitch_deviation_mm",
    "gear_pair.pinion.profile_error_mm", "gear_pair.pinion.thickness_deviation_mm",
    "worm_pair.lead_error_mm", "worm_pair.wheel.radial_composite_error_mm",
    "worm_pair.wheel.cumulative_pitch_deviation_mm", "assembly.gear_centre_distance_error_mm",
    "assembly.gear_eccentricity_mm",
)


def values_used(spec) -> list:
    """``[{"key", "value_um", "origin"}]`` for :data:`LISTED_KEYS` (origin: spec / grade / default)."""
    from wormgear_cli.spec.loader import FIELD_BY_PATH, value_origin

    out = []
    for path in LISTED_KEYS:
        f = FIELD_BY_PATH[path]
        node = spec
        for part in f.section.split("."):
            node = getattr(node, part)
        value = getattr(node, f.attr)
        origin = value_origin(spec, path)
        if path == "assembly.gear_eccentricity_mm" and origin == "default":
            origin = "spec" if value_origin(spec, "assembly.gear_centre_distance_error_mm") == "spec" else origin
        out.append({"key": path, "value_um": round(float(value) * 1000.0, 6), "origin": origin})
    return out
