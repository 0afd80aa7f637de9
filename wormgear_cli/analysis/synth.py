"""Synthetic measurements: measured-like data from the drive model (core of ``wormgear synth``).

No I/O, no typer, no rich.  :func:`synthesize` returns the data columns
and, separately, the truth (everything a diagnosis should recover), so a
user can try a measurement plan before measuring, and tests can check
``diagnose`` against a known answer.

The data follow a test cycle in the style of ISO 230-2: target positions
over the output turn(s), ``runs`` runs, each run one pass forward (targets
ascending, direction +1) then one pass in reverse (targets descending,
direction -1), the clock advancing ``dwell_s`` per point.  The ``iso``
plan spaces the targets irregularly, P_i = i p + r_i (p = span / targets,
r_0 = 0, r_i uniform in +/- ``jitter`` p, rounded to 0.001 deg) so periodic
errors are sampled fairly; the ``dense`` plan scans ``points`` evenly
spaced angles per pass.

Each sample's error is the model (:func:`wormgear_cli.analysis.simulate.simulate`
with the spec's sources at their phases, plus the chosen effects) at that
sample's angle, direction, load, temperature and time, plus noise:

* white noise, independent per point, N(0, ``white_arcsec``);
* run-correlated noise of size ``run_arcsec`` per run: kind ``offset``
  adds one N(0, s) offset to every point of the run (both directions);
  kind ``drift`` adds a drift growing linearly in time from 0 at the run's
  first point to an N(0, s) value at its last point.

Random numbers come from independent streams spawned from one seed
(targets, phases, white noise, run noise), so the same seed gives the same
numbers, and changing the noise does not move the targets.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from wormgear_cli.analysis.simulate import periodic_sources, simulate
from wormgear_cli.drive.train import drive_geometry
from wormgear_cli.errors import UsageError, did_you_mean
from wormgear_cli.physics.effects import EFFECTS, Signals, geometry_absent_reason, params_from_keys, params_to_keys
from wormgear_cli.physics.thermal import (
    centre_distance_change_mm,
    mesh_housing_warmup,
    predicted_centre_distance_um_per_K,
    predicted_drift_arcsec_per_K,
    worm_pair_radii,
)
from wormgear_cli.units import ARCSEC

#: the data columns, in file order
COLUMNS = ("angle_deg", "error_arcsec", "direction", "run", "load_Nm", "temperature_C", "time_s")
#: decimals each column is rounded to (the model is evaluated at the rounded conditions)
DECIMALS = {"angle_deg": 6, "error_arcsec": 4, "load_Nm": 4, "temperature_C": 3, "time_s": 3}

PLAN_KINDS = ("iso", "dense")
RUN_NOISE_KINDS = ("offset", "drift")
TEMPERATURE_KINDS = ("constant", "warmup", "cycle", "mesh-warmup")
LOAD_KINDS = ("constant", "steps")


@dataclass(frozen=True)
class Plan:
    """The measurement plan.

    ``kind``: "iso" (irregular targets) or "dense" (even scan); ``targets``:
    target positions of the iso plan; ``points``: angles per pass of the
    dense plan; ``runs``: runs (each forward then reverse, so ``runs``
    passes per direction); ``revolutions``: output turns spanned [-];
    ``dwell_s``: time per point [s] (None: 10 s for iso, 0.5 s for dense);
    ``jitter``: half-width of the iso target jitter as a fraction of the
    mean spacing (0 <= jitter < 0.5); ``cycles``: the block of ``runs`` runs
    is measured this many times (runs numbered on, 1 .. cycles x runs);
    ``cycle_gap_s``: time between two cycles [s] (the table keeps running, so
    the temperature programme goes on; no rows are recorded).
    """

    kind: str = "iso"
    targets: int = 24
    points: int = 3600
    runs: int = 5
    revolutions: float = 1.0
    dwell_s: float | None = None
    jitter: float = 0.25
    cycles: int = 1
    cycle_gap_s: float = 0.0

    @property
    def dwell(self) -> float:
        if self.dwell_s is not None:
            return float(self.dwell_s)
        return 10.0 if self.kind == "iso" else 0.5

    def check(self) -> None:
        if self.kind not in PLAN_KINDS:
            raise UsageError(f"--plan: expected one of {', '.join(PLAN_KINDS)}, got {self.kind!r}")
        if self.kind == "iso" and not 2 <= self.targets <= 100_000:
            raise UsageError(f"targets: expected an integer in [2, 100000], got {self.targets}", parameter="targets")
        if self.kind == "dense" and not 2 <= self.points <= 10_000_000:
            raise UsageError(f"points: expected an integer in [2, 10000000], got {self.points}", parameter="points")
        if not 1 <= self.runs <= 10_000:
            raise UsageError(f"runs: expected an integer in [1, 10000], got {self.runs}", parameter="runs")
        if not (math.isfinite(self.revolutions) and 0.0 < self.revolutions <= 1000.0):
            raise UsageError(f"--revs: expected a number in (0, 1000], got {self.revolutions:g}")
        if self.dwell_s is not None and not (math.isfinite(self.dwell_s) and self.dwell_s >= 0.0):
            raise UsageError(f"dwell_s: expected a number >= 0 [s], got {self.dwell_s:g}", parameter="dwell_s")
        if not (0.0 <= self.jitter < 0.5):
            raise UsageError(f"jitter: expected a number in [0, 0.5), got {self.jitter:g}", parameter="jitter")
        if not 1 <= self.cycles <= 1000:
            raise UsageError(f"cycles: expected an integer in [1, 1000], got {self.cycles}", parameter="cycles")
        if not (math.isfinite(self.cycle_gap_s) and 0.0 <= self.cycle_gap_s <= 1e7):
            raise UsageError(f"cycle_gap_s: expected a number in [0, 1e7] [s], got {self.cycle_gap_s:g}",
                             parameter="cycle_gap_s")


@dataclass(frozen=True)
class Noise:
    """Noise added to the model [arcsec].

    ``white_arcsec``: standard deviation of independent per-point noise;
    ``run_arcsec``: standard deviation of the run-correlated part;
    ``run_kind``: "offset" (one offset per run) or "drift" (linear in time
    within each run, from 0 to a random end value).
    """

    white_arcsec: float = 0.0
    run_arcsec: float = 0.0
    run_kind: str = "offset"

    def check(self) -> None:
        for name, v in (("--noise-arcsec", self.white_arcsec), ("--run-noise-arcsec", self.run_arcsec)):
            if not (math.isfinite(v) and 0.0 <= v <= 36000.0):
                raise UsageError(f"{name}: expected a number in [0, 36000] [arcsec], got {v:g}")
        if self.run_kind not in RUN_NOISE_KINDS:
            raise UsageError(f"--run-noise: expected one of {', '.join(RUN_NOISE_KINDS)}, got "
                             f"{self.run_kind!r}")


@dataclass(frozen=True)
class Programme:
    """A temperature [degC] or load [N m] programme over the test.

    Temperature kinds: ``constant`` (T); ``warmup`` (T0, T1, tau_s):
    T(t) = T0 + (T1 - T0)(1 - exp(-t / tau)); ``cycle`` (T0, T1, tau_s
    [, t_switch_s]): the warm-up until t_switch (default: half the test),
    then cooling back towards T0 with the same tau,
    T(t) = T0 + (T(t_switch) - T0) exp(-(t - t_switch) / tau);
    ``mesh-warmup`` (T0, T1, tau_s, share, lag_s): the recorded temperature
    is the worm mesh's (sensor at the mesh / in its oil) and warms as
    ``warmup``; the housing rises towards ``share`` of the mesh's rise,
    lagging it by a first-order lag ``lag_s``
    (:func:`wormgear_cli.physics.thermal.mesh_housing_warmup`).
    Load kinds: ``constant`` (L); ``steps`` (L1, L2, ...): run j (1-based)
    at L[(j - 1) mod n].
    """

    kind: str
    values: tuple[float, ...]

    def evaluate(self, t: np.ndarray, run: np.ndarray, duration: float) -> np.ndarray:
        """The programme's value at times ``t`` [s] in runs ``run``; ``duration`` [s] of the whole test."""
        v = self.values
        if self.kind == "constant":
            return np.full(t.shape, v[0])
        if self.kind == "steps":
            levels = np.asarray(v, dtype=float)
            return levels[(run - 1) % len(levels)]
        t0, t1, tau = v[0], v[1], v[2]
        warm = t0 + (t1 - t0) * -np.expm1(-t / tau)
        if self.kind in ("warmup", "mesh-warmup"):
            return warm
        switch = v[3] if len(v) > 3 else 0.5 * duration
        at_switch = t0 + (t1 - t0) * -math.expm1(-switch / tau)
        cool = t0 + (at_switch - t0) * np.exp(-np.maximum(t - switch, 0.0) / tau)
        return np.where(t <= switch, warm, cool)

    def housing(self, t: np.ndarray) -> np.ndarray | None:
        """The housing temperature [degC] at times ``t`` [s] of a ``mesh-warmup``, else None."""
        if self.kind != "mesh-warmup":
            return None

        t0, t1, tau, share, lag = self.values
        return t0 + mesh_housing_warmup(t, t1 - t0, tau, share, lag)[1]

    def describe(self, unit: str) -> str:
        v = self.values
        if self.kind == "constant":
            return f"constant {v[0]:g} {unit}"
        if self.kind == "steps":
            return "steps per run: " + ", ".join(f"{x:g}" for x in v) + f" {unit}"
        if self.kind == "mesh-warmup":  # the housing is not recorded: say where the sensor is, nothing more
            return f"warmup {v[0]:g} -> {v[1]:g} {unit}, tau {v[2]:g} s (sensor at the worm mesh)"
        text = f"{self.kind} {v[0]:g} -> {v[1]:g} {unit}, tau {v[2]:g} s"
        if self.kind == "cycle":
            text += f", cooling from t = {v[3]:g} s" if len(v) > 3 else ", cooling from half-time"
        return text

    def to_dict(self) -> dict:
        names = {"constant": ("value",), "warmup": ("start", "end", "tau_s"),
                 "cycle": ("start", "end", "tau_s", "switch_s"),
                 "mesh-warmup": ("start", "end", "tau_s", "housing_share", "housing_lag_s")}.get(self.kind)
        if names is None:
            return {"kind": self.kind, "levels": list(self.values)}
        return {"kind": self.kind, **dict(zip(names, self.values))}


# --- parsing the command-line forms ---------------------------------------------------


def _numbers(text: str, option: str, parts: list[str]) -> tuple[float, ...]:
    out = []
    for p in parts:
        try:
            x = float(p)
        except ValueError:
            raise UsageError(f"{option}: expected a number, got {p!r} in {text!r}") from None
        if not math.isfinite(x):
            raise UsageError(f"{option}: expected a finite number, got {p!r} in {text!r}")
        out.append(x)
    return tuple(out)


def parse_temperature(text: str, option: str = "--temperature") -> Programme:
    """``constant:T`` | ``warmup:T0:T1:TAU_s`` | ``cycle:T0:T1:TAU_s[:SWITCH_s]`` |
    ``mesh-warmup:T0:T1:TAU_s:SHARE:LAG_s`` -> Programme."""
    kind, *parts = text.strip().split(":")
    forms = ("constant:T, warmup:START:END:TAU_s, cycle:START:PEAK:TAU_s[:SWITCH_s] or "
             "mesh-warmup:START:END:TAU_s:HOUSING_SHARE:HOUSING_LAG_s")
    if kind not in TEMPERATURE_KINDS:
        raise UsageError(f"{option}: expected {forms}, got {text!r}")
    counts = {"constant": (1,), "warmup": (3,), "cycle": (3, 4), "mesh-warmup": (5,)}[kind]
    if len(parts) not in counts:
        raise UsageError(f"{option}: expected {forms}, got {text!r}")
    values = _numbers(text, option, parts)
    for x in values[:2]:
        if not -100.0 <= x <= 300.0:
            raise UsageError(f"{option}: temperature {x:g} degC outside [-100, 300] in {text!r}")
    if kind != "constant" and values[2] <= 0.0:
        raise UsageError(f"{option}: TAU_s must be > 0, got {values[2]:g} in {text!r}")
    if kind == "cycle" and len(values) == 4 and values[3] < 0.0:
        raise UsageError(f"{option}: SWITCH_s must be >= 0, got {values[3]:g} in {text!r}")
    if kind == "mesh-warmup":
        if not 0.0 <= values[3] <= 1.0:
            raise UsageError(f"{option}: HOUSING_SHARE must be in [0, 1] (the housing rises less than the mesh), "
                             f"got {values[3]:g} in {text!r}")
        if values[4] < 0.0:
            raise UsageError(f"{option}: HOUSING_LAG_s must be >= 0, got {values[4]:g} in {text!r}")
    return Programme(kind, values)


def parse_load(text: str, option: str = "--load") -> Programme:
    """``constant:L`` | ``steps:L1:L2:...`` (one level per run, cycling) -> Programme [N m]."""
    kind, *parts = text.strip().split(":")
    forms = "constant:L or steps:L1:L2:... [N m]"
    if kind not in LOAD_KINDS or not parts or (kind == "constant" and len(parts) != 1):
        raise UsageError(f"{option}: expected {forms}, got {text!r}")
    values = _numbers(text, option, parts)
    return Programme(kind, values)


def parse_effect(text: str, option: str = "--effect") -> tuple[str, dict]:
    """``NAME`` or ``NAME:key=value,key=value`` -> (name, {key: value}) in catalogue units.

    Checks the name and the keys against the catalogue (values are checked
    by :func:`resolve_effects`)."""
    name, _, rest = text.strip().partition(":")
    if name not in EFFECTS:
        hint = did_you_mean(name, EFFECTS, otherwise=f" (known: {', '.join(EFFECTS)})")
        raise UsageError(f"{option}: unknown effect {name!r}{hint}")
    keys = [p.key for p in EFFECTS[name].params]
    values: dict = {}
    for item in filter(None, (s.strip() for s in rest.split(","))):
        key, eq, value = item.partition("=")
        key = key.strip()
        if not eq:
            raise UsageError(f"{option}: expected key=value, got {item!r} in {text!r}")
        if key not in keys:
            hint = did_you_mean(key, keys, otherwise=f" (valid: {', '.join(keys)})")
            raise UsageError(f"{option}: {name}: unknown key {key!r}{hint}")
        if key in values:
            raise UsageError(f"{option}: {name}.{key} is given twice in {text!r}")
        try:
            values[key] = float(value)
        except ValueError:
            raise UsageError(f"{option}: {name}.{key}: expected a number, got {value.strip()!r}") from None
    return name, values


def parse_effects(texts, option: str = "--effect") -> dict[str, dict]:
    """Every ``--effect`` text (:func:`parse_effect`) merged: name -> {key: value}; a later
    text's keys override an earlier one's for the same effect."""
    effects: dict = {}
    for text in texts or []:
        name, values = parse_effect(text, option)
        effects.setdefault(name, {}).update(values)
    return effects


def resolve_effects(spec, effects: dict | None = None, include_spec: bool = True) -> dict[str, dict]:
    """Merge the spec's ``[effects.*]`` with ``effects`` (name -> {key: value}, catalogue units).

    Keys given in ``effects`` override the spec's for the same effect.
    Missing optional keys take their catalogue default; a missing
    ``thermal_backlash.centre_distance_um_per_K`` takes the value predicted
    from the spec's materials, a missing ``thermal_drift.arcsec_per_K`` the
    worm's axial growth (when the spec gives the thrust-bearing distance);
    any other missing required key, a value
    outside its physical range or an unknown name raises UsageError.
    Returns name -> {key: value} in catalogue units, in catalogue order.
    """
    merged: dict[str, dict] = {}
    if include_spec:
        for name, params in spec.effects.items():
            merged[name] = params_to_keys(name, params)

    g = drive_geometry(spec) if effects else None
    for name, values in (effects or {}).items():
        if name not in EFFECTS:
            raise UsageError(f"--effect: unknown effect {name!r} (known: {', '.join(EFFECTS)})")
        absent = geometry_absent_reason(name, g) if g is not None else None
        if absent is not None:
            raise UsageError(f"--effect {name}: not an effect of this drive: {absent}")
        merged.setdefault(name, {}).update({k: float(v) for k, v in values.items()})
    out: dict[str, dict] = {}
    for name in EFFECTS:
        if name not in merged:
            continue
        given = merged[name]
        full = {}
        for p in EFFECTS[name].params:
            if p.key in given:
                v = given[p.key]
            elif p.default is not None:
                v = p.default
            elif name == "thermal_backlash" and p.key == "centre_distance_um_per_K":
                v = predicted_centre_distance_um_per_K(spec)
            elif name == "thermal_drift" and p.key == "arcsec_per_K" and predicted_drift_arcsec_per_K(spec):
                v = predicted_drift_arcsec_per_K(spec)
            else:
                raise UsageError(f"--effect {name}: missing {p.key} (a number in [{p.lo:g}, {p.hi:g}] {p.unit})")
            if not (math.isfinite(v) and p.lo <= v <= p.hi):
                raise UsageError(f"--effect {name}: {p.key} = {v:g} outside its range [{p.lo:g}, {p.hi:g}] "
                                 f"{p.unit}")
            full[p.key] = float(v)
        unknown = sorted(set(given) - set(full))
        if unknown:
            raise UsageError(f"--effect {name}: unknown key {unknown[0]!r} "
                             f"(valid: {', '.join(p.key for p in EFFECTS[name].params)})")
        out[name] = full
    return out


# --- the synthesis --------------------------------------------------------------------


def plan_angles(plan: Plan, rng: np.random.Generator | None = None) -> np.ndarray:
    """Target angles of one forward pass [deg], ascending (iso: jittered with ``rng``)."""
    span = 360.0 * plan.revolutions
    if plan.kind == "dense":
        return np.round(np.arange(plan.points) * (span / plan.points), DECIMALS["angle_deg"])
    p = span / plan.targets
    rng = rng if rng is not None else np.random.default_rng(0)
    r = rng.uniform(-plan.jitter * p, plan.jitter * p, plan.targets)
    r[0] = 0.0
    return np.round(np.arange(plan.targets) * p + r, 3)


@dataclass(frozen=True)
class Synthesis:
    """Result of :func:`synthesize`: ``columns`` (name -> array, in :data:`COLUMNS`
    order), ``truth`` (JSON-ready dict) and ``comments`` (the ``#`` lines)."""

    columns: dict
    truth: dict
    comments: tuple = field(default_factory=tuple)

    def __iter__(self):  # allows ``columns, truth = synthesize(...)``
        return iter((self.columns, self.truth))


def synthesize(spec, plan: Plan | None = None, effects: dict | None = None, noise: Noise | None = None,
               seed: int = 0, temperature: Programme | None = None, load: Programme | None = None,
               phases: dict | None = None, random_phases: bool = False, include_spec_effects: bool = True,
               offset_arcsec: float = 0.0) -> Synthesis:
    """Measured-like data from the model of ``spec``.

    Parameters
    ----------
    spec : a loaded drive (:class:`wormgear_cli.spec.loader.Spec`)
    plan : :class:`Plan` (default: iso, 24 targets, 5 runs, one turn, 10 s per point)
    effects : name -> {key: value} in catalogue units (merged over the spec's
        ``[effects.*]``; see :func:`resolve_effects`)
    noise : :class:`Noise` (default: none)
    seed : integer seed of every random number
    temperature : :class:`Programme` [degC] (default: constant 20 degC)
    load : :class:`Programme` [N m] (default: constant 0)
    phases : source name -> phase [rad] overriding the spec's phases
    random_phases : draw every source phase uniformly in [0, 360) deg from the
        seed (``phases`` still wins for the names it gives)
    include_spec_effects : False ignores the spec's ``[effects.*]``
    offset_arcsec : a constant zero offset added to every error [arcsec]

    Returns a :class:`Synthesis` (unpacks as ``columns, truth``).  Columns:
    angle_deg, error_arcsec, direction (+1/-1), run (1..runs), load_Nm,
    temperature_C, time_s, each a numpy array, rows in measuring order.
    """
    plan = plan or Plan()
    noise = noise or Noise()
    temperature = temperature or Programme("constant", (20.0,))
    load = load or Programme("constant", (0.0,))
    plan.check()
    noise.check()
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise UsageError(f"seed: expected a non-negative integer, got {seed!r}", parameter="seed")
    resolved, internal, physical_backlash = _synth_effects(spec, effects, include_spec_effects, temperature)

    rng_targets, rng_phases, rng_white, rng_run = (
        np.random.default_rng(s) for s in np.random.SeedSequence(int(seed)).spawn(4))
    sources = periodic_sources(spec)
    draw = rng_phases.uniform(0.0, 2.0 * math.pi, len(sources))
    used = {src.name: float((phases or {}).get(src.name, random_phase if random_phases else src.phase))
            for src, random_phase in zip(sources, draw)}

    targets = plan_angles(plan, rng_targets)
    n_t = len(targets)
    runs = plan.runs * plan.cycles
    angle, direction, run, time = _schedule(plan, targets)
    n = angle.size
    duration = float(time[-1]) if n else 0.0
    temp = np.round(temperature.evaluate(time, run, duration), DECIMALS["temperature_C"])
    torque = np.round(load.evaluate(time, run, duration), DECIMALS["load_Nm"])

    signals = Signals(np.radians(angle), direction, torque, temp, time)
    model = simulate(spec, signals, used, offset_arcsec * ARCSEC, internal) / ARCSEC
    thermal_truth = None
    if physical_backlash:
        term, thermal_truth = _two_temperature_backlash(spec, signals, temperature)
        model = model + term / ARCSEC

    white, correlated, run_values = _noise_terms(noise, rng_white, rng_run, run, runs, n_t)
    error = np.round(model + white + correlated, DECIMALS["error_arcsec"]) + 0.0  # + 0.0: no "-0.0"

    columns = {
        "angle_deg": angle,
        "error_arcsec": error,
        "direction": direction.astype(int),
        "run": run.astype(int),
        "load_Nm": torque + 0.0,
        "temperature_C": temp + 0.0,
        "time_s": time,
    }
    truth = {
        "generator": "wormgear synth",
        "drive": spec.drive.name,
        "spec": str(spec.source),
        "seed": int(seed),
        "rows": int(n),
        "plan": _plan_truth(plan, targets),
        "phases": {src.name: {"key": src.phase_path, "phase_deg": math.degrees(used[src.name]),
                              "order": src.order} for src in sources},
        "random_phases": bool(random_phases),
        "effects": resolved,
        "spec_effects_included": bool(include_spec_effects),
        "noise": {**asdict(noise), "run_values_arcsec": [float(x) for x in run_values]},
        "temperature": {**temperature.to_dict(),
                        **({"switch_s": 0.5 * duration} if temperature.kind == "cycle"
                           and len(temperature.values) == 3 else {})},
        "load": load.to_dict(),
        "offset_arcsec": float(offset_arcsec),
    }
    if thermal_truth is not None:
        truth["effects"]["thermal_backlash"] = {"centre_distance_um_per_K": thermal_truth["predicted_um_per_K"],
                                               "reference_temperature_C": temperature.values[0]}
        truth["thermal"] = thermal_truth
    comments = _comments(spec, plan, n_t, temperature, load)
    return Synthesis(columns, truth, comments)


def _synth_effects(spec, effects: dict | None, include_spec_effects: bool,
                   temperature: Programme) -> tuple[dict, dict, bool]:
    """(the effects in catalogue keys, the same in the model's parameters, whether ``thermal_backlash``
    comes from the two temperatures): a mesh-warmup makes thermal_backlash from the two temperatures (see
    :func:`_two_temperature_backlash`), so it is left out of the parameters then."""
    two_temperature = temperature.kind == "mesh-warmup"
    if two_temperature and "centre_distance_um_per_K" in ((effects or {}).get("thermal_backlash") or {}):
        raise UsageError("--effect thermal_backlash: with a mesh-warmup temperature the centre-distance growth "
                         "follows from the spec's [materials] and the housing's share of the warm-up; give a bare "
                         "--effect thermal_backlash")
    resolved = resolve_effects(spec, effects, include_spec_effects)
    internal = {name: params_from_keys(name, values) for name, values in resolved.items()}
    physical_backlash = two_temperature and "thermal_backlash" in internal
    if physical_backlash:
        internal.pop("thermal_backlash")
    return resolved, internal, physical_backlash


def _schedule(plan: Plan, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rows in measuring order: angle [deg], direction (+1/-1), run (1..runs x cycles) and time [s]
    (``dwell`` apart, cycles ``cycle_gap_s`` apart); each run goes out over the targets and back."""
    n_t = len(targets)
    runs = plan.runs * plan.cycles
    one_run = np.concatenate([targets, targets[::-1]])
    direction = np.tile(np.concatenate([np.ones(n_t), -np.ones(n_t)]), runs)
    angle = np.tile(one_run, runs)
    run = np.repeat(np.arange(1, runs + 1), 2 * n_t)
    cycle = (run - 1) // plan.runs  # 0-based cycle of each row; cycles are cycle_gap_s apart
    time = np.round(np.arange(angle.size) * plan.dwell + cycle * plan.cycle_gap_s, DECIMALS["time_s"])
    return angle, direction, run, time


def _noise_terms(noise: Noise, rng_white, rng_run, run: np.ndarray, runs: int,
                 n_t: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(white noise of each row, the run-to-run part of each row, each run's value) [arcsec]: the run's
    value as an offset, or as a drift growing from 0 to it over the run's 2 n_t rows."""
    n = run.size
    white = rng_white.normal(0.0, noise.white_arcsec, n) if noise.white_arcsec > 0 else np.zeros(n)
    run_values = rng_run.normal(0.0, noise.run_arcsec, runs) if noise.run_arcsec > 0 else np.zeros(runs)
    if noise.run_kind == "offset":
        correlated = run_values[run - 1]
    else:
        per = 2 * n_t
        frac = (np.arange(n) % per) / max(per - 1, 1)
        correlated = run_values[run - 1] * frac
    return white, correlated, run_values


def _plan_truth(plan: Plan, targets: np.ndarray) -> dict:
    """The truth's ``plan``: the plan's fields that apply to its kind, the dwell, and an iso plan's target
    angles [deg]; the single-cycle truth stays as it was before cycles existed."""
    out = {**asdict(plan), "dwell_s": plan.dwell}
    if plan.kind == "iso":
        out["target_angles_deg"] = [float(x) for x in targets]
    if plan.cycles == 1:
        out.pop("cycles")
        out.pop("cycle_gap_s")
    if plan.kind == "dense":
        out.pop("targets")
        out.pop("jitter")
    else:
        out.pop("points")
    return out


def _two_temperature_backlash(spec, signals: Signals, temperature: Programme):
    """``thermal_backlash`` from the two temperatures of a ``mesh-warmup`` [rad], and its truth.

    Worm and wheel are at the recorded (mesh) temperature T_m, the housing at
    T_H (:meth:`Programme.housing`); the centre distance changes by
    Delta a(t) = a alpha_H dT_H - (r_1 alpha_1 + r_2 alpha_2) dT_m
    (:func:`wormgear_cli.physics.thermal.centre_distance_change_mm`), and the
    catalogue signature turns Delta a into the output error: the backlash
    changes by 2 Delta a tan(alpha_x) at the wheel pitch circle.  The
    temperatures are those of the rounded time column; dT from the
    programme's start temperature.

    The truth's ``thermal_backlash`` coefficient is the physics' own,
    a alpha_H s - (r_1 alpha_1 + r_2 alpha_2)
    (:func:`~wormgear_cli.physics.thermal.predicted_centre_distance_um_per_K`
    with q = the housing share s: exact once the lag has settled).  The
    ``thermal`` block adds the linear equivalent over this test (least
    squares of Delta a on dT_m through the start) and the non-linearity the
    lag leaves (the physical term minus the linear one, RMS and max over the
    rows [arcsec]).
    """
    from wormgear_cli.analysis.accuracy import geometry  # lazy: keeps analysis.accuracy off `simulate`'s start-up

    t0, _t1, _tau, share, lag = temperature.values
    mesh_dt = signals.temperature - t0
    housing = temperature.housing(signals.time)
    assert housing is not None  # (a mesh-warmup programme: the only one with a housing)
    housing_dt = housing - t0
    delta_a = centre_distance_change_mm(spec, mesh_dt, housing_dt)  # [mm]
    g = geometry(spec)
    fn = EFFECTS["thermal_backlash"].function
    # the signature is linear in k (T - T_ref): k = 1 mm/K and T - T_ref = Delta a [mm] give Delta a itself
    unit = Signals(signals.theta, signals.direction, signals.load, delta_a, signals.time)
    term = fn(unit, g, coefficient=1.0, reference_temperature=0.0)
    ss = float(mesh_dt @ mesh_dt)
    k_lin = float(delta_a @ mesh_dt) / ss if ss > 0 else 0.0  # [mm/K]
    linear = fn(signals, g, coefficient=k_lin, reference_temperature=t0)
    dev = (term - linear) / ARCSEC
    a, r1, r2 = worm_pair_radii(spec)
    mat = spec.materials
    truth = {
        "model": "two-temperature: worm and wheel at the recorded (mesh) temperature, housing lagging "
                 "(models/thermal.py mesh_housing_warmup, centre_distance_change_mm)",
        "recorded_temperature": "worm mesh / oil",
        "housing_share": float(share),
        "housing_lag_s": float(lag),
        "housing_temperature_C": [float(t0 + housing_dt.min()), float(t0 + housing_dt.max())],
        "centre_distance_mm": a, "worm_radius_mm": r1, "wheel_radius_mm": r2,
        "expansion_ppm_per_K": {"housing": mat.housing_expansion * 1e6, "worm": mat.worm_expansion * 1e6,
                                "wheel": mat.wheel_expansion * 1e6},
        "centre_distance_change_um": [float(delta_a.min() * 1000.0), float(delta_a.max() * 1000.0)],
        "predicted_um_per_K": predicted_centre_distance_um_per_K(spec, share),
        "linear_equivalent_um_per_K": k_lin * 1000.0,
        "nonlinearity_rms_arcsec": float(np.sqrt(np.mean(dev * dev))),
        "nonlinearity_max_arcsec": float(np.max(np.abs(dev))),
    }
    return term, truth


def _comments(spec, plan: Plan, n_t: int, temperature: Programme, load: Programme) -> tuple[str, ...]:
    span = 360.0 * plan.revolutions
    if plan.kind == "iso":
        layout = f"iso, {n_t} targets over {span:g} deg (irregular spacing)"
    else:
        layout = f"dense, {n_t} evenly spaced angles over {span:g} deg"
    runs = f"{plan.runs} run{'s' if plan.runs != 1 else ''}, each"
    if plan.cycles > 1:
        runs = (f"{plan.cycles} cycles of {plan.runs} run{'s' if plan.runs != 1 else ''} "
                f"({plan.cycle_gap_s:g} s between cycles), each run")
    return (
        f"# synthetic measurement made by wormgear synth from drive {spec.drive.name}",
        f"# plan: {layout}; {runs} forward (+1) then reverse (-1); {plan.dwell:g} s per point",
        f"# temperature: {temperature.describe('degC')}; load: {load.describe('N m')}",
        "# the model settings, effects, noise and seed are kept in a separate truth file",
    )


def format_csv(result: Synthesis) -> str:
    """The data as CSV text: the ``#`` comment lines, the header, one line per row.

    Numbers are written in their shortest round-trip form after rounding
    (see :data:`DECIMALS`), so the same result gives the same bytes."""
    cols = result.columns
    lines = list(result.comments)
    lines.append(",".join(COLUMNS))
    text_cols = []
    for name in COLUMNS:
        arr = cols[name]
        if arr.dtype.kind in "iu":
            text_cols.append([str(int(x)) for x in arr])
        else:
            text_cols.append([_num(x) for x in arr.tolist()])
    lines.extend(",".join(row) for row in zip(*text_cols))
    return "\n".join(lines) + "\n"


def _num(x: float) -> str:
    if x == int(x) and abs(x) < 1e15:
        return str(int(x))
    return repr(x)
