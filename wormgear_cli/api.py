"""The Python API: every ``wormgear`` command as a function, for notebooks and scripts.

Each function calls the same core function as its command and returns a
result object whose angle fields are :class:`~wormgear_cli.angles.Angle`
(one value) or :class:`~wormgear_cli.angles.AngleArray` (many), so no
``unit`` argument is needed to read them.  ``result.to_dict(unit)`` is the
document the command prints with ``--format json --unit UNIT`` (built by
the same report function, so the API and the CLI cannot disagree; the test
``tests/test_api.py`` compares the two).

Functions: :func:`load_spec`, :func:`analyze`, :func:`simulate`,
:func:`read_measurement`, :func:`measure`, :func:`diagnose`,
:func:`sweep`, :func:`tolerance`, :func:`compare`, :func:`compensate`.  Wherever a function takes ``spec`` it
accepts a loaded :class:`~wormgear_cli.spec.loader.Spec` or a path to a TOML file.
Bad input raises the CLI's errors (:class:`~wormgear_cli.errors.SpecError`,
:class:`~wormgear_cli.errors.DataError`,
:class:`~wormgear_cli.errors.UsageError`, all
:class:`~wormgear_cli.errors.WormgearError`), each with ``.problems``,
one line per problem.

Importing this module loads numpy (for :class:`AngleArray`) but no model;
the models load on the first call, scipy only in :func:`diagnose` and
:func:`tolerance`.
Documented with examples in docs/api.md.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Union

import numpy as np

from wormgear_cli.angles import Angle, AngleArray
from wormgear_cli.errors import UsageError
from wormgear_cli.files import atomic_write
from wormgear_cli.units import from_unit

if TYPE_CHECKING:
    from wormgear_cli.analysis.sweep import RatioDistanceSweep
    from wormgear_cli.diagnosis.selection import Diagnosis as _DiagnosisRecord
    from wormgear_cli.measurement.reader import Measurement as _MeasurementRecord
    from wormgear_cli.workflows.compensate import CompensateResult as _CompensateRecord
    from wormgear_cli.workflows.measure import MeasureResult as _MeasureRecord

__all__ = [
    "Angle", "AngleArray",
    "load_spec", "analyze", "simulate", "read_measurement", "measure", "diagnose", "sweep", "tolerance", "compare",
    "compensate",
    "Analysis", "Stage", "Simulation", "SimulationAt", "Measurement", "MeasureResult", "Order", "Peak",
    "PeriodicError",
    "Diagnosis", "Gap", "Sweep", "Tolerance", "MetricStats", "Comparison", "Compensation",
]

PathLike = Union[str, "os.PathLike[str]"]


def _fs(path) -> str | Path:
    """A path argument as the core takes it: a str or Path as given, any other os.PathLike as a Path."""
    return path if isinstance(path, (str, Path)) else Path(os.fspath(path))

# --- bridges to the report builders (the same functions the commands call) ------------------------------------


def _analyze_report(spec, core, unit) -> dict:
    """The JSON document of ``wormgear analyze`` (stages, totals, budget, values used)."""
    # lazy: keeps output.analyze off `import wormgear_cli.api`'s start-up
    from wormgear_cli.output.analyze import document

    return document(spec, core, unit)


def _simulate_report(spec, points, revs, unit, temperature_c, load_nm, phases, effects):
    """(JSON text, curves) of ``wormgear simulate`` (dense scan)."""
    # lazy: keeps workflows.simulate off `import wormgear_cli.api`'s start-up
    from wormgear_cli.workflows.simulate import dense

    r = dense(spec, points, revs, unit, "json", temperature_c, load_nm, phases, effects)
    return r.text, r.curves


def _simulate_at_report(spec, at, unit, temperature_c, load_nm, phases, effects):
    """(JSON text, curves) of ``wormgear simulate --at``."""
    # lazy: keeps workflows.simulate off `import wormgear_cli.api`'s start-up
    from wormgear_cli.workflows.simulate import at_rows

    r = at_rows(spec, at, unit, "json", temperature_c, load_nm, phases, effects)
    return r.text, r.curves


def _simulate_text(spec, points, revs, temperature_c, load_nm, phases, effects, unit: str) -> str:
    """The JSON text of ``wormgear simulate`` in ``unit`` (a :class:`Simulation`'s document)."""
    return _simulate_report(spec, points, revs, unit, temperature_c, load_nm, phases, effects)[0]


def _simulate_at_text(spec, at, temperature_c, load_nm, phases, effects, unit: str) -> str:
    """The JSON text of ``wormgear simulate --at`` in ``unit`` (a :class:`SimulationAt`'s document)."""
    return _simulate_at_report(spec, at, unit, temperature_c, load_nm, phases, effects)[0]


def _sweep_report(sw, data, unit) -> dict:
    """The JSON document of ``wormgear sweep --i/--l-mm`` (whole grid, no shard)."""
    # lazy: keeps output.sweep off `import wormgear_cli.api`'s start-up
    from wormgear_cli.output.sweep import ratio_distance_json

    return ratio_distance_json(sw, data, unit, None, 0, sw.size)


def _plain(doc) -> dict:
    """The document exactly as the CLI writes it, parsed back: NaN -> None, numpy scalars ->
    Python numbers, tuples -> lists (the CLI's ``json_text``)."""
    # lazy: keeps output.formats off `import wormgear_cli.api`'s start-up
    from wormgear_cli.output.formats import json_text

    return json.loads(json_text(doc))


def _angle(x, unit: str = "rad") -> Angle | None:
    return None if x is None else Angle(x, unit)


def _spec(spec):
    """The drive a function evaluates: refused (SpecError) when its own figures are impossible, as
    every command refuses it (:func:`wormgear_cli.analysis.sanity.check_drive`)."""
    from wormgear_cli.analysis.sanity import check_drive  # lazy: keeps analysis off `import wormgear_cli.api`
    from wormgear_cli.spec.loader import Spec  # lazy: keeps spec.loader off `import wormgear_cli.api`'s start-up

    spec = spec if isinstance(spec, Spec) else load_spec(spec)
    check_drive(spec, str(spec.source))
    return spec


def _choice(name: str, value: str, choices: Sequence[str]) -> str:
    """The choice ``value`` names, in any case (as the command line's options take it, ``--hold
    TORQUE``); UsageError for another value."""
    found = next((c for c in choices if isinstance(value, str) and value.lower() == c.lower()), None)
    if found is None:
        raise UsageError(f"{name}={value!r}: expected one of {', '.join(choices)}")
    return found


def _flag(name: str, value) -> bool:
    """``value``, a bool; UsageError for anything else (``figures="no"`` is not False)."""
    if not isinstance(value, bool | np.bool_):
        raise UsageError(f"{name}={value!r}: expected True or False")
    return bool(value)


# --- spec ----------------------------------------------------------------------------------------------------


def load_spec(source: PathLike | str):
    """Read and validate a drive spec.

    Parameters
    ----------
    source : str or path-like
        A path to a TOML drive file, or the TOML text itself (a ``str``
        containing a newline is taken as text).

    Returns
    -------
    Spec
        The validated, immutable spec (internal units: mm, rad, N).

    Raises
    ------
    SpecError
        Every problem, one line each, naming the file and key.

    Examples
    --------
    >>> spec = load_spec("configs/mch50.toml")
    >>> spec.drive.name, spec.gear_pair.output_gear.teeth
    ('MCH50 rotary table', 144)
    """
    from wormgear_cli.spec import loader as core  # lazy: keeps spec.loader off `import wormgear_cli.api`'s start-up

    if isinstance(source, str) and "\n" in source:
        return core.loads_spec(source)
    return core.load_spec(_fs(source))


# --- analyze -------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Stage:
    """One stage's result at its own output shaft (as the paper reports it).

    ``transmission_error`` and ``backlash``: the maxima; ``parts``: their
    components by name (spur: eccentricity, deformation; worm: central
    parts and the envelope half-widths; belt: stretch, periodic, clearance);
    ``at_output``: the stage's contribution at the drive output (its values
    divided by the product of the ratios after it); ``index`` (1-based from
    the motor), ``name``, ``kind`` (worm, spur, belt), ``ratio``.
    """

    transmission_error: Angle
    backlash: Angle
    parts: dict
    at_output: dict
    index: int = 0
    name: str = ""
    kind: str = ""
    ratio: float = 1.0


@dataclass(frozen=True)
class Analysis:
    """Result of :func:`analyze`.

    Attributes
    ----------
    drive : str
    transmission_error, backlash : Angle
        Totals at the drive output.
    stages : tuple of Stage
        Every stage from the motor to the output.
    gear, worm : Stage
        The spur stage and the worm stage of a drive with one of each (the
        paper's names; for other drives read ``stages``).
    ratios : dict
        ``total`` and ``stages`` (each stage's ratio); for a worm + spur
        drive also ``gear`` (i_c = z1/z2) and ``worm`` (z3/z_worm).
    metrics : dict
        The flat columns of ``analyze --format csv`` and ``sweep --param``:
        angle columns as :class:`Angle`, the others as float or None.
    core : wormgear_cli.analysis.accuracy.Analysis
        The core result (angles [rad]).
    """

    drive: str
    transmission_error: Angle
    backlash: Angle
    stages: tuple
    ratios: dict
    metrics: dict
    core: object = field(repr=False, compare=False)
    spec: object = field(repr=False, compare=False, default=None)

    def _only(self, kind: str) -> Stage:
        found = [s for s in self.stages if s.kind == kind]
        if len(found) != 1:
            raise AttributeError(f"this drive has {len(found)} {kind} stages; read Analysis.stages")
        return found[0]

    @property
    def gear(self) -> Stage:
        """The spur stage (the paper's gear stage) of a drive with exactly one."""
        return self._only("spur")

    @property
    def worm(self) -> Stage:
        """The worm stage of a drive with exactly one."""
        return self._only("worm")

    def to_dict(self, unit: str = "arcsec") -> dict:
        """The document of ``wormgear analyze --format json --unit UNIT``."""
        return _plain(_analyze_report(self.spec, self.core, unit))


def analyze(spec) -> Analysis:
    """Transmission error and backlash of each stage and of the whole drive.

    Parameters
    ----------
    spec : Spec or path-like
        The drive.

    Returns
    -------
    Analysis
        Totals at the output: each stage's value at its own output shaft
        divided by the product of the ratios after it (for the paper's worm
        + spur drive Delta phi_c = Delta phi_cc + Delta phi_wc / i_c and
        Delta phi_h = Delta phi_ch + Delta phi_wh / i_c, i_c = z1/z2).

    Examples
    --------
    >>> r = analyze("configs/mch50.toml")
    >>> r.transmission_error  # doctest: +ELLIPSIS
    Angle(53... arcsec)
    >>> r.backlash > r.transmission_error
    True
    >>> [s.kind for s in r.stages]
    ['worm', 'spur']
    """
    # lazy: keeps analysis.accuracy off `import wormgear_cli.api`'s start-up
    from wormgear_cli.analysis.accuracy import analyze as run

    spec = _spec(spec)
    core = run(spec)
    a, i = {k: Angle(v) for k, v in core.angles.items()}, core.info
    rad = core.report("rad")  # the CLI's document in radians: one source for the structure

    def angles(d: dict) -> dict:
        return {k: Angle(v) for k, v in d.items() if isinstance(v, float) and not k.endswith("_pct")}

    angle_cols, info_cols = core.columns
    metrics = {c: a[c] for c in angle_cols}
    metrics.update({c: (None if i[c] is None else float(i[c])) for c in info_cols})
    stages = tuple(Stage(Angle(st["transmission_error"]), Angle(st["backlash"]),
                         {"transmission_error": angles(st["transmission_error_parts"]),
                          "backlash": angles(st["backlash_parts"])}, angles(st["contribution"]),
                         st["stage"], st["name"], st["kind"], st["ratio"]) for st in rad["stages"])
    return Analysis(
        drive=core.drive,
        transmission_error=a["total_transmission_error"],
        backlash=a["total_backlash"],
        stages=stages,
        ratios=dict(rad["ratios"]),
        metrics=metrics,
        core=core,
        spec=spec,
    )


# --- simulate ------------------------------------------------------------------------------------------------

def _effects(spec, effects: dict | None):
    """The effects to simulate: None (the spec's) or the spec's merged with ``effects``
    (name -> {catalogue key: value}), as ``--effect NAME:key=value`` does."""
    # lazy: keeps workflows.simulate off `import wormgear_cli.api`'s start-up
    from wormgear_cli.workflows.simulate import effect_params

    return effect_params(spec, {name: dict(values or {}) for name, values in (effects or {}).items()})


def _check_conditions(temperature_c: float, load_nm: float, revs: float | None = None) -> None:
    """The option checks of ``wormgear simulate`` (same bounds, same messages)."""
    for name, value in (("temperature_c", temperature_c), ("load_nm", load_nm)):
        if not math.isfinite(value):
            raise UsageError(f"{name}: expected a finite number, got {value}")
    if revs is not None and not (math.isfinite(revs) and 0.0 < revs <= 1000.0):
        raise UsageError(f"revs: expected a number in (0, 1000], got {revs:g}")
    if not -100.0 <= temperature_c <= 300.0:
        raise UsageError(f"temperature_c: expected a number in [-100, 300] [degC], got {temperature_c:g}")


@dataclass(frozen=True)
class Simulation:
    """Result of :func:`simulate` (dense scan): the error over the output angle.

    ``angle_deg`` [deg] (numpy array); ``forward``, ``reverse`` (the error,
    actual - target, in each direction), ``common`` (their mean) and
    ``lost_motion`` (reverse - forward): :class:`AngleArray`.
    """

    drive: str
    angle_deg: object
    forward: AngleArray
    reverse: AngleArray
    common: AngleArray
    lost_motion: AngleArray
    _text: Callable[[str], str] = field(repr=False, compare=False)  # unit -> the JSON text

    def to_dict(self, unit: str = "arcsec") -> dict:
        """The document of ``wormgear simulate --format json --unit UNIT``."""
        return json.loads(self._text(unit))


@dataclass(frozen=True)
class SimulationAt:
    """Result of :func:`simulate` with ``at=``: the model at every row of a measurement file.

    ``angle_deg`` [deg], ``direction`` (+1/-1): numpy arrays; ``simulated``
    :class:`AngleArray`; ``measured``: :class:`AngleArray` or None (file
    without errors).
    """

    drive: str
    angle_deg: object
    direction: object
    simulated: AngleArray
    measured: AngleArray | None
    _text: Callable[[str], str] = field(repr=False, compare=False)  # unit -> the JSON text

    def to_dict(self, unit: str = "arcsec") -> dict:
        """The document of ``wormgear simulate --at FILE --format json --unit UNIT``."""
        return json.loads(self._text(unit))


def simulate(spec, points: int = 3600, revs: float = 1.0, *, at: PathLike | None = None,
             temperature_c: float = 20.0, load_nm: float = 0.0, phases: str = "spec",
             effects: dict | None = None):
    """The drive's predicted error over the output angle, forward and reverse.

    Parameters
    ----------
    spec : Spec or path-like
        The drive.
    points : int
        Dense scan: number of output angles (2 to 10 000 000).
    revs : float
        Dense scan: output turns covered, angles from 0, end excluded (0 < revs <= 1000).
    at : path-like or None
        Evaluate at every row of this measurement CSV instead (its
        ``load_Nm`` and ``temperature_C`` columns where present).
    temperature_c : float [degC]
        Drive temperature (-100 to 300).
    load_nm : float [N m]
        External torque on the output.
    phases : str
        ``spec``, ``aligned-error`` or ``aligned-reversal`` (see ``wormgear simulate --help``).
    effects : dict or None
        Effects to add: name -> {catalogue key: value} (catalogue units), e.g.
        ``{"thermal_backlash": {"centre_distance_um_per_K": -0.3}}``; they
        override the spec's ``[effects.NAME]`` keys.

    Returns
    -------
    Simulation or SimulationAt
        ``SimulationAt`` when ``at`` is given.

    Raises
    ------
    UsageError, SpecError, DataError

    Examples
    --------
    >>> s = simulate("configs/mch50.toml", points=720)
    >>> len(s.forward)
    720
    >>> s.lost_motion.max() <= analyze("configs/mch50.toml").backlash
    True
    """
    spec = _spec(spec)
    # lazy: keeps workflows.simulate off `import wormgear_cli.api`'s start-up
    from wormgear_cli.workflows.simulate import PHASE_CHOICES

    phases = _choice("phases", phases, PHASE_CHOICES)
    if at is None:
        if isinstance(points, bool) or not 2 <= int(points) <= 10_000_000:
            raise UsageError(f"points: expected an integer in [2, 10000000], got {points}")
    _check_conditions(temperature_c, load_nm, None if at is not None else revs)
    eff = _effects(spec, effects)
    t_c, l_nm = float(temperature_c), float(load_nm)
    if at is not None:
        _, c = _simulate_at_report(spec, at, "rad", t_c, l_nm, phases, eff)
        return SimulationAt(spec.drive.name, c["angle_deg"], c["direction"], AngleArray(c["simulated"]),
                            None if c["measured"] is None else AngleArray(c["measured"]),
                            partial(_simulate_at_text, spec, at, t_c, l_nm, phases, eff))
    n_points, n_revs = int(points), float(revs)
    # the curves straight from the core model (the report builder would also format the whole
    # curve as text, 20x the cost); to_dict() asks the report builder, and tests/test_api.py
    # checks that both give the same curve
    import numpy as np

    # lazy: keeps analysis.simulate, physics.effects, workflows.simulate off `import wormgear_cli.api`'s start-up
    from wormgear_cli.analysis.simulate import simulate as run
    from wormgear_cli.physics.effects import Signals
    from wormgear_cli.workflows.simulate import phase_map as phase_map_of

    phase_map = phase_map_of(spec, phases)
    angle_deg = np.arange(n_points) * (360.0 * n_revs / n_points)
    theta = np.radians(angle_deg)
    f, r = (run(spec, Signals.make(theta, d, l_nm, t_c, 0.0), phase_map, effects=eff) for d in (1.0, -1.0))
    return Simulation(spec.drive.name, angle_deg, AngleArray(f), AngleArray(r), AngleArray(0.5 * (f + r)),
                      AngleArray(r - f), partial(_simulate_text, spec, n_points, n_revs, t_c, l_nm, phases, eff))


# --- measurements --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Measurement:
    """A validated measurement (result of :func:`read_measurement`).

    ``angle``, ``error``: :class:`AngleArray` (error NaN where the file has
    none); ``direction`` (+1/-1), ``run``, ``load_Nm`` [N m],
    ``temperature_C`` [degC], ``time_s`` [s]: numpy arrays; ``columns``:
    canonical name -> header cell; ``notes``, ``warnings``: what the reader
    inferred and what looks wrong.  ``core``: the core record.
    """

    source: str
    angle: AngleArray
    error: AngleArray
    direction: object
    run: object
    load_Nm: object
    temperature_C: object
    time_s: object
    columns: dict
    notes: tuple
    warnings: tuple
    core: _MeasurementRecord = field(repr=False, compare=False)
    path: object = field(repr=False, compare=False, default=None)
    options: object = field(repr=False, compare=False, default=None)

    def __len__(self) -> int:
        return len(self.core)


def _read_options(column_map, error_unit, angle_unit, input_format=None, guide: dict | None = None):
    # lazy: keeps measurement.guidelog_options, measurement.reader off `import wormgear_cli.api`'s start-up
    from wormgear_cli.measurement.guidelog_options import GuideLogOptions
    from wormgear_cli.measurement.reader import ReadOptions

    pairs = tuple((str(k), str(v)) for k, v in (column_map or {}).items())
    if input_format is not None and input_format != "auto":
        # lazy: keeps measurement.readers off `import wormgear_cli.api`'s start-up
        from wormgear_cli.measurement.readers import find_format

        find_format(input_format)
    guide = guide or {}
    sessions = guide.get("sessions")
    return ReadOptions(column_map=pairs, error_unit=error_unit, angle_unit=angle_unit,
                       input_format=None if input_format in (None, "auto") else input_format,
                       guidelog=GuideLogOptions(() if sessions is None else sessions, guide.get("pixel_scale"),
                                                guide.get("dec_deg"), guide.get("guide_rate")))


def read_measurement(path: PathLike, *, column_map: dict | None = None, error_unit: str | None = None,
                     angle_unit: str | None = None, require_error: bool = True,
                     input_format: str | None = None, sessions=None, pixel_scale: float | None = None,
                     dec_deg: float | None = None, guide_rate: float | None = None) -> Measurement:
    """Read and validate a measurement file as it is (as ``measure`` and ``diagnose`` read it).

    Parameters
    ----------
    path : path-like
        The file: a delimited table (``angle_deg``, ``error_arcsec`` or ``actual_deg``; optional
        ``direction``, ``run``, ``load_Nm``, ``temperature_C``, ``time_s``, ``velocity``) or an
        instrument's export (TwinCAT Scope), its format detected from its content.
    column_map : dict or None
        Canonical name -> header cell, as ``--map`` (e.g. ``{"angle_deg": "Position"}``).
    error_unit : str or None
        Unit of the error column (arcsec, arcmin, deg, urad); None: from the header, else arcsec.
    angle_unit : str or None
        Unit of the angle column (deg, rad); None: from the header, else deg.
    require_error : bool
        Whether the error column must be present.
    input_format : str or None
        A format name of ``wormgear measure --input-format`` (None or "auto": detected).
    sessions : int or sequence of int or None
        A PHD2 guide log's sessions to read (1 for the first; None: all), as ``--session``.
    pixel_scale, dec_deg, guide_rate : float or None
        What a PHD2 guide log may lack, as ``--pixel-scale`` [arcsec/px], ``--dec-deg`` [deg] and
        ``--guide-rate`` [arcsec/s at the equator]; each wins over the log's own value.

    Raises
    ------
    DataError, UsageError
        One line per problem, naming file, line and column (a guide log: the option that supplies
        what is missing).

    Examples
    --------
    >>> m = read_measurement("configs/mch50-warm.csv")
    >>> len(m), round(float(m.temperature_C.max()), 1)
    (720, 44.2)
    """
    # lazy: keeps measurement.readers off `import wormgear_cli.api`'s start-up
    from wormgear_cli.measurement import readers as core

    options = _read_options(column_map, error_unit, angle_unit, input_format,
                            dict(sessions=sessions, pixel_scale=pixel_scale, dec_deg=dec_deg, guide_rate=guide_rate))
    m = core.read_measurement(_fs(path), require_error=_flag("require_error", require_error), options=options)
    return Measurement(m.source, AngleArray(m.angle), AngleArray(m.error), m.direction, m.run, m.load,
                       m.temperature, m.time, dict(m.columns), tuple(m.notes), tuple(m.warnings), m, path, options)


# --- measure -------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Order:
    """One fitted order of :func:`measure`: amplitude [Angle] and phase [deg] of the common
    mode (mean of the directions) and the differential mode (half the reversal); None where
    not fitted (``status`` says why)."""

    order: float
    label: str | None
    status: str
    amplitude: Angle | None
    amplitude_stderr: Angle | None
    phase_deg: float | None
    differential_amplitude: Angle | None
    differential_phase_deg: float | None


@dataclass(frozen=True)
class Peak:
    """One of the strongest orders of the data (:func:`measure`'s ``dominant``): ``order`` [cycles per
    output turn], ``period_s`` (None without a time base), ``amplitude`` and ``amplitude_stderr``
    (zero to peak), ``group`` (lo, hi): the orders the data cannot tell from it, ``label``: the drive's
    shaft or mesh it belongs to (with a drive: "none of the drive's shafts and meshes" when no part
    explains it; None without a drive), ``significant``."""

    order: float
    period_s: float | None
    amplitude: Angle | None
    amplitude_stderr: Angle | None
    group: tuple
    label: str | None
    significant: bool


@dataclass(frozen=True)
class PeriodicError:
    """The periodic error of a guide log (:func:`measure`): ``worm_order`` [cycles per RA turn],
    ``worm_period_s``, ``worm_from`` (the drive's worm or the strongest period), ``peak_to_peak`` (over
    one worm period, each session's drift removed), ``harmonics`` and ``fitted_alongside`` (tuples of
    :class:`Order`-like dicts: order, period_s, amplitude, amplitude_stderr [Angle], phase_deg, label),
    ``rms_raw``, ``rms_drift_removed``, ``rms_worm_removed``, ``rms_residual``, ``cycles`` (worm
    cycles covered), ``curve_time_s`` and ``curve`` (the smoothed error over one worm period)."""

    worm_order: float
    worm_period_s: float
    worm_from: str
    peak_to_peak: Angle | None
    harmonics: tuple
    fitted_alongside: tuple
    rms_raw: Angle | None
    rms_drift_removed: Angle | None
    rms_worm_removed: Angle | None
    rms_residual: Angle | None
    cycles: float
    curve_time_s: object
    curve: AngleArray


@dataclass(frozen=True)
class MeasureResult:
    """Result of :func:`measure`.

    ``iso230_2``: the ISO 230-2 figures by name (A, B, E, M, R and their
    directional variants, see ``wormgear measure``) as :class:`Angle`, None
    where withheld or below the resolution of the data; ``orders``: tuple of
    :class:`Order`; ``residual_rms``: :class:`Angle`; ``verdict``,
    ``warnings``, ``notes``: text; ``resolution``: one step of the readings
    (:class:`Angle`, None when it cannot be told); ``below_resolution``: the
    names of the figures of ``iso230_2`` that are None because every reading
    they come from is equal (their scatter is below one step, not zero);
    ``dominant``: tuple of :class:`Peak`, the strongest orders of the data;
    ``periodic_error``: a guide log's :class:`PeriodicError` (None for other
    data, or when no worm period is known or found).  For a guide log
    ``iso230_2`` is None (ISO 230-2 does not apply: every frame is its own
    target) and ``targets`` 0.
    """

    source: str
    drive: str | None
    rows: int
    targets: int
    iso230_2: dict | None
    orders: tuple
    residual_rms: Angle | None
    verdict: str
    warnings: tuple
    notes: tuple
    resolution: Angle | None = None
    below_resolution: tuple = ()
    dominant: tuple = ()
    periodic_error: PeriodicError | None = None
    core: _MeasureRecord | None = field(repr=False, compare=False, default=None)

    def to_dict(self, unit: str = "arcsec") -> dict:
        """The document of ``wormgear measure --format json --unit UNIT``."""
        # lazy: keeps workflows.measure off `import wormgear_cli.api`'s start-up
        from wormgear_cli.workflows.measure import report

        if self.core is None:
            raise ValueError("this MeasureResult was made without its run: it has no document")
        return _plain(report(self.core, unit))


def measure(data, drive=None, orders: Sequence[float] | None = None, *, harmonics: int = 3,
            column_map: dict | None = None, error_unit: str | None = None,
            angle_unit: str | None = None, input_format: str | None = None, sessions=None,
            pixel_scale: float | None = None, dec_deg: float | None = None,
            guide_rate: float | None = None) -> MeasureResult:
    """ISO 230-2 figures and order amplitudes of a rotary-table measurement; the periodic error of a
    telescope mount's PHD2 guide log.

    Parameters
    ----------
    data : path-like or Measurement
        The measurement CSV, or a :class:`Measurement` from
        :func:`read_measurement` (its file is read with its options).
    drive : path-like or None
        Drive spec: its shaft and mesh orders are the default orders, labelled.
    orders : sequence of float [cycles/rev] or None
        Orders to fit (default: the drive's, else 1, 2, 3, 4).
    harmonics : int
        With ``drive``: harmonics of each shaft/mesh order (1 to 10).
    column_map, error_unit, angle_unit, input_format, sessions, pixel_scale, dec_deg, guide_rate
        As for :func:`read_measurement` (ignored when ``data`` is a Measurement).

    Raises
    ------
    DataError, SpecError, UsageError

    Examples
    --------
    >>> r = measure("configs/mch50-warm.csv", drive="configs/mch50.toml")
    >>> round(r.iso230_2["E"].arcsec, 1), round(r.iso230_2["B"].arcsec, 1)
    (216.7, 159.6)
    >>> g = measure("configs/cge-pro-guidelog.txt", drive="configs/cge-pro-ra.toml")
    >>> pe = g.periodic_error
    >>> round(pe.worm_period_s, 1), round(pe.harmonics[0]["amplitude"].arcsec, 2), round(pe.peak_to_peak.arcsec, 1)
    (478.7, 8.28, 16.8)
    """
    # lazy: keeps workflows.measure off `import wormgear_cli.api`'s start-up
    from wormgear_cli.workflows.measure import measure as run
    from wormgear_cli.workflows.measure import report

    if isinstance(data, Measurement):
        path, options = data.path, data.options
    else:
        path, options = data, _read_options(column_map, error_unit, angle_unit, input_format,
                                            dict(sessions=sessions, pixel_scale=pixel_scale, dec_deg=dec_deg,
                                                 guide_rate=guide_rate))
    if drive is not None and not isinstance(drive, (str, os.PathLike)):
        raise UsageError("drive: expected the path of a drive spec (TOML)")
    if isinstance(harmonics, bool) or not 1 <= int(harmonics) <= 10:
        raise UsageError(f"harmonics: expected an integer in [1, 10], got {harmonics}")
    if orders is not None:
        # lazy: keeps workflows.measure off `import wormgear_cli.api`'s start-up
        from wormgear_cli.workflows.measure import parse_orders

        orders = parse_orders(",".join(repr(float(k)) for k in orders))
    core = run(_fs(path), options, None if drive is None else _fs(drive), orders, int(harmonics))
    doc = report(core, "rad", per_target=False)  # the CLI's document in radians
    items = []
    for it in doc["orders"]["items"]:
        c, d = it["common"], it["differential"]
        items.append(Order(it["order"], it["label"], it["status"], _angle(c["amplitude"]),
                           _angle(c["amplitude_stderr"]), c["phase_deg"], _angle(d["amplitude"]), d["phase_deg"]))
    res = doc["resolution"] or {}
    iso = None if doc["iso230_2"] is None else {k: _angle(v) for k, v in doc["iso230_2"].items()}
    peaks = tuple(Peak(p["order"], p["period_s"], _angle(p["amplitude"]), _angle(p["amplitude_stderr"]),
                       tuple(p["group"]), p["label"], p["significant"])
                  for p in (doc["dominant"] or {}).get("peaks", ()))
    return MeasureResult(doc["source"], doc["drive"], doc["rows"], doc["targets"] or 0, iso, tuple(items),
                         _angle(doc["orders"]["residual_rms"]), doc["verdict"], tuple(doc["warnings"]),
                         tuple(doc["notes"]), _angle(res.get("step")), tuple(res.get("below", ())), peaks,
                         _periodic(doc["periodic_error"]), core)


def _periodic(pe: dict | None) -> PeriodicError | None:
    """The :class:`PeriodicError` of measure's document (angles in rad), None without one."""
    if not pe or pe.get("worm_order") is None:
        return None

    def entry(it: dict) -> dict:
        return {"order": it["order"], "period_s": it["period_s"], "amplitude": _angle(it["amplitude"]),
                "amplitude_stderr": _angle(it["amplitude_stderr"]), "phase_deg": it["phase_deg"],
                "label": it["label"]}

    rms = pe["rms"]
    return PeriodicError(pe["worm_order"], pe["worm_period_s"], pe["worm_from"], _angle(pe["peak_to_peak"]),
                         tuple(entry(it) for it in pe["harmonics"]), tuple(entry(it) for it in pe["fitted_alongside"]),
                         _angle(rms["raw"]), _angle(rms["drift_removed"]), _angle(rms["worm_removed"]),
                         _angle(rms["residual"]), pe["cycles"], np.asarray(pe["curve"]["time_s"]),
                         AngleArray(np.asarray(pe["curve"]["error"], dtype=float)))


# --- compensate ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Compensation:
    """Result of :func:`compensate`.

    ``text``: the file (write it with :meth:`write`); ``format``: the
    writer's name; ``load``: how to load the file (e.g. the LinuxCNC INI
    lines); ``orders`` and ``orders_source``: what the correction is made
    of; ``measured``: figures as measured and ``predicted``: what a repeat
    measurement will show once the file is loaded, each name -> :class:`Angle`
    (a table: the ISO 230-2 ``E``, ``B``, ``A``, ``M``; a mount: ``PE_pp``,
    the peak-to-peak over a worm cycle); ``predicted_range``: name ->
    (5 %, 95 %) of the repeat tests (a table, cross-validated); ``method``:
    how the prediction was made; ``largest_correction``: :class:`Angle`;
    ``exceeded``: it exceeds ``max_correction``; ``warnings``, ``notes``.
    """

    source: str
    format: str
    text: str
    load: tuple
    orders: tuple
    orders_source: str
    measured: dict
    predicted: dict
    predicted_range: dict
    method: str
    largest_correction: Angle
    exceeded: bool
    warnings: tuple
    notes: tuple
    core: _CompensateRecord = field(repr=False, compare=False)

    def to_dict(self, unit: str = "arcsec") -> dict:
        """The document of ``wormgear compensate --report FILE --unit UNIT``."""
        # lazy: keeps workflows.compensate off `import wormgear_cli.api`'s start-up
        from wormgear_cli.workflows.compensate import report

        return _plain(report(self.core, unit))

    def write(self, path: PathLike) -> None:
        """Write the file to ``path`` atomically."""
        atomic_write(_fs(path), self.text)


def _compensation(core) -> Compensation:
    # lazy: keeps workflows.compensate off `import wormgear_cli.api`'s start-up
    from wormgear_cli.workflows.compensate import TableDetails, report

    doc = report(core, "rad")
    if isinstance(core.details, TableDetails):
        pr = doc["prediction"]
        measured = {k: _angle(v) for k, v in pr["before"].items()}
        predicted = {k: _angle(f["median"]) for k, f in pr["after"].items()}
        ranges = {k: (_angle(f["low_5pct"]), _angle(f["high_95pct"])) for k, f in pr["after"].items()}
        method, largest = pr["method"], doc["table"]["largest_correction"]
    else:
        pe = doc["pec"]
        measured, predicted = {"PE_pp": _angle(pe["peak_to_peak_before"])}, {"PE_pp": _angle(pe["peak_to_peak_after"])}
        ranges, method = {}, pe["method"]
        largest = float(abs(core.details.curve.pe).max())
    return Compensation(core.source, core.writer.name, core.text, core.instructions, tuple(doc["orders"]["requested"]),
                        doc["orders"]["source"], measured, predicted, ranges, method, Angle(largest), core.exceeded,
                        core.warnings, core.notes, core)


def compensate(data, format: str | None = None, *, output: PathLike | None = None, drive=None,
               orders: Sequence[float] | None = None, harmonics: int | None = None, points: int | None = None,
               range_deg: tuple[float, float] | None = None, file_type: int | None = None, unit: str = "arcsec",
               max_correction=None, worm_period_s: float | None = None, steps_per_worm: int | None = None,
               column_map: dict | None = None, error_unit: str | None = None,
               angle_unit: str | None = None, input_format: str | None = None, sessions=None,
               pixel_scale: float | None = None, dec_deg: float | None = None,
               guide_rate: float | None = None) -> Compensation:
    """The correction a controller or a mount loads, and what it will leave (``wormgear compensate``).

    Parameters
    ----------
    data : path-like or Measurement
        The measurement CSV, a :class:`Measurement` from :func:`read_measurement`, or a core
        :class:`~wormgear_cli.measurement.reader.Measurement` (e.g. from a guide-log reader).
    format : str or None
        ``linuxcnc``, ``eqmod`` or ``csv`` (any name of the writer registry); None: from
        ``output``'s file name ending.
    output : path-like or None
        Where the file will go: it is written there, and named in the loading instructions.
    drive, orders, harmonics
        As for :func:`measure`; a mount's worm period comes from the drive's worm.  ``harmonics``
        (None: 3) applies with ``drive`` or to a PEC curve (``eqmod``); given for a table without
        ``drive`` it is a UsageError, as on the command line.
    points, range_deg
        Table points and their span [deg] (default: the writer's points; 0 to 360 for data over a
        full turn, the measured arc rounded out to whole degrees for a partial one).
    file_type : int or None
        LinuxCNC COMP_FILE_TYPE (1: corrections, 0: positions reached; None: 1); only for ``linuxcnc``.
    unit : str
        Unit of the CSV values, of ``max_correction`` given as a number, and of ``to_dict``.
    max_correction : Angle, float (in ``unit``) or None
        The largest correction allowed; beyond it ``exceeded`` is True and a warning says so.
    worm_period_s, steps_per_worm
        A mount's worm period [s] and RA motor steps per worm turn.
    column_map, error_unit, angle_unit, input_format, sessions, pixel_scale, dec_deg, guide_rate
        As for :func:`read_measurement` (a file only; a PHD2 guide log is read as it is).

    Raises
    ------
    DataError, SpecError, UsageError

    Examples
    --------
    >>> c = compensate("configs/mch50-warm.csv", "linuxcnc", orders=[1, 8])
    >>> c.format, len(c.text.splitlines()), c.method
    ('linuxcnc', 256, 'cross-validated')
    """
    # lazy: keeps workflows.compensate off `import wormgear_cli.api`'s start-up
    from wormgear_cli.workflows.compensate import CompensateOptions, compensate_measurement
    from wormgear_cli.workflows.compensate import compensate as run

    unit = _choice("unit", unit, ("deg", "arcmin", "arcsec", "urad"))
    if orders is not None:
        # lazy: keeps workflows.measure off `import wormgear_cli.api`'s start-up
        from wormgear_cli.workflows.measure import parse_orders

        orders = tuple(parse_orders(",".join(repr(float(k)) for k in orders)))
    limit = None
    if max_correction is not None:
        limit = float(max_correction) if isinstance(max_correction, Angle) else from_unit(float(max_correction), unit)
    options = CompensateOptions(format=format, drive=drive, orders=orders,
                                harmonics=None if harmonics is None else int(harmonics), points=points,
                                range_deg=(float(range_deg[0]), float(range_deg[1])) if range_deg is not None else None,
                                file_type=None if file_type is None else int(file_type),
                                unit=unit, max_correction=limit, worm_period_s=worm_period_s,
                                steps_per_worm=steps_per_worm, output=None if output is None else str(output))
    if isinstance(data, Measurement):
        core = compensate_measurement(data.core, options)
    elif all(hasattr(data, a) for a in ("angle", "error", "present")):  # a core Measurement
        core = compensate_measurement(data, options)
    else:
        core = run(data, options, _read_options(column_map, error_unit, angle_unit, input_format,
                                                dict(sessions=sessions, pixel_scale=pixel_scale, dec_deg=dec_deg,
                                                     guide_rate=guide_rate)))
    result = _compensation(core)
    if output is not None:
        result.write(output)
    return result


# --- diagnose ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Gap:
    """Measured - model over matched forward/reverse targets: ``rms``, ``max`` and the same for
    the common and differential modes, as :class:`Angle` (None where no forward/reverse pair
    of targets was measured)."""

    rms: Angle | None
    max: Angle | None
    common_rms: Angle | None
    common_max: Angle | None
    differential_rms: Angle | None
    differential_max: Angle | None


def _gap(d: dict | None) -> Gap | None:
    if d is None:
        return None
    return Gap(*(_angle(d[f"{k}_arcsec"], "arcsec") for k in
                 ("rms", "max", "common_rms", "common_max", "differential_rms", "differential_max")))


@dataclass(frozen=True)
class Diagnosis:
    """Result of :func:`diagnose`.

    ``verdict``: one line; ``effects``: names of the effects the data
    support, in order of selection; ``effects_found``: their entries of the
    report (parameters in catalogue units, p-value, interval, stability);
    ``gap_as_specified``, ``gap_before`` (phases fitted), ``gap_after``
    (named effects added): :class:`Gap`; ``noise_floor``: :class:`Angle`.
    """

    drive: str
    verdict: str
    effects: tuple
    effects_found: tuple
    gap_as_specified: Gap | None
    gap_before: Gap | None
    gap_after: Gap | None
    noise_floor: Angle | None
    core: _DiagnosisRecord = field(repr=False, compare=False)
    _doc: dict = field(repr=False, compare=False)
    _data_name: str = field(repr=False, compare=False, default="")

    def to_dict(self) -> dict:
        """The document of ``wormgear diagnose --format json`` (always arcsec: its keys end in
        ``_arcsec``)."""
        return _plain(self._doc)

    def augmented_spec(self) -> str:
        """The augmented drive spec (TOML text: fitted phases, an ``[effects.NAME]`` table per
        named effect), as ``wormgear diagnose`` writes it."""
        # lazy: keeps diagnosis off `import wormgear_cli.api`'s start-up
        from wormgear_cli.diagnosis import augmented_toml

        return augmented_toml(self.core, self._data_name)


def diagnose(spec, data, *, alpha: float = 0.01, keep_phases: bool = False, max_effects: int = 4,
             resamples: int = 50, jobs: int = 1) -> Diagnosis:
    """Where the model and a measurement disagree, and which catalogue effect is missing.

    Parameters
    ----------
    spec : Spec or path-like
        The drive.
    data : path-like or Measurement
        The measurement.
    alpha : float
        Family-wise significance level of each selection step (0 < alpha < 0.5).
    keep_phases : bool
        Hold the spec's phases instead of fitting them.
    max_effects : int
        Name at most this many effects (0 to 20).
    resamples : int
        Resamples of whole runs for the stability check (0: skip).
    jobs : int
        Worker processes (0: every core); the result is the same whatever the count.

    Raises
    ------
    DataError, SpecError, UsageError

    Examples
    --------
    >>> d = diagnose("configs/mch50.toml", "configs/mch50-warm.csv")
    >>> d.effects
    ('thermal_backlash',)
    >>> d.gap_after.rms < d.gap_before.rms
    True
    """
    from wormgear_cli.diagnosis import run_diagnose  # lazy: keeps diagnosis off `import wormgear_cli.api`'s start-up

    fit_phases = not _flag("keep_phases", keep_phases)
    spec = _spec(spec)
    meas = data if isinstance(data, Measurement) else read_measurement(data)
    result = run_diagnose(spec, meas.core, alpha=alpha, fit_phases=fit_phases, max_effects=max_effects,
                          resamples=resamples, jobs=_jobs(jobs))
    core, doc = result.diagnosis, result.document
    found = tuple(doc["effects_found"])
    floor = doc.get("noise", {}).get("floor_arcsec")
    return Diagnosis(doc["drive"], doc["verdict"], tuple(e["name"] for e in found), found,
                     _gap(doc.get("gap_as_specified")), _gap(doc.get("gap_before")), _gap(doc.get("gap_after")),
                     _angle(floor, "arcsec"), core, doc, str(meas.path if meas.path is not None else meas.source))


# --- sweep ---------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Sweep:
    """Result of :func:`sweep`: the (i, l) response surface.

    ``i``, ``l_mm`` [mm]: the grid axes (numpy arrays); ``points``: column
    name -> one value per computed point, in point order (i outermost;
    skipped points left out with ``module_mm``): angle columns as
    :class:`AngleArray`, the others as numpy arrays; ``best``: name of the
    minimised column -> that point's row as a dict.
    """

    drive: str
    i: object
    l_mm: object
    points: dict
    best: dict
    findings: tuple
    core: RatioDistanceSweep = field(repr=False, compare=False)
    _data: dict = field(repr=False, compare=False)

    @property
    def stage(self):
        """The swept spur stage (its record: ``index``, ``name``, ``module``, ...)."""
        return self.core.stage

    def to_dict(self, unit: str = "arcsec") -> dict:
        """The document of ``wormgear sweep --format json --unit UNIT``."""
        return _plain(_sweep_report(self.core, self._data, unit))


def _jobs(jobs: int) -> int:
    """``jobs`` as a worker count (0: every core); UsageError outside 0..MAX_JOBS."""
    from wormgear_cli.batch.pool import resolve_jobs  # lazy: keeps batch.pool off `import wormgear_cli.api`'s start-up

    return resolve_jobs(jobs)


def _axis(value, option: str):
    # lazy: keeps analysis.sweep off `import wormgear_cli.api`'s start-up
    from wormgear_cli.analysis import sweep as core

    if isinstance(value, str):
        return core.parse_range_spec(value, option, positive=True).values()

    arr = np.atleast_1d(np.asarray(value, dtype=float))
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr) & (arr > 0)):
        raise UsageError(f"{option}: expected positive finite values, or START:STOP:N")
    core.check_axis(option, float(arr.min()), float(arr.max()))
    return arr


def sweep(spec, i=None, l_mm=None, *, hold: str = "force", module_mm: float | None = None,
          min_pinion_teeth: int | None = None, jobs: int = 1, stage: int | None = None,
          figures: bool = False) -> Sweep:
    """Gear TE, total TE and total backlash over a grid of gear ratio i and centre distance l.

    Parameters
    ----------
    spec : Spec or path-like
        The drive.
    i : str or array_like or None
        Gear ratio values i = z1/z2: ``"START:STOP:N"`` (as ``--i``) or the
        values; None: the spec's ratio.
    l_mm : str or array_like [mm] or None
        Centre distance values l = R1 + R2, likewise; None: the spec's.
    hold : str
        What stays fixed as i and l change: ``force`` or ``torque``, in any case (as ``--hold``).
    module_mm : float [mm] or None
        Snap every point to whole tooth counts at this module.
    min_pinion_teeth : int or None
        With ``module_mm``: skip designs whose smaller gear has fewer teeth.
    jobs : int
        Worker processes (0: every core); the result is the same whatever the count.
    stage : int or None
        The spur stage swept (1-based from the motor); None: the drive's last spur stage.
    figures : bool
        With ``module_mm``: add each design's sign-off figures (the budget's totals, amplitudes and
        range, and the ISO 230-2 A, E, B, M on the spec's ``[test_plan]``; ranges) as points
        columns [rad], those ``analyze`` gives for the design (about 50 ms a design).

    Raises
    ------
    UsageError, SpecError
        UsageError for a drive without a spur stage, or a ``stage`` that is not one; for
        ``figures`` without ``module_mm``.

    Examples
    --------
    >>> s = sweep("configs/mch50.toml", i="2:10:5", l_mm="100:300:3")
    >>> len(s.points["total_transmission_error"])
    15
    >>> sorted(s.best)
    ['gear_transmission_error', 'total_transmission_error']
    """
    # lazy: keeps analysis.sweep off `import wormgear_cli.api`'s start-up
    from wormgear_cli.analysis import sweep as core

    spec = _spec(spec)
    hold = _choice("hold", hold, ("force", "torque"))
    figures = _flag("figures", figures)
    if min_pinion_teeth is not None and module_mm is None:
        raise UsageError("min_pinion_teeth applies only with module_mm")
    st = core.spur_stage(spec, stage)
    i_values = _axis(i, "--i") if i is not None else [st.gear.teeth / st.pinion.teeth]
    l_values = _axis(l_mm, "--l-mm") if l_mm is not None else [st.module * (st.gear.teeth + st.pinion.teeth) / 2.0]
    sw = core.RatioDistanceSweep(spec, i_values, l_values, hold=hold, module=module_mm, min_teeth=min_pinion_teeth,
                                 stage=st.index, figures=figures)
    data = sw.collect(0, sw.size, jobs=_jobs(jobs))
    doc = _sweep_report(sw, data, "rad")  # the CLI's document in radians
    points = {c: (AngleArray(data[c]) if c in core.ANGLE_COLUMNS else data[c]) for c in sw.columns}

    def row(d: dict) -> dict:
        return {k: (Angle(v) if k in core.ANGLE_COLUMNS else v) for k, v in d.items()}

    summary = doc["summary"]
    return Sweep(doc["drive"], sw.i_values, sw.l_values, points,
                 {k: row(v) for k, v in summary["best"].items()}, tuple(summary["findings"]), sw, data)


# --- tolerance -----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class MetricStats:
    """Statistics of one metric over the sampled drives: ``mean``, ``std``, ``corner`` (the
    worst case, as analyze), ``rss`` (root-sum-square estimate) and ``percentiles`` (key ->
    value: "50", "90", "95", "99", "99.73", "max"), all :class:`Angle` (None where the
    metric has no value)."""

    mean: Angle | None
    std: Angle | None
    percentiles: dict
    corner: Angle | None
    rss: Angle | None


@dataclass(frozen=True)
class Tolerance:
    """Result of :func:`tolerance`.

    ``metrics``: metric name -> :class:`MetricStats`; ``yields``:
    requirement key (or "all") -> {value, low, high, passing} (fractions);
    ``sensitivity``: metric -> first-order indices by varied quantity;
    ``allocation``: the ranking of ``target_yield`` or None.
    """

    drive: str
    samples: int
    seed: int
    metrics: dict
    yields: dict
    sensitivity: dict
    allocation: dict | None
    _run: Callable[[str], dict] = field(repr=False, compare=False)  # unit -> the document
    _docs: dict = field(repr=False, compare=False)

    def to_dict(self, unit: str = "arcsec") -> dict:
        """The document of ``wormgear tolerance --format json --unit UNIT`` (same seed: the same
        samples are drawn again for a unit not computed yet)."""
        if unit not in self._docs:
            self._docs[unit] = self._run(unit)
        return _plain(self._docs[unit])


def _tolerance_doc(spec, options, target_yield):
    """Set-up, run, allocation and document, as ``wormgear tolerance`` (no shard, no summarize)."""
    # lazy: keeps tolerance.engine off `import wormgear_cli.api`'s start-up
    from wormgear_cli.tolerance import engine, study

    s = engine.setup(spec, options)
    return study.finish(s, engine.run(s), target_yield)


def tolerance(spec, samples: int = 100_000, seed: int = 0, *, metrics: str = "all", plan: str = "iso",
              targets: int = 24, points: int = 360, target_yield: float | None = None, jobs: int = 1) -> Tolerance:
    """Statistical tolerance analysis: Monte Carlo over built drives.

    Parameters
    ----------
    spec : Spec or path-like
        The drive (its tolerances, optional ``[statistics]`` and ``[requirements]``).
    samples : int
        Number of built drives (>= 1).
    seed : int
        Seed of every random number (same seed, same result).
    metrics : str
        ``paper`` (total TE and backlash), ``iso`` (ISO 230-2 E, B, M, A of
        the simulated acceptance test) or ``all``.
    plan : str
        Acceptance test: ``iso`` (``targets`` irregular targets) or ``dense`` (``points`` angles).
    targets, points : int
        Sizes of the two plans.
    target_yield : float or None
        Yield to aim at (0 < P < 1; default ``[requirements] min_yield``):
        rank the tolerances by the yield one step of tightening gains.
    jobs : int
        Worker processes (0: every core); the result is the same whatever the count.

    Raises
    ------
    UsageError, SpecError

    Examples
    --------
    >>> t = tolerance("configs/mch50.toml", samples=2000, seed=1, metrics="paper")
    >>> te = t.metrics["total_transmission_error"]
    >>> te.mean < te.percentiles["99"] < te.corner
    True
    """
    from wormgear_cli.tolerance import engine  # lazy: keeps tolerance.engine off `import wormgear_cli.api`'s start-up

    spec = _spec(spec)
    if target_yield is not None and not 0.0 < target_yield < 1.0:
        raise UsageError(f"target_yield: expected a number in (0, 1), got {target_yield:g}")
    options = engine.Options(samples=samples, seed=seed, metrics=metrics, plan=plan, targets=targets,
                             points=points, unit="rad", jobs=_jobs(jobs))

    def run(unit: str) -> dict:
        return _tolerance_doc(spec, replace(options, unit=unit), target_yield)

    doc = run("rad")
    stats = {}
    for name, m in doc["metrics"].items():
        stats[name] = MetricStats(_angle(m["mean"]), _angle(m["std"]),
                                  {k: _angle(v) for k, v in m["percentiles"].items()}, _angle(m["corner"]),
                                  _angle(m["rss"]))
    return Tolerance(doc["drive"], doc["samples"], doc["seed"], stats, doc["yield"], doc["sensitivity"],
                     doc.get("allocation"), run, {"rad": doc})


# --- compare -------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Comparison:
    """Result of :func:`compare`.

    ``drives``: the drives' names, ``files`` their sources (the first is the baseline);
    ``totals``: key (``total_transmission_error``, ``total_backlash``, ``budget_linear``,
    ``budget_statistical``, ``budget_peak``: amplitudes) -> one :class:`Angle` per drive; ``differences``: the same
    keys -> each drive minus the first; ``budget``: source -> one Angle (or None) per drive;
    ``yields``: None, or requirement key (or "all") -> {values, low, high, differences}
    (fractions, None where a drive has no such limit).
    """

    drives: list
    files: list
    totals: dict
    differences: dict
    budget: dict
    yields: dict | None
    _run: Callable[[str], dict] = field(repr=False, compare=False)  # unit -> the document

    def to_dict(self, unit: str = "arcsec") -> dict:
        """The document of ``wormgear compare --format json --unit UNIT``."""
        return _plain(self._run(unit))


def compare(specs: Sequence, *, samples: int | None = None, seed: int = 0) -> Comparison:
    """Drives side by side: the paper's totals, the budget's totals and lines, and (with
    ``samples``) the yield against each drive's own limits, with each drive's difference to
    the first.

    Parameters
    ----------
    specs : sequence of Spec or path-like
        Two or more drives; the first is the baseline.
    samples : int or None
        Built drives sampled per drive for the yield (None: no yield).
    seed : int
        Seed of the yield's samples.

    Raises
    ------
    UsageError, SpecError

    Examples
    --------
    >>> c = compare(["configs/mch50.toml", "configs/rotary-table-precision.toml"])
    >>> c.differences["total_transmission_error"][1] < Angle(0, "arcsec")
    True
    >>> f"{c.totals['budget_statistical'][1]:.2f}"
    '27.00 arcsec'
    """
    # lazy: keeps workflows.compare off `import wormgear_cli.api`'s start-up
    from wormgear_cli.workflows.compare import Options
    from wormgear_cli.workflows.compare import compare as run

    loaded = [_spec(s) for s in specs]
    files = [getattr(s, "source", str(s)) for s in loaded]

    def document(unit: str) -> dict:
        return run(loaded, files, Options(unit=unit, samples=samples, seed=seed))

    doc = document("rad")
    return Comparison(
        drives=[d["drive"] for d in doc["drives"]], files=files,
        totals={k: [Angle(v) for v in q["values"]] for k, q in doc["totals"].items()},
        differences={k: [Angle(v) for v in q["differences"]] for k, q in doc["totals"].items()},
        budget={k: [_angle(v) for v in q["values"]] for k, q in doc["budget"].items()},
        yields=None if doc["yield"] is None else doc["yield"]["requirements"],
        _run=document,
    )
