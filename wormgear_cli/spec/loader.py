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
import dataclasses
import functools
from dataclasses import FrozenInstanceError, dataclass, field
from pathlib import Path
from types import MappingProxyType, SimpleNamespace
from typing import Any

from wormgear_cli.errors import SpecError, did_you_mean
from wormgear_cli.files import read_text_file
from wormgear_cli.physics.deformation import DEFORMATION_MODELS, spur_contact_ratio
from wormgear_cli.spec import stages as _stages
from wormgear_cli.spec.fields import (
    FACTOR,
    MISSING,
    UNIT_SCALE,
    Field,
    check_value,
    field_,
    fmt,
    gear_grade_fields,
    get_path,
    number_problem,
    quote,
    type_name,
)
from wormgear_cli.spec.plausibility import review
from wormgear_cli.spec.toml import MAX_SPEC_BYTES, parse_toml


def _legacy(path: str, **changes) -> Field:
    """The legacy key ``path`` as a field: its stage key's field (kind, unit, default, range, choices: one
    definition, :data:`wormgear_cli.spec.stages.LEGACY_KEYS`) under the legacy path and attribute name (the
    legacy key less the stage key's unit suffix), with ``changes`` (the legacy form's own wording)."""
    kind, key = _stages.LEGACY_KEYS[path]
    f = _stages.STAGE_FIELD_BY_KEY[kind][key]
    suffix = f.key[len(f.attr):]  # "_mm" of runout_mm (attr runout), "" of teeth
    name = path.rsplit(".", 1)[-1]
    return f._replace(path=path, attr=name[:len(name) - len(suffix)] if suffix else name, **changes)


#: The drive-spec schema.  Order = order in the template and the key reference (docs/reference/spec.md).
FIELDS: tuple[Field, ...] = (
    Field("drive.name", "name", "str", "", "derived", "name shown in reports (default: the file name without .toml)"),
    Field("drive.description", "description", "str", "", "", "free text"),
    # --- stage 2: spur gear pair -------------------------------------------------
    _legacy("gear_pair.module_mm"),
    _legacy("gear_pair.pressure_angle_deg"),
    _legacy("gear_pair.face_width_mm"),
    _legacy("gear_pair.kinematics",
            doc="gear-stage kinematics: paper (the paper's Delta phi_cc/Delta phi_ch as printed) or involute "
            "(eccentricity e -> TE e/r_b; centre-distance error -> backlash 2 Delta a tan(alpha), no TE; "
            "tooth-thickness allowances in the backlash; see docs/budget.md)"),
    _legacy("gear_pair.output_gear.teeth", doc="teeth z1 of the output gear (gear 1)"),
    *gear_grade_fields("gear_pair.output_gear", "gear 1"),
    _legacy("gear_pair.output_gear.profile_error_mm",
            doc="profile error of gear 1 (not used by the paper's gear-stage equations)"),
    _legacy("gear_pair.output_gear.thickness_deviation_mm",
            doc="tooth thickness deviation of gear 1 (not used by the paper's gear-stage equations)"),
    _legacy("gear_pair.pinion.teeth", doc="teeth z2 of the pinion (gear 2)"),
    *gear_grade_fields("gear_pair.pinion", "gear 2"),
    _legacy("gear_pair.pinion.profile_error_mm",
            doc="profile error of gear 2 (not used by the paper's gear-stage equations)"),
    _legacy("gear_pair.pinion.thickness_deviation_mm",
            doc="tooth thickness deviation of gear 2 (not used by the paper's gear-stage equations)"),
    # --- stage 1: worm pair ------------------------------------------------------
    _legacy("worm_pair.module_mm"),
    _legacy("worm_pair.normal_pressure_angle_deg"),
    _legacy("worm_pair.lead_angle_deg"),
    _legacy("worm_pair.transverse_pressure_angle_deg"),
    _legacy("worm_pair.face_width_mm"),
    _legacy("worm_pair.lead_error_mm"),
    _legacy("worm_pair.lead_error_phase_deg"),
    _legacy("worm_pair.worm.starts"),
    _legacy("worm_pair.worm.profile_error_mm"),
    _legacy("worm_pair.worm.thickness_deviation_mm"),
    _legacy("worm_pair.wheel.teeth"),
    _legacy("worm_pair.wheel.profile_error_mm"),
    _legacy("worm_pair.wheel.thickness_deviation_mm"),
    _legacy("worm_pair.wheel.radial_composite_error_mm"),
    _legacy("worm_pair.wheel.radial_composite_phase_deg"),
    _legacy("worm_pair.wheel.cumulative_pitch_deviation_mm",
            doc="cumulative pitch deviation F_p of the wheel (budget source, order i_c; part of what F_i measures, "
            "so leave 0 unless measured separately)"),
    _legacy("worm_pair.wheel.cumulative_pitch_phase_deg"),
    # --- assembly ----------------------------------------------------------------
    _legacy("assembly.gear_centre_distance_error_mm"),
    _legacy("assembly.gear_eccentricity_mm", doc="the paper's Delta e (default: gear_centre_distance_error_mm)"),
    _legacy("assembly.gear_eccentricity_phase_deg"),
    _legacy("assembly.worm_centre_distance_error_mm"),
    _legacy("assembly.worm_eccentricity_mm"),
    _legacy("assembly.worm_eccentricity_phase_deg"),
    _legacy("assembly.worm_bearing_clearance_mm", doc="worm bearing clearance C1"),
    _legacy("assembly.wheel_eccentricity_mm"),
    _legacy("assembly.wheel_eccentricity_phase_deg"),
    _legacy("assembly.wheel_bearing_clearance_mm", doc="wheel bearing clearance C2"),
    _legacy("assembly.worm_pair_errors_mm"),
    # --- loads -------------------------------------------------------------------
    _legacy("loads.gear_normal_force_N", default=0.0, table1="666 (text)", doc="normal force F_N on the spur teeth"),
    _legacy("loads.worm_normal_force_N", default=0.0, table1="85 (text)", doc="normal force F_N on the worm mesh"),
    # --- stiffness (deformation model) -------------------------------------------
    Field("stiffness.model", "model", "str", "", "iso6336",
          "deflection model: iso6336 (ISO 6336-1 c') or empirical (the paper's form)",
          choices=tuple(DEFORMATION_MODELS)),
    field_("stiffness.iso_cm", "iso_cm", "-", 0.8, "ISO 6336 C_M (theory-to-measurement)", **FACTOR),
    field_("stiffness.iso_cr", "iso_cr", "-", 1.0, "ISO 6336 C_R (blank; 1 = solid)", **FACTOR),
    field_("stiffness.iso_cb", "iso_cb", "-", 0.975, "ISO 6336 C_B (basic rack)", **FACTOR),
    field_("stiffness.iso_ka", "iso_ka", "-", 1.0,
       "ISO 6336 K_A (application factor) in the line load F_t K_A / b that scales c' below 100 N/mm",
       **FACTOR),
    field_("stiffness.empirical_a1", "empirical_a1", "-", 4.0,
       "the paper's A1 (its calibration: docs/models.md, deformation models)",
       lo=0.0, hi=1000.0),
    field_("stiffness.empirical_b", "empirical_b", "-", 1.0, "the paper's exponent B", lo=-10.0, hi=10.0),
    field_("stiffness.empirical_c", "empirical_c", "-", 1.0, "the paper's exponent C", lo=-10.0, hi=10.0),
    field_("stiffness.contact_ratio", "contact_ratio", "-", "derived",
       "contact ratio eps of the empirical form (default: standard spur eps_alpha)", lo=1.0, hi=3.0),
    field_("stiffness.empirical_lambda2", "empirical_lambda2", "-", 0.0, "the paper's lambda2 (undefined there)",
       lo=0.0, hi=100.0),
    # --- materials ---------------------------------------------------------------
    field_("materials.gear_elastic_modulus_GPa", "gear_elastic_modulus", "GPa", 206.0,
       "Young's modulus E of the spur gears (steel)", lo=1.0, hi=1000.0),
    field_("materials.worm_elastic_modulus_GPa", "worm_elastic_modulus", "GPa", 206.0,
       "Young's modulus of the worm (steel)", lo=1.0, hi=1000.0),
    field_("materials.wheel_elastic_modulus_GPa", "wheel_elastic_modulus", "GPa", 98.0,
       "Young's modulus of the wheel (CuSn12 bronze ~ 98)", lo=1.0, hi=1000.0),
    field_("materials.worm_expansion_ppm_per_K", "worm_expansion", "ppm/K", 11.5,
       "thermal expansion of the worm (steel 11.5)", lo=-5.0, hi=50.0),
    field_("materials.wheel_expansion_ppm_per_K", "wheel_expansion", "ppm/K", 18.5,
       "thermal expansion of the wheel (CuSn12 bronze 18.5)", lo=-5.0, hi=50.0),
    field_("materials.housing_expansion_ppm_per_K", "housing_expansion", "ppm/K", 10.5,
       "thermal expansion of the housing (grey cast iron 10.5)", lo=-5.0, hi=50.0),
    field_("materials.housing_rise_ratio", "housing_rise_ratio", "-", 1.0,
       "the housing's temperature rise per kelvin of the measured (mesh/oil) temperature; used by diagnose's "
       "thermal_backlash prediction (1: the whole drive warms alike; a running worm drive warms at the mesh, "
       "so less than 1)", lo=0.0, hi=1.5, lo_open=True),
    # --- the acceptance test the ISO 230-2 requirements are predicted on --------------
    Field("test_plan.targets", "targets", "int", "-", 24,
          "target positions over one output turn, spaced irregularly (ISO 230-2 asks for irregular spacing so "
          "periodic errors are sampled fairly): i p + r_i, p = 360/targets, r_i uniform in +/- jitter p", 2, 10000),
    Field("test_plan.targets_deg", "targets_deg", "floats", "deg", "",
          "the test's target angles, when given (replaces targets, jitter and seed)", -360000.0, 360000.0),
    Field("test_plan.runs", "runs", "int", "-", 5,
          "runs in each direction (ISO 230-2's standard cycle: 5; each run one pass up, one pass down)", 1, 10000),
    field_("test_plan.jitter", "jitter", "-", 0.25,
           "half-width of the targets' irregular offsets as a fraction of their mean spacing", lo=0.0, hi=0.5,
           hi_open=True),
    Field("test_plan.seed", "seed", "int", "-", 0,
          "seed of the irregular offsets (synth's iso plan with this seed gives the same targets)", 0, 2**31 - 1),
    field_("test_plan.reading_scatter_arcsec", "reading_scatter", "arcsec", 0.0,
           "standard deviation s of repeated readings at one target (the axis' repeatability R = 4 s); enters A "
           "(x +/- 2 s) and the predicted R", lo=0.0, hi=1e6),
    # --- requirements (all optional) ---------------------------------------------
    *(
        field_(f"requirements.max_{name}_arcsec", f"max_{name}", "arcsec", "", f"limit on {what}", lo=0.0, hi=1e9,
           lo_open=True)
        for name, what in (
            ("transmission_error", "the total transmission error at the output, the paper's Delta phi_c: an "
             "amplitude (zero to peak)"),
            ("backlash", "the total backlash at the output, the paper's Delta phi_h: the whole lost motion on a "
             "reversal"),
            ("gear_transmission_error", "the gear-stage TE at its output (an amplitude)"),
            ("gear_backlash", "the gear-stage backlash"),
            ("worm_transmission_error", "the worm-stage TE at the wheel (an amplitude)"),
            ("worm_backlash", "the worm-stage backlash at the wheel"),
            ("budget_linear", "the full budget's TE amplitude at the output, linear sum of the lines' maxima"),
            ("budget_statistical", "the full budget's TE amplitude at the output, static lines + root-sum-square "
             "within an order summed across orders (docs/budget.md)"),
            ("budget_rss", "deprecated name of budget_statistical (judged against the statistical total)"),
            ("budget_peak", "the full budget's TE amplitude at the output, exact peak of the phased curve"),
            ("iso230_A", "ISO 230-2 bidirectional accuracy A of the acceptance test ([test_plan]): a range"),
            ("iso230_E", "ISO 230-2 bidirectional systematic deviation E of the acceptance test: a range"),
            ("iso230_B", "ISO 230-2 reversal value B of the acceptance test (largest |B_i|)"),
            ("iso230_M", "ISO 230-2 mean bidirectional deviation M of the acceptance test: a range"),
        )
    ),
    field_("requirements.min_yield", "min_yield", "-", "", "least fraction of built drives meeting every limit "
       "(estimated by wormgear tolerance; see [statistics])", lo=0.0, hi=1.0, lo_open=True, hi_open=True),
)


FIELD_BY_PATH: dict[str, Field] = {f.path: f for f in FIELDS}
SECTIONS: tuple[str, ...] = tuple(dict.fromkeys(f.section for f in FIELDS))
REQUIRED_SECTIONS = ("gear_pair", "gear_pair.output_gear", "gear_pair.pinion", "worm_pair", "worm_pair.worm",
                     "worm_pair.wheel")
#: the legacy form's tables that hold its two stages (the stage form has [[stage]] tables instead)
LEGACY_TABLES = ("gear_pair", "worm_pair", "assembly", "loads")

#: The drive-level keys of the stage form (``[[stage]]`` tables): [drive] (with the output torque that
#: sets the stages' loads), [stiffness], [materials] and the drive's [requirements]; each stage's keys
#: are :data:`wormgear_cli.spec.stages.STAGE_FIELDS`.
DRIVE_FIELDS: tuple[Field, ...] = (
    *(f for f in FIELDS if f.section == "drive"),
    field_("drive.output_torque_Nm", "output_torque", "N m", "",
           "torque on the output under the process load: the load of every stage that does not give its own "
           "(normal_force_N, effective_tension_N), carried back through the ratios after it (losses neglected)",
           lo=0.0, hi=1e9),
    field_("drive.friction_torque_Nm", "friction_torque", "N m", "",
           "friction torque the drive overcomes at the output (table bearings, seals, clamps); it reverses with the "
           "motion, so the train's compliance winds up by it each way: a lost motion 2 T_f C_out (default: none)",
           lo=0.0, hi=1e9),
    *(f for f in FIELDS if f.section in ("stiffness", "materials", "test_plan")),
    *(f for f in FIELDS if f.section == "requirements" and f.path not in _stages.LEGACY_KEYS),
)

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

    def __hash__(self):  # type: ignore[override]  # SimpleNamespace is unhashable; a frozen record is
        return hash((type(self).__name__, tuple(sorted(self.__dict__.items(), key=lambda kv: kv[0]))))

    def _replace(self, **changes):
        unknown = set(changes) - set(self.__dict__)
        if unknown:
            raise TypeError(f"{type(self).__name__} has no field(s) {sorted(unknown)}")
        return type(self)(**{**self.__dict__, **changes})


def _class_name(section: str) -> str:
    return "".join(part.capitalize() for part in section.replace(".", "_").split("_"))


_SECTION_CLASSES: dict[str, type] = {sec: type(_class_name(sec), (Section,), {"__slots__": ()}) for sec in SECTIONS}


class _Schema:
    """A form's drive-level tables as data: fields, sections (deepest first), which keys each table
    holds (for the unknown-key check), built once at import."""

    def __init__(self, fields: tuple[Field, ...], free: tuple[str, ...]):
        self.fields = fields
        self.paths = [f.path for f in fields]
        self.sections = tuple(dict.fromkeys(f.section for f in fields))
        self.section_set = frozenset(self.sections) | frozenset(free)
        self.free = free
        of: dict[str, list] = {sec: [] for sec in self.sections}
        children: dict[str, list] = {sec: [] for sec in self.sections}
        for f in fields:
            of[f.section].append(f)
        for sec in self.sections:
            if "." in sec and sec.rsplit(".", 1)[0] in children:
                children[sec.rsplit(".", 1)[0]].append(sec)
        self.fields_of = {k: tuple(v) for k, v in of.items()}
        self.subsections_of = {k: tuple(v) for k, v in children.items()}
        self.deepest_first = tuple(sorted(self.sections, key=lambda s: -s.count(".")))
        known: dict[str, set[str]] = {"": set(free)}
        for f in fields:
            parts = f.path.split(".")
            for depth in range(len(parts)):
                known.setdefault(".".join(parts[:depth]), set()).add(parts[depth])
        #: table path ("" = top level) -> the keys and sub-tables valid directly under it
        self.known = {k: frozenset(v) for k, v in known.items()}

    def records(self, v: dict) -> dict:
        """Top-level section -> its record, from complete values ``v`` (path -> internal value)."""
        built: dict[str, Any] = {}
        for sec in self.deepest_first:
            kwargs = {f.attr: v[f.path] for f in self.fields_of[sec]}
            for child in self.subsections_of[sec]:
                kwargs[child.rsplit(".", 1)[1]] = built[child]
            built[sec] = _SECTION_CLASSES[sec](**kwargs)
        return {s: built[s] for s in self.sections if "." not in s}


#: the two forms: the legacy two-table form, and the drive-level tables of the stage form
_LEGACY = _Schema(FIELDS, ("effects", "statistics"))
_STAGE_FORM = _Schema(DRIVE_FIELDS, ("effects", "statistics", "stage"))
_SECTION_SET = _LEGACY.section_set  # (kept: the legacy form's tables)


@dataclass(frozen=True)
class Spec:
    """A validated drive, every value in internal units.

    ``stages``: the drive's stages from the motor to the output, one record per stage
    (:mod:`wormgear_cli.spec.stages`: ``WormStageSpec``, ``SpurStageSpec``, ``BeltStageSpec``).
    Drive-level sections are attributes (``spec.drive.name``, ``spec.stiffness.model``).
    For a drive of one worm stage followed by one spur stage (the legacy form's drive, in
    either form) the legacy sections are there too (``spec.gear_pair.output_gear.teeth``,
    ``spec.worm_pair``, ``spec.assembly``, ``spec.loads``); for any other train they are None.
    ``effects`` maps an effect name to its internal parameters; ``source``
    is the file it came from; ``raw`` the TOML document as read (a
    read-only mapping; use :func:`raw_copy` to derive a changed spec); ``form``: ``"stages"``
    (``[[stage]]`` tables) or ``"legacy"`` (the two-table form); ``warnings``: one line per
    implausible value (:mod:`wormgear_cli.spec.plausibility`), for the commands to print;
    ``test_plan``: the acceptance test the ISO 230-2 requirements are predicted on.
    """

    drive: Any
    gear_pair: Any
    worm_pair: Any
    assembly: Any
    loads: Any
    stiffness: Any
    materials: Any
    requirements: Any
    test_plan: Any = None
    effects: Any = field(default_factory=lambda: MappingProxyType({}))
    source: str = "<spec>"
    raw: Any = field(default_factory=lambda: MappingProxyType({}), repr=False)
    stages: tuple = ()
    form: str = "legacy"
    warnings: tuple = ()


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

    path = Path(path)
    name = str(path)

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
    :func:`load_spec`).

    A :class:`Spec` is immutable: the same text, source and name give the one record, kept for the
    last :data:`KEPT_SPECS` documents read (a notebook, a study or a test suite reading a file again
    and again parses and validates it once); a document that fails raises each time."""
    return _loads_kept(text, source, default_name)


#: documents whose validated :class:`Spec` :func:`loads_spec` keeps (a few kB each)
KEPT_SPECS = 64


@functools.lru_cache(maxsize=KEPT_SPECS)
def _loads_kept(text: str, source: str, default_name: str) -> Spec:
    data = parse_toml(text, source)
    return spec_from_dict(data, source, default_name)


def spec_from_dict(data: dict, source: str = "<spec>", default_name: str = "drive") -> Spec:
    """Validate a TOML document (as a dict) into a :class:`Spec`: the stage form when it has a
    ``stage`` key (``[[stage]]`` tables), else the legacy two-table form."""
    if "stage" in data:
        return _stage_form(data, source, default_name)
    problems: list[str] = []

    def bad(path: str, message: str) -> None:
        problems.append(f"{source}: {path}: {message}")

    _walk_unknown(data, "", problems, source, _LEGACY)
    neither = not any(t in data for t in LEGACY_TABLES)
    if neither:  # neither form: say how a drive is written today, not which legacy tables are missing
        bad("stage", "no stages: a drive is a list of [[stage]] tables from the motor to the output, each with "
                     "kind = \"worm\", \"spur\" or \"belt\"; start from a template: wormgear new FILE --stages worm")
    for sec in REQUIRED_SECTIONS if not neither else ():
        parent = sec.rsplit(".", 1)[0] if "." in sec else ""
        if get_path(data, sec) is None and (not parent or isinstance(get_path(data, parent), dict)):
            bad(sec, f"missing section [{sec}]")
    values = _read_values(data, _LEGACY, bad)
    effects = _load_effects(data.get("effects"), problems, source)
    _apply_grades(values, bad)

    if problems:
        raise SpecError(problems)
    return _build(values, effects, source, default_name, data)


def _read_values(data: dict, schema: _Schema, bad) -> dict[str, Any]:
    """path -> checked internal value (MISSING where absent or wrong) of every key of ``schema``."""
    values: dict[str, Any] = {}
    for f in schema.fields:
        parent = get_path(data, f.section)
        if not isinstance(parent, dict) or f.key not in parent:
            if f.default is None and isinstance(parent, dict):
                bad(f.path, f"missing required key, expected {f.expected()}")
            values[f.path] = MISSING
            continue
        raw = parent[f.key]
        if isinstance(raw, dict):  # reported once, by _walk_unknown ("expected a value, got a table")
            values[f.path] = MISSING
            continue
        err, val = check_value(f, raw)
        if err:
            bad(f.path, err)
            values[f.path] = MISSING
        else:
            values[f.path] = val
    return values


#: keys a user may reasonably try that no standard here covers -> the message (exit 2)
_NOT_COVERED = {f"worm_pair.{key}": message for key, message in _stages.NOT_COVERED.items()}


def _apply_grades(values: dict, bad) -> None:
    """Fill the spur gears' pitch deviations (and profile error) from ``accuracy_grade``
    where the spec does not give them (:func:`wormgear_cli.spec.stages.fill_from_grades`, the
    stage form's rule).  A gear outside the standard's scope is a problem naming the grade key and
    the range."""
    if values["gear_pair.module_mm"] is MISSING:
        return
    _stages.fill_from_grades(values, values["gear_pair.module_mm"], values["gear_pair.face_width_mm"],
                             ("gear_pair.output_gear", "gear_pair.pinion"), bad)


def value_origin(spec: Spec, path: str) -> str:
    """Where the value of ``path`` came from: ``"spec"`` (written in the file),
    ``"grade"`` (derived from the part's ``accuracy_grade``) or ``"default"``.

    ``path`` is a key of the file's form; a stage path (``stage.2.gear.teeth``) and, for a
    [worm, spur] train, a legacy key are understood in both forms."""
    if spec.form == "stages":
        parts = _stages.new_path(spec.stages, path).split(".", 2)
        if len(parts) == 3 and parts[0] == "stage" and parts[1].isdigit() and 1 <= int(parts[1]) <= len(spec.stages):
            return spec.stages[int(parts[1]) - 1].origins.get(parts[2], "default")
        return "spec" if _raw_has(spec.raw, path) else "default"
    return _legacy_origin(spec.raw, _stages.legacy_path(spec.stages, path))


_ABSENT = object()


def raw_value(raw, path: str, default=None):
    """The value at TOML ``path`` in a document as read (``stage.N`` reaches the N-th ``[[stage]]``
    table), or ``default``."""
    node: Any = raw
    parts = path.split(".")
    k = 0
    while k < len(parts):
        part = parts[k]
        if part == "stage" and k == 0 and isinstance(node.get("stage") if hasattr(node, "get") else None,
                                                     (list, tuple)) and k + 1 < len(parts) and parts[k + 1].isdigit():
            items, index = node["stage"], int(parts[k + 1])
            if not 1 <= index <= len(items):
                return default
            node, k = items[index - 1], k + 2
            continue
        if not hasattr(node, "get") or part not in node:
            return default
        node, k = node[part], k + 1
    return node


def _raw_has(raw, path: str) -> bool:
    return raw_value(raw, path, _ABSENT) is not _ABSENT


def _legacy_origin(raw, path: str) -> str:
    if _raw_has(raw, path):
        return "spec"
    section, key = path.rsplit(".", 1) if "." in path else ("", path)
    grade_keys = ("cumulative_pitch_deviation_mm", "single_pitch_deviation_mm", "profile_error_mm")
    if key in grade_keys and section in ("gear_pair.output_gear", "gear_pair.pinion"):
        raw_sec: Any = raw
        for part in section.split("."):
            raw_sec = raw_sec.get(part) if hasattr(raw_sec, "get") else None
        if hasattr(raw_sec, "get") and raw_sec.get("accuracy_grade") is not None:
            return "grade"
    return "default"


def _walk_unknown(data: dict, prefix: str, problems: list[str], source: str, schema: _Schema) -> None:
    if prefix in ("effects", "statistics", "stage"):
        return
    known = schema.known.get(prefix, frozenset())
    for key, value in data.items():
        shown_key = key if key.isprintable() and key.strip() == key and key else quote(key)
        path = f"{prefix}.{shown_key}" if prefix else shown_key
        if key not in known and path in _NOT_COVERED:
            problems.append(f"{source}: {path}: {_NOT_COVERED[path]}")
            continue
        if key not in known:
            problems.append(f"{source}: {path}: unknown {'table' if isinstance(value, dict) else 'key'}"
                            f"{_unknown_hint(key, path, prefix, known, schema)}")
            continue
        is_section = path in schema.section_set
        if is_section and not isinstance(value, dict) and not (path == "stage" and isinstance(value, list)):
            shown = "[[stage]]" if path == "stage" else f"[{path}]"
            problems.append(f"{source}: {path}: expected a table {shown}, got {type_name(value)}")
        elif not is_section and isinstance(value, dict):
            problems.append(f"{source}: {path}: expected a value, got a table")
        elif isinstance(value, dict):
            _walk_unknown(value, path, problems, source, schema)


def _unknown_hint(key: str, path: str, prefix: str, known, schema: _Schema) -> str:
    """The nearest key of this table, else the nearest full path (a misplaced key), else what the
    table holds; in a file of the stage form, where a legacy key belongs."""
    if schema is _STAGE_FORM and (path in _stages.LEGACY_KEYS or path in LEGACY_TABLES):
        if path in LEGACY_TABLES:
            return (" (a table of the legacy two-table form; with [[stage]] tables every stage's keys are in "
                    "its own [[stage]] table: `wormgear upgrade` rewrites a legacy file)")
        kind, stage_key = _stages.LEGACY_KEYS[path]
        return f" (in the stage form: {stage_key} of the {kind} stage's [[stage]] table)"
    hint = (did_you_mean(key, sorted(known), show=lambda m: (prefix + "." if prefix else "") + m)
            or did_you_mean(path, schema.paths, cutoff=0.75))
    if not hint and not prefix:  # nothing close: say what the top level holds
        shown = ("[[stage]]" if k == "stage" else f"[{k}]" for k in sorted(known))
        hint = f" (a drive file holds the tables {', '.join(shown)})"
    return hint


def _load_effects(table, problems: list[str], source: str) -> dict:
    if table is None:
        return {}
    if not isinstance(table, dict):
        return {}
    # lazy: keeps physics.effects (the catalogue) off `analyze`'s start-up; only [effects.*] tables need it
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
            problems.append(f"{source}: {path}: expected a table [{path}], got {type_name(params)}")
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
                                    f"in [{fmt(p.lo)}, {fmt(p.hi)}] [{p.unit}]")
                    ok = False
                continue
            raw = params[p.key]
            pf = Field(f"{path}.{p.key}", p.name, "float", p.unit, p.default, p.doc, p.lo, p.hi)
            err = number_problem(pf, raw)
            if err:
                problems.append(f"{source}: {path}.{p.key}: {err}")
                ok = False
        if ok:
            out[name] = MappingProxyType(params_from_keys(name, params))
    return out


def _defaults(schema: _Schema, values: dict) -> dict:
    """``values`` with the plain defaults of ``schema`` filled in (not the derived ones)."""
    v = dict(values)
    for f in schema.fields:
        if v[f.path] is MISSING and f.default not in ("derived", None):
            d = f.default
            if d == "":
                v[f.path] = None
            elif f.kind == "floats":
                v[f.path] = tuple(x * UNIT_SCALE[f.unit] for x in d)
            elif f.kind == "str":
                v[f.path] = d
            elif f.kind == "int":
                v[f.path] = int(d)
            else:
                v[f.path] = float(d) * UNIT_SCALE[f.unit]
    return v


def _legacy_derived(v: dict) -> None:
    """The derived defaults of the legacy sections (documented in FIELDS), in place."""

    def take(path, fallback):
        return fallback if v[path] is MISSING else v[path]

    v["gear_pair.face_width_mm"] = take("gear_pair.face_width_mm", 10.0 * v["gear_pair.module_mm"])
    v["worm_pair.face_width_mm"] = take("worm_pair.face_width_mm", 10.0 * v["worm_pair.module_mm"])
    if v["worm_pair.transverse_pressure_angle_deg"] is MISSING:
        v["worm_pair.transverse_pressure_angle_deg"] = _stages.wheel_transverse_pressure_angle(
            v["worm_pair.normal_pressure_angle_deg"], v["worm_pair.lead_angle_deg"])
    if v["assembly.gear_eccentricity_mm"] is MISSING:
        v["assembly.gear_eccentricity_mm"] = v["assembly.gear_centre_distance_error_mm"]
    for sec in ("gear_pair.output_gear", "gear_pair.pinion"):
        for key in ("cumulative_pitch_deviation_mm", "single_pitch_deviation_mm"):
            v[f"{sec}.{key}"] = take(f"{sec}.{key}", 0.0)
    if v["stiffness.contact_ratio"] in (MISSING, None):

        v["stiffness.contact_ratio"] = float(spur_contact_ratio(
            v["gear_pair.output_gear.teeth"], v["gear_pair.pinion.teeth"], v["gear_pair.pressure_angle_deg"]))


def _build(values: dict, effects: dict, source: str, default_name: str, data: dict) -> Spec:
    """The Spec of a validated legacy-form file: its sections, and its two stages [worm, spur]."""
    v = _defaults(_LEGACY, values)
    v["drive.name"] = default_name if v["drive.name"] is MISSING else v["drive.name"]
    _legacy_derived(v)
    top = _LEGACY.records(v)
    raw = _freeze(data)
    return _reviewed(Spec(**top, effects=MappingProxyType(effects), source=source, raw=raw,
                          stages=_legacy_stages(v, raw), form="legacy"))


def _reviewed(spec: Spec) -> Spec:
    """``spec`` with its plausibility warnings; SpecError for an impossible value
    (:mod:`wormgear_cli.spec.plausibility`)."""


    problems, warnings = review(spec)
    if problems:
        raise SpecError(problems)
    return dataclasses.replace(spec, warnings=tuple(warnings)) if warnings else spec


def _legacy_stages(v: dict, raw) -> tuple:
    """The stage records [worm, spur] of complete legacy values ``v`` (legacy path -> internal value);
    each stage key's path and origin are those of its legacy key."""
    out = []
    for index, kind in enumerate(_stages.LEGACY_TRAIN, start=1):
        values: dict[str, Any] = {"stiffness_model": v["stiffness.model"], "anti_backlash": "none",
                                  "residual_lost_motion_arcsec": 0.0}
        paths, origins = {}, {}
        for f in _stages.STAGE_FIELDS[kind]:
            old = _stages.STAGE_TO_LEGACY.get((kind, f.path))
            if old is not None:
                values[f.path] = v[old]
                paths[f.path] = old
                origins[f.path] = _legacy_origin(raw, old) if raw is not None else "default"
            else:
                paths[f.path] = _stages.stage_path(index, f.path)
                origins[f.path] = "default"
                if f.path not in values:  # a stage key the legacy form has no table for: its default
                    values[f.path] = _stage_default(f)
        out.append(_stages.make_record(kind, index, _stages.DEFAULT_NAMES[kind], values, paths, origins))
    return tuple(out)


def _stage_default(f: Field):
    """The default of a stage key in internal units (None for an optional key; a derived default of the
    keys below, which only the stage form has, is the default of the key it derives from: 0)."""
    if f.default in ("", None):
        return None
    if f.default == "derived":
        return 0.0
    return float(f.default) * UNIT_SCALE[f.unit] if f.kind == "float" else f.default


def legacy_stages(spec: Spec) -> tuple:
    """The stages [worm, spur] read from ``spec``'s legacy sections as they are now (for code that
    still changes a spec through them, such as the ratio/centre-distance sweep's designs)."""
    v = {f.path: _section_value(spec, f) for f in FIELDS if f.section.split(".")[0] in
         (*LEGACY_TABLES, "requirements", "stiffness")}
    return tuple(s._replace(paths=old.paths, origins=old.origins)
                 for s, old in zip(_legacy_stages(v, None), spec.stages))


def _section_value(spec: Spec, f: Field):
    node: Any = spec
    for part in f.section.split("."):
        node = getattr(node, part)
    return getattr(node, f.attr)


# --- the stage form ---------------------------------------------------------------------------------


def _stage_form(data: dict, source: str, default_name: str) -> Spec:
    """Validate a drive file of the stage form: drive-level tables and ``[[stage]]`` tables."""
    problems: list[str] = []

    def bad(path: str, message: str) -> None:
        problems.append(f"{source}: {path}: {message}")

    _walk_unknown(data, "", problems, source, _STAGE_FORM)
    values = _read_values(data, _STAGE_FORM, bad)
    tables = data["stage"]
    if not isinstance(tables, list) or not tables:
        bad("stage", "expected one or more [[stage]] tables listed from the motor to the output, got "
            + (type_name(tables) if not isinstance(tables, list) else "none"))
        tables = []
    elif len(tables) > _stages.MAX_STAGES:
        bad("stage", f"expected at most {_stages.MAX_STAGES} [[stage]] tables, got {len(tables)}")
        tables = []
    checked = [_stages.check_stage(t, k, source, problems) for k, t in enumerate(tables, start=1)]
    effects = _load_effects(data.get("effects"), problems, source)
    if problems or None in checked:
        raise SpecError(problems)
    v = _defaults(_STAGE_FORM, values)
    v["drive.name"] = default_name if v["drive.name"] is MISSING else v["drive.name"]
    v["stiffness.contact_ratio"] = None if v["stiffness.contact_ratio"] is MISSING else v["stiffness.contact_ratio"]
    stages = _stages.build_stages([c for c in checked if c is not None], source, problems, v["stiffness.model"],
                                  _torque(v))  # every table is checked by now (problems raised above)
    _effects_in_train(effects, stages, source, problems)
    if problems:
        raise SpecError(problems)
    top = _STAGE_FORM.records(v)
    legacy = _legacy_views(v, stages) if _stages.is_legacy_train(stages) else None
    requirements = (legacy or {}).get("requirements") or _SECTION_CLASSES["requirements"](**{
        **{f.attr: None for f in FIELDS if f.section == "requirements"}, **top["requirements"].__dict__})
    tables_of_legacy: dict[str, Any] = {t: (legacy or {}).get(t) for t in LEGACY_TABLES}
    return _reviewed(Spec(drive=top["drive"], stiffness=top["stiffness"], materials=top["materials"],
                          requirements=requirements, test_plan=top["test_plan"],
                          **tables_of_legacy, effects=MappingProxyType(effects),
                          source=source, raw=_freeze(data), stages=stages, form="stages"))


def _effects_in_train(effects: dict, stages: tuple, source: str, problems: list[str]) -> None:
    """An ``[effects.NAME]`` table of an effect this train does not have is a problem (the catalogue's
    rule, :func:`wormgear_cli.physics.effects.absent_reason`)."""
    if not effects or not stages:
        return
    from wormgear_cli.physics.effects import absent_reason  # lazy: as above, only with [effects.*] tables

    kinds = tuple(s.kind for s in stages)
    single = kinds[-1] == "worm" and stages[-1].worm.starts == 1
    for name in effects:
        why = absent_reason(name, kinds, single)
        if why is not None:
            problems.append(f"{source}: effects.{name}: not an effect of this drive: {why}; remove the table")


def _torque(v: dict) -> float | None:
    t = v.get("drive.output_torque_Nm")
    return None if t in (MISSING, None) else float(t)


def _legacy_views(v: dict, stages: tuple) -> dict:
    """The legacy sections (gear_pair, worm_pair, assembly, loads, requirements) of a [worm, spur]
    train of the stage form: the old attribute names on the same values."""
    old = {f.path: v.get(f.path, MISSING) for f in FIELDS}
    for stage in stages:
        for key, value in _stages.record_values(stage).items():
            path = _stages.STAGE_TO_LEGACY.get((stage.kind, key))
            if path is not None:
                old[path] = value
    _legacy_derived(old)
    return _LEGACY.records(old)


def set_path(doc: dict, path: str, value) -> None:
    """Set TOML ``path`` in the document ``doc`` to ``value``, creating tables on the way; a part
    ``stage.N`` addresses the N-th ``[[stage]]`` table (1-based).  Raises SpecError when a part on
    the way is not a table."""
    parts = path.split(".")
    node: Any = doc
    k = 0
    while k < len(parts) - 1:
        part = parts[k]
        if part == "stage" and k == 0 and isinstance(node.get("stage"), list) and k + 1 < len(parts) - 1 \
                and parts[k + 1].isdigit():
            items = node["stage"]
            index = int(parts[k + 1])
            if not 1 <= index <= len(items):
                raise SpecError(f"{path}: no stage {index} (the drive has {len(items)})")
            node = items[index - 1]
            k += 2
            continue
        node = node.setdefault(part, {})
        if not isinstance(node, dict):
            raise SpecError(f"{path}: cannot set, {part} is not a table")
        k += 1
    node[parts[-1]] = value


def with_values(spec: Spec, changes: dict[str, Any]) -> Spec:
    """A new spec with TOML ``path -> value`` changes applied (key units), re-validated.

    Paths of either form reach a [worm, spur] train of either form (``gear_pair.module_mm`` or
    ``stage.2.module_mm``); any other train takes stage paths."""
    data = raw_copy(spec)
    for path, value in changes.items():
        where = (_stages.new_path(spec.stages, path) if spec.form == "stages"
                 else _stages.legacy_path(spec.stages, path))
        try:
            set_path(data, where, value)
        except SpecError as exc:
            raise SpecError(f"{spec.source}: {exc.problems[0]}") from None
    return spec_from_dict(data, spec.source, spec.drive.name)
