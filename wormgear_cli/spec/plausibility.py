"""Plausibility: every length, angle and tolerance of a drive checked against the drive's own scale.

A key's range (:mod:`wormgear_cli.spec.fields`) only says what the models can compute; this module
says what a built drive of this size can be.  Two verdicts, both per key and in one line:

* **implausible** (a warning, the run goes on): a value far beyond what a gear of this size has,
  e.g. a tolerance more than ten times the deviation an ISO 1328 accuracy grade of 12 allows at
  this module and diameter (:func:`wormgear_cli.physics.iso1328.coarse_scale`), most often a
  micrometre value typed into a millimetre key (``lead_error_mm = 3``); the line names the key, the
  value, the scale it was held against and the likely slip;
* **impossible** (an error, exit 2): a value or combination no drive can have, e.g. a
  centre-distance error or a runout deeper than the teeth's working depth 2 m (the gears would
  leave mesh or jam), a deviation larger than the part's pitch radius, a tooth-thickness
  allowance thicker than the tooth, a spur gear or wheel of three teeth or fewer.

The checks are data (:data:`RULES`, :data:`SHAPES`), in the spirit of the validity ranges that
engineering libraries keep beside each correlation: key, the scale it is held against, the
factor beyond which it is implausible and the scale beyond which it is impossible.  No I/O.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from wormgear_cli.physics.iso1328 import coarse_scale
from wormgear_cli.spec.kinds import KINDS
from wormgear_cli.spec.stages import record_values


class Rule(NamedTuple):
    """A tolerance key of the stage kinds ``kinds``: implausible above ``factor`` x the scale
    ``scale``; impossible above the scale ``limit`` (None: never)."""

    key: str
    kinds: tuple
    scale: str
    factor: float
    limit: str | None


#: what each scale is, in messages
SCALE_WORDS = {
    "F_pT": "the cumulative pitch deviation of ISO 1328 grade 12 at this size",
    "f_pT": "the single pitch deviation of ISO 1328 grade 12 at this size",
    "F_alphaT": "the profile deviation of ISO 1328 grade 12 at this size",
    "F_rT": "the runout of ISO 1328 grade 12 at this size",
    "F_i2T": "the radial composite deviation of ISO 1328-2 grade 12 at this size",
    "tooth": "the tooth's thickness pi m / 2",
    "depth": "the teeth's working depth 2 m",
    "radius": "the part's pitch radius",
    "pitch": "the belt's pitch",
}

#: the tolerance keys and their scales (keys of one member share the member's scale): each kind's
#: ``plausible`` (:mod:`wormgear_cli.spec.kinds`)
RULES = tuple(Rule(p.key, (name,), p.scale, p.factor, p.limit) for name, k in KINDS.items() for p in k.plausible)

#: teeth of a spur gear or worm wheel at or below which it cannot work (pointed, undercut away)
FEWEST_TEETH = 3
#: fewer teeth than this on a spur gear: a warning (a standard 20 deg gear is undercut below 17 teeth;
#: motor pinions down to 9 teeth are made with a positive profile shift, e.g. the HEQ5's 9-tooth motor gear)
UNDERCUT_TEETH = 9
#: plausible ranges of shape ratios (warnings): (lo, hi, what, the usual range in words)
SHAPES = {
    "diameter_quotient": (4.0, 40.0, "the worm's diameter quotient q = d1 / m", "6 to 20 are usual (DIN 3975)"),
    "face_width_ratio": (2.0, 60.0, "the face width over the module b / m", "6 to 30 are usual"),
    "pressure_angle": (10.0, 35.0, "the pressure angle [deg]", "14.5 to 25 are made"),
}


def _member(stage, key: str):
    """(reference diameter [mm], pitch radius [mm]) of the part a stage key belongs to (its kind's)."""
    return KINDS[stage.kind].part_size(stage, key)


def _scale(stage, key: str, name: str) -> float:
    """Scale ``name`` [mm] of a stage key (module docstring)."""
    if name == "pitch":
        return stage.pitch
    d, r = _member(stage, key)
    if name == "radius":
        return r
    if name == "tooth":
        return math.pi * stage.module / 2.0
    if name == "depth":
        return 2.0 * stage.module

    return coarse_scale(stage.module, d)[name] * 1e-3


def _value(stage, values: dict, key: str) -> float:
    v = values[key]
    return max(v) if isinstance(v, tuple) else float(v)


def review(spec) -> tuple[list[str], list[str]]:
    """(problems, warnings) of ``spec``: one line each, naming the file, the key (its TOML path), the
    value and what it was held against (module docstring).  Problems are for a SpecError (exit 2)."""
    problems: list[str] = []
    warnings: list[str] = []
    for stage in spec.stages:
        values = record_values(stage)
        for rule in RULES:
            if stage.kind not in rule.kinds or (rule.key == "eccentricity_mm" and
                                                stage.origins.get(rule.key) != "spec"):
                continue
            _judge(spec.source, stage, values, rule, problems, warnings)
        _teeth(spec.source, stage, problems, warnings)
        _shapes(spec.source, stage, warnings)
    return problems, warnings


def _judge(source, stage, values: dict, rule: Rule, problems: list, warnings: list) -> None:
    """One tolerance key against its scale and its limit."""
    value = _value(stage, values, rule.key)
    if value <= 0.0:
        return
    path = stage.paths[rule.key]
    shown = f"{path} = {value:g} mm"
    if rule.limit is not None:
        limit = _scale(stage, rule.key, rule.limit)
        if value > limit:
            problems.append(f"{source}: {shown}: more than {SCALE_WORDS[rule.limit]} ({limit:.4g} mm), which no "
                            f"built drive can have; {_slip(value, limit)}")
            return
    scale = _scale(stage, rule.key, rule.scale)
    if value > rule.factor * scale:
        warnings.append(f"{source}: {shown} is {value / scale:.3g} times {SCALE_WORDS[rule.scale]} "
                        f"({scale:.3g} mm): {_slip(value, rule.factor * scale)}")


def _slip(value: float, plausible: float) -> str:
    """The likely slip: a micrometre value typed into a millimetre key when value / 1000 is plausible."""
    if value / 1000.0 <= plausible:
        return f"micrometres typed as millimetres? ({value:g} um is {value / 1000.0:g} mm)"
    return "check the value and its unit"


def _teeth(source, stage, problems: list, warnings: list) -> None:
    """Spur gears and worm wheels of too few teeth."""
    parts: tuple[tuple[str, Any], ...]
    if stage.kind == "spur":
        parts = (("pinion", stage.pinion), ("gear", stage.gear))
    else:
        parts = (("wheel", stage.wheel),) if stage.kind == "worm" else ()
    for name, part in parts:
        z, path = part.teeth, stage.paths[f"{name}.teeth"]
        if z <= FEWEST_TEETH:
            problems.append(f"{source}: {path} = {z}: a gear of {z} {'tooth' if z == 1 else 'teeth'} cannot mesh "
                            "continuously (its teeth "
                            "would be pointed and undercut away); check the tooth counts")
        elif z < UNDERCUT_TEETH and stage.kind == "spur":
            warnings.append(f"{source}: {path} = {z}: fewer than {UNDERCUT_TEETH} teeth; a standard 20 deg "
                            "spur gear is undercut below 17 teeth (14 with slight undercut), pinions of 9 and more are "
                            "made with a profile shift, which the model does not represent; check the tooth count")


def _shapes(source, stage, warnings: list) -> None:
    """Angles and proportions against the ranges gears are made in (:data:`SHAPES`)."""
    if stage.kind not in ("worm", "spur"):  # the shapes of gear meshes
        return
    checks = [("face_width_ratio", stage.face_width / stage.module, stage.paths["face_width_mm"])]
    if stage.kind == "worm":
        checks.append(("diameter_quotient", stage.worm.starts / math.tan(stage.lead_angle),
                       stage.paths["lead_angle_deg"]))
        checks.append(("pressure_angle", math.degrees(stage.normal_pressure_angle),
                       stage.paths["normal_pressure_angle_deg"]))
    else:
        checks.append(("pressure_angle", math.degrees(stage.pressure_angle), stage.paths["pressure_angle_deg"]))
    for name, value, path in checks:
        lo, hi, what, usual = SHAPES[name]
        if not lo <= value <= hi:
            warnings.append(f"{source}: {path}: gives {what} = {value:.3g}, outside {lo:g} to {hi:g} ({usual}); "
                            "check the value and its unit")
