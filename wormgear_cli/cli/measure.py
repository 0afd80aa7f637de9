"""``wormgear measure``: ISO 230-2 figures and order amplitudes of a measurement."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    AngleUnit,
    FormatOption,
    OutputOption,
    TableFormat,
    UnitOption,
    announce_written,
    count_type,
    csv_text,
    emit_stream,
    fmt_angle,
    json_text,
    output_format,
    output_path_type,
    render,
    say,
)
from wormgear_cli.cli.helptext import HelpCommand
from wormgear_cli.cli.read_options import (
    AngleUnitOption,
    DecDegOption,
    ErrorUnitOption,
    GuideRateOption,
    InputFormatOption,
    MapOption,
    PixelScaleOption,
    SessionOption,
    check_rows_memory,
    read_options,
)
from wormgear_cli.errors import UsageError
from wormgear_cli.files import check_outputs

#: peak memory per row of a measurement file in ``measure`` (reading, figures, orders, the output; about
#: 90 bytes a row on 13e6 short rows and 200 on a dense scan of 2e6 rows, bench/bench_memory.py) [bytes]
MEASURE_BYTES_PER_ROW = 300

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


@app.command(cls=HelpCommand)
def measure(
    data: DataArgument,
    drive: Annotated[Path | None, typer.Option(
        "--drive", "-d", help="Drive spec (TOML): default orders are its shafts and meshes, labelled.",
        show_default=False)] = None,
    orders: Annotated[str | None, typer.Option(
        "--orders", help="Orders to fit [cycles per output revolution], comma-separated, e.g. 1,8,240 "
        "(default: the drive's physical orders with --drive, else 1,2,3,4).", show_default=False)] = None,
    harmonics: Annotated[int, typer.Option(
        "--harmonics", help="With --drive: harmonics of each shaft/mesh order to include.",
        click_type=count_type(1, 10))] = 3,
    column_map: MapOption = None,
    error_unit: ErrorUnitOption = None,
    angle_unit: AngleUnitOption = None,
    input_format: InputFormatOption = "auto",
    session: SessionOption = None,
    pixel_scale: PixelScaleOption = None,
    dec_deg: DecDegOption = None,
    guide_rate: GuideRateOption = None,
    format: FormatOption = TableFormat.table,
    unit: UnitOption = AngleUnit.arcsec,
    output: OutputOption = None,
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Also draw the ISO 230-2 deviation chart to FILE (.png, .svg or .pdf; needs "
        "matplotlib).", show_default=False, click_type=output_path_type("--plot", "plot.png"))] = None,
):
    """ISO 230-2 figures and order amplitudes of a rotary-table measurement.

    Per target and direction the mean deviation and standard deviation;
    the axis accuracy A, reversal B (max |B_i| and mean), systematic
    deviation E, mean bidirectional deviation M and repeatability R; and
    the amplitude and phase at exact orders by least squares on all rows,
    split into the common mode (mean of the directions) and the
    differential mode (half the reversal); orders too close for the span
    to separate are one 'ambiguous' group.  The strongest orders of the
    data, scanned up to the Nyquist limit of the spacing, are reported too.
    The span covered is reported; over a partial arc the slow part is a
    trend (or, over an arc traversed repeatedly, a drift in time) and orders
    too slow for the arc are 'beyond span'.  Spreadsheet
    exports (';' or tab, decimal commas, other headers) are read with
    --map and the unit options.  CSV output is the per-target table.

    Example: wormgear measure test.csv --drive configs/mch50.toml --format json

    Example: wormgear measure export.csv --map angle_deg="Position (deg)" --map error_arcsec=Deviation
    """
    # lazy: keeps workflows.measure off `--help`'s start-up
    from wormgear_cli.workflows.measure import measure as run
    from wormgear_cli.workflows.measure import parse_orders, report, target_row_blocks

    _check_roles(data, drive)
    unit = getattr(unit, "value", unit)
    fmt = output_format(format, output)
    inputs = [data] + ([drive] if drive is not None else [])

    check_outputs([(output, "-o"), (plot, "--plot")], inputs)  # before any work, not when a result is written
    if plot is not None:
        from wormgear_cli.plots import check_plot_path  # lazy: keeps plots off `--help`'s start-up

        check_plot_path(plot)
    options = read_options(column_map, error_unit, angle_unit, input_format, session, pixel_scale, dec_deg, guide_rate)
    check_rows_memory(data, MEASURE_BYTES_PER_ROW, "measure")
    order_list = parse_orders(orders) if orders is not None else None
    result = run(data, options, drive, order_list, harmonics)
    ntargets = 0 if result.figures is None else len(result.figures.targets)  # a guide log has no targets
    few = ntargets <= MAX_TABLE_TARGETS
    # the per-target part of json and csv is streamed a block of targets at a time (a dense scan has a
    # target a row); the table shows it only for a few targets
    doc = report(result, unit, per_target=fmt == "table" and few)
    for w in doc["warnings"]:
        say(f"warning: {w}")

    if plot is not None:
        _plot(result, unit, plot, Path(data).name)
        announce_written(plot)
    if fmt == "json":
        blocks = target_row_blocks(result.figures.targets, unit) if result.figures is not None else iter(())
        emit_stream(json_chunks(doc, blocks), output, inputs)
    elif fmt == "csv":
        say(f"note: {doc['verdict']}")
        for note in doc["notes"]:
            say(f"note: {note}")
        if result.figures is None:
            # lazy: keeps cli.measure_guide off `--help`'s start-up
            from wormgear_cli.cli.measure_guide import frames_csv

            emit_stream([frames_csv(result, unit)], output, inputs)
            return
        emit_stream(_csv_chunks(target_row_blocks(result.figures.targets, unit), unit), output, inputs)
    else:
        render(_tables(doc, ntargets), output, inputs)


def _plot(result, unit: str, plot: Path, title: str) -> None:
    """The deviation chart (ISO 230-2), or a guide log's periodic-error chart."""
    if result.figures is None:
        # lazy: keeps plots.guidelog off `--help`'s start-up
        from wormgear_cli.plots.guidelog import periodic_error_chart

        periodic_error_chart(result.measurement, result.guide, unit, plot, title=title)
        return
    from wormgear_cli.plots.measure import deviation_chart  # lazy: keeps plots.measure off `--help`'s start-up

    deviation_chart(result.figures, result.measurement, unit, plot, title=title)


def _check_roles(data: Path, drive: Path | None) -> None:
    """A drive spec given as DATA.csv (alone, or swapped with --drive's measurement) is a usage
    error that says where each file goes, before any parser sees it."""
    from wormgear_cli.spec.filekind import kind_of_file  # lazy: keeps spec.filekind off `--help`'s start-up

    if kind_of_file(data) != "drive":
        return
    if drive is None:
        raise UsageError(f"{data} is a drive spec, not a measurement; measure reads a measurement CSV and takes "
                         f"the drive as --drive: wormgear measure DATA.csv --drive {data}")
    if kind_of_file(drive) == "table":
        raise UsageError(f"the files look swapped: {data} is a drive spec and {drive} a measurement; "
                         f"wormgear measure {drive} --drive {data}")


def json_chunks(doc: dict, blocks):
    """``json_text`` of the document, in pieces, with its per-target list (``blocks``: lists of rows,
    concatenated; ``doc``'s own list is not read) written last, one compact object per line (fast and
    readable for 100 000 targets), a block at a time: the same text as the whole list at once."""
    head = {k: v for k, v in doc.items() if k != "per_target"}
    head["per_target"] = []  # the list goes last (after the notes): a reader finds the figures first
    text = json_text(head)
    marker = '"per_target": []'
    assert text.count(marker) == 1
    at = text.index(marker)
    first = True
    for rows in blocks:
        if not rows:
            continue
        # one C-encoder pass a block; the rows hold only numbers (NaN for undefined), so "}, {" only
        # occurs between rows and "NaN" only stands for an undefined value
        flat = json.dumps(rows, allow_nan=True, separators=(", ", ": ")).replace("NaN", "null")
        yield (text[:at] + '"per_target": [\n') if first else ",\n"
        first = False
        yield "    " + flat[1:-1].replace("}, {", "},\n    {")
    yield text if first else "\n  ]" + text[at + len(marker):]


def _csv_chunks(blocks, unit: str):
    """The per-target CSV (header, then a row a target) in pieces, a block of targets at a time."""
    cols = [c if c in PLAIN_COLUMNS else f"{c}_{unit}" for c in TARGET_COLUMNS]
    header = True
    for rows in blocks:
        yield csv_text(cols, ([t[c] for c in TARGET_COLUMNS] for t in rows), header=header)
        header = False
    if header:
        yield csv_text(cols, [])


def _tables(doc: dict, ntargets: int) -> list:
    """The table view: verdict line, ISO 230-2 figures, orders (common, then differential), the strongest
    orders of the data, per target, notes.

    Every table fits 80 columns without cutting a number: numbers never wrap
    (no_wrap), labels and long words fold, and wide tables are split."""
    from rich.text import Text  # lazy: keeps rich.text off `--help`'s start-up

    view = _View(doc["unit"])
    out = [Text(doc["verdict"])]
    if doc["iso230_2"] is not None:
        out.append(_iso_table(doc, view))
    else:  # a guide log: its periodic error first
        # lazy: keeps cli.measure_guide off `--help`'s start-up
        from wormgear_cli.cli.measure_guide import periodic_error_tables

        out += periodic_error_tables(doc, view)
    if doc["orders"]["items"]:
        out += _order_tables(doc, view)
    dom = _dominant_table(doc, view)
    if dom is not None:
        out.append(dom)
    if doc["iso230_2"] is not None:
        out += _target_tables(doc, ntargets, view)
    for w in doc["warnings"]:
        out.append(Text(f"warning: {w}"))
    for note in doc["notes"]:
        out.append(Text(f"note: {note}"))
    return out


class _View:
    """Formatting shared by the tables of one document (angles in ``unit``)."""

    def __init__(self, unit: str):
        self.unit = unit

    def a(self, x) -> str:
        return "-" if x is None or not math.isfinite(x) else fmt_angle(x, self.unit)

    def na(self, x) -> str:
        return "n/a" if x is None else fmt_angle(x, self.unit)

    @staticmethod
    def table(title: str):
        # lazy: keeps rich.box, rich.markup, rich.table off `--help`'s start-up
        from rich import box
        from rich.markup import escape
        from rich.table import Table

        return Table(title=escape(title), title_justify="left", box=box.SIMPLE_HEAD, pad_edge=False, padding=(0, 1))

    @staticmethod
    def num(t, name: str) -> None:
        t.add_column(name, justify="right", no_wrap=True)



def _iso_table(doc: dict, view: _View):
    """The ISO 230-2 figures: n/a where not applicable, '<1 step' where below the resolution of the data."""
    iso, unit = doc["iso230_2"], view.unit
    below = set((doc.get("resolution") or {}).get("below", ()))
    fig_keys = ("A", "A_forward", "A_reverse", "E", "E_forward", "E_reverse", "R", "R_forward", "R_reverse", "M", "B",
                "B_signed", "B_mean")
    missing = any(iso[k] is None and k not in below for k in fig_keys)
    st = view.table(f"ISO 230-2 figures [{unit}]" + (" (n/a: see notes)" if missing else ""))
    st.add_column("figure", overflow="fold")
    for col in ("bidirectional", "forward", "reverse"):
        view.num(st, col)

    def na(key: str) -> str:
        return BELOW if key in below else view.na(iso[key])

    st.add_row("accuracy A", na("A"), na("A_forward"), na("A_reverse"))
    st.add_row("systematic deviation E", na("E"), na("E_forward"), na("E_reverse"))
    st.add_row("repeatability R", na("R"), na("R_forward"), na("R_reverse"))
    st.add_row("mean bidirectional deviation M", na("M"), "", "")
    st.add_row("reversal B = max |B_i|", na("B"), "", "")
    st.add_row("  largest B_i, signed", na("B_signed"), "", "")
    st.add_row("mean reversal B_mean", na("B_mean"), "", "")
    return st


def _status_text(it: dict) -> str:
    s = it["status"]
    if it["aliased_with"]:
        s += " ~ " + ("offset" if 0 in it["aliased_with"] else ", ".join(f"{k:g}" for k in it["aliased_with"]))
    if s == "ambiguous" and it["group"]:
        others = ", ".join(f"{k:g}" for k in it["group"] if k != it["order"])
        s += (f": one group with {others}" if it["common"]["amplitude"] is not None else f" ~ {others}")
    return s


def _order_tables(doc: dict, view: _View) -> list:
    from rich.markup import escape  # lazy: keeps rich.markup off `--help`'s start-up

    unit, a = view.unit, view.a
    od, cov = doc["orders"], doc["coverage"]

    def ph(x):
        return "-" if x is None else f"{x:.1f}"

    has_diff = any(it["differential"]["amplitude"] is not None for it in od["items"])
    ot = view.table(f"orders, common mode (mean of directions) [{unit}, phase deg]")
    view.num(ot, "order")
    ot.add_column("shaft / mesh", overflow="fold", ratio=1)
    for col in ("amplitude", "+/-", "phase"):
        view.num(ot, col)
    ot.add_column("status", overflow="fold")
    for it in od["items"]:
        c = it["common"]
        ot.add_row(f"{it['order']:g}", escape(it["label"] or ""),
                   a(c["amplitude"]) if c["amplitude"] is not None else "-",
                   a(c["amplitude_stderr"]) if c["amplitude"] is not None else "-", ph(c["phase_deg"]),
                   escape(_status_text(it)))
    span = "full turn" if cov["full_turn"] else f"span {cov['span_deg']:.4g} deg, trend degree {cov['trend_degree']}"
    ot.caption = escape(f"error ~ offset + A sin(k theta + phase) per order; {span}. Residual RMS "
                        f"{a(od['residual_rms'])}, common offset {a(od['common_offset'])}")
    ot.caption_justify = "left"
    out = [ot]
    if has_diff:
        dt = view.table(f"differential mode (half the reversal) [{unit}, phase deg]")
        view.num(dt, "order")
        for col in ("amplitude", "+/-", "phase"):
            view.num(dt, col)
        for it in od["items"]:
            d = it["differential"]
            if d["amplitude"] is None:
                continue
            dt.add_row(f"{it['order']:g}", a(d["amplitude"]), a(d["amplitude_stderr"]), ph(d["phase_deg"]))
        dt.caption = escape(f"differential offset {a(od['differential_offset'])}")
        dt.caption_justify = "left"
        out.append(dt)
    return out


def _dominant_table(doc: dict, view: _View):
    """The strongest orders of the data, or None when nothing was scanned."""
    from rich.markup import escape  # lazy: keeps rich.markup off `--help`'s start-up

    dom = doc.get("dominant")
    if not dom or not dom["peaks"]:
        return None
    a = view.a
    lo, hi = dom["scanned_orders"]
    tt = view.table(f"strongest orders of the data [{view.unit}] (orders {lo:.4g} to {hi:.4g} scanned)")
    view.num(tt, "order")
    for col in ("amplitude", "+/-"):
        view.num(tt, col)
    timed = any(p["period_s"] is not None for p in dom["peaks"])
    diff = any(p["differential"] is not None for p in dom["peaks"])
    if diff:
        view.num(tt, "diff.")
    if timed:
        view.num(tt, "period s")
    tt.add_column("cannot be told from", overflow="fold")
    tt.add_column("p adj.", justify="right", no_wrap=True)
    for p in dom["peaks"]:
        g_lo, g_hi = p["group"]
        group = "-" if g_hi - g_lo < 1e-9 else f"{g_lo:.5g} to {g_hi:.5g}"
        if p["label"]:
            group = f"{group} ({p['label']})" if group != "-" else p["label"]
        cells = [f"{p['order']:.6g}", a(p["amplitude"]), a(p["amplitude_stderr"])]
        if diff:
            cells.append(a(p["differential"]))
        if timed:
            cells.append("-" if p["period_s"] is None else f"{p['period_s']:.5g}")
        cells += [escape(group), f"{p['p_adjusted']:.2g}" + ("" if p["significant"] else " (n.s.)")]
        tt.add_row(*cells)
    head = "amplitude: common mode; diff.: half the reversal; " if diff else ""
    tt.caption = escape(f"{head}{dom['method']}; residual RMS {a(dom['residual_rms'])}")
    tt.caption_justify = "left"
    return tt


def _target_tables(doc: dict, ntargets: int, view: _View) -> list:
    from rich.text import Text  # lazy: keeps rich.text off `--help`'s start-up

    unit, a = view.unit, view.a
    rows = doc["per_target"]
    if ntargets > MAX_TABLE_TARGETS:
        return [Text(f"{ntargets} targets: the per-target table is in --format csv or json")]
    tt = view.table(f"per target by direction [{unit}; target deg]")
    for col in ("target", "n fwd", "mean fwd", "s fwd", "n rev", "mean rev", "s rev"):
        view.num(tt, col)
    for r in rows:
        fwd, rev = _below(r)
        tt.add_row(f"{r['target_deg']:.4f}", str(r["n_forward"]), a(r["mean_forward"]),
                   BELOW if fwd else a(r["s_forward"]), str(r["n_reverse"]), a(r["mean_reverse"]),
                   BELOW if rev else a(r["s_reverse"]))
    bt = view.table(f"per target bidirectional [{unit}; target deg]")
    for col in ("target", "mean bi", "B_i", "R fwd", "R rev", "R_i"):
        view.num(bt, col)
    for r in rows:
        fwd, rev = _below(r)
        bt.add_row(f"{r['target_deg']:.4f}", a(r["mean_bidirectional"]), a(r["reversal"]),
                   BELOW if fwd else a(r["R_forward"]), BELOW if rev else a(r["R_reverse"]),
                   BELOW if fwd and rev else a(r["R"]))
    return [tt, bt]


def _below(row: dict) -> tuple[bool, bool]:
    """Whether the forward and the reverse readings of a per-target row are all equal."""
    b = row.get("below_resolution")
    return b in ("forward", "both"), b in ("reverse", "both")
