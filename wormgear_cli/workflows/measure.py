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

import numpy as np

from wormgear_cli.measurement.checks import Finding, duplicate_rows, structure_findings  # noqa: F401  (re-exported)

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
    ``findings`` (tuple of :class:`Finding`), ``mixed_directions``.
    """

    measurement: object
    figures: object
    analysis: object
    drive_name: str | None
    findings: tuple
    mixed_directions: bool

    @property
    def verdict(self) -> str:
        """One line: rows, targets, span, and what needs attention."""
        m, a = self.measurement, self.analysis
        cov = a.coverage
        nt = len(self.figures.targets)
        span = ("full turn" if cov.full_turn else "one angle" if cov.distinct < 2
                else f"partial span {math.degrees(cov.span):.4g} deg")
        head = (f"{m.source}: {len(m)} rows, {nt} target{'s' if nt != 1 else ''}, {span} "
                f"({int(np.count_nonzero(m.direction > 0))} forward, {int(np.count_nonzero(m.direction < 0))} "
                "reverse rows)")
        flags = [f.verdict for f in self.findings if f.verdict]
        return head + ("; " + "; ".join(flags) if flags else "")


def parse_orders(text: str) -> list[float]:
    """``"1,8,240.5"`` -> [1.0, 8.0, 240.5]; UsageError unless every item is a finite number in (0, MAX_ORDER]."""
    from wormgear_cli.errors import UsageError

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
        Measurement CSV (:func:`~wormgear_cli.measurement.reader.read_measurement`).
    options : ReadOptions or None
        Column map and units.
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
    from wormgear_cli.measurement.harmonics import physical_orders, physical_priority
    from wormgear_cli.measurement.iso230 import group_targets, iso230_figures, withhold_directional
    from wormgear_cli.measurement.orders import analyse_orders
    from wormgear_cli.measurement.reader import read_measurement

    physical: list = []
    priority = None
    drive_name = None
    if drive is not None:
        from wormgear_cli.analysis.accuracy import geometry
        from wormgear_cli.spec.loader import load_spec

        spec = load_spec(drive)
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
        order_list = list(DEFAULT_ORDERS)
    labels = [_label_for(k, physical) for k in order_list] if physical else None

    m = read_measurement(data, options=options)
    unique = np.unique(m.angle, return_inverse=True)  # one sort of the rows, shared below
    grouping = group_targets(m.angle, unique=unique)
    target_index = grouping[0]
    figures = iso230_figures(m.angle, m.error, m.direction, grouping=grouping)
    repeated = np.bincount(unique[1].ravel())[unique[1].ravel()] > 1
    findings, mixed = structure_findings(m, target_index, repeated=repeated)
    if mixed:
        figures = withhold_directional(figures, "directions mixed (no direction column, targets repeat within a "
                                       "run): one-direction figures withheld")
    analysis = analyse_orders(m.angle, m.error, m.direction, order_list, labels, priority, passes=m.run,
                              unique=unique)
    cov = analysis.coverage
    if not cov.full_turn and cov.distinct >= 2:
        beyond = [f"{it.order:g}" for it in analysis.items if it.status == "beyond span"]
        text = (f"the data cover {math.degrees(cov.span):.4g} deg of the turn, not a full turn"
                + (f": order{'s' if len(beyond) > 1 else ''} {', '.join(beyond)} (period longer than the span) "
                   "cannot be told from a trend and are reported as beyond span, without amplitude" if beyond else "")
                + (f"; a polynomial trend of degree {analysis.trend_degree} over the span stands for the slow part"
                   if analysis.trend_degree else ""))
        findings.append(Finding("span", text, False))
    return MeasureResult(m, figures, analysis, drive_name, tuple(findings), mixed)


def _order_notes(analysis) -> list[str]:
    """One sentence per order not fitted, naming the real reason; alias pairs named together."""
    notes = []
    carriers = {it.order: it for it in analysis.items if it.fitted}
    for it in analysis.items:
        name = f"order {it.order:g}" + (f" ({it.label})" if it.label else "")
        if it.status == "aliased":
            if 0.0 in it.aliased_with:
                notes.append(f"{name} is aliased onto the offset by the target spacing (constant on these "
                             "targets): not fitted")
            else:
                onto = ", ".join(f"{k:g}" for k in it.aliased_with)
                carried = [carriers[k] for k in it.aliased_with if k in carriers]
                if carried:
                    c = carried[0]
                    cname = f"order {c.order:g}" + (f" ({c.label})" if c.label else "")
                    plural = 's' if len(it.aliased_with) > 1 else ''
                    notes.append(f"{name} is aliased by the target spacing onto order{plural} "
                                 f"{onto}: {name} and {cname} are indistinguishable on these targets, the amplitude "
                                 f"shown at order {c.order:g} belongs to either or both")
                else:
                    notes.append(f"{name} is aliased by the target spacing onto order"
                                 f"{'s' if len(it.aliased_with) > 1 else ''} {onto}: not fitted")
        elif it.status == "fitted" and it.aliased_with:
            onto = ", ".join(f"{k:g}" for k in it.aliased_with if k != 0.0)
            if onto:
                notes.append(f"{name} also carries order {onto} (aliased by the target spacing; indistinguishable)")
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
    return notes


def report(result: MeasureResult, unit: str, per_target: bool = True) -> dict:
    """The JSON document of ``wormgear measure`` (angles in ``unit``, phases and positions in degrees).

    ``per_target`` False leaves the per-target list out (the table format
    does not show it beyond 100 targets; saves memory on long files)."""
    from wormgear_cli.units import to_unit

    m, figures, analysis = result.measurement, result.figures, result.analysis

    def a(x) -> float | None:
        x = float(x)
        return float(to_unit(x, unit)) if math.isfinite(x) else None

    t = figures.targets
    rows = []
    if per_target:
        def column(values) -> list:
            # NaN (undefined) stays NaN here: null in JSON, empty in CSV, "-" in tables
            return np.asarray(to_unit(np.asarray(values, dtype=float), unit)).tolist()

        # rounded to 1e-9 deg: removes the rad -> deg round-off, far below the grouping tolerance
        cols = {
            "target_deg": np.round(np.degrees(t.target), 9).tolist(),
            "n_forward": t.n_up.tolist(),
            "n_reverse": t.n_down.tolist(),
            "mean_forward": column(t.mean_up),
            "s_forward": column(t.s_up),
            "mean_reverse": column(t.mean_down),
            "s_reverse": column(t.s_down),
            "mean_bidirectional": column(t.mean_bi),
            "reversal": column(t.reversal),
            "R_forward": column(t.r_up),
            "R_reverse": column(t.r_down),
            "R": column(t.r_bi),
        }
        names = list(cols)
        rows = [dict(zip(names, row)) for row in zip(*cols.values())]
    ax = figures.axis()
    iso = {
        "A": a(ax["A"]), "A_forward": a(ax["A_up"]), "A_reverse": a(ax["A_down"]),
        "B": a(ax["B"]), "B_signed": a(ax["B_signed"]), "B_mean": a(ax["B_mean"]),
        "B_mean_abs": a(abs(ax["B_mean"])),
        "E": a(ax["E"]), "E_forward": a(ax["E_up"]), "E_reverse": a(ax["E_down"]),
        "M": a(ax["M"]),
        "R": a(ax["R"]), "R_forward": a(ax["R_up"]), "R_reverse": a(ax["R_down"]),
    }
    notes = list(figures.notes) + _order_notes(analysis)
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
            "reason": it.reason,
            "common": mode(it.common),
            "differential": mode(it.differential),
        })
    runs_f = t.n_up[t.n_up > 0]
    runs_r = t.n_down[t.n_down > 0]
    cov = analysis.coverage
    return {
        "source": m.source,
        "drive": result.drive_name,
        "unit": unit,
        "verdict": result.verdict,
        "rows": len(m),
        "targets": len(t),
        "rows_forward": int(np.count_nonzero(m.direction > 0)),
        "rows_reverse": int(np.count_nonzero(m.direction < 0)),
        "runs_per_target": {
            "forward": [int(runs_f.min()), int(runs_f.max())] if runs_f.size else None,
            "reverse": [int(runs_r.min()), int(runs_r.max())] if runs_r.size else None,
        },
        "columns": dict(m.columns),
        "input_units": dict(m.units),
        "derived_columns": sorted(m.derived),
        "coverage": {
            "span_deg": math.degrees(cov.span),
            "full_turn": cov.full_turn,
            "start_deg": math.degrees(cov.start),
            "distinct_angles": cov.distinct,
            "pass_spans_deg": [math.degrees(x) for x in cov.pass_spans],
            "trend_degree": analysis.trend_degree,
        },
        "iso230_2": iso,
        "orders": {
            "method": "joint least squares on all rows: error = common(theta) + direction * differential(theta), "
                      "each an offset plus A sin(k theta + phase) per order (plus a polynomial trend over a "
                      "partial span)",
            "alias_tolerance": analysis.alias_tol,
            "residual_rms": a(analysis.residual_rms),
            "common_offset": a(analysis.common_offset),
            "differential_offset": a(analysis.differential_offset),
            "angles_unwrapped": analysis.unwrapped,
            "items": items,
        },
        "warnings": [f.text for f in result.findings if f.warning],
        "checks": [{"kind": f.kind, "text": f.text or f.verdict, "warning": f.warning} for f in result.findings],
        "per_target": rows,
        "notes": notes + [f.text for f in result.findings if not f.warning and f.text],
    }
