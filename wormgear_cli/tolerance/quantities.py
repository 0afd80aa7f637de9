"""The registry of varied quantities (data) and the spec's ``[statistics]`` table.

Every toleranced key a stage's model reads (the paper's equations, the full budget's pitch
deviations, the involute spur reading, a belt's runouts and clearance) is one
:class:`StageQuantity` of its kind (:data:`STAGE_QUANTITIES`): its stage key, its :class:`Kind`
(which sets its default distribution and the interval it lives in) and whether an ISO 1328
accuracy grade drives its tolerance.  A drive's quantities are those of its stages
(:func:`train_quantities`), each a :class:`Quantity` addressed by its TOML path in the file's own
form: ``stage.N.KEY`` in a file of ``[[stage]]`` tables, the legacy key (``assembly.wheel_eccentricity_mm``)
in a legacy two-table file.  The spec value of the key is read as the tolerance T.

* ``radial``: a magnitude (eccentricity, runout, radial composite error,
  bearing clearance, a belt's pitch variation and clearance); values in [0, T]; default Rayleigh.
* ``signed``: a deviation that may have either sign (lead, centre distance); values in
  [-T, T]; default normal with T at 3 sigma.
* ``allowance``: a tooth-thickness allowance T, the thinning that makes the backlash (ISO
  21771's E_sn, DIN 3967): one-sided, a tooth is never thicker than nominal; values in [0, T];
  default normal centred on T/2 with its ends at 3 sigma.
* ``unknown``: a process we know nothing about (profile errors, the six
  alignment errors e_i, a belt's tooth-meshing error); values in [0, T]; default uniform.

``[statistics]`` overrides the distribution per key, keyed by the key's TOML path (either form
for a worm + spur drive)::

    [statistics]
    "stage.2.wheel.runout_mm" = { distribution = "uniform" }
    "assembly.wheel_eccentricity_mm" = { distribution = "uniform" }      # legacy form
    "stage.2.wheel.thickness_deviation_mm" = { distribution = "normal", cp = 1.33, cpk = 1.0 }

Random-stream rows (:class:`Layout`): the legacy [worm, spur] train keeps the rows of
:data:`STREAM_ROWS` (so its samples are those of every earlier release, in either form); any
other train's rows are its quantities' columns stage by stage (motor -> output), then its phases
in the registry's order, grouped by the release that added a key (:attr:`StageQuantity.since`:
a later key's rows come after every earlier one, so a train's existing samples never move).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import NamedTuple

from wormgear_cli.drive.registry import build
from wormgear_cli.errors import SpecError, did_you_mean
from wormgear_cli.spec.kinds import KINDS
from wormgear_cli.spec.loader import FIELD_BY_PATH, LEGACY_TABLES
from wormgear_cli.spec.stages import (
    LEGACY_KEYS,
    LEGACY_TRAIN,
    STAGE_FIELD_BY_KEY,
    is_legacy_train,
    legacy_path,
    new_path,
    record_values,
)
from wormgear_cli.tolerance.distributions import DISTRIBUTIONS, Kind

#: default distribution per kind
DEFAULT_DISTRIBUTION = {Kind.radial: "rayleigh", Kind.signed: "normal", Kind.unknown: "uniform",
                        Kind.allowance: "normal"}


@dataclass(frozen=True)
class Quantity:
    """One toleranced key of the spec that a sample varies.

    ``path``: TOML path; ``kind``: :class:`Kind`; ``grade_driven``: True when
    an ISO 1328 accuracy grade sets its tolerance (allocation then tightens it
    by one grade once grades are known; see :mod:`.allocation`); ``length``:
    number of elements of an array key (1 for a number); ``stage``: the stage (1-based, motor
    -> output) and ``key`` its stage key (0 and "" for a quantity of no stage).
    """

    path: str
    kind: Kind
    grade_driven: bool = False
    length: int = 1
    #: the spur stage's kinematics (``kinematics``, legacy ``gear_pair.kinematics``) under which the
    #: model reads the key; None: always.  Under another kinematics the quantity keeps its
    #: random-stream row but is not varied (tolerance 0).
    kinematics: str | None = None
    stage: int = 0
    key: str = ""

    def columns(self) -> tuple[str, ...]:
        """Column names: the path, or ``path[i]`` per element of an array key."""
        if self.length == 1:
            return (self.path,)
        return tuple(f"{self.path}[{i}]" for i in range(self.length))


class StageQuantity(NamedTuple):
    """A toleranced key of a stage kind: ``key`` (stage key), ``kind``, ``grade_driven``, ``length``,
    ``kinematics`` (see :class:`Quantity`), ``since``: the release generation that added it (rows of
    a later generation come after every earlier row)."""

    key: str
    kind: Kind
    grade_driven: bool = False
    length: int = 1
    kinematics: str | None = None
    since: int = 1


#: stage kind -> its toleranced keys, in a fixed order (the kind's ``toleranced``,
#: :class:`wormgear_cli.spec.kinds.base.StageKind`: append new keys at the end with a higher ``since``,
#: never reorder)
STAGE_QUANTITIES: dict[str, tuple[StageQuantity, ...]] = {
    name: tuple(StageQuantity(t.key, Kind(t.kind), t.grade_driven, t.length, t.kinematics, t.since)
                for t in k.toleranced)
    for name, k in KINDS.items()
}
STAGE_QUANTITY_BY_KEY = {kind: {q.key: q for q in qs} for kind, qs in STAGE_QUANTITIES.items()}


def _legacy_quantity(path: str) -> Quantity:
    kind, key = LEGACY_KEYS[path]
    q = STAGE_QUANTITY_BY_KEY[kind][key]
    return Quantity(path, q.kind, q.grade_driven, q.length, q.kinematics, LEGACY_TRAIN.index(kind) + 1, key)


#: The legacy [worm, spur] train's quantities by their legacy keys, in a fixed order (the first
#: release's 13, then the full budget's, then the involute reading's); their random-stream rows
#: are :data:`STREAM_ROWS`.
QUANTITIES: tuple[Quantity, ...] = tuple(_legacy_quantity(p) for p in (
    "assembly.gear_eccentricity_mm",
    "worm_pair.lead_error_mm",
    "worm_pair.worm.profile_error_mm",
    "worm_pair.worm.thickness_deviation_mm",
    "worm_pair.wheel.profile_error_mm",
    "worm_pair.wheel.thickness_deviation_mm",
    "worm_pair.wheel.radial_composite_error_mm",
    "assembly.worm_centre_distance_error_mm",
    "assembly.worm_eccentricity_mm",
    "assembly.worm_bearing_clearance_mm",
    "assembly.wheel_eccentricity_mm",
    "assembly.wheel_bearing_clearance_mm",
    "assembly.worm_pair_errors_mm",
    # --- the full budget's pitch deviations (simulate's and the budget's sources; ISO 1328-1 grade) ---
    "gear_pair.output_gear.cumulative_pitch_deviation_mm",
    "gear_pair.pinion.cumulative_pitch_deviation_mm",
    "worm_pair.wheel.cumulative_pitch_deviation_mm",
    "gear_pair.output_gear.single_pitch_deviation_mm",
    "gear_pair.pinion.single_pitch_deviation_mm",
    # --- read only by the involute gear stage (physics.spur.involute_stage) ---
    "assembly.gear_centre_distance_error_mm",
    "gear_pair.output_gear.thickness_deviation_mm",
    "gear_pair.pinion.thickness_deviation_mm",
))
QUANTITY_BY_PATH = {q.path: q for q in QUANTITIES}

#: phase keys of the legacy train's periodic sources (the registry's), drawn uniformly in [0, 360) deg
PHASES: tuple[str, ...] = (
    "assembly.gear_eccentricity_phase_deg",
    "worm_pair.lead_error_phase_deg",
    "assembly.worm_eccentricity_phase_deg",
    "worm_pair.wheel.radial_composite_phase_deg",
    "assembly.wheel_eccentricity_phase_deg",
    "gear_pair.output_gear.cumulative_pitch_phase_deg",
    "gear_pair.pinion.cumulative_pitch_phase_deg",
    "worm_pair.wheel.cumulative_pitch_phase_deg",
    "gear_pair.output_gear.single_pitch_phase_deg",
    "gear_pair.pinion.single_pitch_phase_deg",
)

#: the legacy train's budget phases -> the key that sizes their source: a phase is an output column
#: only when that key varies (the paper's five phases are always columns)
PHASE_SIZE = {
    "gear_pair.output_gear.cumulative_pitch_phase_deg": "gear_pair.output_gear.cumulative_pitch_deviation_mm",
    "gear_pair.pinion.cumulative_pitch_phase_deg": "gear_pair.pinion.cumulative_pitch_deviation_mm",
    "worm_pair.wheel.cumulative_pitch_phase_deg": "worm_pair.wheel.cumulative_pitch_deviation_mm",
    "gear_pair.output_gear.single_pitch_phase_deg": "gear_pair.output_gear.single_pitch_deviation_mm",
    "gear_pair.pinion.single_pitch_phase_deg": "gear_pair.pinion.single_pitch_deviation_mm",
}

#: The legacy train's random-stream rows (one uniform per sample each), in the order they were
#: added: the paper's five phases and its 13 quantities first (the first release), then the full
#: budget's quantities and phases.  Append only (new quantities' columns and new phases at the end,
#: never reorder), so every existing sample stays the same when the registry grows.
_FIRST_PHASES, _FIRST_QUANTITIES = 5, 13
STREAM_ROWS: tuple[str, ...] = (
    *PHASES[:_FIRST_PHASES],
    *(c for q in QUANTITIES[:_FIRST_QUANTITIES] for c in q.columns()),
    *(c for q in QUANTITIES[_FIRST_QUANTITIES:] for c in q.columns()),
    *PHASES[_FIRST_PHASES:],
)
assert len(set(STREAM_ROWS)) == len(STREAM_ROWS) == len(PHASES) + sum(q.length for q in QUANTITIES)

#: stage kind -> its keys with a tolerance that the model does not read (why they are not varied)
NOT_VARIED_KEYS = {
    "spur": {"gear.profile_error_mm": "is not used by the gear-stage equations (paper or involute)",
             "pinion.profile_error_mm": "is not used by the gear-stage equations (paper or involute)"},
}
#: the legacy form's keys of :data:`NOT_VARIED_KEYS`
NOT_VARIED = {
    "gear_pair.output_gear.profile_error_mm": NOT_VARIED_KEYS["spur"]["gear.profile_error_mm"],
    "gear_pair.pinion.profile_error_mm": NOT_VARIED_KEYS["spur"]["pinion.profile_error_mm"],
}

#: why a kinematics-bound spur key (:attr:`Quantity.kinematics`) is not varied under the paper's
#: kinematics ({kinematics}: the key naming the stage's kinematics, {eccentricity}: its eccentricity key)
NOT_READ_UNDER_KEYS = {
    "centre_distance_error_mm": "enters the paper's kinematics only as the default of {eccentricity} (vary "
    "that key); it is varied with {kinematics} = \"involute\"",
    "gear.thickness_deviation_mm": "is not used by the paper's spur-stage equations; it is varied with "
    "{kinematics} = \"involute\"",
    "pinion.thickness_deviation_mm": "is not used by the paper's spur-stage equations; it is varied with "
    "{kinematics} = \"involute\"",
}
#: the legacy form's messages of :data:`NOT_READ_UNDER_KEYS`
NOT_READ_UNDER = {
    "assembly.gear_centre_distance_error_mm": "enters the paper's kinematics only as the default of "
    "assembly.gear_eccentricity_mm (vary that key); it is varied with gear_pair.kinematics = \"involute\"",
    "gear_pair.output_gear.thickness_deviation_mm": "is not used by the paper's gear-stage equations; it is "
    "varied with gear_pair.kinematics = \"involute\"",
    "gear_pair.pinion.thickness_deviation_mm": "is not used by the paper's gear-stage equations; it is "
    "varied with gear_pair.kinematics = \"involute\"",
}


# --- a drive's quantities, phases and random-stream rows ------------------------------------------------------


def train_quantities(spec) -> tuple[Quantity, ...]:
    """The quantities of ``spec``'s train, addressed in the file's form (module docstring): the legacy
    train's in the order of :data:`QUANTITIES`, any other train's stage by stage (motor -> output)."""

    stages = spec.stages
    if is_legacy_train(stages):
        return tuple(replace(q, path=stages[q.stage - 1].paths[q.key]) for q in QUANTITIES)
    return tuple(Quantity(s.paths[q.key], q.kind, q.grade_driven, q.length, q.kinematics, s.index, q.key)
                 for s in stages for q in STAGE_QUANTITIES[s.kind])


class Layout(NamedTuple):
    """How a drive's samples are drawn: ``quantities`` (:func:`train_quantities`), ``phases`` (phase
    paths of the registry's periodic sources, the budget's included), ``rows`` (column or phase path ->
    its random-stream row), ``row_count`` (rows drawn per sample), ``phase_size`` (phase path -> the
    quantity paths sizing a budget source: its phase is an output column only when one of them
    varies; the model's own sources' phases are always columns)."""

    quantities: tuple
    phases: tuple
    rows: dict
    row_count: int
    phase_size: dict


def layout(spec, registry=None) -> Layout:
    """The :class:`Layout` of ``spec`` (module docstring).  ``registry``: the spec's registry (built
    when omitted)."""

    qs = train_quantities(spec)
    if is_legacy_train(spec.stages):
        to_file = (lambda p: new_path(spec.stages, p)) if spec.form == "stages" else (lambda p: p)
        rows = {_file_column(to_file, c): k for k, c in enumerate(STREAM_ROWS)}
        return Layout(qs, tuple(to_file(p) for p in PHASES), rows, len(STREAM_ROWS),
                      {to_file(p): (to_file(k),) for p, k in PHASE_SIZE.items()})

    reg = registry if registry is not None else build(spec)
    sources = reg.periodic(all_budget_sources=True)
    phases = tuple(dict.fromkeys(src.phase_path for src in sources))
    since = {q.path: STAGE_QUANTITY_BY_KEY[spec.stages[q.stage - 1].kind][q.key].since for q in qs}
    phase_since = {src.phase_path: max([since.get(p, 1) for p in src.size_paths] or [1]) for src in sources}
    order = []
    for gen in sorted(set(since.values()) | set(phase_since.values())):
        order += [c for q in qs if since[q.path] == gen for c in q.columns()]
        order += [p for p in phases if phase_since[p] == gen]
    phase_size = {src.phase_path: tuple(p for p in src.size_paths if p in since) for src in sources if src.tier > 0}
    return Layout(qs, phases, {name: k for k, name in enumerate(order)}, len(order), phase_size)


def _file_column(to_file, column: str) -> str:
    """A legacy column (``assembly.worm_pair_errors_mm[2]``) in the file's form."""
    path, bracket, rest = column.partition("[")
    return to_file(path) + bracket + rest


#: keys of one ``[statistics]`` entry
ENTRY_KEYS = ("distribution", "cp", "cpk", "inspected")


@dataclass(frozen=True)
class Varied:
    """A quantity as this spec varies it: tolerance ``tolerance`` [mm] (per element
    for an array key), the interval [``low``, ``high``] each value lies in,
    ``distribution`` name and process capabilities ``cp``, ``cpk`` (None: not given); ``inspected``:
    parts are inspected against the tolerance, so the law is truncated at it (the default); False, the
    process's whole law (parts beyond the tolerance are built too: a magnitude or an allowance still
    never below zero)."""

    quantity: Quantity
    tolerance: tuple[float, ...]
    distribution: str
    cp: float | None = None
    cpk: float | None = None
    inspected: bool = True

    @property
    def path(self) -> str:
        return self.quantity.path

    def bounds(self, element: int = 0) -> tuple[float, float]:
        """Interval [mm] of element ``element``: [-T, T] for a signed deviation, else [0, T]."""
        t = self.tolerance[element]
        return (-t, t) if self.quantity.kind is Kind.signed else (0.0, t)

    def with_tolerance(self, tolerance: tuple[float, ...]) -> Varied:
        return Varied(self.quantity, tuple(tolerance), self.distribution, self.cp, self.cpk, self.inspected)


def spec_value(spec, path: str):
    """The value of a TOML ``path`` in a loaded spec (internal units; a tuple for an array key)."""

    f = FIELD_BY_PATH[path]
    node = spec
    for part in f.section.split("."):
        node = getattr(node, part)
    return getattr(node, f.attr)


def _stage_of(spec, quantity: Quantity):
    """The stage record a quantity belongs to (its ``stage``; a legacy quantity of a [worm, spur]
    train by its key)."""
    if quantity.stage:
        return spec.stages[quantity.stage - 1]

    return spec.stages[LEGACY_TRAIN.index(LEGACY_KEYS[quantity.path][0])]


def applies(spec, quantity: Quantity) -> bool:
    """Whether the model reads ``quantity`` under its spur stage's kinematics."""
    return quantity.kinematics is None or quantity.kinematics == _stage_of(spec, quantity).kinematics


def tolerance_value(spec, quantity: Quantity):
    """The tolerance the model reads for ``quantity`` [mm] (a tuple for an array key): the
    spec value; 0 when the stage's kinematics does not read the key; for a spur stage's
    eccentricity under the involute kinematics only an eccentricity written in the spec
    (:attr:`~wormgear_cli.spec.stages.SpurStageSpec.model_eccentricity`)."""
    if not applies(spec, quantity):
        return (0.0,) * quantity.length if quantity.length > 1 else 0.0

    stage = _stage_of(spec, quantity)
    key = quantity.key or LEGACY_KEYS[quantity.path][1]
    if stage.kind == "spur" and key == "eccentricity_mm":
        return stage.model_eccentricity
    return record_values(stage)[key]


def varied_quantities(spec) -> tuple[Varied, ...]:
    """Every quantity of ``spec``'s train (:func:`train_quantities`) with its tolerance and distribution.

    Quantities whose tolerance is 0 (every element) are included (they then
    never vary: their columns are left out of the output by the engine).
    Raises :class:`SpecError` (one line per problem) for a bad ``[statistics]``
    table; see :func:`statistics_table`.
    """
    settings = statistics_table(spec)
    out = []
    for q in train_quantities(spec):
        value = tolerance_value(spec, q)
        tol = tuple(float(v) for v in value) if q.length > 1 else (float(value),)
        s = settings.get(q.path, {})
        out.append(Varied(q, tol, s.get("distribution", DEFAULT_DISTRIBUTION[q.kind]), s.get("cp"), s.get("cpk"),
                          s.get("inspected", True)))
    return tuple(out)


def _in_file_form(spec, written: str) -> str:
    """A ``[statistics]`` key as the file's own path: a legacy key of a [worm, spur] train in a file of
    stages as its stage path, a stage path in a legacy file as its legacy key."""

    return new_path(spec.stages, written) if spec.form == "stages" else legacy_path(spec.stages, written)


def _not_variable(spec, path: str) -> str | None:
    """Why a spec key that is not a quantity of this train cannot be varied, or None when it is not a key
    of this drive at all."""

    nominal = ("cannot be varied: the key has no tolerance (a nominal value such as teeth or module); toleranced "
               "keys: {}, ...")
    by_stage = {k: s for s in spec.stages for k in {s.paths[f]: f for f in s.paths}}
    if path in by_stage:
        stage = by_stage[path]
        key = next(f for f, p in stage.paths.items() if p == path)
        if key in NOT_VARIED_KEYS.get(stage.kind, {}):
            return f"cannot be varied: the key {NOT_VARIED_KEYS[stage.kind][key]}"
        if key.endswith("_phase_deg"):
            return "phases are always drawn uniformly in [0, 360) deg; remove this entry"
        return nominal if key in STAGE_FIELD_BY_KEY[stage.kind] else None

    if path in FIELD_BY_PATH and (spec.form == "legacy" or path.split(".")[0] not in LEGACY_TABLES):
        return nominal
    return None


def _legacy_hint(spec, path: str) -> str:
    """Where a legacy key of the two-table form is in a drive of stages: `` (did you mean "stage.2.KEY"?)``
    for each stage of the key's kind, or ""."""

    if path not in LEGACY_KEYS:
        return ""
    kind, key = LEGACY_KEYS[path]
    paths = [s.paths[key] for s in spec.stages if s.kind == kind]
    return f" (did you mean {' or '.join(chr(34) + p + chr(34) for p in paths)}?)" if paths else ""


def _not_read_message(spec, q: Quantity) -> str:
    stage = _stage_of(spec, q)
    if spec.form == "legacy":
        return NOT_READ_UNDER[q.path]
    return NOT_READ_UNDER_KEYS[q.key].format(kinematics=stage.paths["kinematics"],
                                             eccentricity=stage.paths["eccentricity_mm"])


def statistics_table(spec) -> dict[str, dict]:
    """The validated ``[statistics]`` table of ``spec``: path (the file's form) -> {distribution, cp, cpk,
    inspected (only when false)}.

    Problems (all reported at once, one line each, exit 2): a key that is not
    a spec key (with the nearest valid key), a spec key without a tolerance
    (teeth, module: nominal values), a phase key (always uniform), an entry
    that is not a table, an unknown entry key, an unknown distribution, a
    distribution that does not fit the quantity's kind, ``cp``/``cpk`` not a
    positive number, ``cpk`` > ``cp``, ``cp``/``cpk`` with the uniform law.
    """
    table = spec.raw.get("statistics")
    if table is None:
        return {}
    src = spec.source
    if not hasattr(table, "items"):
        raise SpecError(f"{src}: statistics: expected a table [statistics], got a value")
    problems: list[str] = []
    out: dict[str, dict] = {}
    quantities = {q.path: q for q in train_quantities(spec)}
    valid = list(quantities)
    for written, entry in table.items():
        where = f"{src}: statistics.\"{written}\""
        path = _in_file_form(spec, written)
        if path not in quantities:
            why = _not_variable(spec, path)
            if why is not None:
                problems.append(f"{where}: {why.format(', '.join(valid[:3]))}")
            else:
                hint = _legacy_hint(spec, path) or did_you_mean(path, valid, show=lambda m: f'"{m}"', cutoff=0.5)
                problems.append(f"{where}: unknown key, expected the TOML path of a toleranced key{hint}")
            continue
        if not hasattr(entry, "items"):
            problems.append(f"{where}: expected a table such as {{ distribution = \"uniform\" }}")
            continue
        q = quantities[path]
        if not applies(spec, q):
            stage = _stage_of(spec, q)
            problems.append(f"{where}: cannot be varied with {stage.paths['kinematics']} = "
                            f"\"{stage.kinematics}\": the key {_not_read_message(spec, q)}")
            continue
        ok = True
        for key in entry:
            if key not in ENTRY_KEYS:
                hint = did_you_mean(key, ENTRY_KEYS, otherwise=f" (valid: {', '.join(ENTRY_KEYS)})")
                problems.append(f"{where}.{key}: unknown key{hint}")
                ok = False
        name = entry.get("distribution", DEFAULT_DISTRIBUTION[q.kind])
        if not isinstance(name, str) or name not in DISTRIBUTIONS:
            shown = f'"{name}"' if isinstance(name, str) else repr(name)
            hint = did_you_mean(str(name).lower(), DISTRIBUTIONS, show=lambda m: f'"{m}"',
                                otherwise=f" (known: {', '.join(DISTRIBUTIONS)})")
            problems.append(f"{where}.distribution: unknown distribution {shown}{hint}")
            continue
        law = DISTRIBUTIONS[name]
        if q.kind.value not in law.kinds:
            problems.append(f"{where}.distribution: \"{name}\" does not fit a {q.kind.value} quantity "
                            f"(use {' or '.join(n for n, d in DISTRIBUTIONS.items() if q.kind.value in d.kinds)})")
            ok = False
        caps = {}
        for key in ("cp", "cpk"):
            if key not in entry:
                continue
            v = entry[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                problems.append(f"{where}.{key}: expected a number > 0 (a process capability), got {v!r}")
                ok = False
            elif not law.capability:
                problems.append(f"{where}.{key}: the {name} distribution takes no process capability; "
                                "remove it or use distribution = \"normal\"")
                ok = False
            elif v > 100:
                problems.append(f"{where}.{key}: expected a number in (0, 100], got {v!r}")
                ok = False
            else:
                caps[key] = float(v)
        inspected = entry.get("inspected", True)
        if not isinstance(inspected, bool):
            problems.append(f"{where}.inspected: expected true (parts inspected: the law truncated at the "
                            f"tolerance) or false (the process's whole law), got {inspected!r}")
            ok = False
        elif not inspected:
            caps["inspected"] = False
        if ok and "cp" in caps and "cpk" in caps and caps["cpk"] > caps["cp"]:
            problems.append(f"{where}: cpk = {caps['cpk']:g} exceeds cp = {caps['cp']:g} (cpk <= cp by definition)")
            ok = False
        if ok:
            out[path] = {"distribution": name, **caps}
    if problems:
        raise SpecError(problems)
    return out
