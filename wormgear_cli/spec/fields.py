"""The building blocks of the drive-file schema: a key as data (:class:`Field`), units, ranges
and the check of one value.

Shared by the two forms of a drive file: the stage form (``[[stage]]`` tables,
:mod:`wormgear_cli.spec.stages`) and the legacy two-table form (:data:`wormgear_cli.spec.loader.FIELDS`).
"""

from __future__ import annotations

import json
import math
from typing import Any, NamedTuple

from wormgear_cli.errors import did_you_mean
from wormgear_cli.units import ARCSEC, DEG

#: unit suffix -> factor to the internal unit
UNIT_SCALE = {
    "mm": 1.0,
    "um": 1e-3,
    "deg": DEG,
    "N": 1.0,
    "GPa": 1000.0,
    "ppm/K": 1e-6,
    "arcsec": ARCSEC,
    "N m": 1.0,
    "K": 1.0,
    "N/um": 1000.0,  # -> N/mm
    "N m/arcmin": 1.0 / (60.0 * ARCSEC),  # -> N m/rad
    "-": 1.0,
    "": 1.0,
}


# an immutable named record built as a NamedTuple, not a frozen dataclass: it is created when
# ``analyze`` starts (0.1 ms against 0.6 ms; docs/development.md, "Start-up")
class Field(NamedTuple):
    """One key of the drive spec.

    ``path``: dotted TOML path.  ``attr``: attribute name on the section
    dataclass.  ``kind``: "float", "int", "str", "floats" (array).
    ``unit``: unit of the key (see :data:`UNIT_SCALE`).  ``default``: in the
    key's unit; ``None`` means required; ``"derived"`` is computed from
    other keys (described in ``doc``).  ``lo``/``hi``: allowed range in the
    key's unit with ``lo_open``/``hi_open`` for strict bounds.  ``table1``:
    the value the paper's Table 1 (or its text) gives for the MCH50, or "".
    """

    path: str
    attr: str
    kind: str
    unit: str
    default: Any
    doc: str
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    table1: str = ""
    choices: tuple = ()
    length: int | None = None

    @property
    def section(self) -> str:
        """The table holding the key ("" for a key at the top of a stage table)."""
        return self.path.rsplit(".", 1)[0] if "." in self.path else ""

    @property
    def key(self) -> str:
        return self.path.rsplit(".", 1)[-1]

    def expected(self) -> str:
        """Human description of what the key takes."""
        if self.kind == "str":
            if self.choices:
                return "one of " + ", ".join(f'"{c}"' for c in self.choices)
            return "a string"
        if self.kind == "int":
            what = "an integer"
        elif self.kind == "floats":
            what = f"an array of {self.length} numbers" if self.length else "an array of numbers"
        else:
            what = "a number"
        rng = ""
        if self.lo is not None and self.hi is not None:
            rng = f" in {'(' if self.lo_open else '['}{fmt(self.lo)}, {fmt(self.hi)}{')' if self.hi_open else ']'}"
        elif self.lo is not None:
            rng = f" {'>' if self.lo_open else '>='} {fmt(self.lo)}"
        unit = f" [{self.unit}]" if self.unit not in ("", "-") else ""
        return what + rng + unit


def fmt(x: float) -> str:
    return f"{x:g}"


def field_(path, attr, unit, default, doc, lo=None, hi=None, lo_open=False, hi_open=False, table1="", kind="float"):
    return Field(path, attr, kind, unit, default, doc, lo, hi, lo_open, hi_open, table1)


def teeth_field(path, attr, doc, table1, lo=1):
    return Field(path, attr, "int", "-", None, doc, lo, 10000, False, False, table1)


def tol_field(path, attr, doc, table1="", default=0.0):
    return field_(path, attr, "mm", default, doc, **TOLERANCE, table1=table1)


# Physical ranges shared by several keys (in the keys' units).  Upper bounds keep the
# models finite and catch unit mistakes (a tolerance of 30 mm was meant as 30 um).
MODULE = dict(lo=0.05, hi=100.0)  # [mm]
PRESSURE_ANGLE = dict(lo=1.0, hi=45.0, hi_open=True)  # [deg]
FACE_WIDTH = dict(lo=0.1, hi=5000.0)  # [mm]
TOLERANCE = dict(lo=0.0, hi=10.0)  # [mm]
FORCE = dict(lo=0.0, hi=1e8)  # [N]
FACTOR = dict(lo=0.01, hi=10.0)  # ISO 6336 correction factors [-]


def phase_field(path, attr, doc):
    return field_(path, attr, "deg", 0.0, doc, lo=-360.0, hi=360.0)


#: gear-stage kinematics readings (``gear_pair.kinematics``)
KINEMATICS = ("paper", "involute")


def gear_grade_fields(section, name):
    """ISO 1328-1 grade and the pitch deviations it sets (explicit keys win over the grade)."""
    return (
        Field(f"{section}.accuracy_grade", "accuracy_grade", "int", "-", "",
              f"ISO 1328-1:2013 flank tolerance class A of {name}; sets the deviations below (and the "
              "profile error) unless given explicitly", 1, 11),
        field_(f"{section}.cumulative_pitch_deviation_mm", "cumulative_pitch_deviation", "mm", "derived",
               f"cumulative pitch deviation F_p of {name} (default: F_pT of accuracy_grade, else 0)", **TOLERANCE),
        field_(f"{section}.single_pitch_deviation_mm", "single_pitch_deviation", "mm", "derived",
               f"single pitch deviation f_p of {name} (default: f_pT of accuracy_grade, else 0)", **TOLERANCE),
        phase_field(f"{section}.cumulative_pitch_phase_deg", "cumulative_pitch_phase",
                    f"phase of the cumulative pitch deviation of {name} (once per turn of its shaft)"),
        phase_field(f"{section}.single_pitch_phase_deg", "single_pitch_phase",
                    f"phase of the single pitch (mesh-order) error of {name}"),
    )


class Missing:
    def __repr__(self):
        return "<missing>"


MISSING = Missing()


def get_path(data: dict, dotted: str):
    node: Any = data
    for part in dotted.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return node


def quote(text: str) -> str:
    """A string value as shown in a message: double-quoted, escapes visible, one line."""
    return json.dumps(text, ensure_ascii=False)


def type_name(v) -> str:
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "an array",
            dict: "a table"}.get(type(v), type(v).__name__)


def check_value(f: Field, raw) -> tuple[str | None, Any]:
    """Return (problem, converted value)."""
    if f.kind == "str":
        if not isinstance(raw, str):
            return f"expected {f.expected()}, got {type_name(raw)}", None
        if f.path == "drive.name" and not raw.isprintable():
            return f"expected a single-line name without control characters, got {quote(raw)}", None
        if f.choices and raw not in f.choices:
            lowered = {c.lower(): c for c in f.choices}
            hint = did_you_mean(raw.lower(), lowered, show=lambda m: f'"{lowered[m]}"')
            return f"expected {f.expected()}, got {quote(raw)}{hint}", None
        return None, raw
    if f.kind == "floats":
        if not isinstance(raw, list):
            return f"expected {f.expected()}, got {type_name(raw)}", None
        if f.length is not None and len(raw) != f.length:
            return f"expected {f.expected()}, got {len(raw)} values", None
        out = []
        for i, item in enumerate(raw):
            err = number_problem(f, item)
            if err:
                return f"element {i}: {err}", None
            out.append(float(item) * UNIT_SCALE[f.unit])
        return None, tuple(out)
    err = number_problem(f, raw)
    if err:
        return err, None
    if f.kind == "int":
        return None, int(raw)
    return None, float(raw) * UNIT_SCALE[f.unit]


def number_problem(f: Field, raw) -> str | None:
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        shown = quote(raw) if isinstance(raw, str) else type_name(raw)
        return f"expected {f.expected()}, got {shown}"
    if f.kind == "int" and not isinstance(raw, int):
        if isinstance(raw, float) and math.isfinite(raw) and raw.is_integer():
            pass
        else:
            return f"expected {f.expected()}, got {raw!r} (not a whole number)"
    if isinstance(raw, float) and not math.isfinite(raw):
        return f"expected {f.expected()}, got {raw!r}"
    if isinstance(raw, int) and abs(raw) > 1e300:
        return f"expected {f.expected()}, got an integer of {len(str(abs(raw)))} digits"
    v = float(raw)
    if f.lo is not None and (v < f.lo or (f.lo_open and v == f.lo)):
        return f"expected {f.expected()}, got {raw!r}"
    if f.hi is not None and (v > f.hi or (f.hi_open and v == f.hi)):
        return f"expected {f.expected()}, got {raw!r}"
    return None


