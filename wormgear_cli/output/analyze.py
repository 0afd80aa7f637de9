"""Output of ``wormgear analyze``: the JSON document (the table is drawn from it).

Core code, shared by the CLI and the Python API (:func:`wormgear_cli.api.analyze`).
"""

from __future__ import annotations

from wormgear_cli.spec.kinds import KINDS


def document(spec, result, unit: str) -> dict:
    """The JSON document of ``wormgear analyze`` (angles in ``unit``): each stage's and the total
    values (:meth:`wormgear_cli.analysis.accuracy.Analysis.report`), the full error budget
    (:func:`wormgear_cli.analysis.budget.budget`) and the values used with their origin."""
    from wormgear_cli.analysis.budget import budget  # lazy: keeps analysis.budget off `analyze`'s start-up

    return {**result.report(unit), **budget(spec, result).report(unit), "values_used": values_used(spec)}


#: stage keys whose value and origin analyze lists, per kind: (the parts' tolerances, the assembly's); the
#: kinds' ``listed`` (:mod:`wormgear_cli.spec.kinds`)
LISTED_STAGE_KEYS = {name: k.listed for name, k in KINDS.items()}


def values_used(spec) -> list:
    """``[{"key", "value_um", "origin"}]`` of the tolerances the model reads (origin: spec / grade /
    default), keyed by their TOML path: the parts' tolerances stage by stage from the output back,
    then the assembly's (a spur stage's centre distance and eccentricity: the eccentricity the stage's
    kinematics uses, under the involute reading 0 unless the file states one)."""
    # lazy: spec.stages pulls in numpy, ctypes; this module loads without it
    from wormgear_cli.spec.stages import record_values

    back = spec.stages[::-1]
    out = []
    for group in (0, 1):
        for stage in back:
            values = record_values(stage)
            for key in LISTED_STAGE_KEYS[stage.kind][group]:
                origin, value = stage.origins.get(key, "default"), values[key]
                if key == "eccentricity_mm":  # the Delta e the kinematics uses (involute: only a stated one)
                    value = stage.model_eccentricity
                    if origin == "default" and stage.kinematics == "paper":  # the paper's: the centre-distance error
                        origin = "spec" if stage.origins.get("centre_distance_error_mm") == "spec" else origin
                out.append({"key": stage.paths[key], "value_um": round(float(value) * 1000.0, 6), "origin": origin})
    return out
