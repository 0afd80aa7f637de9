"""Drive specs: load and validate a TOML drive file into immutable dataclasses.

The schema is data (:data:`FIELDS`): every key with its section, unit,
default, physical range, whether the paper's Table 1 gives it, and a
description.  The loader, ``wormgear new`` (the commented template), the
generated key reference (docs/reference/spec.md) and ``sweep --param`` all read it.

Units live in key names (``module_mm``, ``pressure_angle_deg``) and are
converted once, here, to the internal system: lengths [mm], forces [N],
moduli [N/mm^2], angles [rad], expansion [1/K], temperatures [degC].

Every problem is collected and reported at once as a :class:`SpecError`,
one line each: ``FILE: KEY: what is expected``.
"""

from __future__ import annotations

import copy
import math
from dataclasses import FrozenInstanceError, dataclass, field
from pathlib import Path
from types import MappingProxyType, SimpleNamespace
from typing import Any, NamedTuple

from wormgear_cli.errors import SpecError, did_you_mean
from wormgear_cli.physics.deformation import DEFORMATION_MODELS
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
        return self.path.rsplit(".", 1)[0]

    @property
    def key(self) -> str:
        return self.path.rsplit(".", 1)[1]

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
            rng = f" in {'(' if self.lo_open else '['}{_fmt(self.lo)}, {_fmt(self.hi)}{')' if self.hi_open else ']'}"
        elif self.lo is not None:
            rng = f" {'>' if self.lo_open else '>='} {_fmt(self.lo)}"
        unit = f" [{self.unit}]" if self.unit not in ("", "-") else ""
        return what + rng + unit


def _fmt(x: float) -> str:
    return f"{x:g}"


def _f(path, attr, unit, default, doc, lo=None, hi=None, lo_open=False, hi_open=False, table1="", kind="float"):
    return Field(path, attr, kind, unit, default, doc, lo, hi, lo_open, hi_open, table1)


def _teeth(path, attr, doc, table1, lo=1):
    return Field(path, attr, "int", "-", None, doc, lo, 10000, False, False, table1)


def _tol(path, attr, doc, table1="", default=0.0):
    return _f(path, attr, "mm", default, doc, **TOLERANCE, table1=table1)


# Physical ranges shared by several keys (in the keys' units).  Upper bounds keep the
# models finite and catch unit mistakes (a tolerance of 30 mm was meant as 30 um).
MODULE = dict(lo=0.05, hi=100.0)  # [mm]
PRESSURE_ANGLE = dict(lo=1.0, hi=45.0, hi_open=True)  # [deg]
FACE_WIDTH = dict(lo=0.1, hi=5000.0)  # [mm]
TOLERANCE = dict(lo=0.0, hi=10.0)  # [mm]
FORCE = dict(lo=0.0, hi=1e8)  # [N]
FACTOR = dict(lo=0.01, hi=10.0)  # ISO 6336 correction factors [-]


def _phase(path, attr, doc):
    return _f(path, attr, "deg", 0.0, doc, lo=-360.0, hi=360.0)


#: gear-stage kinematics readings (``gear_pair.kinematics``)
KINEMATICS = ("paper", "involute")


def _gear_grade_fields(section, name):
    """ISO 1328-1 grade and the pitch deviations it sets (explicit keys win over the grade)."""
    return (
        Field(f"{section}.accuracy_grade", "accuracy_grade", "int", "-", "",
              f"ISO 1328-1:2013 flank tolerance class A of {name}; sets the deviations below (and the "
              "profile error) unless given explicitly", 1, 11),
        _f(f"{section}.cumulative_pitch_deviation_mm", "cumulative_pitch_deviation", "mm", "derived",
           f"cumulative pitch deviation F_p of {name} (default: F_pT of accuracy_grade, else 0)", **TOLERANCE),
        _f(f"{section}.single_pitch_deviation_mm", "single_pitch_deviation", "mm", "derived",
           f"single pitch deviation f_p of {name} (default: f_pT of accuracy_grade, else 0)", **TOLERANCE),
        _phase(f"{section}.cumulative_pitch_phase_deg", "cumulative_pitch_phase",
               f"phase of the cumulative pitch deviation of {name} (once per turn of its shaft)"),
        _phase(f"{section}.single_pitch_phase_deg", "single_pitch_phase",
               f"phase of the single pitch (mesh-order) error of {name}"),
    )


#: The drive-spec schema.  Order = order in the template and the key reference (docs/reference/spec.md).
FIELDS: tuple[Field, ...] = (
    Field("drive.name", "name", "str", "", "derived", "name shown in reports (default: the file name without .toml)"),
    Field("drive.description", "description", "str", "", "", "free text"),
    # --- stage 2: spur gear pair -------------------------------------------------
    _f("gear_pair.module_mm", "module", "mm", None, "module m1 of the spur pair", **MODULE, table1="2.5"),
    _f("gear_pair.pressure_angle_deg", "pressure_angle", "deg", None, "pressure angle alpha", **PRESSURE_ANGLE,
       table1="20"),
    _f("gear_pair.face_width_mm", "face_width", "mm", "derived",
       "face width b of the spur mesh (default: 10 x module)", **FACE_WIDTH),
    Field("gear_pair.kinematics", "kinematics", "str", "", "paper",
          "gear-stage kinematics: paper (the paper's Delta phi_cc/Delta phi_ch as printed) or involute "
          "(eccentricity e -> TE e/r_b; centre-distance error -> backlash 2 Delta a tan(alpha), no TE; "
          "tooth-thickness allowances in the backlash; see docs/budget.md)",
          choices=KINEMATICS),
    _teeth("gear_pair.output_gear.teeth", "teeth", "teeth z1 of the output gear (gear 1)", "144"),
    *_gear_grade_fields("gear_pair.output_gear", "gear 1"),
    _tol("gear_pair.output_gear.profile_error_mm", "profile_error",
         "profile error of gear 1 (not used by the paper's gear-stage equations)", "0.007"),
    _tol("gear_pair.output_gear.thickness_deviation_mm", "thickness_deviation",
         "tooth thickness deviation of gear 1 (not used by the paper's gear-stage equations)", "0.055"),
    _teeth("gear_pair.pinion.teeth", "teeth", "teeth z2 of the pinion (gear 2)", "18"),
    *_gear_grade_fields("gear_pair.pinion", "gear 2"),
    _tol("gear_pair.pinion.profile_error_mm", "profile_error", "profile error of gear 2 (not used by the paper's "
         "gear-stage equations)", "0.008"),
    _tol("gear_pair.pinion.thickness_deviation_mm", "thickness_deviation",
         "tooth thickness deviation of gear 2 (not used by the paper's gear-stage equations)", "0.045"),
    # --- stage 1: worm pair ------------------------------------------------------
    _f("worm_pair.module_mm", "module", "mm", None, "axial module m2 (= wheel transverse module)", **MODULE,
       table1="2.5"),
    _f("worm_pair.normal_pressure_angle_deg", "normal_pressure_angle", "deg", None, "normal pressure angle alpha_n",
       **PRESSURE_ANGLE, table1="20"),
    _f("worm_pair.lead_angle_deg", "lead_angle", "deg", None, "lead angle lambda of the worm", lo=0.1, hi=45.0,
       hi_open=True, table1="3.178"),
    _f("worm_pair.transverse_pressure_angle_deg", "transverse_pressure_angle", "deg", "derived",
       "wheel transverse pressure angle alpha_2 (default: atan(tan alpha_n / cos lambda), DIN 3975)",
       **PRESSURE_ANGLE),
    _f("worm_pair.face_width_mm", "face_width", "mm", "derived", "face width of the wheel (default: 10 x module)",
       **FACE_WIDTH),
    _tol("worm_pair.lead_error_mm", "lead_error", "worm lead error f_hL", "0.030"),
    _phase("worm_pair.lead_error_phase_deg", "lead_error_phase", "phase of the lead error (once per worm turn)"),
    Field("worm_pair.worm.starts", "starts", "int", "-", None, "number of worm starts (threads)", 1, 100,
          table1="1"),
    _tol("worm_pair.worm.profile_error_mm", "profile_error", "worm profile error f_t1", "0.036"),
    _tol("worm_pair.worm.thickness_deviation_mm", "thickness_deviation", "worm thickness deviation T_s1", "0.045"),
    _teeth("worm_pair.wheel.teeth", "teeth", "teeth z3 of the worm wheel", "30"),
    _tol("worm_pair.wheel.profile_error_mm", "profile_error", "wheel profile error f_t2", "0.011"),
    _tol("worm_pair.wheel.thickness_deviation_mm", "thickness_deviation", "wheel thickness deviation T_s2",
         "0.090"),
    _tol("worm_pair.wheel.radial_composite_error_mm", "radial_composite_error", "wheel radial composite error F_i",
         "0.036"),
    _phase("worm_pair.wheel.radial_composite_phase_deg", "radial_composite_phase",
           "phase of the radial composite error (once per wheel turn)"),
    _tol("worm_pair.wheel.cumulative_pitch_deviation_mm", "cumulative_pitch_deviation",
         "cumulative pitch deviation F_p of the wheel (budget source, order i_c; part of what F_i "
         "measures, so leave 0 unless measured separately)"),
    _phase("worm_pair.wheel.cumulative_pitch_phase_deg", "cumulative_pitch_phase",
           "phase of the wheel's cumulative pitch deviation (once per wheel turn)"),
    # --- assembly ----------------------------------------------------------------
    _tol("assembly.gear_centre_distance_error_mm", "gear_centre_distance_error",
         "centre-distance error of the spur pair", "0.030"),
    _f("assembly.gear_eccentricity_mm", "gear_eccentricity", "mm", "derived",
       "the paper's Delta e (default: gear_centre_distance_error_mm)", **TOLERANCE),
    _phase("assembly.gear_eccentricity_phase_deg", "gear_eccentricity_phase",
           "phase of Delta e (once per pinion turn)"),
    _tol("assembly.worm_centre_distance_error_mm", "worm_centre_distance_error",
         "centre-distance error f_a of the worm pair", "0.035"),
    _tol("assembly.worm_eccentricity_mm", "worm_eccentricity", "worm shaft eccentricity S1"),
    _phase("assembly.worm_eccentricity_phase_deg", "worm_eccentricity_phase", "phase of S1 (once per worm turn)"),
    _tol("assembly.worm_bearing_clearance_mm", "worm_bearing_clearance", "worm bearing clearance C1"),
    _tol("assembly.wheel_eccentricity_mm", "wheel_eccentricity", "wheel eccentricity S2"),
    _phase("assembly.wheel_eccentricity_phase_deg", "wheel_eccentricity_phase", "phase of S2 (once per wheel turn)"),
    _tol("assembly.wheel_bearing_clearance_mm", "wheel_bearing_clearance", "wheel bearing clearance C2"),
    Field("assembly.worm_pair_errors_mm", "worm_pair_errors", "floats", "mm", (0.0,) * 6,
          "the paper's six e_i of the worm pair (shaft-position and alignment errors entering Delta j)",
          0.0, 10.0, length=6),
    # --- loads -------------------------------------------------------------------
    _f("loads.gear_normal_force_N", "gear_normal_force", "N", 0.0, "normal force F_N on the spur teeth", **FORCE,
       table1="666 (text)"),
    _f("loads.worm_normal_force_N", "worm_normal_force", "N", 0.0, "normal force F_N on the worm mesh", **FORCE,
       table1="85 (text)"),
    # --- stiffness (deformation model) -------------------------------------------
    Field("stiffness.model", "model", "str", "", "iso6336",
          "deflection model: iso6336 (ISO 6336-1 c') or empirical (the paper's form)",
          choices=tuple(DEFORMATION_MODELS)),
    _f("stiffness.iso_cm", "iso_cm", "-", 0.8, "ISO 6336 C_M (theory-to-measurement)", **FACTOR),
    _f("stiffness.iso_cr", "iso_cr", "-", 1.0, "ISO 6336 C_R (blank; 1 = solid)", **FACTOR),
    _f("stiffness.iso_cb", "iso_cb", "-", 0.975, "ISO 6336 C_B (basic rack)", **FACTOR),
    _f("stiffness.iso_ka", "iso_ka", "-", 1.0,
       "ISO 6336 K_A (application factor) in the line load F_t K_A / b that scales c' below 100 N/mm",
       **FACTOR),
    _f("stiffness.empirical_a1", "empirical_a1", "-", 4.0,
       "the paper's A1 (its calibration: docs/models.md, deformation models)",
       lo=0.0, hi=1000.0),
    _f("stiffness.empirical_b", "empirical_b", "-", 1.0, "the paper's exponent B", lo=-10.0, hi=10.0),
    _f("stiffness.empirical_c", "empirical_c", "-", 1.0, "the paper's exponent C", lo=-10.0, hi=10.0),
    _f("stiffness.contact_ratio", "contact_ratio", "-", "derived",
       "contact ratio eps of the empirical form (default: standard spur eps_alpha)", lo=1.0, hi=3.0),
    _f("stiffness.empirical_lambda2", "empirical_lambda2", "-", 0.0, "the paper's lambda2 (undefined there)",
       lo=0.0, hi=100.0),
    # --- materials ---------------------------------------------------------------
    _f("materials.gear_elastic_modulus_GPa", "gear_elastic_modulus", "GPa", 206.0,
       "Young's modulus E of the spur gears (steel)", lo=1.0, hi=1000.0),
    _f("materials.worm_elastic_modulus_GPa", "worm_elastic_modulus", "GPa", 206.0,
       "Young's modulus of the worm (steel)", lo=1.0, hi=1000.0),
    _f("materials.wheel_elastic_modulus_GPa", "wheel_elastic_modulus", "GPa", 98.0,
       "Young's modulus of the wheel (CuSn12 bronze ~ 98)", lo=1.0, hi=1000.0),
    _f("materials.worm_expansion_ppm_per_K", "worm_expansion", "ppm/K", 11.5,
       "thermal expansion of the worm (steel 11.5)", lo=-5.0, hi=50.0),
    _f("materials.wheel_expansion_ppm_per_K", "wheel_expansion", "ppm/K", 18.5,
       "thermal expansion of the wheel (CuSn12 bronze 18.5)", lo=-5.0, hi=50.0),
    _f("materials.housing_expansion_ppm_per_K", "housing_expansion", "ppm/K", 10.5,
       "thermal expansion of the housing (grey cast iron 10.5)", lo=-5.0, hi=50.0),
    _f("materials.housing_rise_ratio", "housing_rise_ratio", "-", 1.0,
       "the housing's temperature rise per kelvin of the measured (mesh/oil) temperature; used by diagnose's "
       "thermal_backlash prediction (1: the whole drive warms alike; a running worm drive warms at the mesh, "
       "so less than 1)", lo=0.0, hi=1.5, lo_open=True),
    # --- requirements (all optional) ---------------------------------------------
    *(
        _f(f"requirements.max_{name}_arcsec", f"max_{name}", "arcsec", "", f"limit on {what}", lo=0.0, hi=1e9,
           lo_open=True)
        for name, what in (
            ("transmission_error", "the total transmission error at the output"),
            ("backlash", "the total backlash at the output"),
            ("gear_transmission_error", "the gear-stage TE at its output"),
            ("gear_backlash", "the gear-stage backlash"),
            ("worm_transmission_error", "the worm-stage TE at the wheel"),
            ("worm_backlash", "the worm-stage backlash at the wheel"),
            ("budget_linear", "the full budget's TE at the output, linear sum of the lines' maxima"),
            ("budget_rss", "the full budget's TE at the output, static lines + root-sum-square of the periodic"),
            ("budget_peak", "the full budget's TE at the output, exact peak of the phased curve"),
        )
    ),
    _f("requirements.min_yield", "min_yield", "-", "", "least fraction of built drives meeting every limit "
       "(estimated by wormgear tolerance; see [statistics])", lo=0.0, hi=1.0, lo_open=True, hi_open=True),
)

FIELD_BY_PATH: dict[str, Field] = {f.path: f for f in FIELDS}
SECTIONS: tuple[str, ...] = tuple(dict.fromkeys(f.section for f in FIELDS))
REQUIRED_SECTIONS = ("gear_pair", "gear_pair.output_gear", "gear_pair.pinion", "worm_pair", "worm_pair.worm",
                     "worm_pair.wheel")

# --- immutable records, one class per section, generated from the schema -----------------


class Section(SimpleNamespace):
    """An immutable record of one spec section (attributes = the section's ``attr`` names
    and its sub-sections).  Cheaper to create than a dataclass per section, which
    keeps start-up fast; ``_replace(**changes)`` returns a changed copy."""

    __slots__ = ()

    def __setattr__(self, name, value):
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name):
        raise FrozenInstanceError(f"cannot delete field {name!r}")

    def __hash__(self):
        return hash((type(self).__name__, tuple(sorted(self.__dict__.items(), key=lambda kv: kv[0]))))

    def _replace(self, **changes):
        unknown = set(changes) - set(self.__dict__)
        if unknown:
            raise TypeError(f"{type(self).__name__} has no field(s) {sorted(unknown)}")
        return type(self)(**{**self.__dict__, **changes})


def _class_name(section: str) -> str:
    return "".join(part.capitalize() for part in section.replace(".", "_").split("_"))


_SECTION_CLASSES: dict[str, type] = {sec: type(_class_name(sec), (Section,), {"__slots__": ()}) for sec in SECTIONS}
_SECTION_SET = frozenset(SECTIONS)


def _section_tables() -> tuple[dict[str, tuple], dict[str, tuple]]:
    fields: dict[str, list] = {sec: [] for sec in SECTIONS}
    children: dict[str, list] = {sec: [] for sec in SECTIONS}
    for f in FIELDS:
        fields[f.section].append(f)
    for sec in SECTIONS:
        if "." in sec and sec.rsplit(".", 1)[0] in children:
            children[sec.rsplit(".", 1)[0]].append(sec)
    return {k: tuple(v) for k, v in fields.items()}, {k: tuple(v) for k, v in children.items()}


#: section -> its fields, and its direct sub-sections; sections deepest first (built once)
_FIELDS_OF, _SUBSECTIONS_OF = _section_tables()
_SECTIONS_DEEPEST_FIRST = tuple(sorted(SECTIONS, key=lambda s: -s.count(".")))


@dataclass(frozen=True)
class Spec:
    """A validated drive, every value in internal units.

    Sections are attributes (``spec.gear_pair.output_gear.teeth``).
    ``effects`` maps an effect name to its internal parameters; ``source``
    is the file it came from; ``raw`` the TOML document as read (a
    read-only mapping; use :func:`raw_copy` to derive a changed spec).
    """

    drive: Any
    gear_pair: Any
    worm_pair: Any
    assembly: Any
    loads: Any
    stiffness: Any
    materials: Any
    requirements: Any
    effects: Any = field(default_factory=lambda: MappingProxyType({}))
    source: str = "<spec>"
    raw: Any = field(default_factory=lambda: MappingProxyType({}), repr=False)


def raw_copy(spec: Spec) -> dict:
    """A mutable deep copy of the TOML document behind ``spec``."""
    return copy.deepcopy(_thaw(spec.raw))


def _thaw(obj):
    if isinstance(obj, MappingProxyType) or isinstance(obj, dict):
        return {k: _thaw(v) for k, v in obj.items()}
    if isinstance(obj, (tuple, list)):
        return [_thaw(v) for v in obj]
    return obj


def _freeze(obj):
    if isinstance(obj, dict):
        return MappingProxyType({k: _freeze(v) for k, v in obj.items()})
    if isinstance(obj, list):
        return tuple(_freeze(v) for v in obj)
    return obj


# --- loading ------------------------------------------------------------------------


def load_spec(path: str | Path) -> Spec:
    """Read and validate a drive file.  Raises :class:`SpecError` listing every problem."""
    from wormgear_cli.files import read_text_file

    path = Path(path)
    name = str(path)
    from wormgear_cli.spec.toml import MAX_SPEC_BYTES

    text = read_text_file(path, "a TOML drive file", SpecError, encoding="utf-8-sig",  # a BOM is tolerated
                          max_bytes=MAX_SPEC_BYTES)
    if not text.strip():
        raise SpecError(f"{name}: file is empty, expected a TOML drive file (try `wormgear new`)")
    from wormgear_cli.errors import quote  # a file name holding control characters is shown, never run
    from wormgear_cli.spec.filekind import first_line, looks_like_table

    if looks_like_table(text):  # a measurement CSV where a drive belongs: say so, not a TOML syntax error
        raise SpecError(f"{name}: a table of data (first line: {first_line(text)}), not a TOML drive file; "
                        "give the drive spec here (wormgear new writes one)")
    return loads_spec(text, name, default_name=quote(path.stem))


def loads_spec(text: str, source: str = "<spec>", default_name: str = "drive") -> Spec:
    """Parse TOML text (bounded, see :mod:`wormgear_cli.spec.toml`) and validate it (see
    :func:`load_spec`)."""
    from wormgear_cli.spec.toml import parse_toml

    data = parse_toml(text, source)
    return spec_from_dict(data, source, default_name)


def spec_from_dict(data: dict, source: str = "<spec>", default_name: str = "drive") -> Spec:
    """Validate a TOML document (as a dict) into a :class:`Spec`."""
    problems: list[str] = []
    values: dict[str, Any] = {}

    def bad(path: str, message: str) -> None:
        problems.append(f"{source}: {path}: {message}")

    _walk_unknown(data, "", problems, source)

    for sec in REQUIRED_SECTIONS:
        parent = sec.rsplit(".", 1)[0] if "." in sec else ""
        if _get(data, sec) is None and (not parent or isinstance(_get(data, parent), dict)):
            bad(sec, f"missing section [{sec}]")

    for f in FIELDS:
        parent = _get(data, f.section)
        if not isinstance(parent, dict) or f.key not in parent:
            if f.default is None and isinstance(parent, dict):
                bad(f.path, f"missing required key, expected {f.expected()}")
            values[f.path] = _MISSING
            continue
        raw = parent[f.key]
        if isinstance(raw, dict):  # reported once, by _walk_unknown ("expected a value, got a table")
            values[f.path] = _MISSING
            continue
        err, val = _check_value(f, raw)
        if err:
            bad(f.path, err)
            values[f.path] = _MISSING
        else:
            values[f.path] = val

    effects = _load_effects(data.get("effects"), problems, source)
    _apply_grades(values, bad)

    if problems:
        raise SpecError(problems)
    return _build(values, effects, source, default_name, data)


#: keys a user may reasonably try that no standard here covers -> the message (exit 2)
_NOT_COVERED = {
    f"worm_pair.{part}.accuracy_grade": (
        "worm pairs are not covered by ISO 1328-1/-2 (cylindrical involute gears only) and no public, "
        "citable worm-gear grade system (DIN 3974) is available here; give the worm pair's tolerances "
        "explicitly (lead_error_mm, profile_error_mm, radial_composite_error_mm, ...)")
    for part in ("worm", "wheel")
}


def _apply_grades(values: dict, bad) -> None:
    """Fill the spur gears' pitch deviations (and profile error) from ``accuracy_grade``
    where the spec does not give them (ISO 1328-1:2013; explicit keys win).  A gear
    outside the standard's scope is a problem naming the grade key and the range."""
    module = values["gear_pair.module_mm"]
    if module is _MISSING:
        return
    face = values["gear_pair.face_width_mm"]
    face = 10.0 * module if face is _MISSING else face
    for sec in ("gear_pair.output_gear", "gear_pair.pinion"):
        grade = values[f"{sec}.accuracy_grade"]
        if grade is _MISSING or grade is None:
            continue
        teeth = values[f"{sec}.teeth"]
        if teeth is _MISSING:
            continue
        from wormgear_cli.physics.iso1328 import GradeError, flank_tolerances

        try:
            tol = flank_tolerances(grade, module, module * teeth, face, teeth)
        except GradeError as exc:
            bad(f"{sec}.accuracy_grade", f"{exc}; give the deviations explicitly instead")
            continue
        for key, um in (("cumulative_pitch_deviation_mm", tol.F_pT), ("single_pitch_deviation_mm", tol.f_pT),
                        ("profile_error_mm", tol.F_alphaT)):
            if values[f"{sec}.{key}"] is _MISSING:
                values[f"{sec}.{key}"] = um * 1e-3


def value_origin(spec: Spec, path: str) -> str:
    """Where the value of ``path`` came from: ``"spec"`` (written in the file),
    ``"grade"`` (derived from the part's ``accuracy_grade``) or ``"default"``."""
    node: Any = spec.raw
    for part in path.split("."):
        if not hasattr(node, "get") or part not in node:
            node = None
            break
        node = node[part]
    if node is not None:
        return "spec"
    section, key = path.rsplit(".", 1)
    grade_keys = ("cumulative_pitch_deviation_mm", "single_pitch_deviation_mm", "profile_error_mm")
    if key in grade_keys and section in ("gear_pair.output_gear", "gear_pair.pinion"):
        raw_sec: Any = spec.raw
        for part in section.split("."):
            raw_sec = raw_sec.get(part) if hasattr(raw_sec, "get") else None
        if hasattr(raw_sec, "get") and raw_sec.get("accuracy_grade") is not None:
            return "grade"
    return "default"


class _Missing:
    def __repr__(self):
        return "<missing>"


_MISSING = _Missing()


def _get(data: dict, dotted: str):
    node: Any = data
    for part in dotted.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return node


def _quote(text: str) -> str:
    """A string value as shown in a message: double-quoted, escapes visible, one line."""
    import json

    return json.dumps(text, ensure_ascii=False)


def _type_name(v) -> str:
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "an array",
            dict: "a table"}.get(type(v), type(v).__name__)


def _check_value(f: Field, raw) -> tuple[str | None, Any]:
    """Return (problem, converted value)."""
    if f.kind == "str":
        if not isinstance(raw, str):
            return f"expected {f.expected()}, got {_type_name(raw)}", None
        if f.path == "drive.name" and not raw.isprintable():
            return f"expected a single-line name without control characters, got {_quote(raw)}", None
        if f.choices and raw not in f.choices:
            lowered = {c.lower(): c for c in f.choices}
            hint = did_you_mean(raw.lower(), lowered, show=lambda m: f'"{lowered[m]}"')
            return f"expected {f.expected()}, got {_quote(raw)}{hint}", None
        return None, raw
    if f.kind == "floats":
        if not isinstance(raw, list):
            return f"expected {f.expected()}, got {_type_name(raw)}", None
        if f.length is not None and len(raw) != f.length:
            return f"expected {f.expected()}, got {len(raw)} values", None
        out = []
        for i, item in enumerate(raw):
            err = _number_problem(f, item)
            if err:
                return f"element {i}: {err}", None
            out.append(float(item) * UNIT_SCALE[f.unit])
        return None, tuple(out)
    err = _number_problem(f, raw)
    if err:
        return err, None
    if f.kind == "int":
        return None, int(raw)
    return None, float(raw) * UNIT_SCALE[f.unit]


def _number_problem(f: Field, raw) -> str | None:
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        shown = _quote(raw) if isinstance(raw, str) else _type_name(raw)
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


def _known_children(prefix: str) -> frozenset[str]:
    """Keys and sub-tables valid directly under ``prefix`` ("" = top level)."""
    return _KNOWN_CHILDREN.get(prefix, frozenset())


def _children_table() -> dict[str, frozenset[str]]:
    out: dict[str, set[str]] = {"": {"effects", "statistics"}}  # free-form tables, validated by their own modules
    for f in FIELDS:
        parts = f.path.split(".")
        for depth in range(len(parts)):
            out.setdefault(".".join(parts[:depth]), set()).add(parts[depth])
    return {k: frozenset(v) for k, v in out.items()}


#: table path ("" = top level) -> the keys and sub-tables valid directly under it (built once)
_KNOWN_CHILDREN = _children_table()


def _walk_unknown(data: dict, prefix: str, problems: list[str], source: str) -> None:
    if prefix in ("effects", "statistics"):
        return
    known = _known_children(prefix)
    for key, value in data.items():
        shown_key = key if key.isprintable() and key.strip() == key and key else _quote(key)
        path = f"{prefix}.{shown_key}" if prefix else shown_key
        if key not in known and path in _NOT_COVERED:
            problems.append(f"{source}: {path}: {_NOT_COVERED[path]}")
            continue
        if key not in known:
            # the nearest key of this table, else the nearest full path (a misplaced key)
            hint = (did_you_mean(key, sorted(known), show=lambda m: (prefix + "." if prefix else "") + m)
                    or did_you_mean(path, [f.path for f in FIELDS], cutoff=0.75))
            if not hint and not prefix:  # nothing close: say what the top level holds
                hint = f" (a drive file holds the tables {', '.join('[' + k + ']' for k in sorted(known))})"
            what = "table" if isinstance(value, dict) else "key"
            problems.append(f"{source}: {path}: unknown {what}{hint}")
            continue
        is_section = path in _SECTION_SET or path in ("effects", "statistics")
        if is_section and not isinstance(value, dict):
            problems.append(f"{source}: {path}: expected a table [{path}], got {_type_name(value)}")
        elif not is_section and isinstance(value, dict):
            problems.append(f"{source}: {path}: expected a value, got a table")
        elif isinstance(value, dict):
            _walk_unknown(value, path, problems, source)


def _load_effects(table, problems: list[str], source: str) -> dict:
    if table is None:
        return {}
    if not isinstance(table, dict):
        return {}
    from wormgear_cli.physics.effects import EFFECTS, params_from_keys

    out = {}
    for name, params in table.items():
        path = f"effects.{name}"
        if name not in EFFECTS:
            hint = did_you_mean(name, EFFECTS, show=lambda m: f"effects.{m}",
                                otherwise=f" (known: {', '.join(EFFECTS)})")
            problems.append(f"{source}: {path}: unknown effect{hint}")
            continue
        if not isinstance(params, dict):
            problems.append(f"{source}: {path}: expected a table [{path}], got {_type_name(params)}")
            continue
        eff = EFFECTS[name]
        keys = [p.key for p in eff.params]
        ok = True
        for key in params:
            if key not in keys:
                hint = did_you_mean(key, keys, show=lambda m: f"{path}.{m}", otherwise=f" (valid: {', '.join(keys)})")  # noqa: B023
                problems.append(f"{source}: {path}.{key}: unknown key{hint}")
                ok = False
        for p in eff.params:
            if p.key not in params:
                if p.default is None:
                    problems.append(f"{source}: {path}.{p.key}: missing required key, expected a number "
                                    f"in [{_fmt(p.lo)}, {_fmt(p.hi)}] [{p.unit}]")
                    ok = False
                continue
            raw = params[p.key]
            pf = Field(f"{path}.{p.key}", p.name, "float", p.unit, p.default, p.doc, p.lo, p.hi)
            err = _number_problem(pf, raw)
            if err:
                problems.append(f"{source}: {path}.{p.key}: {err}")
                ok = False
        if ok:
            out[name] = MappingProxyType(params_from_keys(name, params))
    return out


def _build(values: dict, effects: dict, source: str, default_name: str, data: dict) -> Spec:
    v = dict(values)

    def take(path, fallback):
        return fallback if v[path] is _MISSING else v[path]

    # defaults, including the derived ones (documented in FIELDS)
    for f in FIELDS:
        if v[f.path] is _MISSING and f.default not in ("derived", None):
            d = f.default
            if d == "":
                v[f.path] = None
            elif f.kind == "floats":
                v[f.path] = tuple(x * UNIT_SCALE[f.unit] for x in d)
            elif f.kind == "str":
                v[f.path] = d
            else:
                v[f.path] = float(d) * UNIT_SCALE[f.unit]
    v["drive.name"] = take("drive.name", default_name)
    v["gear_pair.face_width_mm"] = take("gear_pair.face_width_mm", 10.0 * v["gear_pair.module_mm"])
    v["worm_pair.face_width_mm"] = take("worm_pair.face_width_mm", 10.0 * v["worm_pair.module_mm"])
    if v["worm_pair.transverse_pressure_angle_deg"] is _MISSING:
        an, lam = v["worm_pair.normal_pressure_angle_deg"], v["worm_pair.lead_angle_deg"]
        v["worm_pair.transverse_pressure_angle_deg"] = math.atan(math.tan(an) / math.cos(lam))
    if v["assembly.gear_eccentricity_mm"] is _MISSING:
        v["assembly.gear_eccentricity_mm"] = v["assembly.gear_centre_distance_error_mm"]
    for sec in ("gear_pair.output_gear", "gear_pair.pinion"):
        for key in ("cumulative_pitch_deviation_mm", "single_pitch_deviation_mm"):
            v[f"{sec}.{key}"] = take(f"{sec}.{key}", 0.0)
    if v["stiffness.contact_ratio"] is _MISSING:
        from wormgear_cli.physics.deformation import spur_contact_ratio

        v["stiffness.contact_ratio"] = float(spur_contact_ratio(
            v["gear_pair.output_gear.teeth"], v["gear_pair.pinion.teeth"], v["gear_pair.pressure_angle_deg"]))

    built: dict[str, Any] = {}
    for sec in _SECTIONS_DEEPEST_FIRST:
        kwargs = {f.attr: v[f.path] for f in _FIELDS_OF[sec]}
        for child in _SUBSECTIONS_OF[sec]:
            kwargs[child.rsplit(".", 1)[1]] = built[child]
        built[sec] = _SECTION_CLASSES[sec](**kwargs)
    top = {s: built[s] for s in SECTIONS if "." not in s}
    return Spec(**top, effects=MappingProxyType(effects), source=source, raw=_freeze(data))


def with_values(spec: Spec, changes: dict[str, Any]) -> Spec:
    """A new spec with TOML ``path -> value`` changes applied (key units), re-validated."""
    data = raw_copy(spec)
    for path, value in changes.items():
        parts = path.split(".")
        node = data
        for part in parts[:-1]:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise SpecError(f"{spec.source}: {path}: cannot set, {part} is not a table")
        node[parts[-1]] = value
    return spec_from_dict(data, spec.source, spec.drive.name)
