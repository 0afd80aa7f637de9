"""``wormgear measure``: ISO 230-2 figures and order amplitudes of a measurement."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Optional

import typer

from wormgear_cli.cli.app import app
from wormgear_cli.cli.common import (
    FormatOption,
    OutputOption,
    UnitOption,
    csv_text,
    emit,
    fmt_angle,
    json_text,
    render,
)

#: default orders without a drive spec
DEFAULT_ORDERS = (1.0, 2.0, 3.0, 4.0)
#: per-target rows shown in the table format before it is left to --format csv
MAX_TABLE_TARGETS = 100
#: per-target CSV columns (angles in --unit; the column names carry the unit)
TARGET_COLUMNS = ("target_deg", "n_forward", "n_reverse", "mean_forward", "s_forward", "mean_reverse", "s_reverse",
                  "mean_bidirectional", "reversal", "R_forward", "R_reverse", "R")

DataArgument = Annotated[Path, typer.Argument(help="Measurement CSV (angle_deg, error_arcsec; optional direction, "
                                              "run, load_Nm, temperature_C, time_s).", show_default=False)]


#: largest order accepted by --orders: beyond it, 1/1000 deg of angle error is a sizeable phase error
MAX_ORDER = 100_000.0


def parse_orders(text: str) -> list[float]:
    """``"1,8,240.5"`` -> [1.0, 8.0, 240.5]; UsageError unless every item is a finite number > 0."""
    from wormgear_cli.errors import UsageError

    items = [t.strip() for t in text.split(",")]
    out = []
    for item in items:
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


def _label_for(order: float, physical: list[tuple[float, str]]) -> Optional[str]:
    for k, label in physical:
        if abs(k - order) <= 1e-9 * max(abs(k), 1.0):
            return label
    return None


@app.command()
def measure(
    data: DataArgument,
    drive: Annotated[Optional[Path], typer.Option(
        "--drive", "-d", help="Drive spec (TOML): default orders are its shafts and meshes, labelled.",
        show_default=False)] = None,
    orders: Annotated[Optional[str], typer.Option(
        "--orders", help="Orders to fit [cycles per output revolution], comma-separated, e.g. 1,8,240 "
        "(default: the drive's physical orders with --drive, else 1,2,3,4).", show_default=False)] = None,
    harmonics: Annotated[int, typer.Option(
        "--harmonics", help="With --drive: harmonics of each shaft/mesh order to include.", min=1,
        max=10)] = 3,
    format: FormatOption = "table",
    unit: UnitOption = "arcsec",
    output: OutputOption = None,
    plot: Annotated[Optional[Path], typer.Option(
        "--plot", help="Also draw the ISO 230-2 deviation chart to FILE (.png, .svg or .pdf; needs the "
        "'plot' extra).", show_default=False)] = None,
):
    """ISO 230-2 figures and order amplitudes of a rotary-table measurement.

    Per target and direction the mean deviation and standard deviation;
    the axis accuracy A, reversal B (max |B_i| and mean), systematic
    deviation E, mean bidirectional deviation M and repeatability R; and
    the amplitude and phase at exact orders by least squares on all rows,
    split into the common mode (mean of the directions) and the
    differential mode (half the reversal), with a warning where the target
    spacing aliases an order.  CSV output is the per-target table.

    Example: wormgear measure test.csv --drive configs/mch50.toml --format json
    """
    from wormgear_cli.harmonics import analyse_orders, physical_orders, physical_priority
    from wormgear_cli.iso230 import measurement_figures
    from wormgear_cli.measurement import read_measurement

    unit = getattr(unit, "value", unit)
    fmt = getattr(format, "value", format)
    inputs = [data] + ([drive] if drive is not None else [])
    if plot is not None:
        from wormgear_cli.plots import check_plot_path

        check_plot_path(plot)
        from wormgear_cli.io import refuse_input

        refuse_input(plot, inputs, "--plot")
    spec = None
    physical: list[tuple[float, str]] = []
    priority = None
    if drive is not None:
        from wormgear_cli.analysis import geometry
        from wormgear_cli.spec import load_spec

        spec = load_spec(drive)
        geo, starts = geometry(spec), spec.worm_pair.worm.starts
        physical = physical_orders(geo, harmonics, worm_starts=starts)
        priority = physical_priority(geo, harmonics, worm_starts=starts)
    if orders is not None:
        order_list = parse_orders(orders)
        priority = None  # the user's order is the priority
    elif physical:
        order_list = [k for k, _ in physical]
    else:
        order_list = list(DEFAULT_ORDERS)
    labels = [_label_for(k, physical) for k in order_list] if physical else None

    m = read_measurement(data)
    figures = measurement_figures(m)
    analysis = analyse_orders(m.angle, m.error, m.direction, order_list, labels, priority)
    doc = report(m, figures, analysis, unit, spec.drive.name if spec is not None else None)

    if plot is not None:
        from wormgear_cli.plots.measure import deviation_chart

        deviation_chart(figures, m, unit, plot, title=Path(data).name)
    if fmt == "json":
        emit(_json(doc), output, inputs)
    elif fmt == "csv":
        for note in doc["notes"]:
            typer.echo(f"note: {note}", err=True)
        cols = [c if c.startswith(("target_deg", "n_")) else f"{c}_{unit}" for c in TARGET_COLUMNS]
        emit(csv_text(cols, ([t[c] for c in TARGET_COLUMNS] for t in doc["per_target"])), output, inputs)
    else:
        render(_tables(doc), output, inputs)


def report(m, figures, analysis, unit: str, drive_name: Optional[str]) -> dict:
    """The JSON document of ``wormgear measure`` (angles in ``unit``, phases and targets in degrees)."""
    import numpy as np

    from wormgear_cli.units import to_unit

    def a(x) -> Optional[float]:
        x = float(x)
        return float(to_unit(x, unit)) if math.isfinite(x) else None

    t = figures.targets

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
    per_target = [dict(zip(names, row)) for row in zip(*cols.values())]
    ax = figures.axis()
    iso = {
        "A": a(ax["A"]), "A_forward": a(ax["A_up"]), "A_reverse": a(ax["A_down"]),
        "B": a(ax["B"]), "B_signed": a(ax["B_signed"]), "B_mean": a(ax["B_mean"]),
        "B_mean_abs": a(abs(ax["B_mean"])),
        "E": a(ax["E"]), "E_forward": a(ax["E_up"]), "E_reverse": a(ax["E_down"]),
        "M": a(ax["M"]),
        "R": a(ax["R"]), "R_forward": a(ax["R_up"]), "R_reverse": a(ax["R_down"]),
    }
    notes = list(figures.notes)
    items = []
    unresolved = []
    carriers = {it.order for it in analysis.items if it.fitted}
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
            "common": mode(it.common),
            "differential": mode(it.differential),
        })
        name = f"order {it.order:g}" + (f" ({it.label})" if it.label else "")
        if it.status == "aliased":
            if 0.0 in it.aliased_with:
                notes.append(f"{name} is aliased onto the offset by the target spacing (constant on these "
                             "targets): not fitted")
            else:
                onto = ", ".join(f"{k:g}" for k in it.aliased_with)
                carried = [f"{k:g}" for k in it.aliased_with if k in carriers]
                tail = f", its content is in the amplitude of order {carried[0]}" if carried else ""
                notes.append(f"{name} is aliased by the target spacing onto order{'s' if len(it.aliased_with) > 1 else ''} "
                             f"{onto}: not fitted{tail}")
        elif it.status == "fitted" and it.aliased_with:
            onto = ", ".join(f"{k:g}" for k in it.aliased_with)
            notes.append(f"{name} also carries order {onto} (aliased by the target spacing)")
        elif it.status == "folded":
            notes.append(f"{name}: the targets see only one phase component of it (cos and sin collinear): "
                         "not fitted")
        elif it.status == "unresolved":
            unresolved.append(f"{it.order:g}")
    if unresolved:
        notes.append(f"{analysis.distinct_angles} distinct target angles cannot resolve all orders together: "
                     f"order{'s' if len(unresolved) > 1 else ''} {', '.join(unresolved)} not fitted (lower "
                     "harmonics and earlier orders kept first)")
    runs_f = t.n_up[t.n_up > 0]
    runs_r = t.n_down[t.n_down > 0]
    return {
        "source": m.source,
        "drive": drive_name,
        "unit": unit,
        "rows": len(m),
        "targets": len(t),
        "rows_forward": int(np.count_nonzero(m.direction > 0)),
        "rows_reverse": int(np.count_nonzero(m.direction < 0)),
        "runs_per_target": {
            "forward": [int(runs_f.min()), int(runs_f.max())] if runs_f.size else None,
            "reverse": [int(runs_r.min()), int(runs_r.max())] if runs_r.size else None,
        },
        "iso230_2": iso,
        "orders": {
            "method": "joint least squares on all rows: error = common(theta) + direction * differential(theta), "
                      "each an offset plus A sin(k theta + phase) per order",
            "alias_tolerance": analysis.alias_tol,
            "residual_rms": a(analysis.residual_rms),
            "common_offset": a(analysis.common_offset),
            "differential_offset": a(analysis.differential_offset),
            "items": items,
        },
        "per_target": per_target,
        "notes": notes,
    }


def _json(doc: dict) -> str:
    """``json_text`` of the document, with the per-target list written one
    compact object per line (fast and readable for 100 000 targets)."""
    import json

    head = dict(doc)
    rows = head.pop("per_target")
    text = json_text({**head, "per_target": []})
    if not rows:
        return text
    # one C-encoder pass; the rows hold only numbers (NaN for undefined), so "}, {" only occurs between
    # rows and "NaN" only stands for an undefined value
    flat = json.dumps(rows, allow_nan=True, separators=(", ", ": ")).replace("NaN", "null")
    body = "    " + flat[1:-1].replace("}, {", "},\n    {")
    marker = '"per_target": []'
    assert text.count(marker) == 1
    return text.replace(marker, '"per_target": [\n' + body + "\n  ]")


def _tables(doc: dict) -> list:
    from rich.markup import escape
    from rich.table import Table
    from rich.text import Text

    unit = doc["unit"]

    def a(x) -> str:
        return "-" if x is None or not math.isfinite(x) else fmt_angle(x, unit)

    iso = doc["iso230_2"]
    out = []
    head = (f"{doc['source']}: {doc['rows']} rows, {doc['targets']} targets "
            f"({doc['rows_forward']} forward, {doc['rows_reverse']} reverse rows)")
    out.append(Text(head))
    st = Table(title=escape(f"ISO 230-2 figures [{unit}]"), title_justify="left")
    for col in ("figure", "bidirectional", "forward", "reverse"):
        st.add_column(col, justify="left" if col == "figure" else "right")
    st.add_row("accuracy A", a(iso["A"]), a(iso["A_forward"]), a(iso["A_reverse"]))
    st.add_row("systematic deviation E", a(iso["E"]), a(iso["E_forward"]), a(iso["E_reverse"]))
    st.add_row("repeatability R", a(iso["R"]), a(iso["R_forward"]), a(iso["R_reverse"]))
    st.add_row("mean bidirectional deviation M", a(iso["M"]), "", "")
    st.add_row("reversal B = max |B_i|", a(iso["B"]), "", "")
    st.add_row("  largest B_i, signed", a(iso["B_signed"]), "", "")
    st.add_row("mean reversal B_mean", a(iso["B_mean"]), "", "")
    out.append(st)

    od = doc["orders"]
    ot = Table(title=escape(f"orders (least squares at exact orders, all rows) [{unit}, phase in deg]"),
               title_justify="left")
    for col in ("order", "shaft / mesh", "common", "phase", "differential", "phase", "status"):
        ot.add_column(col, justify="left" if col in ("shaft / mesh", "status") else "right")

    def ph(x):
        return "-" if x is None else f"{x:.1f}"

    def amp(m):
        if m["amplitude"] is None:
            return "-"
        return f"{a(m['amplitude'])} +/- {a(m['amplitude_stderr'])}"

    for it in od["items"]:
        c, d = it["common"], it["differential"]
        status = it["status"]
        if it["aliased_with"]:
            status += " ~ " + ("offset" if 0 in it["aliased_with"] else
                               ", ".join(f"{k:g}" for k in it["aliased_with"]))
        ot.add_row(f"{it['order']:g}", escape(it["label"] or ""), amp(c), ph(c["phase_deg"]), amp(d), ph(d["phase_deg"]),
                   status)
    ot.caption = escape(f"error ~ offset + A sin(k theta + phase); common = mean of directions, differential = half the "
                  f"reversal. Residual RMS {a(od['residual_rms'])}, common offset {a(od['common_offset'])}, "
                  f"differential offset {a(od['differential_offset'])}")
    ot.caption_justify = "left"
    out.append(ot)

    rows = doc["per_target"]
    if len(rows) <= MAX_TABLE_TARGETS:
        tt = Table(title=escape(f"per target [{unit}; target in deg]"), title_justify="left")
        for col in ("target", "n fwd", "mean fwd", "s fwd", "n rev", "mean rev", "s rev", "mean bi", "B_i", "R_i"):
            tt.add_column(col, justify="right")
        for r in rows:
            tt.add_row(f"{r['target_deg']:.4f}", str(r["n_forward"]), a(r["mean_forward"]), a(r["s_forward"]),
                       str(r["n_reverse"]), a(r["mean_reverse"]), a(r["s_reverse"]), a(r["mean_bidirectional"]),
                       a(r["reversal"]), a(r["R"]))
        out.append(tt)
    else:
        out.append(Text(f"{len(rows)} targets: the per-target table is in --format csv or json"))
    for note in doc["notes"]:
        out.append(Text(f"note: {note}"))
    return out
