"""``compensate`` as a library call: read a measurement, choose the orders, make the correction a
controller or a mount loads, say what it will leave, and write it through the writer registry.

:func:`compensate` takes a file, :func:`compensate_measurement` a
:class:`~wormgear_cli.measurement.reader.Measurement` already read (a guide log read by its own
reader goes there); both return a :class:`CompensateResult` whose ``text`` is the file.
:func:`report` is the JSON document of ``--report``, :func:`summary` the lines the command
prints on stderr.

Two paths, chosen by what the writer accepts:

* a **correction table** (``linuxcnc``, ``csv``): the orders fitted per direction
  (:mod:`~wormgear_cli.compensation.model`), per-target means added where the orders do not
  explain the data, evaluated at evenly spaced points, orders the spacing cannot carry left
  out, and the ISO 230-2 figures of a repeat test predicted by cross-validation over the runs
  (:mod:`~wormgear_cli.compensation.predict`);
* a **PEC curve** (``eqmod``): one worm period of a mount's tracking error, drift removed
  (:mod:`~wormgear_cli.compensation.pec`), with the PE peak-to-peak it will leave,
  cross-validated over worm cycles.

Orders: ``--orders``; else the drive's shafts and meshes (``--drive``); else the strongest
orders found (:func:`~wormgear_cli.compensation.scan.strongest_orders` for a table, the
strongest period for a mount).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from wormgear_cli.analysis.accuracy import geometry
from wormgear_cli.compensation import pec
from wormgear_cli.compensation.model import fit_plan, parameters, plan_model
from wormgear_cli.compensation.noise import noise_components
from wormgear_cli.compensation.pec import continuous
from wormgear_cli.compensation.predict import Figure, predict_table
from wormgear_cli.compensation.scan import MAX_ORDERS, strongest_orders
from wormgear_cli.compensation.table import CorrectionTable, TableGrid, build_table, interpolation_loss, uncarried
from wormgear_cli.errors import DataError, UsageError
from wormgear_cli.measurement.checks import structure_findings
from wormgear_cli.measurement.coverage import TREND_DEGREE, coverage, trend_columns
from wormgear_cli.measurement.iso230 import group_targets, withhold_directional
from wormgear_cli.measurement.readers import read_measurement
from wormgear_cli.output import writers
from wormgear_cli.output.writers import PEC_CURVE, WriteOptions
from wormgear_cli.spec.loader import load_spec
from wormgear_cli.units import to_unit
from wormgear_cli.workflows.guidelog import longest_run
from wormgear_cli.workflows.measure import _label_for, _order_notes, _orders_asked
from wormgear_cli.workflows.measure import strongest_orders as measured_strongest_orders

if TYPE_CHECKING:
    from wormgear_cli.compensation.model import CorrectionModel, ModelPlan, TargetTest
    from wormgear_cli.compensation.pec import PecCurve, PecPrediction
    from wormgear_cli.compensation.predict import TablePrediction
    from wormgear_cli.compensation.scan import Selection
    from wormgear_cli.measurement.orders import OrdersAnalysis
    from wormgear_cli.output.writers import Writer

#: harmonics of each shaft and mesh order with --drive (as ``measure``)
DEFAULT_HARMONICS = 3
#: a tracking record whose angle runs faster or slower than sidereal by more than this is warned about
SIDEREAL_TOLERANCE = 0.02


@dataclass(frozen=True)
class CompensateOptions:
    """Everything ``compensate`` is asked for (angles in rad).

    ``format``: writer name (None: from the ``output`` file name's
    ending); ``drive``: spec path; ``orders``: orders to fit [cycles/rev];
    ``harmonics``: with ``drive`` or for a PEC curve (None: :data:`DEFAULT_HARMONICS`);
    ``points``: table points (None: the writer's default); ``range_deg``: (start, end) of the
    table [deg] (None: :func:`_default_range`);
    ``file_type``: LinuxCNC COMP_FILE_TYPE (None: 1); ``unit``: unit of the CSV
    values and the report; ``max_correction`` [rad]: the largest correction
    allowed (None: no limit); ``worm_period_s`` [s] and ``steps_per_worm``:
    a mount's; ``output``: where the file goes (None: stdout), used for the
    format and the loading instructions.
    """

    format: str | None = None
    drive: str | Path | None = None
    orders: tuple[float, ...] | None = None
    harmonics: int | None = None
    points: int | None = None
    range_deg: tuple[float, float] | None = None
    file_type: int | None = None
    unit: str = "arcsec"
    max_correction: float | None = None
    worm_period_s: float | None = None
    steps_per_worm: int | None = None
    output: str | None = None

    def writer(self):
        """The writer: ``format``, else the one owning ``output``'s file name ending."""
        if self.format is not None:
            return writers.get(self.format)
        found = writers.for_path(self.output)
        if found is None:
            endings = ", ".join(f"{e} ({n})" for e, n in writers.extensions().items())
            raise UsageError(f"--format: give one of {', '.join(writers.WRITERS)} (or an -o file ending in "
                             f"{endings})")
        return found

    @property
    def harmonic_count(self) -> int:
        """The harmonics asked for: ``harmonics``, else :data:`DEFAULT_HARMONICS`."""
        return DEFAULT_HARMONICS if self.harmonics is None else self.harmonics

    def check(self) -> None:
        problems = []
        if self.file_type not in (None, 0, 1):
            problems.append(f"--type: expected 0 or 1 (LinuxCNC COMP_FILE_TYPE), got {self.file_type}")
        if self.harmonics is not None and not 1 <= self.harmonics <= 10:
            problems.append(f"--harmonics: expected an integer in [1, 10], got {self.harmonics}")
        if self.max_correction is not None and not (math.isfinite(self.max_correction) and self.max_correction > 0):
            problems.append("--max-correction: expected a positive number")
        if self.worm_period_s is not None and not (math.isfinite(self.worm_period_s)
                                                   and 1.0 <= self.worm_period_s <= 86400.0):
            problems.append(f"--worm-period: expected a number of seconds in [1, 86400], got {self.worm_period_s:g}")
        if self.steps_per_worm is not None and not 1 <= self.steps_per_worm <= 10**9:
            problems.append(f"--steps-per-worm: expected an integer in [1, 1e9], got {self.steps_per_worm}")
        if problems:
            raise UsageError(problems)


@dataclass(frozen=True)
class OrderChoice:
    """The orders asked for and where they come from (``source``, a phrase); ``labels`` and
    ``priority`` from a drive spec; ``worm_order`` of the drive (None without one)."""

    orders: tuple[float, ...] | None
    labels: tuple | None
    priority: tuple | None
    source: str
    worm_order: float | None = None
    drive_name: str | None = None


@dataclass(frozen=True)
class CompensateResult:
    """Result of :func:`compensate`.

    ``source``: the data's name; ``writer``
    (:class:`~wormgear_cli.output.writers.Writer`); ``text``: the file;
    ``instructions``: how to load it; ``choice``: :class:`OrderChoice`;
    ``warnings`` and ``notes``: sentences; ``exceeded``: the correction
    exceeds ``max_correction``; ``details``: the path's own results
    (:class:`TableDetails` or :class:`PecDetails`); ``options``.
    """

    source: str
    writer: Writer
    text: str
    instructions: tuple
    choice: OrderChoice
    warnings: tuple
    notes: tuple
    exceeded: bool
    details: TableDetails | PecDetails
    options: CompensateOptions = field(repr=False)


@dataclass(frozen=True)
class TableDetails:
    """The correction-table path: ``plan``, ``model`` (the fitted model, orders not carried
    left out), ``analysis`` (which orders could be fitted), ``target_test``, ``grid``,
    ``table``, ``dropped`` (orders the table cannot carry), ``loss`` [rad] (largest
    interpolation loss between points), ``prediction``
    (:class:`~wormgear_cli.compensation.predict.TablePrediction`), ``selection`` (the strongest
    orders search, or None)."""

    plan: ModelPlan
    model: CorrectionModel
    analysis: OrdersAnalysis
    target_test: TargetTest
    grid: TableGrid
    table: CorrectionTable
    dropped: tuple
    loss: float
    prediction: TablePrediction
    selection: Selection | None = None


@dataclass(frozen=True)
class PecDetails:
    """The PEC path: ``curve`` (:class:`~wormgear_cli.compensation.pec.PecCurve`),
    ``prediction`` (:class:`~wormgear_cli.compensation.pec.PecPrediction`), ``steps_per_worm``."""

    curve: PecCurve
    prediction: PecPrediction
    steps_per_worm: int | None


def choose_orders(options: CompensateOptions) -> OrderChoice:
    """The orders from ``--orders`` and the drive spec (labels, priority, worm order)."""
    physical: list = []
    priority = worm = name = None
    if options.drive is not None:
        spec = load_spec(options.drive)
        _, _, priority, physical, name = _orders_asked(spec, None, options.harmonic_count)
        priority = tuple(priority)
        worm = float(geometry(spec).worm_order)
    if options.orders is not None:
        labels = tuple(_label_for(k, physical) for k in options.orders) if physical else None
        return OrderChoice(tuple(options.orders), labels, None, "--orders", worm, name)
    if physical:
        return OrderChoice(tuple(k for k, _ in physical), tuple(lab for _, lab in physical), priority,
                           f"the drive's shafts and meshes ({name}, {options.harmonic_count} harmonics)", worm, name)
    return OrderChoice(None, None, None, "", None, name)


def compensate(data, options: CompensateOptions | None = None, read_options=None) -> CompensateResult:
    """Read the measurement file ``data`` and make its correction (:func:`compensate_measurement`).

    Raises DataError, SpecError, UsageError."""
    options = options or CompensateOptions()
    options.check()
    _check_applies(options, options.writer())  # a bad --format or a stray option fails before the file is read
    return compensate_measurement(read_measurement(data, options=read_options), options)


def compensate_measurement(measurement, options: CompensateOptions | None = None) -> CompensateResult:
    """The correction of a :class:`~wormgear_cli.measurement.reader.Measurement`: a table
    (``linuxcnc``, ``csv``) or a mount's PEC curve (``eqmod``), with what it will leave.

    The one call a reader of another kind (a guide log) needs: read the file
    into a Measurement (angle: the axis angle; error: actual - ideal; time;
    run: one per session), then call this."""
    options = options or CompensateOptions()
    options.check()
    writer = options.writer()
    _check_applies(options, writer)
    choice = choose_orders(options)
    m = measurement
    details: TableDetails | PecDetails
    if writer.accepts == PEC_CURVE:
        details, warnings, notes, choice = _pec_path(m, options, choice)
        steps = options.steps_per_worm
        largest = float(np.max(np.abs(details.curve.pe)))
        caption = f"PEC of {Path(m.source).name} by wormgear compensate: worm order {details.curve.worm_order:.6g}"
        written: object = details.curve
    else:
        details, warnings, notes, choice = _table_path(m, options, writer, choice)
        steps = None
        largest = details.table.largest
        caption = ""
        written = details.table
    exceeded = options.max_correction is not None and largest > options.max_correction
    if exceeded:
        u = options.unit
        warnings.append(f"the largest correction, {to_unit(largest, u):.4g} {u}, exceeds --max-correction "
                        f"{to_unit(options.max_correction, u):.4g} {u}")
    file_type = 1 if options.file_type is None else options.file_type
    wopts = WriteOptions(unit=options.unit, file_type=file_type, steps_per_worm=steps, caption=caption,
                         path=options.output)
    text = writer.write(written, wopts)
    return CompensateResult(m.source, writer, text, tuple(writer.instructions(wopts)), choice, tuple(warnings),
                            tuple(notes), bool(exceeded), details, options)


def _check_applies(options: CompensateOptions, writer) -> None:
    """UsageError for an option the file being written has no use for (it would be ignored without a
    word): a table's (--points, --range, --type) with a PEC curve, a mount's (--worm-period,
    --steps-per-worm) with a table, --type with another table than LinuxCNC's, --harmonics with a table
    and no --drive (it counts the harmonics of the drive's orders, or of a PEC curve's worm order)."""
    is_pec = writer.accepts == PEC_CURVE
    table, mount = "a table (--format linuxcnc or csv)", "a mount's PEC curve (--format eqmod)"
    rules = [("--points", options.points, not is_pec, table), ("--range", options.range_deg, not is_pec, table),
             ("--type", options.file_type, writer.name == "linuxcnc", "LinuxCNC's table (--format linuxcnc)"),
             ("--worm-period", options.worm_period_s, is_pec, mount),
             ("--steps-per-worm", options.steps_per_worm, is_pec, mount)]
    if options.harmonics is not None and not is_pec and options.drive is None:
        raise UsageError(f"--harmonics applies with --drive (the harmonics of its shafts and meshes) or to {mount}, "
                         f"not to the {writer.name} table being written without --drive; drop it, give --drive, "
                         "or choose that format (--format, or the -o file's ending)")
    for flag, value, applies, whose in rules:
        if value is not None and not applies:
            raise UsageError(f"{flag} is an option of {whose}, not of the {writer.name} file being written; drop it "
                             "or choose that format (--format, or the -o file's ending)")


# --- the table path --------------------------------------------------------------------------------------


#: highest whole order a search for a table's orders tries (the worm orders of tables and mounts)
SEARCH_MAX_ORDER = 360
#: per-target means a search works on at most, per direction (finer scans are averaged in bins)
SEARCH_POINTS = 2048


def _select_table_orders(theta, y, d, run, candidates=None) -> Selection:
    """The orders of a rotary-axis measurement that stand out of the noise: a forward selection on
    the per-target means (:func:`~wormgear_cli.compensation.scan.strongest_orders`) among
    ``candidates`` (default: whole orders 1 to the Nyquist order of the mean target spacing, at
    most :data:`SEARCH_MAX_ORDER`)."""
    index, targets = group_targets(theta)
    cell = 2 * index + (d < 0)
    _, first, ci, counts = np.unique(cell, return_index=True, return_inverse=True, return_counts=True)
    means = np.bincount(ci.ravel(), weights=y) / counts
    noise = noise_components(cell, run, y)
    noise_var = noise.within if noise.replicated and math.isfinite(noise.within) and noise.within > 0 else None
    cov = coverage(theta, run)
    if candidates is None:
        nyquist = math.pi * cov.distinct / cov.span if cov.span > 0 else 0.0
        candidates = range(1, int(min(SEARCH_MAX_ORDER, nyquist)) + 1)
    candidates = [float(k) for k in candidates if not cov.beyond(k)]
    at, dc, means, counts = _binned(targets[index[first]], d[first], means, counts, cov)
    base = None
    if not cov.full_turn:  # over a partial span the slow part is a trend, not an order
        t = trend_columns(at, cov, max(0, min(TREND_DEGREE, cov.distinct - 2)))
        both = bool(np.any(dc > 0) and np.any(dc < 0))
        base = np.hstack([np.ones((at.size, 1)), t] + ([dc[:, None], t * dc[:, None]] if both else []))
    return strongest_orders(at, means, dc, candidates, noise_var, weights=counts, max_orders=MAX_ORDERS,
                            base=base)


def _binned(at, dc, means, counts, cov):
    """Per-target means averaged into at most :data:`SEARCH_POINTS` bins of angle per direction
    (weighted by their rows), when there are more: (angles, directions, means, weights)."""
    if at.size <= 2 * SEARCH_POINTS:
        return at, dc, means, counts
    u = np.mod(at - cov.start, 2.0 * math.pi)
    width = max(cov.span, 1e-12) / SEARCH_POINTS
    key = np.minimum((u / width).astype(np.int64), SEARCH_POINTS - 1) * 2 + (dc < 0)
    _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    inv = inv.ravel()
    w = np.bincount(inv, weights=counts)
    angle = np.bincount(inv, weights=counts * u) / w + cov.start
    return angle, dc[first], np.bincount(inv, weights=counts * means) / w, w


def _table_path(m, options: CompensateOptions, writer: Writer,
                choice: OrderChoice) -> tuple[TableDetails, list[str], list[str], OrderChoice]:
    theta, y, d, run = m.angle, m.error, m.direction, m.run
    span = options.range_deg or _default_range(m.angle)
    grid = TableGrid(options.points or writer.default_points or 361, *span)
    grid.check(writer.max_points)
    selection = None
    if choice.orders is None:
        selection = _select_table_orders(theta, y, d, run)
        top = int(max(selection.candidates, default=0))
        source = (f"the strongest found among whole orders 1 to {top}" if top else
                  "no whole order fits in the span and targets measured")
        choice = OrderChoice(tuple(selection.orders), None, None, source, choice.worm_order, choice.drive_name)
    elif options.orders is None:  # the drive's orders: those that stand out of the noise (a table must not overfit)
        selection = _select_table_orders(theta, y, d, run, choice.orders)
        label = dict(zip(choice.orders, choice.labels or ()))
        kept = tuple(k for k in choice.orders if k in selection.orders)
        choice = OrderChoice(kept, tuple(label[k] for k in kept), None,
                             choice.source.replace("the drive's shafts and meshes", "the drive's shafts and meshes "
                                                   "that stand out of the noise", 1), choice.worm_order,
                             choice.drive_name)
    plan, analysis, test, model = plan_model(theta, y, d, choice.orders or (), choice.labels, choice.priority, run)
    dropped = tuple(uncarried(plan.orders, grid.spacing_deg))
    carried = model.without(dropped)
    table = build_table(carried, grid)

    def make(mask):
        return build_table(fit_plan(plan, theta[mask], y[mask], d[mask], run[mask]).without(dropped), grid)

    prediction = predict_table(make, theta, y, d, run, tuple(plan.orders) + dropped, parameters(plan, theta, d))
    details = TableDetails(plan, carried, analysis, test, grid, table, dropped, interpolation_loss(carried, table),
                           prediction, selection)
    warnings, notes, mixed = _structure(m)
    if mixed:  # forward and reverse cannot be told apart: no one-direction figure, no E, A, R or B
        details = replace(details, prediction=_withheld(prediction))
    more_warnings, more_notes = _table_findings(details, theta, options)
    return details, warnings + more_warnings, notes + more_notes, choice


def _default_range(theta) -> tuple[float, float]:
    """The table's span when --range is not given [deg]: 0 to 360 for data over a full turn; the
    measured arc rounded out to whole degrees for a partial one (a table over the whole turn would
    spend its points where nothing was measured, and spread them too far for the orders seen)."""
    if coverage(theta).full_turn:
        return 0.0, 360.0
    deg = np.degrees(theta)
    lo, hi = float(math.floor(deg.min())), float(math.ceil(deg.max()))
    return (lo, hi) if hi > lo else (lo - 1.0, lo + 1.0)  # one whole-degree angle: a degree either side


def _withheld(prediction):
    """The prediction with every figure that needs the directions told apart withheld (NaN):
    all but M, as measured and after correction (``measure`` withholds the same)."""
    before = withhold_directional(prediction.before, "directions mixed: one-direction figures withheld")
    before = replace(before, B=math.nan)
    after = {k: (v if k == "M" else Figure(math.nan, math.nan, math.nan)) for k, v in prediction.after.items()}
    return replace(prediction, before=before, after=after)


def _structure(m) -> tuple[list, list, bool]:
    """What the file does not state (``measure``'s checks), as warnings and notes for a table, and
    whether forward and reverse visits are mixed."""
    findings, mixed = structure_findings(m, group_targets(m.angle)[0])
    warnings = [f.text for f in findings if f.warning]
    notes = [f.text for f in findings if not f.warning and f.text]
    if mixed:
        warnings.append("forward and reverse visits cannot be told apart: the table's two columns are the same "
                        "mixture and lost motion is not corrected")
    return warnings, notes, mixed


def _table_findings(t: TableDetails, theta, options: CompensateOptions) -> tuple[list, list]:
    """The warnings and notes of the table path, as sentences (angles in ``options.unit``)."""
    u = options.unit
    warnings, notes = [], list(_order_notes(t.analysis))
    if t.selection is not None:
        chosen = ", ".join(f"{k:g}" for k in t.selection.orders) or "none"
        notes.append(f"orders selected by a forward selection on the per-target means: {chosen} of "
                     f"{len(t.selection.candidates)} candidates; stopped because {t.selection.reason}")
    spacing = t.grid.spacing_deg
    amplitude = {it.order: it.common[:2] for it in t.analysis.items if it.fitted}
    top = max((a for a, _ in amplitude.values() if math.isfinite(a)), default=0.0)
    for k in t.dropped:
        amp, se = amplitude.get(k, (math.nan, math.nan))
        said = (f"order {k:g} has a period of {360.0 / k:.4g} deg, {360.0 / k / spacing:.2g} table spacings of "
                f"{spacing:.4g} deg: a table of {t.grid.points} points cannot carry it (fewer than 4 spacings per "
                f"period), so it is left out")
        if amp > max(2.0 * se, 1e-3 * top) or not math.isfinite(amp):  # what stays is worth a warning
            warnings.append(f"{said} and its {to_unit(amp, u):.3g} {u} amplitude stays")
        else:  # within twice its standard error, or a thousandth of the largest order: nothing is lost
            why = (f"within twice its standard error, {to_unit(se, u):.2g} {u}" if amp <= 2.0 * se else
                   f"under a thousandth of the largest order's, {to_unit(top, u):.3g} {u}")
            notes.append(f"{said}; its amplitude, {to_unit(amp, u):.2g} {u}, is negligible ({why})")
    cov = t.plan.coverage
    deg = np.degrees(theta)
    slack = max(spacing, 1.0)  # the default span is the measured arc rounded out to whole degrees
    unmeasured = (t.grid.end_deg - t.grid.start_deg) - math.degrees(cov.span)  # at the ends or in a gap
    if not cov.full_turn and unmeasured > 2.0 * slack:
        warnings.append(f"the data cover {math.degrees(cov.span):.4g} deg ({deg.min():.4g} to {deg.max():.4g} deg), "
                        f"less than the table's {t.grid.start_deg:g} to {t.grid.end_deg:g} deg: outside the "
                        "measured arc the table holds the correction of the nearer end, and across a gap it "
                        "interpolates between its edges")
    if deg.min() < t.grid.start_deg - 1e-9 or deg.max() > t.grid.end_deg + 1e-9:
        warnings.append(f"measured angles run from {deg.min():.4g} to {deg.max():.4g} deg, beyond the table's "
                        f"{t.grid.start_deg:g} to {t.grid.end_deg:g} deg (--range): the controller holds the end "
                        "values there")
    if not t.plan.both:
        warnings.append("only one direction was measured: the reverse column repeats the forward correction and "
                        "lost motion is not corrected")
    test = t.target_test
    if t.plan.per_target:
        worst = ", ".join(f"{math.degrees(a):.4g} deg {'forward' if s > 0 else 'reverse'} "
                          f"{to_unit(v, u):+.3g}" for a, s, v in test.worst[:3])
        notes.append(f"the fitted orders leave {to_unit(test.rms, u):.3g} {u} RMS at the targets against "
                     f"{to_unit(test.expected_rms, u):.3g} {u} from the noise (p = {test.p_value:.2g}): the "
                     "per-target means of the residual are added, a cubic spline between the targets"
                     + (f" (largest {worst} {u})" if worst else ""))
    elif test.testable:
        notes.append(f"the fitted orders explain the data at the targets: residual {to_unit(test.rms, u):.3g} {u} "
                     f"RMS against {to_unit(test.expected_rms, u):.3g} {u} from the noise (p = {test.p_value:.2g}); "
                     "no per-target means added")
    else:
        notes.append(f"{test.reason}; the table is the fitted orders only")
    if t.prediction.method == "in-sample":
        warnings.append("one run only: the prediction is the table applied to the data it was made from "
                        "(in-sample, optimistic); measure several runs to have it cross-validated")
    return warnings, notes



# --- the PEC path ----------------------------------------------------------------------------------------


def _worm_order(m, th, run, options: CompensateOptions,
                choice: OrderChoice) -> tuple[float, str, tuple[float, float] | None]:
    """(worm order [cycles per axis turn], where it comes from, the orders the record cannot tell it from
    (None: not taken from the record)) of the tracking rows ``m``; DataError when none can be had.
    Without a drive or orders, the strongest period ``measure`` finds
    (:func:`~wormgear_cli.workflows.measure.strongest_orders`)."""
    if options.worm_period_s is not None:
        return pec.order_of(options.worm_period_s), f"--worm-period {options.worm_period_s:g} s", None
    if choice.worm_order is not None:
        return choice.worm_order, f"the drive's worm ({choice.drive_name})", None
    if choice.orders:
        whole = [k for k in choice.orders if pec.cycles_covered(th, run, k) >= 1.0]
        if whole:
            return min(whole), "the lowest of --orders with a whole cycle in the record", None
    found = [p for p in measured_strongest_orders(m).significant
             if pec.cycles_covered(th, run, p.order) >= 1.0 and pec.period_of(p.order) >= pec.MIN_WORM_PERIOD_S]
    if not found:
        raise DataError(f"{m.source}: no period of {pec.MIN_WORM_PERIOD_S:g} s or longer stands out of the noise in "
                        "the record, or it is too short to find a worm period in it; give --worm-period or --drive")
    return found[0].order, "the strongest period found in the record", found[0].group


def _rows(m, keep: np.ndarray):
    """The measurement ``m`` with only the rows ``keep`` (``m`` itself when every row is kept)."""
    if keep.all():
        return m

    n = len(m)
    arrays = {f.name: getattr(m, f.name) for f in fields(m)}
    return replace(m, **{k: v[keep] for k, v in arrays.items() if isinstance(v, np.ndarray) and v.shape[:1] == (n,)})


#: a PEC curve whose standard error (RMS over the worm cycle) exceeds this fraction of the curve's own
#: RMS is refused: the record does not determine it (its sessions' drifts look like pieces of it)
PEC_UNDETERMINED = 0.5
#: ... and above this fraction a warning says how uncertain it is (real guide logs: under 0.1)
PEC_UNCERTAIN = 0.15


def _check_determined(source: str, th, run, curve, period: float, cycles: float, unit: str,
                      warnings: list[str]) -> None:
    """DataError when the record does not determine the curve (:data:`PEC_UNDETERMINED`); a warning
    when it fixes it only roughly (:data:`PEC_UNCERTAIN`)."""
    se = pec.curve_standard_error(th, run, curve)
    rms = float(np.sqrt(np.mean(curve.pe ** 2)))
    ratio = se / rms if rms > 0 else math.inf
    if ratio <= PEC_UNCERTAIN:
        return
    longest = longest_run(th, run) / (2.0 * math.pi / curve.worm_order) * period  # [s]
    said = (f"the curve's standard error is {to_unit(se, unit):.3g} {unit} RMS over the worm cycle, "
            f"{ratio:.0%} of the curve itself ({to_unit(rms, unit):.3g} {unit} RMS)"
            if math.isfinite(ratio) else "the curve's standard error cannot be had")
    if longest < period:
        why = (f"the sessions (the longest {longest:.4g} s) are short beside the worm period ({period:.4g} s), so "
               "each session's drift looks like a piece of the curve")
        fix = "record sessions of at least a worm period, or fit fewer harmonics (--harmonics)"
    else:
        why = (f"its terms and each session's drift are hard to tell apart on these rows ({cycles:.3g} worm cycles "
               f"of {period:.4g} s)")
        fix = "record more worm cycles, or fit fewer harmonics (--harmonics)"
    if ratio > PEC_UNDETERMINED:
        raise DataError(f"{source}: the record does not determine a PEC curve: {said}; {why}; {fix}")
    warnings.append(f"the PEC curve is uncertain: {said}; {why}")


def _pec_path(m, options: CompensateOptions,
              choice: OrderChoice) -> tuple[PecDetails, list[str], list[str], OrderChoice]:
    warnings, notes = [], []
    keep = np.ones(len(m), dtype=bool)
    if np.any(m.direction > 0) and np.any(m.direction < 0):
        keep = m.direction > 0
        notes.append("the record holds both directions: the PEC curve is made from the forward (tracking) rows")
    theta, y, run = m.angle[keep], m.error[keep], m.run[keep]
    th = pec.continuous(theta, run)
    worm, where, group = _worm_order(_rows(m, keep), th, run, options, choice)
    period = pec.period_of(worm)
    cycles = pec.cycles_covered(th, run, worm)
    if group is not None:  # a curve of a period a few per cent off drifts out of phase within a night
        slow, fast = pec.period_of(group[0]), pec.period_of(group[1])
        warnings.append(f"the worm period, {period:.4g} s, is the strongest in the record, which cannot tell it from "
                        f"{fast:.4g} to {slow:.4g} s ({cycles:.2g} worm cycles): a PEC curve of a period even 1 % off "
                        "is half a cycle out of phase after 50 worm turns; give the mount's own, --drive or "
                        "--worm-period")
    if cycles < 1.0:
        raise DataError(f"{m.source}: the record covers {cycles * period:.4g} s of tracking, less than one worm "
                        f"period ({period:.4g} s, order {worm:.6g}): no PEC curve can be made from it")
    orders = list(options.orders) if options.orders else [worm * h for h in range(1, options.harmonic_count + 1)]
    if not any(abs(k - worm) <= 1e-9 * worm for k in orders):
        orders.insert(0, worm)
    rows, terms, told = pec.determinacy(th, run, orders)
    if told < terms or rows < 2 * terms:  # an underdetermined fit gives any curve at all
        raise DataError(f"{m.source}: {rows} rows cannot give a PEC curve of {terms} terms (orders "
                        f"{', '.join(f'{k:.6g}' for k in orders)} and a drift per session; the rows tell {told} "
                        f"apart): at least {2 * terms} rows spread over the worm cycle are needed; record longer "
                        "or more often, or fit fewer orders (--harmonics, --orders)")
    harmonics = max(int(round(k / worm)) for k in orders if abs(k / worm - round(k / worm)) < 1e-6)
    empty, bins = pec.phase_bins_empty(th, worm, harmonics)
    if empty:
        raise DataError(f"{m.source}: the rows leave {empty} of {bins} equal parts of the worm cycle (period "
                        f"{period:.4g} s) without a reading: the curve is not determined there; record at least "
                        "one worm period without gaps")
    curve = pec.pec_curve(theta, y, run, worm, orders)
    _check_determined(m.source, th, run, curve, period, cycles, options.unit, warnings)
    prediction = pec.predict_pec(theta, y, run, curve)
    source = where if options.orders is None or options.worm_period_s or choice.worm_order else "--orders"
    choice = OrderChoice(tuple(orders), choice.labels, None, source, worm, choice.drive_name)
    if cycles < 2.0:
        warnings.append(f"the record holds {cycles:.2g} worm cycles: fewer than two, so the curve cannot be "
                        "cross-validated and cycle-to-cycle changes are unknown; record at least two worm periods")
    for k in curve.extra:
        notes.append(f"order {k:.6g} (period {pec.period_of(k):.4g} s) is not a whole harmonic of the worm order: "
                     "fitted alongside, but a curve of one worm period cannot carry it")
    if options.steps_per_worm is None:
        warnings.append("no --steps-per-worm: the file has no !StepsPerWorm line and its motor column holds "
                        "seconds; EQASCOM phases the curve by motor position, so give the mount's steps per worm")
    rate = _tracking_rate(m, keep)
    if rate is not None and abs(rate / (2.0 * math.pi / pec.SIDEREAL_DAY_S) - 1.0) > SIDEREAL_TOLERANCE:
        warnings.append(f"the axis angle advances at {math.degrees(rate) * 3600.0:.4g} deg/h, not the sidereal "
                        f"{360.0 * 3600.0 / pec.SIDEREAL_DAY_S:.4g} deg/h: the worm period in seconds assumes "
                        "sidereal tracking")
    if prediction.method != "cross-validated" and cycles >= 2.0:
        notes.append("the curve could not be cross-validated (fewer than two whole worm cycles to leave out)")
    return PecDetails(curve, prediction, options.steps_per_worm), warnings, notes, choice


def _tracking_rate(m, keep) -> float | None:
    """The axis angle's rate [rad/s] over the time of the rows ``keep`` (each run from its own
    start), or None without a time column."""
    if "time_s" not in m.present or not np.ptp(m.time[keep]) > 0:
        return None

    run = m.run[keep]
    th = continuous(m.angle[keep], run)
    _, ri = np.unique(run, return_inverse=True)
    ri = ri.ravel()
    time = m.time[keep]
    t = time - (np.bincount(ri, weights=time) / np.bincount(ri))[ri]
    a = th - (np.bincount(ri, weights=th) / np.bincount(ri))[ri]
    tt = float(t @ t)
    return float(t @ a) / tt if tt > 0 else None


# --- the document and the summary ------------------------------------------------------------------------


def _u(x, unit: str):
    x = float(x)
    return float(to_unit(x, unit)) if math.isfinite(x) else None


#: report names of the ISO 230-2 figures (the core's _up / _down are forward / reverse)
_FIGURE_NAMES = {"E": "E", "B": "B", "A": "A", "M": "M", "R": "R", "E_up": "E_forward", "A_up": "A_forward",
                 "E_down": "E_reverse", "A_down": "A_reverse"}


def _table_doc(t: TableDetails, unit: str) -> dict:
    p = t.prediction
    test = t.target_test
    before = {name: _u(getattr(p.before, k), unit) for k, name in _FIGURE_NAMES.items()}
    items = []
    for it in t.analysis.items:
        items.append({"order": it.order, "label": it.label, "status": it.status,
                      "carried": it.fitted and it.order not in t.dropped,
                      "common": {"amplitude": _u(it.common[0], unit), "phase_deg": _deg(it.common[2])},
                      "differential": {"amplitude": _u(it.differential[0], unit),
                                       "phase_deg": _deg(it.differential[2])},
                      "reason": it.reason})
    return {
        "table": {"points": t.grid.points, "start_deg": t.grid.start_deg, "end_deg": t.grid.end_deg,
                  "spacing_deg": t.grid.spacing_deg, "largest_correction": _u(t.table.largest, unit),
                  "interpolation_loss": _u(t.loss, unit), "orders_not_carried": list(t.dropped)},
        "model": {"orders": items, "per_target_means": t.plan.per_target, "trend_degree": t.plan.trend_degree,
                  "target_test": {"testable": test.testable, "residual_rms": _u(test.rms, unit),
                                  "noise_rms": _u(test.expected_rms, unit), "p_value": _finite(test.p_value),
                                  "dof": test.dof, "significant": test.significant}},
        "prediction": {
            "method": p.method, "runs_left_out": p.folds, "replicates": p.replicates,
            "before": before,
            "after": {_FIGURE_NAMES[k]: {"median": _u(f.median, unit), "low_5pct": _u(f.low, unit),
                                         "high_95pct": _u(f.high, unit)} for k, f in p.after.items()},
            "R_unchanged": before["R"],
            "noise": {"within_run": _u(math.sqrt(p.noise.within), unit) if math.isfinite(p.noise.within) else None,
                      "between_runs": _u(math.sqrt(p.noise.between_runs), unit)},
            "remainder_rms": _u(p.remainder_rms, unit),
            "residual_orders": [{"order": k, "common": _u(a, unit), "differential": _u(b, unit)}
                                for k, a, b in p.residual_orders],
        },
    }


def _deg(x) -> float | None:
    return float(math.degrees(x)) if math.isfinite(x) else None


def _finite(x) -> float | None:
    return float(x) if math.isfinite(x) else None


def _pec_doc(pd: PecDetails, unit: str) -> dict:
    c, p = pd.curve, pd.prediction
    return {"pec": {
        "worm_order": c.worm_order, "worm_period_s": c.period_s, "rows": c.rows, "steps_per_worm": pd.steps_per_worm,
        "cycles": c.cycles, "harmonics": list(c.harmonics), "not_carried": list(c.extra),
        "peak_to_peak_before": _u(p.before, unit), "peak_to_peak_after": _u(p.after, unit),
        "method": p.method, "cycles_left_out": p.folds,
        "residual_orders": [{"order": k, "amplitude": _u(a, unit)} for k, a in p.residual_orders]}}


def report(result: CompensateResult, unit: str | None = None) -> dict:
    """The JSON document of ``compensate --report`` (angles in ``unit``, default the options')."""
    unit = unit or result.options.unit
    orders: dict[str, object] = {"source": result.choice.source,
                                 "requested": list(result.choice.orders) if result.choice.orders else []}
    doc: dict[str, object] = {"source": result.source, "drive": result.choice.drive_name,
                              "format": result.writer.name, "kind": result.writer.accepts, "unit": unit,
                              "orders": orders}
    if isinstance(result.details, TableDetails):
        doc.update(_table_doc(result.details, unit))
        if result.details.selection is not None:
            orders["search"] = {"chosen": list(result.details.selection.orders),
                                       "p_values": list(result.details.selection.p_values),
                                       "stopped": result.details.selection.reason}
    else:
        doc.update(_pec_doc(result.details, unit))
    doc.update({"load": list(result.instructions), "exceeded_max_correction": result.exceeded,
                "warnings": list(result.warnings), "notes": list(result.notes)})
    return doc


def summary(result: CompensateResult, unit: str | None = None) -> list[str]:
    """The lines ``compensate`` prints on stderr: what the file is made from, what it will leave,
    how to load it (warnings and notes follow, printed by the caller)."""
    unit = unit or result.options.unit
    doc = report(result, unit)
    orders = ", ".join(f"{k:.6g}" for k in doc["orders"]["requested"]) or "none"
    lines = [f"{Path(result.source).name}: orders {orders} ({doc['orders']['source']})"]
    if "table" in doc:
        tb, pr = doc["table"], doc["prediction"]
        lines.append(f"table: {tb['points']} points, {tb['start_deg']:g} to {tb['end_deg']:g} deg every "
                     f"{tb['spacing_deg']:.4g} deg; largest correction {_fmt(tb['largest_correction'])} {unit}")
        shown = _shown_figures(pr["before"])
        if all(pr["before"][k] is None for k in shown):
            lines.append("ISO 230-2 figures withheld, as measured and predicted: forward and reverse visits "
                         "cannot be told apart")
        else:
            lines += _prediction_lines(pr, shown, unit)
        left = pr["residual_orders"]
    else:
        pe = doc["pec"]
        lines.append(f"worm order {pe['worm_order']:.6g}: period {pe['worm_period_s']:.6g} s, {pe['rows']} rows; "
                     f"{pe['cycles']:.3g} worm cycles recorded")
        after = (f"{_fmt(pe['peak_to_peak_after'])} {unit} left (predicted, cross-validated over "
                 f"{pe['cycles_left_out']} worm cycles)" if pe["peak_to_peak_after"] is not None else "not predicted")
        lines.append(f"PE peak-to-peak: {_fmt(pe['peak_to_peak_before'])} {unit} as measured, {after}")
        left = [{"order": o["order"], "common": o["amplitude"]} for o in pe["residual_orders"]]
    if left:  # largest first, as the line says (the table path finds them one after the other)
        left = sorted(left, key=lambda o: -(o["common"] or 0.0))
        lines.append("largest orders left: " + ", ".join(f"{o['order']:.6g} ({_fmt(o['common'])})" for o in left)
                     + f" {unit}")
    lines += [f"load: {line}" for line in doc["load"]]
    return lines


def _prediction_lines(pr: dict, shown: tuple, unit: str) -> list[str]:
    """The summary's figures as measured and predicted after correction."""
    lines = ["as measured:  " + "  ".join(f"{k} {_fmt(pr['before'][k])}" for k in shown) + f" {unit}"]
    how = (f"cross-validated over {pr['runs_left_out']} runs" if pr["method"] == "cross-validated"
           else "in-sample")
    lines.append(f"predicted after correction (a repeat of this test, {how}; 5-95 %):")
    after = pr["after"]
    lines.append("              " + "  ".join(
        f"{k} {_fmt(after[k]['median'])}" + (f" ({_fmt(after[k]['low_5pct'])}-{_fmt(after[k]['high_95pct'])})"
                                             if after[k]["low_5pct"] != after[k]["high_95pct"] else "")
        for k in shown) + f" {unit}")
    return lines


def _shown_figures(before: dict) -> tuple[str, ...]:
    """The figures the summary shows: E, B, A; with one direction (no bidirectional E) that
    direction's E and A."""
    if before["E"] is not None or before["B"] is not None:
        return ("E", "B", "A")
    if before["E_forward"] is not None:
        return ("E_forward", "A_forward")
    return ("E_reverse", "A_reverse") if before["E_reverse"] is not None else ("M",)


def _fmt(x) -> str:
    return "-" if x is None else f"{x:.3g}"
