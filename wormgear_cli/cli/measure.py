"""``wormgear measure``: ISO 230-2 figures and order amplitudes of a measurement."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    FormatOption,
    OutputOption,
    UnitOption,
    announce_written,
    csv_text,
    emit,
    fmt_angle,
    json_text,
    render,
)
from wormgear_cli.cli.read_options import (
    AngleUnitOption,
    ErrorUnitOption,
    InputFormatOption,
    MapOption,
    read_options,
)

#: per-target rows shown in the table format before it is left to --format csv
MAX_TABLE_TARGETS = 100
#: per-target CSV columns (angles in --unit; the column names carry the unit)
TARGET_COLUMNS = ("target_deg", "n_forward", "n_reverse", "mean_forward", "s_forward", "mean_reverse", "s_reverse",
                  "mean_bidirectional", "reversal", "R_forward", "R_reverse", "R", "below_resolution")
#: per-target CSV columns that are not angles (no unit in their name)
PLAIN_COLUMNS = ("target_deg", "n_forward", "n_reverse", "below_resolution")
#: a table cell for s or R below the resolution of the data (the step is in the notes)
BELOW = "<1 step"

DataArgument = Annotated[Path, typer.Argument(help="Measurement file, read as it is: a delimited table (angle_deg, "
                                              "error_arcsec or actual_deg; optional direction, run, load_Nm, "
                                              "temperature_C, time_s, velocity; other headers via --map) or an "
                                              "instrument export (see --input-format).",
                                              show_default=False, metavar="DATA.csv")]


@app.command()
def measure(
    data: DataArgument,
    drive: Annotated[Path | None, typer.Option(
        "--drive", "-d", help="Drive spec (TOML): default orders are its shafts and meshes, labelled.",
        show_default=False)] = None,
    orders: Annotated[str | None, typer.Option(
        "--orders", help="Orders to fit [cycles per output revolution], comma-separated, e.g. 1,8,240 "
        "(default: the drive's physical orders with --drive, else 1,2,3,4).", show_default=False)] = None,
    harmonics: Annotated[int, typer.Option(
        "--harmonics", help="With --drive: harmonics of each shaft/mesh order to include.", min=1,
        max=10)] = 3,
    column_map: MapOption = None,
    error_unit: ErrorUnitOption = None,
    angle_unit: AngleUnitOption = None,
    input_format: InputFormatOption = "auto",
    format: FormatOption = "table",
    unit: UnitOption = "arcsec",
    output: OutputOption = None,
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Also draw the ISO 230-2 deviation chart to FILE (.png, .svg or .pdf; needs the "
        "'plot' extra).", show_default=False)] = None,
):
    """ISO 230-2 figures and order amplitudes of a rotary-table measurement.

    Per target and direction the mean deviation and standard deviation;
    the axis accuracy A, reversal B (max |B_i| and mean), systematic
    deviation E, mean bidirectional deviation M and repeatability R; and
    the amplitude and phase at exact orders by least squares on all rows,
    split into the common mode (mean of the directions) and the
    differential mode (half the reversal).  The span covered is reported;
    orders longer than a partial span are 'beyond span'.  Spreadsheet
    exports (';' or tab, decimal commas, other headers) are read with
    --map and the unit options.  CSV output is the per-target table.

    Example: wormgear measure test.csv --drive configs/mch50.toml --format json

    Example: wormgear measure export.csv --map angle_deg="Position (deg)" --map error_arcsec=Deviation
    """
    from wormgear_cli.workflows.measure import measure as run
    from wormgear_cli.workflows.measure import parse_orders, report

    unit = getattr(unit, "value", unit)
    fmt = getattr(format, "value", format)
    inputs = [data] + ([drive] if drive is not None else [])
    if plot is not None:
        from wormgear_cli.plots import check_plot_path

        check_plot_path(plot)
        from wormgear_cli.files import refuse_input, refuse_same_outputs

        refuse_input(plot, inputs, "--plot")
        refuse_same_outputs([(output, "-o"), (plot, "--plot")])
    options = read_options(column_map, error_unit, angle_unit, input_format)
    order_list = parse_orders(orders) if orders is not None else None
    result = run(data, options, drive, order_list, harmonics)
    few = len(result.figures.targets) <= MAX_TABLE_TARGETS
    doc = report(result, unit, per_target=fmt != "table" or few)
    for w in doc["warnings"]:
        typer.echo(f"warning: {w}", err=True)

    if plot is not None:
        from wormgear_cli.plots.measure import deviation_chart

        deviation_chart(result.figures, result.measurement, unit, plot, title=Path(data).name)
        announce_written(plot)
    if fmt == "json":
        emit(_json(doc), output, inputs)
    elif fmt == "csv":
        typer.echo(f"note: {doc['verdict']}", err=True)
        for note in doc["notes"]:
            typer.echo(f"note: {note}", err=True)
        cols = [c if c in PLAIN_COLUMNS else f"{c}_{unit}" for c in TARGET_COLUMNS]
        emit(csv_text(cols, ([t[c] for c in TARGET_COLUMNS] for t in doc["per_target"])), output, inputs)
    else:
        render(_tables(doc, len(result.figures.targets)), output, inputs)


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


def _tables(doc: dict, ntargets: int) -> list:
    """The table view: verdict line, ISO 230-2 figures, orders (common, then differential), per target, notes.

    Every table fits 80 columns without cutting a number: numbers never wrap
    (no_wrap), labels and long words fold, and wide tables are split."""
    from rich import box
    from rich.markup import escape
    from rich.table import Table
    from rich.text import Text

    unit = doc["unit"]

    def a(x) -> str:
        return "-" if x is None or not math.isfinite(x) else fmt_angle(x, unit)

    def table(title: str) -> Table:
        return Table(title=escape(title), title_justify="left", box=box.SIMPLE_HEAD, pad_edge=False,
                     padding=(0, 1))

    def num(t: Table, name: str) -> None:
        t.add_column(name, justify="right", no_wrap=True)

    out = [Text(doc["verdict"]), _figures_table(doc, table, num)]

    od = doc["orders"]
    cov = doc["coverage"]

    def ph(x):
        return "-" if x is None else f"{x:.1f}"

    def status(it):
        s = it["status"]
        if it["aliased_with"]:
            s += " ~ " + ("offset" if 0 in it["aliased_with"] else ", ".join(f"{k:g}" for k in it["aliased_with"]))
        return s

    has_diff = any(it["differential"]["amplitude"] is not None for it in od["items"])
    ot = table(f"orders, common mode (mean of directions) [{unit}, phase deg]")
    num(ot, "order")
    ot.add_column("shaft / mesh", overflow="fold", ratio=1)
    for col in ("amplitude", "+/-", "phase"):
        num(ot, col)
    ot.add_column("status", overflow="fold")
    for it in od["items"]:
        c = it["common"]
        ot.add_row(f"{it['order']:g}", escape(it["label"] or ""),
                   a(c["amplitude"]) if c["amplitude"] is not None else "-",
                   a(c["amplitude_stderr"]) if c["amplitude"] is not None else "-", ph(c["phase_deg"]),
                   escape(status(it)))
    span = "full turn" if cov["full_turn"] else f"span {cov['span_deg']:.4g} deg, trend degree {cov['trend_degree']}"
    ot.caption = escape(f"error ~ offset + A sin(k theta + phase) per order; {span}. Residual RMS "
                        f"{a(od['residual_rms'])}, common offset {a(od['common_offset'])}")
    ot.caption_justify = "left"
    out.append(ot)
    if has_diff:
        dt = table(f"differential mode (half the reversal) [{unit}, phase deg]")
        num(dt, "order")
        for col in ("amplitude", "+/-", "phase"):
            num(dt, col)
        for it in od["items"]:
            d = it["differential"]
            if d["amplitude"] is None:
                continue
            dt.add_row(f"{it['order']:g}", a(d["amplitude"]), a(d["amplitude_stderr"]), ph(d["phase_deg"]))
        dt.caption = escape(f"differential offset {a(od['differential_offset'])}")
        dt.caption_justify = "left"
        out.append(dt)

    rows = doc["per_target"]
    if ntargets <= MAX_TABLE_TARGETS:
        tt = table(f"per target by direction [{unit}; target deg]")
        for col in ("target", "n fwd", "mean fwd", "s fwd", "n rev", "mean rev", "s rev"):
            num(tt, col)
        for r in rows:
            fwd, rev = _below(r)
            tt.add_row(f"{r['target_deg']:.4f}", str(r["n_forward"]), a(r["mean_forward"]),
                       BELOW if fwd else a(r["s_forward"]), str(r["n_reverse"]), a(r["mean_reverse"]),
                       BELOW if rev else a(r["s_reverse"]))
        out.append(tt)
        bt = table(f"per target bidirectional [{unit}; target deg]")
        for col in ("target", "mean bi", "B_i", "R fwd", "R rev", "R_i"):
            num(bt, col)
        for r in rows:
            fwd, rev = _below(r)
            bt.add_row(f"{r['target_deg']:.4f}", a(r["mean_bidirectional"]), a(r["reversal"]),
                       BELOW if fwd else a(r["R_forward"]), BELOW if rev else a(r["R_reverse"]),
                       BELOW if fwd and rev else a(r["R"]))
        out.append(bt)
    else:
        out.append(Text(f"{ntargets} targets: the per-target table is in --format csv or json"))
    for w in doc["warnings"]:
        out.append(Text(f"warning: {w}"))
    for note in doc["notes"]:
        out.append(Text(f"note: {note}"))
    return out


def _below(row: dict) -> tuple[bool, bool]:
    """Whether the forward and the reverse readings of a per-target row are all equal."""
    b = row.get("below_resolution")
    return b in ("forward", "both"), b in ("reverse", "both")


def _figures_table(doc: dict, table, num):
    """The ISO 230-2 figures: n/a where not applicable, '<1 step' where below the resolution of the data."""
    unit = doc["unit"]
    iso = doc["iso230_2"]
    below = set((doc.get("resolution") or {}).get("below", ()))
    fig_keys = ("A", "A_forward", "A_reverse", "E", "E_forward", "E_reverse", "R", "R_forward", "R_reverse", "M", "B",
                "B_signed", "B_mean")
    missing = any(iso[k] is None and k not in below for k in fig_keys)
    st = table(f"ISO 230-2 figures [{unit}]" + (" (n/a: see notes)" if missing else ""))
    st.add_column("figure", overflow="fold")
    for col in ("bidirectional", "forward", "reverse"):
        num(st, col)

    def na(key: str) -> str:
        x = iso[key]
        return BELOW if key in below else "n/a" if x is None else fmt_angle(x, unit)

    st.add_row("accuracy A", na("A"), na("A_forward"), na("A_reverse"))
    st.add_row("systematic deviation E", na("E"), na("E_forward"), na("E_reverse"))
    st.add_row("repeatability R", na("R"), na("R_forward"), na("R_reverse"))
    st.add_row("mean bidirectional deviation M", na("M"), "", "")
    st.add_row("reversal B = max |B_i|", na("B"), "", "")
    st.add_row("  largest B_i, signed", na("B_signed"), "", "")
    st.add_row("mean reversal B_mean", na("B_mean"), "", "")
    return st
