"""The registry of varied quantities (data) and the spec's ``[statistics]`` table.

Every toleranced key the model reads (the paper's equations, the full budget's
pitch deviations, the involute gear stage) is one :class:`Quantity`: its
TOML path, its :class:`Kind` (which sets its default distribution and the
interval it lives in) and whether an ISO 1328 accuracy grade drives its
tolerance.  The spec value of the key is read as the tolerance T.

* ``radial``: a magnitude (eccentricity, runout, radial composite error,
  bearing clearance); values in [0, T]; default Rayleigh.
* ``signed``: a deviation that may have either sign (lead, tooth thickness,
  centre distance); values in [-T, T]; default normal with T at 3 sigma.
* ``unknown``: a process we know nothing about (profile errors, the six
  alignment errors e_i); values in [0, T]; default uniform.

``[statistics]`` overrides the distribution per key, keyed by the key's TOML
path::

    [statistics]
    "assembly.wheel_eccentricity_mm" = { distribution = "uniform" }
    "worm_pair.wheel.thickness_deviation_mm" = { distribution = "normal", cp = 1.33, cpk = 1.0 }
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from wormgear_cli.errors import SpecError, did_you_mean
from wormgear_cli.tolerance.distributions import DISTRIBUTIONS, Kind

#: default distribution per kind
DEFAULT_DISTRIBUTION = {Kind.radial: "rayleigh", Kind.signed: "normal", Kind.unknown: "uniform"}


@dataclass(frozen=True)
class Quantity:
    """One toleranced key of the spec that a sample varies.

    ``path``: TOML path; ``kind``: :class:`Kind`; ``grade_driven``: True when
    an ISO 1328 accuracy grade sets its tolerance (allocation then tightens it
    by one grade once grades are known; see :mod:`.allocation`); ``length``:
    number of elements of an array key (1 for a number).
    """

    path: str
    kind: Kind
    grade_driven: bool = False
    length: int = 1
    #: the gear-stage kinematics (``gear_pair.kinematics``) under which the model reads the key;
    #: None: always.  Under another kinematics the quantity keeps its random-stream row but is
    #: not varied (tolerance 0).
    kinematics: str | None = None

    def columns(self) -> tuple[str, ...]:
        """Column names: the path, or ``path[i]`` per element of an array key."""
        if self.length == 1:
            return (self.path,)
        return tuple(f"{self.path}[{i}]" for i in range(self.length))


R, S, U = Kind.radial, Kind.signed, Kind.unknown

#: The registry: every toleranced key the model reads, in a fixed order (append new quantities at
#: the end, never reorder; their random-stream rows are :data:`STREAM_ROWS`).
QUANTITIES: tuple[Quantity, ...] = (
    Quantity("assembly.gear_eccentricity_mm", R, grade_driven=True),
    Quantity("worm_pair.lead_error_mm", S, grade_driven=True),
    Quantity("worm_pair.worm.profile_error_mm", U, grade_driven=True),
    Quantity("worm_pair.worm.thickness_deviation_mm", S),
    Quantity("worm_pair.wheel.profile_error_mm", U, grade_driven=True),
    Quantity("worm_pair.wheel.thickness_deviation_mm", S),
    Quantity("worm_pair.wheel.radial_composite_error_mm", R, grade_driven=True),
    Quantity("assembly.worm_centre_distance_error_mm", S),
    Quantity("assembly.worm_eccentricity_mm", R),
    Quantity("assembly.worm_bearing_clearance_mm", R),
    Quantity("assembly.wheel_eccentricity_mm", R),
    Quantity("assembly.wheel_bearing_clearance_mm", R),
    Quantity("assembly.worm_pair_errors_mm", U, length=6),
    # --- the full budget's pitch deviations (simulate's and the budget's sources; ISO 1328-1 grade) ---
    Quantity("gear_pair.output_gear.cumulative_pitch_deviation_mm", R, grade_driven=True),
    Quantity("gear_pair.pinion.cumulative_pitch_deviation_mm", R, grade_driven=True),
    Quantity("worm_pair.wheel.cumulative_pitch_deviation_mm", R),
    Quantity("gear_pair.output_gear.single_pitch_deviation_mm", U, grade_driven=True),
    Quantity("gear_pair.pinion.single_pitch_deviation_mm", U, grade_driven=True),
    # --- read only by the involute gear stage (models.gear.involute_stage) ---
    Quantity("assembly.gear_centre_distance_error_mm", S, kinematics="involute"),
    Quantity("gear_pair.output_gear.thickness_deviation_mm", S, kinematics="involute"),
    Quantity("gear_pair.pinion.thickness_deviation_mm", S, kinematics="involute"),
)
QUANTITY_BY_PATH = {q.path: q for q in QUANTITIES}

#: phase keys of the periodic sources (simulation.periodic_sources), drawn uniformly in [0, 360) deg
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

#: the budget's phases -> the key that sizes their source: a phase is an output column only when
#: that key varies (the paper's five phases are always columns)
PHASE_SIZE = {
    "gear_pair.output_gear.cumulative_pitch_phase_deg": "gear_pair.output_gear.cumulative_pitch_deviation_mm",
    "gear_pair.pinion.cumulative_pitch_phase_deg": "gear_pair.pinion.cumulative_pitch_deviation_mm",
    "worm_pair.wheel.cumulative_pitch_phase_deg": "worm_pair.wheel.cumulative_pitch_deviation_mm",
    "gear_pair.output_gear.single_pitch_phase_deg": "gear_pair.output_gear.single_pitch_deviation_mm",
    "gear_pair.pinion.single_pitch_phase_deg": "gear_pair.pinion.single_pitch_deviation_mm",
}

#: The random-stream rows (one uniform per sample each), in the order they were added: the paper's
#: five phases and its 13 quantities first (the first release), then the full budget's quantities
#: and phases.  Append only (new quantities' columns and new phases at the end, never reorder), so
#: every existing sample stays the same when the registry grows.
_FIRST_PHASES, _FIRST_QUANTITIES = 5, 13
STREAM_ROWS: tuple[str, ...] = (
    *PHASES[:_FIRST_PHASES],
    *(c for q in QUANTITIES[:_FIRST_QUANTITIES] for c in q.columns()),
    *(c for q in QUANTITIES[_FIRST_QUANTITIES:] for c in q.columns()),
    *PHASES[_FIRST_PHASES:],
)
assert len(set(STREAM_ROWS)) == len(STREAM_ROWS) == len(PHASES) + sum(q.length for q in QUANTITIES)

#: spec keys with a tolerance that the model does not read (why they are not varied)
NOT_VARIED = {
    "gear_pair.output_gear.profile_error_mm": "is not used by the gear-stage equations (paper or involute)",
    "gear_pair.pinion.profile_error_mm": "is not used by the gear-stage equations (paper or involute)",
}

#: why a kinematics-bound quantity (:attr:`Quantity.kinematics`) is not varied under the other one
NOT_READ_UNDER = {
    "assembly.gear_centre_distance_error_mm": "enters the paper's kinematics only as the default of "
    "assembly.gear_eccentricity_mm (vary that key); it is varied with gear_pair.kinematics = \"involute\"",
    "gear_pair.output_gear.thickness_deviation_mm": "is not used by the paper's gear-stage equations; it is "
    "varied with gear_pair.kinematics = \"involute\"",
    "gear_pair.pinion.thickness_deviation_mm": "is not used by the paper's gear-stage equations; it is "
    "varied with gear_pair.kinematics = \"involute\"",
}

#: keys of one ``[statistics]`` entry
ENTRY_KEYS = ("distribution", "cp", "cpk")


@dataclass(frozen=True)
class Varied:
    """A quantity as this spec varies it: tolerance ``tolerance`` [mm] (per element
    for an array key), the interval [``low``, ``high``] each value lies in,
    ``distribution`` name and process capabilities ``cp``, ``cpk`` (None: not given)."""

    quantity: Quantity
    tolerance: tuple[float, ...]
    distribution: str
    cp: float | None = None
    cpk: float | None = None

    @property
    def path(self) -> str:
        return self.quantity.path

    def bounds(self, element: int = 0) -> tuple[float, float]:
        """Interval [mm] of element ``element``: [-T, T] for a signed deviation, else [0, T]."""
        t = self.tolerance[element]
        return (-t, t) if self.quantity.kind is Kind.signed else (0.0, t)

    def with_tolerance(self, tolerance: tuple[float, ...]) -> Varied:
        return Varied(self.quantity, tuple(tolerance), self.distribution, self.cp, self.cpk)


def spec_value(spec, path: str):
    """The value of a TOML ``path`` in a loaded spec (internal units; a tuple for an array key)."""
    from wormgear_cli.spec.loader import FIELD_BY_PATH

    f = FIELD_BY_PATH[path]
    node = spec
    for part in f.section.split("."):
        node = getattr(node, part)
    return getattr(node, f.attr)


def applies(spec, quantity: Quantity) -> bool:
    """Whether the model reads ``quantity`` under the spec's gear-stage kinematics."""
    return quantity.kinematics is None or quantity.kinematics == spec.gear_pair.kinematics


def tolerance_value(spec, quantity: Quantity):
    """The tolerance the model reads for ``quantity`` [mm] (a tuple for an array key): the
    spec value; 0 when the spec's kinematics does not read the key; for the gear
    eccentricity under the involute kinematics only an eccentricity written in the spec
    (:func:`wormgear_cli.analysis.accuracy.gear_eccentricity`)."""
    if not applies(spec, quantity):
        return (0.0,) * quantity.length if quantity.length > 1 else 0.0
    if quantity.path == "assembly.gear_eccentricity_mm":
        from wormgear_cli.analysis.accuracy import gear_eccentricity

        return gear_eccentricity(spec)
    return spec_value(spec, quantity.path)


def varied_quantities(spec) -> tuple[Varied, ...]:
    """Every registry quantity of ``spec`` with its tolerance and distribution.

    Quantities whose tolerance is 0 (every element) are included (they then
    never vary: their columns are left out of the output by the engine).
    Raises :class:`SpecError` (one line per problem) for a bad ``[statistics]``
    table; see :func:`statistics_table`.
    """
    settings = statistics_table(spec)
    out = []
    for q in QUANTITIES:
        value = tolerance_value(spec, q)
        tol = tuple(float(v) for v in value) if q.length > 1 else (float(value),)
        s = settings.get(q.path, {})
        out.append(Varied(q, tol, s.get("distribution", DEFAULT_DISTRIBUTION[q.kind]), s.get("cp"), s.get("cpk")))
    return tuple(out)


def statistics_table(spec) -> dict[str, dict]:
    """The validated ``[statistics]`` table of ``spec``: path -> {distribution, cp, cpk}.

    Problems (all reported at once, one line each, exit 2): a key that is not
    a spec key (with the nearest valid key), a spec key without a tolerance
    (teeth, module: nominal values), a phase key (always uniform), an entry
    that is not a table, an unknown entry key, an unknown distribution, a
    distribution that does not fit the quantity's kind, ``cp``/``cpk`` not a
    positive number, ``cpk`` > ``cp``, ``cp``/``cpk`` with the uniform law.
    """
    from wormgear_cli.spec.loader import FIELD_BY_PATH
    from wormgear_cli.spec.stages import legacy_path

    table = spec.raw.get("statistics")
    if table is None:
        return {}
    src = spec.source
    if not hasattr(table, "items"):
        raise SpecError(f"{src}: statistics: expected a table [statistics], got a value")
    problems: list[str] = []
    out: dict[str, dict] = {}
    valid = [q.path for q in QUANTITIES]
    for written, entry in table.items():
        where = f"{src}: statistics.\"{written}\""
        path = legacy_path(spec.stages, written)  # a stage path (stage.1.wheel.runout_mm) of a worm + spur drive
        if path not in QUANTITY_BY_PATH:
            if path in PHASES:
                problems.append(f"{where}: phases are always drawn uniformly in [0, 360) deg; remove this entry")
            elif path in NOT_VARIED:
                problems.append(f"{where}: cannot be varied: the key {NOT_VARIED[path]}")
            elif path in FIELD_BY_PATH:
                problems.append(f"{where}: cannot be varied: the key has no tolerance (a nominal value such as "
                                f"teeth or module); toleranced keys: {', '.join(valid[:3])}, ...")
            else:
                hint = did_you_mean(path, valid, show=lambda m: f'"{m}"', cutoff=0.5)
                problems.append(f"{where}: unknown key, expected the TOML path of a toleranced key{hint}")
            continue
        if not hasattr(entry, "items"):
            problems.append(f"{where}: expected a table such as {{ distribution = \"uniform\" }}")
            continue
        q = QUANTITY_BY_PATH[path]
        if not applies(spec, q):
            problems.append(f"{where}: cannot be varied with gear_pair.kinematics = "
                            f"\"{spec.gear_pair.kinematics}\": the key {NOT_READ_UNDER[path]}")
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
        if ok and "cp" in caps and "cpk" in caps and caps["cpk"] > caps["cp"]:
            problems.append(f"{where}: cpk = {caps['cpk']:g} exceeds cp = {caps['cp']:g} (cpk <= cp by definition)")
            ok = False
        if ok:
            out[path] = {"distribution": name, **caps}
    if problems:
        raise SpecError(problems)
    return out
