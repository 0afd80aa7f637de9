"""The commented drive template written by ``wormgear new``, generated from the schema."""

from __future__ import annotations

import json

from wormgear_cli.spec import FIELDS, Field


def _toml_value(f: Field, value) -> str:
    if f.kind == "str":
        return f'"{value}"'
    if f.kind == "floats":
        return "[" + ", ".join(_num(v) for v in value) + "]"
    if f.kind == "int":
        return str(int(float(value)))
    return _num(value)


def _num(v) -> str:
    v = float(v)
    return str(int(v)) + ".0" if v.is_integer() else repr(v)


def _example(f: Field):
    """Value for the template: Table 1's where it gives one, else the default."""
    if f.table1:
        return f.table1.split()[0]
    return f.default


def template(name: str = "my drive") -> str:
    """A complete, valid drive spec; every key commented with unit, range and default."""
    lines = [
        "# wormgear drive spec.  Units are in the key names; mm for lengths as in the paper's Table 1.",
        "# Values below are the MCH50 rotary table of the paper (Table 1) where it gives them,",
        "# otherwise the documented defaults.  Check it with: wormgear check THIS.toml",
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
        t1 = f"; Table 1: {f.table1}" if f.table1 else ""
        lines.append(f"# {f.doc}. {f.expected()}; {dflt}{t1}")
        if f.path == "drive.name":
            lines.append(f"name = {json.dumps(name, ensure_ascii=False)}")  # a TOML basic string, escaped
        elif f.default == "derived" and not f.table1:
            lines.append(f"# {f.key} = ")
        elif f.section == "requirements":
            lines.append(f"# {f.key} = 60.0")
        elif f.default == "" and f.kind == "str":
            lines.append(f'{f.key} = ""')
        elif f.default == "":  # optional, no value (e.g. accuracy_grade)
            lines.append(f"# {f.key} = ")
        else:
            lines.append(f"{f.key} = {_toml_value(f, _example(f))}")
    lines += [
        "",
        "# Effects the paper's model lacks (none is on by default); see README 'effect catalogue'.",
        "# [effects.thermal_backlash]",
        "# centre_distance_um_per_K = -0.3",
        "# reference_temperature_C = 20.0",
        "",
    ]
    return "\n".join(lines)
