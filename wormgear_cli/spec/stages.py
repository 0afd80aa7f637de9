"""The stage form of a drive file: ``[[stage]]`` tables listed from the motor to the output.

A drive is an ordered list of stages, each with ``kind = "worm" | "spur" | "belt"`` and the keys
of that kind (the schema as data: :data:`STAGE_FIELDS`, keys relative to the stage table, units
in the key names).  Each stage becomes an immutable record of its kind
(:class:`WormStageSpec`, :class:`SpurStageSpec`, :class:`BeltStageSpec`; typed named tuples,
cheap to create at start-up), every value in internal units (mm, rad, N, N/mm^2).

Every record also carries ``paths`` (stage key -> the TOML path it was read from, which names
the key in messages, budgets and phase tables) and ``origins`` (stage key -> ``"spec"`` written
in the file, ``"grade"`` derived from an ISO 1328 accuracy grade, ``"default"``).

The legacy two-table form (``[gear_pair]``, ``[worm_pair]``, ``[assembly]``, ``[loads]``) is the
train [worm, spur]: :data:`LEGACY_KEYS` maps each of its keys to a stage key, the one table
behind loading the old form, ``wormgear upgrade`` and the old attribute names.

Problems are reported by position and kind: ``FILE: stage 2 (spur): module_mm: expected ...``.
"""

from types import MappingProxyType
from typing import Any, NamedTuple

from wormgear_cli.errors import did_you_mean
from wormgear_cli.physics.iso1328 import GradeError, flank_tolerances
from wormgear_cli.spec.fields import MISSING, UNIT_SCALE, Field, check_value, quote, type_name
from wormgear_cli.spec.kinds import KINDS, StageKind

# the kinds' records and geometry, where they were before the kinds had their own modules
from wormgear_cli.spec.kinds.belt import (  # noqa: F401
    BeltStageSpec,
    Pulley,
    belt_centre_distance,
    pulley_radius,
)
from wormgear_cli.spec.kinds.spur import SpurGear, SpurStageSpec  # noqa: F401
from wormgear_cli.spec.kinds.worm import Wheel, Worm, WormStageSpec, wheel_transverse_pressure_angle  # noqa: F401

#: stage kinds, in the order the docs list them (:data:`wormgear_cli.spec.kinds.KINDS`)
STAGE_KINDS = tuple(KINDS)
#: the most stages a drive may have
MAX_STAGES = 16
#: default stage name per kind ("gear": the paper's name of its spur stage)
DEFAULT_NAMES = {name: k.default_name for name, k in KINDS.items()}
#: anti-backlash arrangements a kind may have (``anti_backlash``)
ANTI_BACKLASH = {name: k.anti_backlash for name, k in KINDS.items()}


def _kind_fields(kind: StageKind) -> tuple[Field, ...]:
    """All keys of a kind: ``kind`` and ``name``, which every stage has, then the kind's own."""
    names = [k.default_name for k in KINDS.values()]
    return (
        Field("kind", "kind", "str", "", None, f"stage kind: {_either(STAGE_KINDS)}", choices=STAGE_KINDS),
        Field("name", "name", "str", "", "derived",
              f"name shown in reports (default: {_either(names)}; numbered by position when a kind repeats)"),
        *kind.fields,
    )


def _either(words) -> str:
    """``a, b or c``."""
    words = list(words)
    return ", ".join(words[:-1]) + " or " + words[-1] if len(words) > 1 else words[0]


#: kind -> its keys (paths relative to the stage table; order = template and reference order)
STAGE_FIELDS: dict[str, tuple[Field, ...]] = {name: _kind_fields(k) for name, k in KINDS.items()}
STAGE_FIELD_BY_KEY: dict[str, dict[str, Field]] = {k: {f.path: f for f in fs} for k, fs in STAGE_FIELDS.items()}
#: kind -> its sub-tables (members), the input shaft's first
MEMBERS = {name: tuple(k.members) for name, k in KINDS.items()}
#: kind -> (its record type, member table -> its record type)
RECORDS = {name: (k.record, k.members) for name, k in KINDS.items()}
WORM_FIELDS, SPUR_FIELDS, BELT_FIELDS = STAGE_FIELDS["worm"], STAGE_FIELDS["spur"], STAGE_FIELDS["belt"]



def stage_path(index: int, key: str) -> str:
    """The TOML path of a stage key: ``stage.INDEX.KEY`` (1-based index)."""
    return f"stage.{index}.{key}"


def stage_label(index: int, kind: str) -> str:
    """How messages name a stage: ``stage 2 (spur)``."""
    return f"stage {index} ({kind})"


# --- validation -----------------------------------------------------------------------------------------------


def _known_children() -> dict[str, dict[str, frozenset[str]]]:
    out: dict[str, dict[str, frozenset[str]]] = {}
    for kind, fields in STAGE_FIELDS.items():
        table: dict[str, set[str]] = {"": set()}
        for f in fields:
            head, _, tail = f.path.partition(".")
            table[""].add(head)
            if tail:
                table.setdefault(head, set()).add(tail)
        out[kind] = {k: frozenset(v) for k, v in table.items()}
    return out


#: kind -> table ("" = the stage table, or a member) -> the keys valid directly under it (built once)
_KNOWN = _known_children()

#: keys a user may reasonably try that no standard here covers -> the message (exit 2)
NOT_COVERED = {
    f"{part}.accuracy_grade": (
        "worm pairs are not covered by ISO 1328-1/-2 (cylindrical involute gears only) and no public, "
        "citable worm-gear grade system (DIN 3974) is available here; give the worm pair's tolerances "
        "explicitly (lead_error_mm, profile_error_mm, radial_composite_error_mm, ...)")
    for part in ("worm", "wheel")
}


class StageInput(NamedTuple):
    """One ``[[stage]]`` table as checked: ``values`` stage key -> internal value (or MISSING),
    ``written``: the keys the file gives, ``grade_keys``: keys set from an accuracy grade."""

    index: int  # type: ignore[assignment]  # a field named as tuple.index, by design
    kind: str
    values: dict
    written: frozenset
    grade_keys: frozenset


def check_stage(table, index: int, source: str, problems: list[str]) -> StageInput | None:
    """Check one ``[[stage]]`` table (position ``index``, 1-based); every problem is appended to
    ``problems`` as ``SOURCE: stage INDEX (KIND): KEY: what is expected``.  None when the table is
    not usable at all (not a table, no valid kind)."""
    where = f"{source}: stage {index}"
    if not isinstance(table, dict):
        problems.append(f"{where}: expected a table [[stage]], got {type_name(table)}")
        return None
    kind = table.get("kind")
    if kind is None:
        problems.append(f"{where}: kind: missing required key, expected one of "
                        + ", ".join(f'"{k}"' for k in STAGE_KINDS))
        return None
    err, _ = check_value(STAGE_FIELD_BY_KEY[STAGE_KINDS[0]]["kind"], kind)
    if err:
        problems.append(f"{where}: kind: {err}")
        return None
    label = f"{source}: {stage_label(index, kind)}"
    _walk(table, kind, "", problems, label)
    values: dict[str, Any] = {}
    written = set()
    for f in STAGE_FIELDS[kind]:
        head, _, tail = f.path.partition(".")
        parent = table.get(head) if tail else table
        key = tail or head
        if not isinstance(parent, dict) or key not in parent or isinstance(parent[key], dict):
            if f.default is None and isinstance(parent, dict) and key not in parent:
                problems.append(f"{label}: {f.path}: missing required key, expected {f.expected()}")
            elif tail and parent is None and f.default is None:
                problems.append(f"{label}: {f.path}: missing required key, expected {f.expected()} "
                                f"(in a [stage.{head}] table)")
            values[f.path] = MISSING
            continue
        err, val = check_value(f, parent[key])
        if err:
            problems.append(f"{label}: {f.path}: {err}")
            values[f.path] = MISSING
        else:
            values[f.path] = val
            written.add(f.path)
    if values.get("name") not in (None, MISSING) and (not values["name"].isprintable() or not values["name"]):
        problems.append(f"{label}: name: expected a non-empty single-line name, got {quote(values['name'])}")
        values["name"] = MISSING
    grade_keys = _apply_grades(kind, values, problems, label)
    return StageInput(index, kind, values, frozenset(written), frozenset(grade_keys))


def _walk(table: dict, kind: str, prefix: str, problems: list[str], label: str) -> None:
    known = _KNOWN[kind].get(prefix, frozenset())
    for key, value in table.items():
        shown = key if key.isprintable() and key.strip() == key and key else quote(key)
        rel = f"{prefix}.{shown}" if prefix else shown
        if key not in known:
            if rel in NOT_COVERED and kind == "worm":
                problems.append(f"{label}: {rel}: {NOT_COVERED[rel]}")
                continue
            # a key of another kind first (it is exactly that), else the nearest key of this table, else the
            # nearest path of this kind (a misplaced key)
            hint = (_other_kind(rel, kind)
                    or did_you_mean(key, sorted(known), show=lambda m: (prefix + "." if prefix else "") + m)
                    or did_you_mean(rel, list(STAGE_FIELD_BY_KEY[kind]), cutoff=0.75))
            what = "table" if isinstance(value, dict) else "key"
            problems.append(f"{label}: {rel}: unknown {what}{hint}")
            continue
        is_member = not prefix and key in MEMBERS[kind]
        if is_member and not isinstance(value, dict):
            problems.append(f"{label}: {rel}: expected a table [stage.{rel}], got {type_name(value)}")
        elif not is_member and isinstance(value, dict):
            problems.append(f"{label}: {rel}: expected a value, got a table")
        elif isinstance(value, dict):
            _walk(value, kind, rel, problems, label)


def _other_kind(rel: str, kind: str) -> str:
    """A hint when the key belongs to another kind of stage (a spur key in a worm stage)."""
    others = [k for k in STAGE_KINDS if k != kind and rel in STAGE_FIELD_BY_KEY[k]]
    if others:
        return f" (a key of {' and '.join(others)} stages; this stage has kind = \"{kind}\")"
    return ""


def _apply_grades(kind: str, values: dict, problems: list[str], label: str) -> set[str]:
    """Fill the pitch deviations (and profile errors) of a stage's members that have an
    ``accuracy_grade`` key (a spur stage's gears) from their grade (:func:`fill_from_grades`).
    Returns the keys set."""
    graded = [m for m in MEMBERS[kind] if f"{m}.accuracy_grade" in STAGE_FIELD_BY_KEY[kind]]
    if not graded or values["module_mm"] is MISSING:
        return set()

    def bad(key: str, message: str) -> None:
        problems.append(f"{label}: {key}: {message}")

    return fill_from_grades(values, values["module_mm"], values["face_width_mm"], graded, bad)


def fill_from_grades(values: dict, module: float, face, parts, bad) -> set[str]:
    """Fill each part's pitch deviations (and profile error) from its ``accuracy_grade`` where
    ``values`` (key -> internal value or MISSING) does not give them (ISO 1328-1:2013; explicit keys
    win); the one rule of both forms of a drive file.  ``parts``: the key prefix of each graded part
    (``gear``, ``gear_pair.output_gear``); ``face``: the face width [mm] (MISSING: 10 x ``module``);
    ``bad(key, message)`` for a part outside the standard's scope.  Returns the keys set."""
    out: set[str] = set()
    face = 10.0 * module if face is MISSING else face
    for part in parts:
        grade, teeth = values[f"{part}.accuracy_grade"], values[f"{part}.teeth"]
        if grade in (MISSING, None) or teeth is MISSING:
            continue

        try:
            tol = flank_tolerances(grade, module, module * teeth, face, teeth)
        except GradeError as exc:
            bad(f"{part}.accuracy_grade", f"{exc}; give the deviations explicitly instead")
            continue
        for key, um in (("cumulative_pitch_deviation_mm", tol.F_pT), ("single_pitch_deviation_mm", tol.f_pT),
                        ("profile_error_mm", tol.F_alphaT)):
            if values[f"{part}.{key}"] is MISSING:
                values[f"{part}.{key}"] = um * 1e-3
                out.add(f"{part}.{key}")
    return out


# --- defaults, names, loads and the records -------------------------------------------------------------------


def _defaults(s: StageInput, model_default: str, label: str, problems: list[str]) -> dict:
    """The stage's values with every default and derived value filled in (key units -> internal)."""
    v = dict(s.values)
    for f in STAGE_FIELDS[s.kind]:
        if v[f.path] is not MISSING or f.default in ("derived", None):
            continue
        d = f.default
        if d == "":
            v[f.path] = None
        elif f.kind == "floats":
            v[f.path] = tuple(x * UNIT_SCALE[f.unit] for x in d)
        elif f.kind == "str":
            v[f.path] = d
        else:
            v[f.path] = float(d) * UNIT_SCALE[f.unit]
    if "stiffness_model" in v:  # a gear mesh's stage
        if v["face_width_mm"] is MISSING and v["module_mm"] is not MISSING:
            v["face_width_mm"] = 10.0 * v["module_mm"]
        if v["stiffness_model"] is MISSING:
            v["stiffness_model"] = model_default
        if "residual_lost_motion_arcsec" in s.written and v["anti_backlash"] == "none" and \
                v["residual_lost_motion_arcsec"] not in (0.0, MISSING):
            problems.append(f"{label}: residual_lost_motion_arcsec: only with an anti-backlash arrangement; set "
                            f"anti_backlash = \"{ANTI_BACKLASH[s.kind][1]}\" or remove the key")
    KINDS[s.kind].derive(v, label, problems)
    return v


def _ratio(kind: str, v: dict) -> float | None:
    out, inp = (v[k] for k in KINDS[kind].ratio_keys)
    return None if MISSING in (out, inp) else out / inp


def _loads(stages: list[StageInput], values: list[dict], torque_nm: float | None) -> None:
    """Fill each stage's load not given in the file: the output torque T carried back to the stage's
    output shaft, T / O (O = product of the ratios after the stage; losses neglected), over its load
    radius (the kind's ``load_radius``); 0 without a torque."""
    after = 1.0
    for s, v in zip(reversed(stages), reversed(values)):
        key = KINDS[s.kind].load_key
        if v[key] is MISSING:
            radius = KINDS[s.kind].load_radius(v)
            v[key] = 0.0 if (torque_nm is None or not radius) else torque_nm * 1000.0 / after / radius
        ratio = _ratio(s.kind, v)
        after *= ratio if ratio else 1.0


def _names(stages: list[StageInput], source: str, problems: list[str]) -> list[str]:
    counts: dict[str, int] = {}
    for s in stages:
        counts[s.kind] = counts.get(s.kind, 0) + 1
    names = []
    for s in stages:
        given = s.values.get("name", MISSING)
        base = DEFAULT_NAMES[s.kind]
        names.append(given if given not in (MISSING, None) else (base if counts[s.kind] == 1 else f"{base}{s.index}"))
    for s, name in zip(stages, names):
        first = names.index(name)
        if stages[first].index != s.index:
            problems.append(f"{source}: {stage_label(s.index, s.kind)}: name: \"{name}\" is also the name of "
                            f"{stage_label(stages[first].index, stages[first].kind)}; give each stage its own name")
    return names


def build_stages(stages: list[StageInput], source: str, problems: list[str], model_default: str,
                 torque_nm: float | None, paths: list[dict] | None = None) -> tuple:
    """The records of checked stage tables (motor -> output), or () when ``problems`` is not empty.

    ``model_default``: ``[stiffness] model``; ``torque_nm``: ``[drive] output_torque_Nm`` (None: not
    given); ``paths``: per stage, stage key -> TOML path (default ``stage.INDEX.KEY``)."""
    names = _names(stages, source, problems)
    values = [_defaults(s, model_default, f"{source}: {stage_label(s.index, s.kind)}", problems) for s in stages]
    _loads(stages, values, torque_nm)
    if problems:
        return ()
    out = []
    for k, (s, v, name) in enumerate(zip(stages, values, names)):
        where = paths[k] if paths is not None else {f.path: stage_path(s.index, f.path) for f in STAGE_FIELDS[s.kind]}
        origins = {f.path: ("spec" if f.path in s.written else "grade" if f.path in s.grade_keys else "default")
                   for f in STAGE_FIELDS[s.kind]}
        load = KINDS[s.kind].load_key
        if load not in s.written and torque_nm is not None:
            origins[load] = "spec"  # derived from the drive's output torque, a value the file gives
        out.append(make_record(s.kind, s.index, name, v, where, origins))
    return tuple(out)


def make_record(kind: str, index: int, name: str, values: dict, paths: dict, origins: dict):
    """The record of kind ``kind`` from complete ``values`` (stage key -> internal value)."""
    cls, member_classes = RECORDS[kind]
    top: dict[str, Any] = {"index": index, "name": name, "paths": MappingProxyType(dict(paths)),
                           "origins": MappingProxyType(dict(origins))}
    members: dict[str, dict] = {m: {} for m in member_classes}
    for f in STAGE_FIELDS[kind]:
        if f.path in ("kind", "name"):
            continue
        head, _, tail = f.path.partition(".")
        if tail:
            members[head][f.attr] = values[f.path]
        else:
            top[f.attr] = values[f.path]
    for m, mcls in member_classes.items():
        top[m] = mcls(**members[m])
    return cls(**top)


def record_values(record) -> dict:
    """stage key -> internal value of a stage record (the inverse of :func:`make_record`)."""
    out: dict[str, Any] = {"kind": record.kind, "name": record.name}
    for f in STAGE_FIELDS[record.kind]:
        if f.path in ("kind", "name"):
            continue
        head, _, tail = f.path.partition(".")
        out[f.path] = getattr(getattr(record, head), f.attr) if tail else getattr(record, f.attr)
    return out


# --- the legacy two-table form: the train [worm, spur] ------------------------------------------------------


def _legacy_keys() -> dict[str, tuple[str, str]]:
    worm = {
        "worm_pair.module_mm": "module_mm", "worm_pair.normal_pressure_angle_deg": "normal_pressure_angle_deg",
        "worm_pair.lead_angle_deg": "lead_angle_deg",
        "worm_pair.transverse_pressure_angle_deg": "transverse_pressure_angle_deg",
        "worm_pair.face_width_mm": "face_width_mm", "worm_pair.lead_error_mm": "lead_error_mm",
        "worm_pair.lead_error_phase_deg": "lead_error_phase_deg",
        "assembly.worm_centre_distance_error_mm": "centre_distance_error_mm",
        "assembly.worm_pair_errors_mm": "alignment_errors_mm",
        "assembly.worm_eccentricity_mm": "worm.runout_mm",
        "assembly.worm_eccentricity_phase_deg": "worm.runout_phase_deg",
        "assembly.worm_bearing_clearance_mm": "worm.bearing_clearance_mm",
        "assembly.wheel_eccentricity_mm": "wheel.runout_mm",
        "assembly.wheel_eccentricity_phase_deg": "wheel.runout_phase_deg",
        "assembly.wheel_bearing_clearance_mm": "wheel.bearing_clearance_mm",
        "loads.worm_normal_force_N": "normal_force_N",
        "requirements.max_worm_transmission_error_arcsec": "max_transmission_error_arcsec",
        "requirements.max_worm_backlash_arcsec": "max_backlash_arcsec",
        **{f"worm_pair.worm.{k}": f"worm.{k}" for k in ("starts", "profile_error_mm", "thickness_deviation_mm")},
        **{f"worm_pair.wheel.{k}": f"wheel.{k}" for k in (
            "teeth", "profile_error_mm", "thickness_deviation_mm", "radial_composite_error_mm",
            "radial_composite_phase_deg", "cumulative_pitch_deviation_mm", "cumulative_pitch_phase_deg")},
    }
    member_keys = ("teeth", "accuracy_grade", "cumulative_pitch_deviation_mm", "single_pitch_deviation_mm",
                   "cumulative_pitch_phase_deg", "single_pitch_phase_deg", "profile_error_mm",
                   "thickness_deviation_mm")
    spur = {
        **{f"gear_pair.{k}": k for k in ("module_mm", "pressure_angle_deg", "face_width_mm", "kinematics")},
        **{f"gear_pair.output_gear.{k}": f"gear.{k}" for k in member_keys},
        **{f"gear_pair.pinion.{k}": f"pinion.{k}" for k in member_keys},
        "assembly.gear_centre_distance_error_mm": "centre_distance_error_mm",
        "assembly.gear_eccentricity_mm": "eccentricity_mm",
        "assembly.gear_eccentricity_phase_deg": "eccentricity_phase_deg",
        "loads.gear_normal_force_N": "normal_force_N",
        "requirements.max_gear_transmission_error_arcsec": "max_transmission_error_arcsec",
        "requirements.max_gear_backlash_arcsec": "max_backlash_arcsec",
    }
    return {**{k: ("worm", v) for k, v in worm.items()}, **{k: ("spur", v) for k, v in spur.items()}}


#: legacy key (two-table form) -> (stage kind, stage key): the worm pair is stage 1, the spur pair stage 2
LEGACY_KEYS: dict[str, tuple[str, str]] = _legacy_keys()
#: the legacy form's train, motor -> output
LEGACY_TRAIN = ("worm", "spur")
#: (kind, stage key) -> legacy key
STAGE_TO_LEGACY: dict[tuple[str, str], str] = {v: k for k, v in LEGACY_KEYS.items()}


def is_legacy_train(stages) -> bool:
    """Whether the train is one worm stage followed by one spur stage (the legacy form's drive)."""
    return tuple(s.kind for s in stages) == LEGACY_TRAIN


def legacy_path(stages, path: str) -> str:
    """A TOML path of the stage form (``stage.2.module_mm``) as the legacy key of a [worm, spur]
    train (``gear_pair.module_mm``); other paths, and any path of another train, unchanged."""
    parts = path.split(".", 2)
    if len(parts) == 3 and parts[0] == "stage" and parts[1].isdigit() and is_legacy_train(stages):
        if not 1 <= int(parts[1]) <= len(LEGACY_TRAIN):
            return path
        return STAGE_TO_LEGACY.get((LEGACY_TRAIN[int(parts[1]) - 1], parts[2]), path)
    return path


def new_path(stages, path: str) -> str:
    """A legacy key as the stage-form path of a [worm, spur] train (``gear_pair.module_mm`` ->
    ``stage.2.module_mm``); other paths unchanged.  ``stages`` None: the legacy form's train."""
    hit = LEGACY_KEYS.get(path)
    if hit is None or (stages is not None and not is_legacy_train(stages)):
        return path
    return stage_path(LEGACY_TRAIN.index(hit[0]) + 1, hit[1])
