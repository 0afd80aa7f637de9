"""``wormgear sweep``: the gear-ratio / centre-distance response surface and any-parameter grids.

Thin layer over :mod:`wormgear_cli.sweep`: parse the options, run the core in blocks, and
write CSV (streamed, numpy-formatted), JSON or a heat-map table; ``--plot`` draws the map.
"""

from __future__ import annotations

import sys
from enum import Enum
from pathlib import Path
from typing import Annotated, Optional

import typer

from wormgear_cli.cli.app import app
from wormgear_cli.cli.common import DriveArgument, FormatOption, OutputOption, UnitOption

#: significant digits of numbers in the (i, l) CSV ('%.12g'; ~1e-12 relative)
CSV_DIGITS = 12
#: most points of one (i, l) run (the whole grid, or this --shard's part), by output; checked
#: from the axes' N before any array is built.  --format table and --plot hold the whole grid
#: as arrays (~160 bytes per point); --format json holds every point as a Python object and
#: its text (~3 KB per point); csv with -o holds the file text for the atomic write (~115
#: bytes per point); csv on stdout is streamed in blocks (memory constant, ~2.5 us per point).
MAX_COLLECTED_POINTS = 2_000_000
MAX_JSON_POINTS = 100_000
MAX_CSV_FILE_POINTS = 2_000_000
MAX_CSV_STREAM_POINTS = 1_000_000_000
#: most points of one --param run with --format json (~9 KB per point: 30 columns); every
#: --param grid is also limited to wormgear_cli.sweep.MAX_PARAM_POINTS points
MAX_PARAM_JSON_POINTS = 50_000
#: estimated seconds per point, for deciding whether to show a progress bar
_SECONDS_PER_RL_POINT = 3e-6
_SECONDS_PER_PARAM_POINT = 5e-3
#: heat-map size shown in the table (rows = i values, columns = l values)
_TABLE_ROWS, _TABLE_COLS = 12, 8
#: rows of the --param table
_TABLE_PARAM_ROWS = 40
#: --param CSV rows written to stdout at a time (about 0.1 s of work)
_CSV_PARAM_BATCH = 100


class HoldMode(str, Enum):
    force = "force"
    torque = "torque"


@app.command()
def sweep(
    drive: DriveArgument,
    i: Annotated[Optional[str], typer.Option("--i", metavar="START:STOP:N",
                                             help="Gear ratio i = R2/R1 = z1/z2: N values from START to STOP "
                                                  "(default: the spec's ratio).", show_default=False)] = None,
    l_mm: Annotated[Optional[str], typer.Option("--l-mm", metavar="START:STOP:N",
                                                help="Centre distance l = R1 + R2 [mm]: N values from START to "
                                                     "STOP (default: the spec's).", show_default=False)] = None,
    param: Annotated[Optional[list[str]], typer.Option(
        "--param", metavar="KEY=START:STOP:N",
        help="Sweep a numeric spec key (TOML path, the key's unit), e.g. worm_pair.lead_error_mm=0:0.05:11. "
             "Repeatable: the grid spans all of them (first key outermost), at most 100000 points. Every "
             "analyze metric is a column. Not for effects.* keys; not combinable with --i/--l-mm.",
        show_default=False)] = None,
    hold: Annotated[Optional[HoldMode], typer.Option(
        "--hold", help="What stays fixed as i and l change: the normal tooth forces (force, default) or "
                       "the output torque (torque).", case_sensitive=False, show_default=False)] = None,
    module_mm: Annotated[Optional[float], typer.Option(
        "--module-mm", help="Snap every point to whole tooth counts at this module [mm], 0.05 to 100; adds "
                            "columns z1, z2, i_used, l_used_mm.", show_default=False)] = None,
    min_pinion_teeth: Annotated[Optional[int], typer.Option(
        "--min-pinion-teeth", help="With --module-mm: skip designs whose smaller gear has fewer teeth "
                                   "(default: undercut limit 2/sin^2(alpha), 17 at 20 deg).",
        show_default=False)] = None,
    shard: Annotated[Optional[str], typer.Option(
        "--shard", metavar="K/N", help="Compute only part K of N contiguous parts of the point list "
                                       "(csv/json); parts concatenate to the full CSV.", show_default=False)] = None,
    plot: Annotated[Optional[Path], typer.Option(
        "--plot", help="Also draw the response surface with line cuts (.png/.svg/.pdf; needs the 'plot' "
                       "extra).", show_default=False)] = None,
    format: FormatOption = "table",
    unit: UnitOption = "arcsec",
    output: OutputOption = None,
):
    """Gear TE, total TE and total backlash over a grid of gear ratio i and centre distance l.

    The paper's design study (its Figure 1): for every (i, l), R1 = l/(1+i) and R2 = l i/(1+i),
    all other inputs from the drive spec; the gear TE is the exact maximum over the pinion
    angle.  CSV columns start with i, l_mm, gear_transmission_error, total_transmission_error,
    total_backlash.  The table shows heat maps and checks the paper's three findings on the
    grid.  --param sweeps any numeric spec key instead, with every analyze metric as a column.

    Example: wormgear sweep configs/mch50.toml --i 2:10:9 --l-mm 100:300:11 --unit arcsec
    """
    from wormgear_cli.errors import UsageError
    from wormgear_cli.plots import check_plot_path

    fmt = getattr(format, "value", format)
    unit = getattr(unit, "value", unit)
    params = list(param or [])
    if params and (i is not None or l_mm is not None or module_mm is not None or hold is not None
                   or min_pinion_teeth is not None):
        raise UsageError("--param cannot be combined with --i, --l-mm, --module-mm, --hold or "
                         "--min-pinion-teeth; run two sweeps")
    if not params and i is None and l_mm is None:
        raise UsageError("nothing to sweep: give --i START:STOP:N and/or --l-mm START:STOP:N, "
                         "or --param KEY=START:STOP:N")
    if min_pinion_teeth is not None and module_mm is None:
        raise UsageError("--min-pinion-teeth applies only with --module-mm")
    if shard is not None and fmt == "table":
        raise UsageError("--shard works with --format csv or json (a table needs the whole grid)")
    if shard is not None and plot is not None:
        raise UsageError("--plot cannot be combined with --shard (a plot needs the whole grid)")
    if plot is not None:
        check_plot_path(plot)
        if output is not None and Path(plot).resolve() == Path(output).resolve():
            raise UsageError(f"{plot}: --plot and -o name the same file")

    from wormgear_cli import sweep as core

    k_n = core.parse_shard(shard) if shard is not None else None
    if params:
        axes = [core.parse_param(p) for p in params]
        core.check_param_axes(axes)
        total = core.param_size(axes)
        start, stop = core.shard_bounds(total, *k_n) if k_n else (0, total)
        if fmt == "json" and stop - start > MAX_PARAM_JSON_POINTS:
            counts = " x ".join(str(len(ax.values)) for ax in axes)
            raise UsageError(f"--param: {counts} = {total} points" + (f" ({stop - start} in this shard)" if k_n else "")
                             + f" are more than the limit of {MAX_PARAM_JSON_POINTS} for --format json (it holds "
                             "every point as an object); use --format csv or --shard K/N")
        if plot is not None:
            from wormgear_cli.plots.sweep import check_param_plot

            check_param_plot([len(ax.values) for ax in axes])
            _require_matplotlib()
        from wormgear_cli.spec import load_spec

        spec = load_spec(drive)
        _param_sweep(spec, drive, axes, fmt, unit, output, plot, k_n)
        return

    # sizes first: nothing is built, loaded or printed before the grid is known to be feasible
    i_range = core.parse_range_spec(i, "--i", positive=True) if i is not None else None
    l_range = core.parse_range_spec(l_mm, "--l-mm", positive=True) if l_mm is not None else None
    if module_mm is not None:
        core.check_module(module_mm)
    n_i = i_range.n if i_range is not None else 1
    n_l = l_range.n if l_range is not None else 1
    _check_rl_size(n_i, n_l, fmt, plot, output, k_n)
    if plot is not None:
        from wormgear_cli.plots.sweep import check_ratio_distance_plot

        check_ratio_distance_plot(n_i, n_l)
        _require_matplotlib()

    import numpy as np

    from wormgear_cli.spec import load_spec

    spec = load_spec(drive)
    gp = spec.gear_pair
    i_values = i_range.values() if i_range is not None else np.array([gp.output_gear.teeth / gp.pinion.teeth])
    l_values = l_range.values() if l_range is not None else \
        np.array([gp.module * (gp.output_gear.teeth + gp.pinion.teeth) / 2.0])
    sw = core.RatioDistanceSweep(spec, i_values, l_values, hold=(hold.value if hold is not None else "force"),
                                 module=module_mm, min_teeth=min_pinion_teeth)
    _ratio_distance_sweep(sw, drive, fmt, unit, output, plot, k_n)


def _require_matplotlib() -> None:
    """Exit 2 with the install hint now, rather than after the sweep."""
    from wormgear_cli.plots import pyplot

    pyplot()


def _rl_limits(fmt, plot, output) -> list:
    """(limit, what it is for, what to do instead) for an (i, l) run with these outputs."""
    if fmt == "table":
        out = [(MAX_COLLECTED_POINTS, "--format table (it holds the whole grid)",
                "use --format csv or fewer values")]
    elif fmt == "json":
        out = [(MAX_JSON_POINTS, "--format json (it holds every point as an object)",
                "use --format csv, fewer values or --shard K/N")]
    elif output is not None:
        out = [(MAX_CSV_FILE_POINTS, "--format csv with -o (the file is written at once)",
                "write to stdout instead (it is streamed: > FILE) or use --shard K/N")]
    else:
        out = [(MAX_CSV_STREAM_POINTS, "--format csv (about 2.5 us per point)", "split it with --shard K/N")]
    if plot is not None:
        out.append((MAX_COLLECTED_POINTS, "--plot (it holds the whole grid)", "plot a coarser grid"))
    return out


def _check_rl_size(n_i: int, n_l: int, fmt, plot, output, k_n) -> None:
    """Refuse a run whose point count exceeds the limit of its output (see MAX_* above)."""
    from wormgear_cli.errors import UsageError
    from wormgear_cli.sweep import shard_bounds

    total = n_i * n_l
    start, stop = shard_bounds(total, *k_n) if k_n else (0, total)
    points = stop - start
    where = f"--i x --l-mm: {n_i} x {n_l} = {total} points" + (f" ({points} in this shard)" if k_n else "")
    for limit, what, instead in _rl_limits(fmt, plot, output):
        if points > limit:
            raise UsageError(f"{where} are more than the limit of {limit} for {what}; {instead}")
    if fmt == "json" and n_i + n_l > MAX_JSON_POINTS:
        raise UsageError(f"--i x --l-mm: {n_i} + {n_l} grid values are more than the limit of {MAX_JSON_POINTS} "
                         "for --format json (it lists the grid); use --format csv")


# --- progress --------------------------------------------------------------------------------


class _Progress:
    """A rich progress bar on stderr when it is a terminal and the work may take > 1 s."""

    def __init__(self, total: int, seconds: float, label: str):
        from wormgear_cli.cli.common import stderr_is_terminal

        self.bar = None
        if total > 0 and seconds > 1.0 and stderr_is_terminal():
            from rich.console import Console
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeRemainingColumn

            self.bar = Progress("[progress.description]{task.description}", BarColumn(), MofNCompleteColumn(),
                                TimeRemainingColumn(), console=Console(stderr=True), transient=True)
            self.task = self.bar.add_task(label, total=total)

    def __enter__(self):
        if self.bar is not None:
            self.bar.start()
        return self

    def __exit__(self, *exc):
        if self.bar is not None:
            self.bar.stop()

    def advance(self, n: int) -> None:
        if self.bar is not None:
            self.bar.advance(self.task, n)


# --- the (i, l) sweep ------------------------------------------------------------------------


def _ratio_distance_sweep(sw, drive, fmt, unit, output, plot, k_n):
    from wormgear_cli.errors import UsageError
    from wormgear_cli.sweep import shard_bounds

    total = sw.size
    start, stop = shard_bounds(total, *k_n) if k_n else (0, total)
    if sw.module is not None and k_n is None and sw.kept_count() == 0:
        raise UsageError(f"no design left: at --module-mm {sw.module:g} every point of the grid has a gear with "
                         f"fewer than {sw.min_teeth} teeth; raise l, or lower --min-pinion-teeth")
    seconds = (stop - start) * _SECONDS_PER_RL_POINT
    if fmt == "csv" and plot is None:
        with _Progress(stop - start, seconds, "sweep") as bar:
            _stream_csv(sw, start, stop, unit, output, drive, bar.advance)
        return
    with _Progress(stop - start, seconds, "sweep") as bar:
        data = sw.collect(start, stop, progress=bar.advance)
    if fmt == "csv":
        _write_collected_csv(sw, data, unit, output, drive)
    elif fmt == "json":
        from wormgear_cli.cli.common import emit, json_text

        emit(json_text(_rl_json(sw, data, unit, k_n, start, stop)), output, [drive])
    else:
        from wormgear_cli.cli.common import render

        render(_rl_tables(sw, data, unit), output, [drive])
    if plot is not None:
        from wormgear_cli.plots.sweep import plot_ratio_distance

        plot_ratio_distance(plot, sw, data, unit)


def _write_collected_csv(sw, data, unit, output, drive) -> None:
    """CSV of collected points, formatted a block at a time into one buffer (formatting every
    column at once would need ~500 bytes per point; the buffer is freed on return)."""
    import io

    from wormgear_cli.sweep import CHUNK_POINTS

    buf = io.BytesIO()
    buf.write(_csv_header(sw.columns)[0])
    for a in range(0, data["_point"].size, CHUNK_POINTS):
        buf.write(_csv_rows(sw.columns, {c: data[c][a:a + CHUNK_POINTS] for c in sw.columns}, unit))
    _write(buf.getvalue(), output, drive)


def _csv_header(columns) -> list:
    return [(",".join(columns) + "\n").encode()]


def _column_values(name, values, unit):
    from wormgear_cli.sweep import ANGLE_COLUMNS
    from wormgear_cli.units import to_unit

    return to_unit(values, unit) if name in ANGLE_COLUMNS else values


def _csv_rows(columns, block, unit) -> bytes:
    return csv_block([_column_values(c, block[c], unit) for c in columns])


def _formatted_blocks(sw, start, stop, unit, advance):
    """CSV bytes of each block, in order: blocks are computed here and formatted by two worker
    threads (numpy releases the GIL), at most three blocks in flight."""
    from collections import deque
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=2) as pool:
        pending = deque()
        for block in sw.chunks(start, stop, progress=advance):
            pending.append(pool.submit(_csv_rows, sw.columns, block, unit))
            if len(pending) >= 3:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()


def _stream_csv(sw, start, stop, unit, output, drive, advance):
    """CSV of points [start, stop), written block by block (stdout) or atomically (-o)."""
    parts = _csv_header(sw.columns)
    if output is None:
        out = sys.stdout
        out.flush()
        buf = getattr(out, "buffer", None)
        write = buf.write if buf is not None else (lambda b: out.write(b.decode("ascii")))
        write(parts[0])
        for data in _formatted_blocks(sw, start, stop, unit, advance):
            write(data)
        (buf or out).flush()
        return
    import io

    # one growing buffer (getvalue() hands it over without a copy): ~1x the file in memory,
    # where collecting the blocks and joining them would need 2x
    buf = io.BytesIO()
    buf.write(parts[0])
    for data in _formatted_blocks(sw, start, stop, unit, advance):
        buf.write(data)
    _write(buf.getvalue(), output, drive)


def _write(data: bytes, output, drive):
    from wormgear_cli.io import atomic_write

    if output is None:
        sys.stdout.flush()
        buf = getattr(sys.stdout, "buffer", None)
        if buf is not None:
            buf.write(data)
            buf.flush()
        else:
            sys.stdout.write(data.decode("ascii"))
        return
    atomic_write(output, data, (drive,))


def _point_dict(sw, data, k, unit) -> dict:
    from wormgear_cli.sweep import INTEGER_COLUMNS

    out = {}
    for c in sw.columns:
        v = _column_values(c, data[c][k], unit)
        out[c] = int(v) if c in INTEGER_COLUMNS else float(v)
    return out


def _rl_json(sw, data, unit, k_n, start, stop) -> dict:
    from wormgear_cli.sweep import INTEGER_COLUMNS, best_points, findings

    doc = {
        "drive": sw.spec.drive.name,
        "unit": unit,
        "hold": sw.hold,
        "module_mm": sw.module,
        "min_pinion_teeth": sw.min_teeth,
        "grid": {"i": sw.i_values.tolist(), "l_mm": sw.l_values.tolist()},
        "columns": list(sw.columns),
    }
    cols = [(c, _column_values(c, data[c], unit)) for c in sw.columns]
    conv = [(c, (v.astype(int).tolist() if c in INTEGER_COLUMNS else v.tolist())) for c, v in cols]
    n = data["_point"].size
    doc["points"] = [dict(zip(sw.columns, row)) for row in zip(*(v for _, v in conv))] if n else []
    if sw.module is not None:
        doc["skipped"] = int((stop - start) - n)
    if k_n is not None:
        doc["shard"] = {"k": k_n[0], "n": k_n[1], "first_point": start, "stop_point": stop,
                        "total_points": sw.size}
        return doc
    best = best_points(data)
    doc["summary"] = {
        "points": n,
        "best": {key: _point_dict(sw, data, k, unit) for key, k in best.items()},
        "findings_model": "continuous (no tooth snapping)" if sw.module is not None else "as swept",
        "findings": findings(sw),
    }
    return doc


def _subsample(n: int, k: int):
    import numpy as np

    return np.unique(np.linspace(0, n - 1, min(n, k)).round().astype(int))


def _grid2d(sw, data, name):
    """Full (n_i, n_l) array of a column, NaN at skipped points."""
    import numpy as np

    grid = np.full(sw.size, np.nan)
    grid[data["_point"]] = data[name]
    return grid.reshape(sw.i_values.size, sw.l_values.size)


_HEAT_STYLES = ("bold green", "green", "yellow", "dark_orange", "bold red")


def _heat_table(sw, data, name, label, unit, rows, cols):
    import numpy as np
    from rich.table import Table
    from rich.text import Text

    from wormgear_cli.cli.common import fmt_angle
    from wormgear_cli.units import to_unit

    from rich.markup import escape

    grid = to_unit(_grid2d(sw, data, name), unit)[np.ix_(rows, cols)]
    finite = grid[np.isfinite(grid)]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 0.0)
    t = Table(title=escape(f"{label} [{unit}]: rows i, columns l [mm]"), title_justify="left")
    t.add_column("i \\ l", justify="right")
    for c in cols:
        t.add_column(f"{sw.l_values[c]:g}", justify="right")
    for r_pos, r in enumerate(rows):
        cells = []
        for c_pos in range(len(cols)):
            v = grid[r_pos, c_pos]
            if not np.isfinite(v):
                cells.append(Text("-", style="dim"))
                continue
            band = 0 if hi <= lo else min(len(_HEAT_STYLES) - 1, int((v - lo) / (hi - lo) * len(_HEAT_STYLES)))
            cells.append(Text(fmt_angle(float(v), unit), style=_HEAT_STYLES[band]))
        t.add_row(f"{sw.i_values[r]:g}", *cells)
    return t


def _rl_tables(sw, data, unit) -> list:
    from rich.markup import escape
    from rich.table import Table

    from wormgear_cli.cli.common import fmt_angle
    from wormgear_cli.sweep import best_points, findings

    rows = _subsample(sw.i_values.size, _TABLE_ROWS)
    cols = _subsample(sw.l_values.size, _TABLE_COLS)
    hold = "normal forces held" if sw.hold == "force" else "output torque held"
    snap = f", snapped to whole teeth at m = {sw.module:g} mm (min {sw.min_teeth} teeth)" if sw.module else ""
    out = []
    g = _heat_table(sw, data, "gear_transmission_error", f"{sw.spec.drive.name}: gear TE (paper's Delta phi_cc)",
                    unit, rows, cols)
    shown = []
    if rows.size < sw.i_values.size:
        shown.append(f"{rows.size} of {sw.i_values.size} i values")
    if cols.size < sw.l_values.size:
        shown.append(f"{cols.size} of {sw.l_values.size} l values")
    caption = f"{hold}{snap}"
    if shown:
        caption += f"; showing {' and '.join(shown)} (all points: --format csv)"
    if sw.module:
        caption += "; '-' = skipped (too few teeth)"
    g.caption = escape(caption)
    g.caption_justify = "left"
    out.append(g)
    out.append(_heat_table(sw, data, "total_transmission_error", "total TE at the output", unit, rows, cols))
    n = data["_point"].size
    summary = Table(title=f"summary ({n} design{'s' if n != 1 else ''}"
                          + (f", {sw.size - n} skipped" if sw.module else "") + ")", title_justify="left")
    summary.add_column("best by")
    summary.add_column("i", justify="right")
    summary.add_column(escape("l [mm]"), justify="right")
    if sw.module:
        summary.add_column("z1/z2", justify="right")
    for c in ("gear TE", "total TE", "total backlash"):
        summary.add_column(escape(f"{c} [{unit}]"), justify="right")
    from wormgear_cli.units import to_unit

    for key, k in best_points(data).items():
        iv = data["i_used"][k] if sw.module else data["i"][k]
        lv = data["l_used_mm"][k] if sw.module else data["l_mm"][k]
        cells = [{"total_transmission_error": "total TE", "gear_transmission_error": "gear TE"}[key],
                 f"{iv:.4g}", f"{lv:.5g}"]
        if sw.module:
            cells.append(f"{int(data['z1'][k])}/{int(data['z2'][k])}")
        cells += [fmt_angle(float(to_unit(data[c][k], unit)), unit)
                  for c in ("gear_transmission_error", "total_transmission_error", "total_backlash")]
        summary.add_row(*cells)
    out.append(summary)
    f = Table(title="the paper's findings on this grid" + (" (continuous model)" if sw.module else ""),
              title_justify="left", show_header=True)
    f.add_column("check")
    f.add_column("finding", overflow="fold")
    for item in findings(sw):
        mark = {True: "holds", False: "FAILS", None: "n/a"}[item["holds"]]
        f.add_row(mark, escape(item["statement"]))
    out.append(f)
    return out


# --- --param sweeps --------------------------------------------------------------------------


def _param_sweep(spec, drive, axes, fmt, unit, output, plot, k_n):
    from wormgear_cli.analysis import INFO_COLUMNS, METRIC_COLUMNS
    from wormgear_cli.cli.common import csv_text, emit, json_text, render
    from wormgear_cli.sweep import param_rows, param_size, shard_bounds

    total = param_size(axes)
    start, stop = shard_bounds(total, *k_n) if k_n else (0, total)
    keys = [ax.key for ax in axes]
    columns = keys + list(METRIC_COLUMNS) + list(INFO_COLUMNS)

    def computed_rows(bar):
        for values, result in param_rows(spec, axes, start, stop, progress=bar.advance):
            m = result.metrics(unit)
            yield list(values) + [m[c] for c in columns[len(keys):]]

    with _Progress(stop - start, (stop - start) * _SECONDS_PER_PARAM_POINT, "sweep") as bar:
        if fmt == "csv" and output is None and plot is None:
            # stdout: rows are written as they are computed, a batch at a time (no rows held)
            out = sys.stdout
            out.write(csv_text(columns, []))
            batch = []
            for row in computed_rows(bar):
                batch.append(row)
                if len(batch) >= _CSV_PARAM_BATCH:
                    out.write(csv_text(columns, batch, header=False))
                    out.flush()
                    batch = []
            out.write(csv_text(columns, batch, header=False))
            out.flush()
            return
        rows = list(computed_rows(bar))
    if fmt == "csv":
        emit(csv_text(columns, rows), output, [drive])
    elif fmt == "json":
        doc = {"drive": spec.drive.name, "unit": unit,
               "params": [{"key": ax.key, "values": list(ax.values)} for ax in axes],
               "columns": columns, "points": [dict(zip(columns, r)) for r in rows]}
        if k_n is not None:
            doc["shard"] = {"k": k_n[0], "n": k_n[1], "first_point": start, "stop_point": stop,
                            "total_points": total}
        elif rows:
            k = min(range(len(rows)), key=lambda j: rows[j][columns.index("total_transmission_error")])
            doc["summary"] = {"points": len(rows), "best": {"total_transmission_error": dict(zip(columns, rows[k]))}}
        emit(json_text(doc), output, [drive])
    else:
        render(_param_tables(spec, keys, columns, rows, unit), output, [drive])
    if plot is not None:
        from wormgear_cli.plots.sweep import plot_params

        plot_params(plot, spec.drive.name, axes, columns, rows, unit)


def _param_tables(spec, keys, columns, rows, unit) -> list:
    from rich.markup import escape
    from rich.table import Table

    from wormgear_cli.cli.common import fmt_angle

    shown_cols = ("gear_transmission_error", "total_transmission_error", "total_backlash")
    idx = [columns.index(c) for c in shown_cols]
    picks = _subsample(len(rows), _TABLE_PARAM_ROWS) if rows else []
    t = Table(title=escape(f"{spec.drive.name}: sweep of {', '.join(keys)} [{unit}]"), title_justify="left")
    for k in keys:
        t.add_column(escape(k), justify="right")
    for c in ("gear TE", "total TE", "total backlash"):
        t.add_column(c, justify="right")
    for p in picks:
        r = rows[p]
        t.add_row(*(f"{v:g}" for v in r[:len(keys)]), *(fmt_angle(r[j], unit) for j in idx))
    if len(picks) < len(rows):
        t.caption = f"showing {len(picks)} of {len(rows)} points (all points and metrics: --format csv)"
        t.caption_justify = "left"
    out = [t]
    if rows:
        j = columns.index("total_transmission_error")
        k = min(range(len(rows)), key=lambda q: rows[q][j])
        best = ", ".join(f"{key} = {rows[k][n]:g}" for n, key in enumerate(keys))
        b = Table(title="summary", title_justify="left", show_header=False)
        b.add_column("what")
        b.add_column("value")
        b.add_row("points", str(len(rows)))
        b.add_row("lowest total TE", escape(f"{fmt_angle(rows[k][j], unit)} {unit} at {best}"))
        out.append(b)
    return out


# --- fast deterministic number formatting ----------------------------------------------------
#
# CSV of 10^6 rows is mostly number formatting; Python's per-value repr costs ~1 us each.
# These functions produce exactly '%.{digits}g' % v for every value, vectorised: the decimal
# mantissa is one rounded scaling (rows whose scaled mantissa is within the scaling's error of
# a rounding tie are handed to Python, so the result is exact), its digits come from a 4-digit
# lookup table, and each field is laid out in a fixed-width byte matrix whose unused bytes are
# 0 and deleted at the end.


def _tables():
    import numpy as np

    global _DIGITS4, _POW10
    if _DIGITS4 is None:
        _DIGITS4 = np.frombuffer("".join(f"{k:04d}" for k in range(10000)).encode(), dtype=np.uint32).copy()
        _POW10 = np.array([float(f"1e{k}") for k in range(-330, 331)])  # exact decimal -> nearest double
    return _DIGITS4, _POW10


_DIGITS4 = None
_POW10 = None


def format_g(x, digits: int = CSV_DIGITS):
    """'%.{digits}g' % v for every v of ``x`` as an (n, W) uint8 matrix of ASCII bytes, unused
    bytes 0 (NaN gives an empty field).  1 <= digits <= 15."""
    import numpy as np

    p = int(digits)
    if not 1 <= p <= 15:
        raise ValueError("digits must be in 1..15")
    digits4, pow10 = _tables()
    x = np.ascontiguousarray(x, dtype=float).ravel()
    n = x.size
    a = np.abs(x)
    finite = np.isfinite(x)
    zero = a == 0.0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        e = np.floor(np.log10(np.where(finite & ~zero, a, 1.0))).astype(np.int64)
        e = np.clip(e, -320, 320)
        e -= a < pow10[e + 330]
        e += a >= pow10[np.minimum(e + 331, 660)]
        sh = p - 1 - e
        ok = finite & ~zero & (np.abs(e) <= 280)  # the rest (|x| < 1e-280 or > 1e280) by Python
        sh = np.where(ok, sh, 0)
        scaled = np.where(sh >= 0, a * pow10[np.clip(sh, 0, 330) + 330], a / pow10[np.clip(-sh, 0, 330) + 330])
        scaled = np.where(ok, scaled, 0.0)
        rounded = np.rint(scaled)
    # one rounding of the scaling: error < 2^-52 * 10^p; near-ties go to Python (exact)
    ok &= np.abs(scaled - rounded) < 0.5 - 1e-3 * 10.0 ** (p - 12)
    m = np.where(ok, rounded, 0.0).astype(np.int64)
    up = m >= 10 ** p
    m = np.where(up, m // 10, m)
    e = np.where(up, e + 1, e)
    hi, lo = np.divmod(m, 10 ** 8)
    d4 = np.empty((n, 4), np.uint32)
    d4[:, 0] = digits4[hi // 10000]
    d4[:, 1] = digits4[hi % 10000]
    d4[:, 2] = digits4[lo // 10000]
    d4[:, 3] = digits4[lo % 10000]
    raw = d4.view(np.uint8)[:, 16 - p:]  # all p digits
    nz = raw != 48
    k = np.where(m == 0, 1, p - np.argmax(nz[:, ::-1], axis=1))  # significant digits kept
    dig = raw * (np.arange(p)[None, :] < k[:, None])  # trailing zeros -> 0 (deleted)
    width = 1 + max(p + 1, p + 5, p + 7)
    out = np.zeros((n, width), np.uint8)
    out[:, 0] = (np.signbit(x) & finite) * np.uint8(ord("-"))
    dot = np.uint8(ord("."))
    sci = ok & ((e < -4) | (e >= p))
    idx = np.flatnonzero(sci)
    if idx.size:
        sub = np.zeros((idx.size, width), np.uint8)
        ds, ks, es = dig[idx], k[idx], e[idx]
        sub[:, 1] = ds[:, 0]
        sub[:, 2] = (ks > 1) * dot
        sub[:, 3:2 + p] = ds[:, 1:]
        sub[:, 2 + p] = ord("e")
        sub[:, 3 + p] = np.where(es < 0, ord("-"), ord("+"))
        ae = np.abs(es)
        sub[:, 4 + p] = (ae >= 100) * (48 + ae // 100)
        sub[:, 5 + p] = 48 + (ae // 10) % 10
        sub[:, 6 + p] = 48 + ae % 10
        out[idx, 1:] = sub[:, 1:]
    pos = ok & ~sci
    for ev in np.unique(e[pos]):
        sel = pos & (e == ev)
        full = bool(sel.all())
        idx = None if full else np.flatnonzero(sel)
        ds, rs, ks = (dig, raw, k) if full else (dig[idx], raw[idx], k[idx])
        sub = out if full else np.zeros((idx.size, width), np.uint8)
        if ev >= 0:
            ni = int(ev) + 1
            sub[:, 1:1 + ni] = rs[:, :ni]
            sub[:, 1 + ni] = (ks > ni) * dot
            sub[:, 2 + ni:2 + p] = ds[:, ni:]
        else:
            z = -int(ev) - 1
            sub[:, 1] = 48
            sub[:, 2] = dot
            sub[:, 3:3 + z] = 48
            sub[:, 3 + z:3 + z + p] = ds
        if not full:
            out[idx, 1:] = sub[:, 1:]
    out[zero & finite, 1] = 48
    for j in np.flatnonzero(~ok & ~zero):
        v = float(x[j])
        text = b"" if v != v else (b"%.*g" % (p, v))
        out[j, :] = 0
        out[j, :len(text)] = np.frombuffer(text, np.uint8)
    if n:
        used = np.flatnonzero(out.any(axis=0))
        out = out[:, :used[-1] + 1] if used.size else out[:, :1]
        if out.shape[1] > 1 and not out[:, 0].any():
            out = out[:, 1:]
    return out


def csv_block(columns, digits: int = CSV_DIGITS) -> bytes:
    """CSV rows (no header) of equal-length numeric columns, each value '%.{digits}g'."""
    import numpy as np

    fields = [format_g(c, digits) for c in columns]
    n = fields[0].shape[0] if fields else 0
    if n == 0:
        return b""
    width = sum(f.shape[1] + 1 for f in fields)
    rows = np.empty((n, width), np.uint8)
    o = 0
    for j, f in enumerate(fields):
        rows[:, o:o + f.shape[1]] = f
        o += f.shape[1]
        rows[:, o] = ord(",") if j < len(fields) - 1 else ord("\n")
        o += 1
    return rows.tobytes().translate(None, b"\x00")
