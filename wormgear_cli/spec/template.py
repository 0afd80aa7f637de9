"""The commented templates written by ``wormgear new``, generated from the schema.

A template is a complete drive file of ``[[stage]]`` tables in the order asked for (``--stages``,
motor -> output; default ``worm,spur``, the paper's MCH50 rotary table).  Every key of every
table is there: a value with its source, or a comment.  Keys whose value is derived by default are
written as comments holding the value the drive derives, so uncommenting any line keeps the file
valid TOML (and, for the derived keys, the same drive).

Example values, each with its source:

* worm and spur stages: the MCH50 of the paper (its Table 1, its text for the loads, and the
  assumptions named in ``configs/mch50.toml`` for what the paper does not give);
* belt stage: an EQ6-class telescope mount's motor reduction (``configs/eq6-belt-worm.toml``):
  a 12 -> 47 tooth reduction, the 47:12 = 3.917 that, with a 180-tooth worm wheel, gives the
  705 motor turns per RA turn EQMOD mounts report; belt and error sizes are marked as assumptions.
"""

from __future__ import annotations

import json
import math

from wormgear_cli.physics.deformation import rack_contact_ratio, spur_contact_ratio
from wormgear_cli.spec import stages as st
from wormgear_cli.spec.kinds import KINDS
from wormgear_cli.spec.loader import DRIVE_FIELDS, UNIT_SCALE, Field, spec_from_dict

#: example values per stage kind (key units) and where each comes from (the kinds' ``examples``)
STAGE_EXAMPLES: dict[str, dict[str, tuple]] = {name: k.examples for name, k in KINDS.items()}
#: the drive-level tables: values of the MCH50 (configs/mch50.toml)
DRIVE_EXAMPLES: dict[str, tuple] = {
    "stiffness.model": ("iso6336", "ISO 6336-1"),
    "requirements.max_transmission_error_arcsec": (36.0, "the paper's measured +/-0.010 deg, an amplitude"),
    "requirements.max_backlash_arcsec": (252.0, "the paper's measured +/-0.035 deg, the whole reversal"),
}
#: value shown on the commented lines of the optional requirement keys
EXAMPLE_LIMIT_ARCSEC = 60.0
#: values shown on the commented lines of other optional keys (each valid when uncommented)
OPTIONAL_EXAMPLES = {"accuracy_grade": 6, "min_yield": 0.99, "output_torque_Nm": 20.0, "friction_torque_Nm": 2.0,
                     "axial_stiffness_N_per_um": 300.0, "shaft_stiffness_Nm_per_arcmin": 100.0,
                     "targets_deg": (0.0, 47.5, 91.0, 136.5, 178.0, 226.5, 271.0, 317.5)}
#: keys with a default that the template leaves commented (they take effect only with another key)
COMMENTED_DEFAULTS = ("residual_lost_motion_arcsec",)
#: the stage orders ``wormgear new --stages`` offers in its help (any order of kinds is accepted)
SUGGESTED = ("worm", "belt,worm", "spur,worm", "worm,spur")


def _toml_value(f: Field, value) -> str:
    if f.kind == "str":
        return json.dumps(str(value), ensure_ascii=False)  # a TOML basic string, escaped
    if f.kind == "floats":
        return "[" + ", ".join(_num(v) for v in value) + "]"
    if f.kind == "int":
        return str(int(float(value)))
    return _num(value)


def _num(v) -> str:
    v = float(v)
    return str(int(v)) + ".0" if v.is_integer() else repr(v)


def _dflt(f: Field) -> str:
    if f.default is None:
        return "required"
    if f.default == "derived":
        return "derived, see text"
    if f.default == "":
        return "none"
    return f"default {_toml_value(f, f.default)}"


def _document(name: str, kinds: tuple[str, ...]) -> dict:
    """The template's values as a TOML document (dict), for its derived values."""
    doc: dict = {"drive": {"name": name}, "stage": []}
    for kind in kinds:
        table: dict = {"kind": kind}
        for key, (value, _) in STAGE_EXAMPLES[kind].items():
            head, _, tail = key.partition(".")
            (table.setdefault(head, {}) if tail else table)[tail or head] = list(value) if isinstance(
                value, tuple) else value
        doc["stage"].append(table)
    for path, (value, _) in _drive_examples(kinds).items():
        section, key = path.split(".")
        doc.setdefault(section, {})[key] = value
    return doc


def _drive_examples(kinds: tuple[str, ...]) -> dict:
    """The drive-level values: the MCH50's requirements only for the MCH50's own train (its measured
    spans would mean nothing for another drive; there they are commented examples)."""
    if kinds == ("worm", "spur"):
        return DRIVE_EXAMPLES
    return {k: v for k, v in DRIVE_EXAMPLES.items() if not k.startswith("requirements.")}


def _key_lines(f: Field, key: str, value, source: str, derived) -> list[str]:
    src = f"; {source}" if source else ""
    lines = [f"# {f.doc}. {f.expected()}; {_dflt(f)}{src}"]
    if value is not None:
        lines.append(f"{key} = {_toml_value(f, value)}")
    elif derived is not None:
        lines.append(f"# {key} = {_toml_value(f, derived)}  # the value derived for this drive")
    elif f.default not in (None, "", "derived") and key not in COMMENTED_DEFAULTS:
        lines.append(f"{key} = {_toml_value(f, f.default)}")
    elif f.default not in (None, "", "derived"):
        lines.append(f"# {key} = {_toml_value(f, f.default)}")
    elif key in OPTIONAL_EXAMPLES:
        lines.append(f"# {key} = {_toml_value(f, OPTIONAL_EXAMPLES[key])}")
    elif key.startswith("max_"):
        lines.append(f"# {key} = {_num(EXAMPLE_LIMIT_ARCSEC)}")
    elif f.path == "drive.description":
        lines.append(f'{key} = ""')
    else:  # optional, no value for this drive
        lines.append(f"# {key} = {_toml_value(f, OPTIONAL_EXAMPLES.get(key, 0))}")
    return lines


def _derived_value(f: Field, record_values: dict, key: str):
    v = record_values.get(key)
    if v is None or f.default != "derived":
        return None
    if f.kind == "str":
        return v
    return float(f"{v / UNIT_SCALE[f.unit]:.6g}") if f.kind in ("float", "int") else None


def _contact_ratio(spec) -> float:
    """The empirical form's default contact ratio of the template's drive (its last spur stage's, else the
    last worm wheel's against a rack), for the commented ``[stiffness] contact_ratio``."""


    spurs = [s for s in spec.stages if s.kind == "spur"]
    if spurs:
        s = spurs[-1]
        return float(spur_contact_ratio(s.gear.teeth, s.pinion.teeth, s.pressure_angle))
    worms = [s for s in spec.stages if s.kind == "worm"]
    if worms:
        w = worms[-1]
        return float(rack_contact_ratio(w.wheel.teeth / math.cos(w.lead_angle) ** 3, w.transverse_pressure_angle))
    return 1.5


def template(name: str = "my drive", stages=("worm", "spur")) -> str:
    """A complete, valid drive spec of ``[[stage]]`` tables of the kinds ``stages`` (motor -> output),
    every key commented with unit, range, default and source; derived keys commented out with their
    derived value (module docstring).  Raises ValueError for an unknown kind."""

    kinds = tuple(stages)
    bad = [k for k in kinds if k not in st.STAGE_KINDS]
    if bad or not kinds:
        raise ValueError(f"unknown stage kind {bad[0]!r}" if bad else "no stage")
    spec = spec_from_dict(_document(name, kinds), "<template>", name)
    lines = [
        "# wormgear drive spec: the stages from the motor (input) to the output, one [[stage]] table each.",
        "# Units are in the key names; mm for lengths.  Worm and spur values are the MCH50 rotary table of",
        "# the paper (as configs/mch50.toml): its Table 1, its text for the loads, and the assumptions of",
        "# configs/mch50.toml; belt values an EQ6-class mount's motor reduction (configs/eq6-belt-worm.toml).",
        "# Each value says where it comes from.  Check it with: wormgear check THIS.toml",
        "", "[drive]",
    ]
    for f in DRIVE_FIELDS:
        if f.section == "drive":
            lines += _key_lines(f, f.key, name if f.key == "name" else None, "", None)
    for stage, kind in zip(spec.stages, kinds):
        lines += _stage_lines(stage, kind, len(kinds))
    section = None
    for f in DRIVE_FIELDS:
        if f.section == "drive":
            continue
        if f.section != section:
            section = f.section
            lines += ["", f"[{section}]"]
        value, source = _drive_examples(kinds).get(f.path, (None, ""))
        derived = float(f"{_contact_ratio(spec):.6g}") if f.path == "stiffness.contact_ratio" else None
        lines += _key_lines(f, f.key, value, source, derived)
    lines += ["", "# Effects the stage models lack (none is on by default); see the effect catalogue.",
              "# [effects.thermal_backlash]", "# centre_distance_um_per_K = -0.3", "# reference_temperature_C = 20.0",
              ""]
    return "\n".join(lines)


def _stage_lines(stage, kind: str, count: int) -> list[str]:
    """The lines of one ``[[stage]]`` table and its member tables."""
    values = st.record_values(stage)
    where = "motor" if stage.index == 1 else "output" if stage.index == count else "next"
    lines = ["", f"# stage {stage.index} ({kind}){' from the motor' if where == 'motor' else ''}"
             f"{' to the output' if stage.index == count else ''}", "[[stage]]"]
    member = ""
    for f in st.STAGE_FIELDS[kind]:
        head, _, tail = f.path.partition(".")
        if tail and head != member:
            member = head
            lines += ["", f"[stage.{member}]"]
        value, source = STAGE_EXAMPLES[kind].get(f.path, (None, ""))
        if f.path == "kind":
            value, source = kind, ""
        lines += _key_lines(f, tail or head, value, source, _derived_value(f, values, f.path))
    return lines
