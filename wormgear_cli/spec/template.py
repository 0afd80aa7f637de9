"""The commented drive template written by ``wormgear new``, generated from the schema.

The template is the paper's MCH50 rotary table: the values of ``configs/mch50.toml``
(Table 1 of the paper, its text for the loads, and the assumptions named in that file for
what the paper does not give).  Keys whose value is derived by default are written as
comments holding the value the drive derives, so uncommenting any line keeps the file
valid TOML (and, for the derived keys, the same drive).
"""

from __future__ import annotations

import json

from wormgear_cli.spec.loader import FIELDS, UNIT_SCALE, Field

#: values of configs/mch50.toml that the paper's Table 1 does not give (the assumptions named
#: and justified in that file), in key units
MCH50_ASSUMPTIONS: dict = {
    "gear_pair.face_width_mm": 50.0,
    "worm_pair.face_width_mm": 37.5,
    "assembly.worm_eccentricity_mm": 0.012,
    "assembly.worm_bearing_clearance_mm": 0.010,
    "assembly.wheel_eccentricity_mm": 0.016,
    "assembly.wheel_bearing_clearance_mm": 0.015,
    "assembly.worm_pair_errors_mm": (0.030, 0.030, 0.030, 0.030, 0.040, 0.040),
    "requirements.max_transmission_error_arcsec": 72.0,
    "requirements.max_backlash_arcsec": 252.0,
}
#: value shown on the commented lines of the optional requirement keys
EXAMPLE_LIMIT_ARCSEC = 60.0
#: values shown on the commented lines of other optional keys (each valid when uncommented)
OPTIONAL_EXAMPLES = {"accuracy_grade": 6, "min_yield": 0.99}


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


def _value(f: Field):
    """The MCH50 value of a key (key units), or None when the key stays a comment."""
    if f.path in MCH50_ASSUMPTIONS:
        return MCH50_ASSUMPTIONS[f.path]
    if f.table1:
        return f.table1.split()[0]
    if f.default in ("derived", "", None):
        return None
    return f.default


def _derived(values: dict, name: str) -> dict:
    """path -> the value (key units) the drive derives for each key left out of ``values``."""
    from wormgear_cli.spec.loader import spec_from_dict

    data: dict = {}
    for path, v in values.items():
        node = data
        *parents, key = path.split(".")
        for p in parents:
            node = node.setdefault(p, {})
        node[key] = list(v) if isinstance(v, tuple) else v
    spec = spec_from_dict(data, "<template>", name)
    out = {}
    for f in FIELDS:
        if f.path in values or f.kind not in ("float", "int"):
            continue
        record = spec
        for part in f.section.split("."):
            record = getattr(record, part)
        v = getattr(record, f.attr)
        if v is not None:
            out[f.path] = float(f"{v / UNIT_SCALE[f.unit]:.6g}")
    return out


def template(name: str = "my drive") -> str:
    """A complete, valid drive spec: the MCH50 drive of the paper (``configs/mch50.toml``),
    every key commented with unit, range, default and source; derived keys commented out
    with their derived value."""
    values = {"drive.name": name}
    for f in FIELDS:
        v = _value(f)
        if v is not None and f.path != "drive.name":
            values[f.path] = float(v) if f.kind == "float" else (int(float(v)) if f.kind == "int" else v)
    derived = _derived(values, name)
    lines = [
        "# wormgear drive spec.  Units are in the key names; mm for lengths as in the paper's Table 1.",
        "# The values are the MCH50 rotary table of the paper (as configs/mch50.toml): Table 1 where",
        "# it gives them, the paper's text for the loads, and the assumptions of configs/mch50.toml",
        "# (marked 'assumed') elsewhere.  Check it with: wormgear check THIS.toml",
    ]
    section = None
    for f in FIELDS:
        if f.section != section:
            section = f.section
            lines += ["", f"[{section}]"]
        default = f.default
        if default is None:
            dflt = "required"
        elif default == "derived":
            dflt = "derived, see text"
        elif default == "":
            dflt = "none"
        else:
            dflt = f"default {_toml_value(f, default)}"
        src = f"; Table 1: {f.table1}" if f.table1 else ""
        if f.path in MCH50_ASSUMPTIONS:
            src = "; MCH50: " + ("the paper's measured span" if f.section == "requirements" else "assumed") + \
                " (see configs/mch50.toml)"
        lines.append(f"# {f.doc}. {f.expected()}; {dflt}{src}")
        if f.path in values:
            lines.append(f"{f.key} = {_toml_value(f, values[f.path])}")
        elif f.path in derived:
            lines.append(f"# {f.key} = {_toml_value(f, derived[f.path])}  # the value derived for this drive")
        elif f.key in OPTIONAL_EXAMPLES:
            lines.append(f"# {f.key} = {_toml_value(f, OPTIONAL_EXAMPLES[f.key])}")
        elif f.section == "requirements":
            lines.append(f"# {f.key} = {_num(EXAMPLE_LIMIT_ARCSEC)}")
        elif f.kind == "str":
            lines.append(f'{f.key} = ""')
        else:  # optional, no value for this drive (accuracy_grade, pitch deviations without a grade)
            lines.append(f"# {f.key} = {_toml_value(f, OPTIONAL_EXAMPLES.get(f.key, 0))}")
    lines += [
        "",
        "# Effects the paper's model lacks (none is on by default); see the effect catalogue.",
        "# [effects.thermal_backlash]",
        "# centre_distance_um_per_K = -0.3",
        "# reference_temperature_C = 20.0",
        "",
    ]
    return "\n".join(lines)
