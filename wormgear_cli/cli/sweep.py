"""``wormgear sweep``: the gear-ratio / centre-distance response surface and any-parameter grids.

Thin layer: parse the options, check the size policy (:mod:`wormgear_cli.analysis.sweep`), run the
core and draw its outputs (:mod:`wormgear_cli.output.sweep`); ``--plot`` draws the map.
"""

from __future__ import annotations

from enum import Enum
from pathlib import Path
from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    AngleUnit,
    DriveArgument,
    FormatOption,
    JobsOption,
    OutputOption,
    PartOutput,
    Progress,
    ShardOption,
    TableFormat,
    UnitOption,
    announce_written,
    count_type,
    emit,
    is_stdout,
    jobs_count,
    json_text,
    load_drive,
    output_file,
    output_format,
    output_path_type,
    render,
    say,
    shard_part,
    warn_if_absurd,
)
from wormgear_cli.cli.helptext import HelpCommand
from wormgear_cli.files import atomic_stream, check_memory, refuse_same_outputs
from wormgear_cli.output.formats import csv_text

#: estimated seconds per point, for deciding whether to show a progress bar
_SECONDS_PER_RL_POINT = 3e-6
#: peak memory per grid point of an (i, l) run that holds its grid (the size policy's figures,
#: :mod:`wormgear_cli.analysis.sweep_limits`); CSV on stdout is streamed (constant) [bytes]
_BYTES_PER_POINT = {"table": 160, "json": 3000, "csv": 115, "plot": 160}
_SECONDS_PER_PARAM_POINT = 5e-3
_FIGURES_HELP = ("With --module-mm: add each design's sign-off figures (the budget's totals, the ISO 230-2 A, E, B, "
                 "M on the [test_plan]) as columns, as analyze --format csv prints them; about 50 ms a design.")


class HoldMode(str, Enum):
    force = "force"
    torque = "torque"


@app.command(cls=HelpCommand)
def sweep(
    drive: DriveArgument,
    i: Annotated[str | None, typer.Option("--i", metavar="START:STOP:N",
                                             help="Gear ratio i = R2/R1 = z1/z2: N values from START to STOP "
                                                  "(default: the spec's ratio).", show_default=False)] = None,
    l_mm: Annotated[str | None, typer.Option("--l-mm", metavar="START:STOP:N",
                                                help="Centre distance l = R1 + R2 [mm]: N values from START to "
                                                     "STOP (default: the spec's).", show_default=False)] = None,
    param: Annotated[list[str] | None, typer.Option(
        "--param", metavar="KEY=START:STOP:N",
        help="Sweep a numeric spec key (TOML path, the key's unit; a stage's key as stage.N.KEY), e.g. "
             "worm_pair.lead_error_mm=0:0.05:11 or stage.2.lead_error_mm=0:0.05:11. "
             "Repeatable: the grid spans all of them (first key outermost), at most 100000 points. Every "
             "analyze metric is a column. Not for effects.* keys; not combinable with --i/--l-mm.",
        show_default=False)] = None,
    stage: Annotated[int | None, typer.Option(
        "--stage", metavar="N", help="The spur stage --i/--l-mm vary: its position from the motor (1 = the "
                                     "first stage; default: the drive's last spur stage).",
        show_default=False, min=1)] = None,
    hold: Annotated[HoldMode | None, typer.Option(
        "--hold", help="What stays fixed as i and l change: the normal tooth forces (force, default) or "
                       "the output torque (torque).", case_sensitive=False, show_default=False)] = None,
    module_mm: Annotated[float | None, typer.Option(
        "--module-mm", help="Snap every point to whole tooth counts at this module [mm], 0.05 to 100; adds "
                            "columns z1, z2, i_used, l_used_mm.", show_default=False)] = None,
    min_pinion_teeth: Annotated[int | None, typer.Option(
        "--min-pinion-teeth", help="With --module-mm: skip designs whose smaller gear has fewer teeth "
                                   "(default: undercut limit 2/sin^2(alpha), 17 at 20 deg).",
        show_default=False, click_type=count_type())] = None,
    figures: Annotated[bool, typer.Option("--figures", help=_FIGURES_HELP)] = False,
    shard: ShardOption = None,
    jobs: JobsOption = 1,
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Also draw the response surface with line cuts (.png/.svg/.pdf; needs "
                       "matplotlib).", show_default=False, click_type=output_path_type("--plot", "plot.png"))] = None,
    format: FormatOption = TableFormat.table,
    unit: UnitOption = AngleUnit.arcsec,
    output: OutputOption = None,
):
    """Gear TE, total TE and total backlash over a grid of gear ratio i and centre distance l.

    The paper's design study (its Figure 1): for every (i, l), a spur stage (--stage N, default
    the drive's last spur stage) gets R1 = l/(1+i) and R2 = l i/(1+i), all other inputs from the
    drive spec; the gear TE is the exact maximum over the pinion angle.  CSV columns start with
    i, l_mm, gear_transmission_error, total_transmission_error, total_backlash.  The table shows
    heat maps and checks the paper's three findings on the grid.  --param sweeps any numeric
    spec key instead (a stage's as stage.N.KEY), with every analyze metric as a column.

    Example: wormgear sweep configs/mch50.toml --i 2:10:9 --l-mm 100:300:11 --unit arcsec
    """
    # lazy: keeps analysis.sweep, analysis.sweep_limits, plots off `--help`'s start-up
    from wormgear_cli.analysis import sweep as core
    from wormgear_cli.analysis import sweep_limits as limits
    from wormgear_cli.plots import check_plot_path

    fmt = output_format(format, output)
    unit = getattr(unit, "value", unit)
    params = list(param or [])
    limits.check_options(params=params, i=i, l_mm=l_mm, module_mm=module_mm, hold=hold, min_teeth=min_pinion_teeth,
                         shard=shard, fmt=fmt, plot=plot is not None, stage=stage, figures=figures)
    if plot is not None:
        check_plot_path(plot)

        refuse_same_outputs([(output, "-o"), (plot, "--plot")])
    part = shard_part(shard)
    k_n = (part.k, part.n) if part is not None else None
    jobs = jobs_count(jobs)
    if params:
        _param_command(drive, params, fmt, unit, output, part, k_n, plot, jobs)
        return
    # sizes first: nothing is built, loaded or printed before the grid is known to be feasible
    i_range = core.parse_range_spec(i, "--i", positive=True) if i is not None else None
    l_range = core.parse_range_spec(l_mm, "--l-mm", positive=True) if l_mm is not None else None
    if module_mm is not None:
        core.check_module(module_mm)
    n_i, n_l = (i_range.n if i_range is not None else 1), (l_range.n if l_range is not None else 1)
    limits.check_ratio_distance_size(n_i, n_l, fmt, plot is not None, k_n, figures)
    _check_memory(n_i * n_l, k_n, fmt, plot is not None)
    if plot is not None:
        # lazy: keeps plots.sweep off `--help`'s start-up
        from wormgear_cli.plots.sweep import check_ratio_distance_plot

        check_ratio_distance_plot(n_i, n_l)
        _require_matplotlib()
    total = n_i * n_l
    start, stop = core.shard_bounds(total, *k_n) if k_n else (0, total)
    spec = load_drive(drive)
    st = core.spur_stage(spec, stage)  # a drive without a spur stage: exit 2 before anything is written
    parameters = {"i": _range_key(i_range), "l_mm": _range_key(l_range), "hold": getattr(hold, "value", hold),
                  "module_mm": module_mm, "min_pinion_teeth": min_pinion_teeth, "format": fmt, "unit": unit}
    if stage is not None:
        parameters["stage"] = st.index
    parameters.update({"figures": True} if figures else {})  # a part's manifest: the old runs' stay the same
    out = PartOutput("sweep", drive, output, part, parameters, start, stop, total)
    if out.done():
        return
    sw = core.ratio_distance_sweep(spec, i_range, l_range, hold=getattr(hold, "value", hold),
                                   module=module_mm, min_teeth=min_pinion_teeth, stage=st.index, figures=figures)
    _ratio_distance_sweep(sw, drive, fmt, unit, out, plot, k_n, jobs)


def _param_command(drive: Path, params: list[str], fmt: str, unit: str, output, part, k_n, plot, jobs: int) -> None:
    """sweep --param: the grid of spec keys, sized and checked before anything is built."""
    # lazy: keeps analysis.sweep, analysis.sweep_limits off `--help`'s start-up
    from wormgear_cli.analysis import sweep as core
    from wormgear_cli.analysis import sweep_limits as limits

    spec = load_drive(drive)  # the keys are the drive's (stage.N.KEY by its stages' kinds)
    axes = [core.parse_param(p, spec) for p in params]
    limits.check_param_size(axes, fmt, k_n)
    if plot is not None:
        from wormgear_cli.plots.sweep import check_param_plot  # lazy: keeps plots.sweep off `--help`'s start-up

        check_param_plot([len(ax.values) for ax in axes])
        _require_matplotlib()
    total = core.param_size(axes)
    start, stop = core.shard_bounds(total, *k_n) if k_n else (0, total)
    parameters = {"param": [[ax.key, list(ax.values)] for ax in axes], "format": fmt, "unit": unit}
    out = PartOutput("sweep", drive, output, part, parameters, start, stop, total)
    if not out.done():
        _param_sweep(spec, drive, axes, fmt, unit, out, plot, k_n, jobs)


def _range_key(r):
    """A parsed range in a part's manifest (2:10:1e3 and 2:10:1000 are one grid)."""
    return None if r is None else [r.start, r.stop, r.n]


def _check_memory(total: int, k_n, fmt: str, plot: bool) -> None:
    """Refuse, before the grid is built, an (i, l) run that holds more points than the machine can."""
    from wormgear_cli.analysis.sweep import shard_bounds  # lazy: keeps analysis.sweep off `--help`'s start-up

    start, stop = shard_bounds(total, *k_n) if k_n else (0, total)
    streamed = fmt == "csv" and not plot  # to stdout or through a staged file, block by block
    per = max(0 if streamed else _BYTES_PER_POINT[fmt], _BYTES_PER_POINT["plot"] if plot else 0)
    check_memory((stop - start) * per, f"sweep: {stop - start:,} grid points held for --format {fmt}"
                 + (" and --plot" if plot else ""), "use fewer values or --shard K/N")


def _require_matplotlib() -> None:
    """Exit 2 with the install hint now, rather than after the sweep."""
    from wormgear_cli.plots import pyplot  # lazy: keeps plots off `--help`'s start-up

    pyplot()


def _note_skipped(sw, skipped: int, start: int, stop: int) -> None:
    """Say on stderr how many designs --module-mm skipped (the CSV has no row for them): too few teeth,
    and with --figures those the drive file does not hold for (the first one's reason, when known)."""
    if sw.module is None or skipped <= 0:
        return
    teeth = (stop - start) - sw.kept_count(start, stop)
    if teeth:
        say(f"note: {teeth} design{'s' if teeth != 1 else ''} skipped: at m = {sw.module:g} mm the smaller "
            f"gear would have fewer than {sw.min_teeth} teeth (--min-pinion-teeth)")
    invalid = skipped - teeth
    if invalid:
        why = ""
        if sw.first_invalid is not None:
            i, l, z1, z2, problem = sw.first_invalid
            why = f"; the first, i = {i:g}, l = {l:g} mm ({z1}/{z2} teeth): {problem}"
        say(f"note: {invalid} design{'s' if invalid != 1 else ''} skipped by --figures: the drive file does not "
            f"hold for {'them' if invalid != 1 else 'it'} (narrow --i/--l-mm to the designs it does){why}")


def _ratio_distance_sweep(sw, drive, fmt, unit, out: PartOutput, plot, k_n, jobs: int):
    from wormgear_cli.output import sweep as report  # lazy: keeps output.sweep off `--help`'s start-up

    output = out.output
    start, stop = sw.run_bounds(k_n)
    per_point = _SECONDS_PER_PARAM_POINT * 10 if sw.figures else _SECONDS_PER_RL_POINT
    with Progress(stop - start, (stop - start) * per_point, "sweep") as bar:
        if fmt == "csv" and plot is None:
            chunks = report.ratio_distance_csv(sw, start, stop, unit, bar.advance, jobs)
            rows = -1  # the header line
            file = output_file(output)
            if file is None:
                for data in chunks:  # streamed block by block: memory stays constant
                    rows += data.count(b"\n")
                    emit(data, None)
                _note_skipped(sw, stop - start - rows, start, stop)
                return

            with atomic_stream(file, (drive,)) as write:  # streamed to a staged file, renamed at the end
                write_part = out.hash.wrap(write)
                for data in chunks:
                    rows += data.count(b"\n")
                    write_part(data)
            announce_written(file)
            out.finish([drive])
            _note_skipped(sw, stop - start - rows, start, stop)
            return
        data = sw.collect(start, stop, progress=bar.advance, jobs=jobs)
    _note_skipped(sw, stop - start - int(data["_point"].size), start, stop)
    from wormgear_cli.analysis.sweep import ANGLE_COLUMNS  # lazy: keeps analysis.sweep off `--help`'s start-up

    warn_if_absurd({c: data[c] for c in sorted(ANGLE_COLUMNS) if c in data},
                   f"{drive} swept over --i/--l-mm (some grid points)")  # the file itself may be fine
    if fmt == "csv":
        out.emit(report.collected_csv(sw, data, unit), [drive])
    elif fmt == "json":
        out.emit(json_text(report.ratio_distance_json(sw, data, unit, k_n, start, stop)), [drive])
    else:
        render(report.ratio_distance_tables(sw, data, unit), output, [drive])
    if plot is not None:
        from wormgear_cli.plots.sweep import plot_ratio_distance  # lazy: keeps plots.sweep off `--help`'s start-up

        plot_ratio_distance(plot, sw, data, unit)
        announce_written(plot)


def _param_sweep(spec, drive, axes, fmt, unit, out: PartOutput, plot, k_n, jobs: int):
    # lazy: keeps analysis.sweep, output.sweep off `--help`'s start-up
    from wormgear_cli.analysis.sweep import param_size, shard_bounds
    from wormgear_cli.output import sweep as report

    output = out.output
    start, stop = shard_bounds(param_size(axes), *k_n) if k_n else (0, param_size(axes))
    with Progress(stop - start, (stop - start) * _SECONDS_PER_PARAM_POINT, "sweep") as bar:
        if fmt == "csv" and is_stdout(output) and plot is None:
            for text in report.param_csv(spec, axes, start, stop, unit, bar.advance, jobs):  # rows as computed
                emit(text, None)
            return
        rows = list(report.param_table_rows(spec, axes, start, stop, unit, bar.advance, jobs))
    if fmt == "csv":
        out.emit(csv_text(report.param_columns(axes, spec), rows), [drive])
    elif fmt == "json":
        out.emit(json_text(report.param_json(spec, axes, rows, unit, k_n, start, stop)), [drive])
    else:
        render(report.param_tables(spec, axes, rows, unit), output, [drive])
    if plot is not None:
        from wormgear_cli.plots.sweep import plot_params  # lazy: keeps plots.sweep off `--help`'s start-up

        plot_params(plot, spec.drive.name, axes, report.param_columns(axes, spec), rows, unit,
                    report.stage_te_column(spec))
        announce_written(plot)
