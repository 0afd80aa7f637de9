"""``measure`` as a library call: read a measurement, ISO 230-2 figures, orders, checks, JSON document.

:func:`measure` does all the work of ``wormgear measure`` and returns a
:class:`MeasureResult`; :func:`report` turns it into the JSON document
(angles in the requested unit).  The CLI only parses options and renders.

Checks on structure the file does not state (each a :class:`Finding`, the
serious ones also in the verdict line):

* no direction column yet a run visits a target more than once (an up/down
  table flattened): warned, and the one-direction figures are withheld
  (:func:`~wormgear_cli.measurement.iso230.withhold_directional`);
* passes inferred where ``time_s`` goes backwards (from the reader);
* exact duplicate rows; ``time_s`` going backwards inside a run;
* one direction only; one target only (one-position test);
* the span covered (a partial turn) and the orders beyond it;
* the reader's plausibility warnings (a likely unit mix-up).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from wormgear_cli.errors import UsageError
from wormgear_cli.measurement.arrays import unique as lean_unique
from wormgear_cli.measurement.checks import (  # noqa: F401  (re-exported)
    Finding,
    duplicate_rows,
    guide_log_findings,
    structure_findings,
)
from wormgear_cli.measurement.iso230 import group_targets, iso230_figures, withhold_directional
from wormgear_cli.measurement.readers import read_measurement
from wormgear_cli.measurement.resolution import reading_resolution
from wormgear_cli.spec.loader import load_spec
from wormgear_cli.units import to_unit
from wormgear_cli.workflows.guidelog import (
    ISO_NOT_APPLICABLE,
    guide_doc,
    guide_periodic_error,
    guide_verdict,
    is_guide_log,
    longest_run,
    mount_parts,
)

if TYPE_CHECKING:  # the records' types only: the modules are imported where they are used
    from wormgear_cli.measurement.dominant import Dominant
    from wormgear_cli.measurement.iso230 import Iso230Figures
    from wormgear_cli.measurement.orders import OrdersAnalysis
    from wormgear_cli.measurement.reader import Measurement
    from wormgear_cli.measurement.resolution import Resolution
    from wormgear_cli.workflows.guidelog import GuideResult

#: default orders without a drive spec
DEFAULT_ORDERS = (1.0, 2.0, 3.0, 4.0)
#: largest order accepted: beyond it, 1/1000 deg of angle error is a sizeable phase error
MAX_ORDER = 100_000.0


@dataclass(frozen=True)
class MeasureResult:
    """Result of :func:`measure`.

    ``measurement`` (:class:`~wormgear_cli.measurement.reader.Measurement`),
    ``figures`` (:class:`~wormgear_cli.measurement.iso230.Iso230Figures`, one-direction
    values withheld when the directions are mixed), ``analysis``
    (:class:`~wormgear_cli.measurement.orders.OrdersAnalysis`), ``drive_name``,
    ``findings`` (tuple of :class:`Finding`), ``mixed_directions``, ``resolution``
    (:class:`~wormgear_cli.measurement.resolution.Resolution` of the error readings, or None), ``dominant``
    (:class:`~wormgear_cli.measurement.dominant.Dominant`: the strongest orders of the
    data, scanned up to the Nyquist limit of the spacing), ``outside`` (the strongest
    orders left outside the fitted ones when the residual is far above the noise), ``guide``
    (:class:`~wormgear_cli.workflows.guidelog.GuideResult`: the periodic error of a guide log, whose
    ``figures`` and ``resolution`` are None: ISO 230-2 does not apply).
    """

    measurement: Measurement
    figures: Iso230Figures | None
    analysis: OrdersAnalysis
    drive_name: str | None
    findings: tuple
    mixed_directions: bool
    dominant: Dominant | None = None
    outside: tuple = ()
    resolution: Resolution | None = None
    guide: GuideResult | None = None

    @property
    def verdict(self) -> str:
        """One line: rows, targets, span, and what needs attention (a guide log: sessions, frames, time
        and span)."""
        m, a = self.measurement, self.analysis
        flags = [f.verdict for f in self.findings if f.verdict]
        if self.figures is None:
            return guide_verdict(m, self.guide) + ("; " + "; ".join(flags) if flags else "")
        cov = a.coverage
        assert cov is not None  # (analyse_orders always measures the coverage)
        nt = len(self.figures.targets)
        span = ("full turn" if cov.full_turn else "one angle" if cov.distinct < 2
                else f"partial span {math.degrees(cov.span):.4g} deg")
        head = (f"{m.source}: {len(m)} rows, {nt} target{'s' if nt != 1 else ''}, {span} "
                f"({int(np.count_nonzero(m.direction > 0))} forward, {int(np.count_nonzero(m.direction < 0))} "
                "reverse rows)")
        return head + ("; " + "; ".join(flags) if flags else "")


def parse_orders(text: str) -> list[float]:
    """``"1,8,240.5"`` -> [1.0, 8.0, 240.5]; UsageError unless every item is a finite number in (0, MAX_ORDER]."""
    out = []
    for item in (t.strip() for t in text.split(",")):
        try:
            value = float(item)
        except ValueError:
            value = math.nan
        if not math.isfinite(value) or value <= 0:
            raise UsageError(f"--orders: expected positive numbers separated by commas, got {item!r}")
        if value > MAX_ORDER:
            raise UsageError(f"--orders: {item} is above {MAX_ORDER:g} cycles per revolution, finer than "
                             "angle readings resolve")
        if value not in out:
            out.append(value)
    return out


def _label_for(order: float, physical) -> str | None:
    for k, label in physical:
        if abs(k - order) <= 1e-9 * max(abs(k), 1.0):
            return label
    return None


def measure(data: str | Path, options=None, drive: str | Path | None = None, orders: Sequence[float] | None = None,
            harmonics: int = 3) -> MeasureResult:
    """ISO 230-2 figures, order amplitudes and checks of a measurement file.

    Parameters
    ----------
    data : str or Path
        Measurement file in any input format (:func:`~wormgear_cli.measurement.readers.read_measurement`).
    options : ReadOptions or None
        Column map, units and input format.
    drive : str or Path or None
        Drive spec (TOML): its shaft and mesh orders (with ``harmonics``
        harmonics) are the default orders and label the matching ones.
    orders : sequence of float [cycles/rev] or None
        Orders to fit (default: the drive's, else :data:`DEFAULT_ORDERS`).
    harmonics : int
        Harmonics of each shaft/mesh order with ``drive``.

    Raises
    ------
    DataError, SpecError, UsageError
        Bad file, bad spec, bad option.
    """
    spec = _load_drive(drive)
    m = read_measurement(data, options=options)
    if is_guide_log(m):
        return _measure_guide_log(m, spec, orders, harmonics)
    order_list, labels, priority, physical, drive_name = _orders_asked(spec, orders, harmonics)
    unique = lean_unique(m.angle)  # one sort of the rows, shared below
    grouping = group_targets(m.angle, unique=unique)
    target_index = grouping[0]
    figures = iso230_figures(m.angle, m.error, m.direction, grouping=grouping)
    resolution = reading_resolution(m.error, dict(m.units)["error"], target_index)
    repeated = (np.bincount(unique[1]) > 1)[unique[1]]
    findings, mixed = structure_findings(m, target_index, repeated=repeated)
    if mixed:
        figures = withhold_directional(figures, "directions mixed (no direction column, targets repeat within a "
                                       "run): one-direction figures withheld")
    analysis, dominant = _orders_and_dominant(m, order_list, labels, priority, physical, unique)
    outside = _left_outside(m, analysis)
    return MeasureResult(m, figures, analysis, drive_name, tuple(findings), mixed, dominant, outside, resolution)


def _load_drive(drive):
    """The loaded drive spec of ``--drive`` (None without one)."""
    if drive is None:
        return None

    return load_spec(drive)


def _measure_guide_log(m, spec, orders, harmonics: int) -> MeasureResult:
    """``measure`` of a PHD2 guide log: no ISO 230-2 figures (every frame its own target); each session
    its own offset and drift; the orders asked for (or the drive's), the strongest orders, the periodic
    error."""
    order_list, labels, priority, physical, drive_name = _orders_asked(spec, orders, harmonics,
                                                                       default=())
    findings = guide_log_findings(m)
    analysis, dominant = _orders_and_dominant(m, order_list, labels, priority, physical, None)
    outside = _left_outside(m, analysis) if order_list else ()
    guide = guide_periodic_error(m, dominant, None if spec is None else mount_parts(spec), orders=orders)
    return MeasureResult(m, None, analysis, drive_name, tuple(findings), False, dominant, outside, None, guide)


def _orders_asked(spec, orders, harmonics, default=DEFAULT_ORDERS):
    """(orders to fit, their labels or None, tie-break priority or None, the drive's (order, label) pairs,
    the drive's name) from the options (``spec``: the loaded drive or None; ``default``: the orders
    without either)."""
    # lazy: keeps measurement.harmonics off `measure`'s start-up
    from wormgear_cli.measurement.harmonics import physical_orders, physical_priority

    physical: list = []
    priority = None
    drive_name = None
    if spec is not None:
        from wormgear_cli.analysis.accuracy import geometry  # lazy: keeps analysis.accuracy off `measure`'s start-up

        drive_name = spec.drive.name
        geo = geometry(spec)  # the worm's starts are part of the geometry
        physical = physical_orders(geo, harmonics)
        priority = physical_priority(geo, harmonics)
    if orders is not None:
        order_list = [float(k) for k in orders]
        priority = None  # the user's order breaks ties
    elif physical:
        order_list = [k for k, _ in physical]
    else:
        order_list = list(default)
    labels = [_label_for(k, physical) for k in order_list] if physical else None
    return order_list, labels, priority, physical, drive_name


def _orders_and_dominant(m, order_list, labels, priority, physical, unique):
    """The joint fit at the orders asked for, and the strongest orders of the data."""
    # lazy: keeps measurement.orders off `measure`'s start-up
    from wormgear_cli.measurement.orders import OrdersOptions, analyse_orders

    time = m.time if "time_s" in m.present else None
    per_run = m.run_drift  # each session of a guide log has its own offset and drift
    options = OrdersOptions(labels=None if labels is None else tuple(labels),
                            priority=None if priority is None else tuple(priority), passes=m.run, time=time,
                            unique=unique, drift_per_run=per_run)
    analysis = analyse_orders(m.angle, m.error, m.direction, order_list, options)
    return analysis, strongest_orders(m, physical)


def strongest_orders(m, physical=()):
    """The strongest orders of the measurement ``m``
    (:func:`~wormgear_cli.measurement.dominant.dominant_orders`: each guide-log session its own offset and
    drift; ``physical``: the drive's (order, label) pairs that name them).  ``measure``'s ``dominant``, and
    the worm period ``compensate`` takes without a drive."""
    # lazy: keeps measurement.dominant off `measure`'s start-up
    from wormgear_cli.measurement.dominant import ScanOptions, dominant_orders

    time = m.time if "time_s" in m.present else None
    per_run = m.run_drift
    window = 0.0
    if per_run:  # the sessions' relative phases are known as well as the logged hour angle: half a resolution

        window = math.pi / max(longest_run(m.angle, m.run), 1e-12)
    return dominant_orders(m.angle, m.error, m.direction, time, m.run,
                           ScanOptions(labels=tuple(physical), drift_per_run=per_run, label_window=window))


def _left_outside(m, analysis) -> tuple:
    """When the fit's residual is more than EXCESS_FACTOR times the point-to-point noise: the significant
    strongest orders of the data with the fitted orders held (projected out), outside their groups;
    else ()."""
    # lazy: keeps diagnosis.thresholds, measurement.dominant off `measure`'s start-up
    from wormgear_cli.diagnosis.thresholds import EXCESS_FACTOR
    from wormgear_cli.measurement.dominant import ScanOptions, dominant_orders

    noise, rms = analysis.point_noise, analysis.residual_rms
    if not (math.isfinite(noise) and noise > 0 and rms > EXCESS_FACTOR * noise):
        return ()
    fitted = tuple(it.order for it in analysis.items if it.fitted)
    time = m.time if "time_s" in m.present else None
    left = dominant_orders(m.angle, m.error, m.direction, time, m.run,
                           ScanOptions(held=fitted, drift_per_run=m.run_drift))
    return tuple(p for p in left.significant if not any(p.group[0] - 1e-9 <= k <= p.group[1] + 1e-9
                                                        or abs(k - p.order) < 1e-6 for k in fitted))


def _span_finding(analysis, unit: str) -> Finding | None:
    """The partial span, the orders beyond it and what stands for the slow part (with its size in ``unit``)."""
    cov = analysis.coverage
    if cov.full_turn or cov.distinct < 2:
        return None
    beyond = [f"{it.order:g}" for it in analysis.items if it.status == "beyond span"]
    slow = analysis.slow
    size = ("" if slow is None or not math.isfinite(slow.size) or not slow.degree
            else f", {round(float(to_unit(slow.size, unit)), 4):.4g} {unit} peak to peak")
    per_run = slow is not None and slow.per_run
    why = ("(period longer than the longest run) cannot be told from the runs' offsets and drifts" if per_run else
           "(less than an eighth of a period over the span) cannot be told from the offset"
           if slow is not None and slow.kind == "time" else "(period longer than the span) cannot be told from a trend")
    text = (f"the data cover {math.degrees(cov.span):.4g} deg of the turn, not a full turn"
            + (f": order{'s' if len(beyond) > 1 else ''} {', '.join(beyond)} {why} and "
               f"{'are' if len(beyond) > 1 else 'is'} reported as beyond span, without amplitude" if beyond else ""))
    if per_run:
        text += f"; each run (session) has an offset and a drift of its own: {slow.describe()}{size}"
    elif slow is not None and slow.kind == "time" and slow.degree:
        text += (f"; the arc is traversed {slow.traversals} times, so the slow part is {slow.describe()}{size}, "
                 "fitted apart from the errors fixed to the angle (a once-per-turn runout among them), which are "
                 "fitted as orders")
    elif analysis.trend_degree:
        text += f"; a polynomial trend of degree {analysis.trend_degree} over the span stands for the slow part{size}"
    return Finding("span", text, False)


def _excess_finding(analysis, outside: tuple, unit: str) -> Finding | None:
    """A note when the fit's residual is far above the point-to-point noise and the strongest content of
    the data lies outside the orders fitted (``outside``: :func:`_left_outside`; angles in ``unit``)."""
    if not outside:
        return None
    noise, rms = analysis.point_noise, analysis.residual_rms
    fitted = [it.order for it in analysis.items if it.fitted]
    names = ", ".join(f"{p.order:.6g} ({to_unit(p.size, unit):.3g} {unit})" for p in outside)
    text = (f"the residual of the fit ({to_unit(rms, unit):.3g} {unit} RMS) is {rms / noise:.1f} times the "
            f"point-to-point noise ({to_unit(noise, unit):.3g} {unit}), and the strongest content of the data lies "
            f"outside the orders fitted: order{'s' if len(outside) > 1 else ''} {names}; add "
            f"{'them' if len(outside) > 1 else 'it'} with --orders, e.g. --orders "
            + ",".join(f"{k:g}" for k in [*fitted, *(round(p.order, 6) for p in outside)]))
    return Finding("excess", text, False)


def _order_notes(analysis) -> list[str]:
    """One sentence per order not fitted, naming the real reason; alias pairs named together; one per group
    of orders the span cannot separate; how the standard errors were made when the rows correlate."""
    notes = _alias_notes(analysis)
    for grp in analysis.groups:
        carrier = next((it for it in analysis.items if it.status == "ambiguous" and it.fitted and
                        it.order in grp.orders), None)
        span = 360.0 if analysis.coverage.full_turn else math.degrees(analysis.coverage.span)
        text = grp.describe(span)
        notes.append(text + (f": fitted as one order, at {carrier.order:g}, whose amplitude is the group's"
                             if carrier is not None else ": not fitted"))
    grouped: dict = {}
    for it in analysis.items:
        if it.status in ("folded", "unresolved", "beyond span"):
            grouped.setdefault(it.reason, []).append(it)
    for reason, its in grouped.items():
        if len(its) == 1:
            it = its[0]
            notes.append(f"order {it.order:g}" + (f" ({it.label})" if it.label else "") + f" not fitted: {reason}")
        else:
            notes.append(f"orders {', '.join(f'{it.order:g}' for it in its)} not fitted: {reason}")
    serial = analysis.serial
    if serial is not None and not serial.independent:
        notes.append(f"the residual is serially correlated: standard errors from the {serial.describe()}")
    return notes


def _alias_notes(analysis) -> list[str]:
    notes = []
    carriers = {it.order: it for it in analysis.items if it.fitted}
    for it in analysis.items:
        name = f"order {it.order:g}" + (f" ({it.label})" if it.label else "")
        if it.status == "aliased":
            if 0.0 in it.aliased_with:
                notes.append(f"{name} is aliased onto the offset by the target spacing (constant on these "
                             "targets): not fitted")
                continue
            onto = ", ".join(f"{k:g}" for k in it.aliased_with)
            plural = 's' if len(it.aliased_with) > 1 else ''
            carried = [carriers[k] for k in it.aliased_with if k in carriers]
            if carried:
                c = carried[0]
                cname = f"order {c.order:g}" + (f" ({c.label})" if c.label else "")
                notes.append(f"{name} is aliased by the target spacing onto order{plural} "
                             f"{onto}: {name} and {cname} are indistinguishable on these targets, the amplitude "
                             f"shown at order {c.order:g} belongs to either or both")
            else:
                notes.append(f"{name} is aliased by the target spacing onto order{plural} {onto}: not fitted")
        elif it.fitted and it.aliased_with:
            onto = ", ".join(f"{k:g}" for k in it.aliased_with if k != 0.0)
            if onto:
                notes.append(f"{name} also carries order {onto} (aliased by the target spacing; indistinguishable)")
    return notes


def report(result: MeasureResult, unit: str, per_target: bool = True) -> dict:
    """The JSON document of ``wormgear measure`` (angles in ``unit``, phases and positions in degrees).

    ``per_target`` False leaves the per-target list out (the table format
    does not show it beyond 100 targets; saves memory on long files)."""
    m, figures, analysis = result.measurement, result.figures, result.analysis

    def a(x) -> float | None:
        x = float(x)
        return float(to_unit(x, unit)) if math.isfinite(x) else None


    findings = list(result.findings) + [f for f in (_span_finding(analysis, unit),
                                                    _excess_finding(analysis, result.outside, unit)) if f]
    if figures is None:  # a guide log: ISO 230-2 does not apply, said once
        notes = [ISO_NOT_APPLICABLE] + (_order_notes(analysis) if analysis.items else [])
    else:
        notes = list(figures.notes) + _resolution_notes(result, unit) + _order_notes(analysis)
    cov = analysis.coverage
    assert cov is not None  # (analyse_orders always measures the coverage)
    return {
        "source": m.source,
        "drive": result.drive_name,
        "unit": unit,
        "verdict": result.verdict,
        "rows": len(m),
        "targets": None if figures is None else len(figures.targets),
        "rows_forward": int(np.count_nonzero(m.direction > 0)),
        "rows_reverse": int(np.count_nonzero(m.direction < 0)),
        "runs_per_target": None if figures is None else _runs_per_target(figures.targets),
        "columns": dict(m.columns),
        "input_units": dict(m.units),
        "derived_columns": sorted(m.derived),
        "coverage": {
            "span_deg": math.degrees(cov.span),
            "full_turn": cov.full_turn,
            "start_deg": math.degrees(cov.start),
            "largest_gap_deg": math.degrees(cov.largest_gap),
            "distinct_angles": cov.distinct,
            "pass_spans_deg": [math.degrees(x) for x in cov.pass_spans],
            "trend_degree": analysis.trend_degree,
        },
        "iso230_2": None if figures is None else _iso_doc(figures, a),
        "resolution": None if figures is None else _resolution_doc(result, a),
        "orders": _orders_doc(analysis, a),
        "dominant": _dominant_doc(result.dominant, a, result.drive_name is not None),
        "periodic_error": guide_doc(result.guide, a),
        "warnings": [f.text for f in findings if f.warning],
        "checks": [{"kind": f.kind, "text": f.text or f.verdict, "warning": f.warning} for f in findings],
        "per_target": _target_rows(figures.targets, unit) if per_target and figures is not None else [],
        "notes": notes + [f.text for f in findings if not f.warning and f.text],
    }


def _runs_per_target(t) -> dict:
    """The fewest and most runs per target, by direction (None where the direction has no rows)."""
    runs_f = t.n_up[t.n_up > 0]
    runs_r = t.n_down[t.n_down > 0]
    return {"forward": [int(runs_f.min()), int(runs_f.max())] if runs_f.size else None,
            "reverse": [int(runs_r.min()), int(runs_r.max())] if runs_r.size else None}


#: names of the axis figures in the document
_AXIS_NAMES = {"R_up": "R_forward", "R_down": "R_reverse", "R": "R"}


#: targets made into rows of the document at a time by :func:`target_row_blocks` (a dict a target is
#: about 1 kB: a dense scan's per-target part is written a block at a time, never held whole)
TARGET_BLOCK = 4096


def target_row_blocks(t, unit: str, block: int | None = None):
    """The per-target list of the document (:func:`report`'s ``per_target``), ``block`` targets at a
    time (None: :data:`TARGET_BLOCK`): lists of dicts whose concatenation is the whole list."""
    block = block or TARGET_BLOCK
    for a in range(0, len(t), block):
        yield _target_rows(t, unit, slice(a, a + block))


def _target_rows(t, unit: str, part: slice = slice(None)) -> list[dict]:
    """The per-target list of the document (the targets ``part``): numbers in ``unit``; s and R of a cell
    whose readings are all equal are None (below the resolution of the data), said by ``below_resolution``."""
    def column(values, blank=None) -> list:
        # NaN (undefined) stays NaN here: null in JSON, empty in CSV, "-" in tables
        values = np.asarray(values, dtype=float)[part]
        if blank is not None and np.any(blank):
            values = np.where(blank, np.nan, values)
        return np.asarray(to_unit(values, unit)).tolist()

    target = t.target[part]
    eq_up = t.equal_up[part] if t.equal_up is not None else np.zeros(target.shape[0], dtype=bool)
    eq_dn = t.equal_down[part] if t.equal_down is not None else np.zeros(target.shape[0], dtype=bool)
    below = np.array([None, "forward", "reverse", "both"], dtype=object)[eq_up.astype(int) + 2 * eq_dn.astype(int)]
    # rounded to 1e-9 deg: removes the rad -> deg round-off, far below the grouping tolerance
    cols = {
        "target_deg": np.round(np.degrees(target), 9).tolist(),
        "n_forward": t.n_up[part].tolist(),
        "n_reverse": t.n_down[part].tolist(),
        "mean_forward": column(t.mean_up),
        "s_forward": column(t.s_up, eq_up),
        "mean_reverse": column(t.mean_down),
        "s_reverse": column(t.s_down, eq_dn),
        "mean_bidirectional": column(t.mean_bi),
        "reversal": column(t.reversal),
        "R_forward": column(t.r_up, eq_up),
        "R_reverse": column(t.r_down, eq_dn),
        "R": column(t.r_bi, eq_up & eq_dn),
        "below_resolution": below.tolist(),
    }
    names = list(cols)
    return [dict(zip(names, row)) for row in zip(*cols.values())]


def _resolution_doc(result: MeasureResult, a) -> dict | None:
    """``resolution`` of the document: the step of the readings (in the document's unit), whether they
    are quantised, how the step was found, the axis figures and the cells below it."""
    assert result.figures is not None  # (a measurement with ISO 230-2 figures)
    res, t = result.resolution, result.figures.targets
    up = int(np.count_nonzero(t.equal_up)) if t.equal_up is not None else 0
    dn = int(np.count_nonzero(t.equal_down)) if t.equal_down is not None else 0
    if res is None and not (up or dn):
        return None
    return {"step": None if res is None else a(res.step), "quantised": bool(res is not None and res.quantised),
            "basis": None if res is None else res.basis,
            "below": [_AXIS_NAMES[k] for k in result.figures.below],
            "cells_below": {"forward": up, "reverse": dn}}


def _resolution_notes(result: MeasureResult, unit: str) -> list[str]:
    """A sentence for the cells whose readings are all equal: their s and R are below the resolution."""
    assert result.figures is not None  # (a measurement with ISO 230-2 figures)
    t = result.figures.targets
    if t.equal_up is None or not (np.any(t.equal_up) or np.any(t.equal_down)):
        return []
    res = result.resolution
    step = ("one step unknown: the readings carry full precision" if res is None
            else f"one step = {float(to_unit(res.step, unit)):.6g} {unit}: {res.basis}")
    parts = []
    for name, eq, n in (("forward", t.equal_up, t.n_up), ("reverse", t.equal_down, t.n_down)):
        k = 0 if eq is None else int(np.count_nonzero(eq))
        if not k:
            continue
        if len(t) == 1:
            parts.append(f"all {int(n[0])} {name} readings are equal")
        else:
            parts.append(f"at {k} target{'s' if k > 1 else ''} all {name} readings are equal")
    return [f"{' and '.join(parts)}: their s and R are below the resolution of the data ({step}), not zero"]


def _iso_doc(figures, a) -> dict:
    ax = {k: (math.nan if k in figures.below else v) for k, v in figures.axis().items()}
    return {
        "A": a(ax["A"]), "A_forward": a(ax["A_up"]), "A_reverse": a(ax["A_down"]),
        "B": a(ax["B"]), "B_signed": a(ax["B_signed"]), "B_mean": a(ax["B_mean"]),
        "B_mean_abs": a(abs(ax["B_mean"])),
        "E": a(ax["E"]), "E_forward": a(ax["E_up"]), "E_reverse": a(ax["E_down"]),
        "M": a(ax["M"]),
        "R": a(ax["R"]), "R_forward": a(ax["R_up"]), "R_reverse": a(ax["R_down"]),
    }


def _orders_doc(analysis, a) -> dict:
    items = []
    for it in analysis.items:
        def mode(tr):
            amp, se, ph = tr
            return {"amplitude": a(amp), "amplitude_stderr": a(se),
                    "phase_deg": float(np.degrees(ph)) if math.isfinite(ph) else None}

        items.append({
            "order": it.order,
            "label": it.label,
            "status": it.status,
            "aliased_with": list(it.aliased_with),
            "group": list(it.group),
            "reason": it.reason,
            "common": mode(it.common),
            "differential": mode(it.differential),
        })
    slow = analysis.slow
    return {
        "method": "joint least squares on all rows: error = common(theta) + direction * differential(theta), "
                  "each an offset plus A sin(k theta + phase) per order (plus a polynomial trend over a "
                  "partial span)",
        "alias_tolerance": analysis.alias_tol,
        "residual_rms": a(analysis.residual_rms),
        "point_noise": a(analysis.point_noise),
        "common_offset": a(analysis.common_offset),
        "differential_offset": a(analysis.differential_offset),
        "angles_unwrapped": analysis.unwrapped,
        "standard_errors": analysis.serial.describe() if analysis.serial is not None else None,
        "slow_part": None if slow is None or slow.kind == "none" else {
            "kind": slow.kind, "signal": slow.signal, "degree": slow.degree, "traversals": slow.traversals,
            "peak_to_peak": a(slow.size), "description": slow.describe()},
        "groups": [{"orders": list(g.orders), "correlation": g.correlation, "span_needed_deg": g.span_needed_deg}
                   for g in analysis.groups],
        "items": items,
    }


#: what a strong order of the data belongs to when it matches none of the drive's shafts and meshes
NO_PART = "none of the drive's shafts and meshes"


def _dominant_doc(dominant, a, drive: bool = False) -> dict | None:
    """The strongest orders of the data (:func:`~wormgear_cli.measurement.dominant.dominant_orders`); with a
    ``drive``, a peak no shaft or mesh of it explains is labelled :data:`NO_PART`."""
    if dominant is None:
        return None
    slow = dominant.slow
    peaks = [{"order": p.order, "amplitude": a(p.amplitude), "amplitude_stderr": a(p.amplitude_stderr),
              "phase_deg": math.degrees(p.phase), "differential": a(p.differential),
              "differential_stderr": a(p.differential_stderr), "p_adjusted": p.p_adjusted,
              "significant": p.significant, "group": list(p.group), "period_s": p.period_s,
              "label": p.label if p.label or not drive else NO_PART,
              "aliases": [{"order": o, "correlation": c, "label": lab} for o, c, lab in p.aliases]}
             for p in dominant.peaks]
    return {
        "method": dominant.method,
        "scanned_orders": list(dominant.scanned),
        "resolution": dominant.resolution,
        "nyquist_order": dominant.nyquist,
        "independent_orders": dominant.independent,
        "seconds_per_turn": dominant.seconds_per_turn,
        "slow_part": None if slow.kind == "none" else {"kind": slow.kind, "signal": slow.signal,
                                                        "degree": slow.degree, "peak_to_peak": a(slow.size)},
        "residual_rms": a(dominant.residual_rms),
        "standard_errors": dominant.serial.describe(),
        "note": dominant.note,
        "peaks": peaks,
    }
