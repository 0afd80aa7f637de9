"""``wormgear compensate``: the correction table a controller or a mount loads, and what it will leave."""

from __future__ import annotations

from enum import Enum
from pathlib import Path
from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    AngleUnit,
    OutputOption,
    UnitOption,
    count_type,
    emit,
    output_format,
    output_path_type,
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
    read_options,
)
from wormgear_cli.files import check_outputs
from wormgear_cli.output.formats import json_text
from wormgear_cli.output.writers import WRITERS
from wormgear_cli.units import from_unit

#: the formats and the file name endings that stand for them (from the writer registry)
FORMATS = "|".join(WRITERS)
#: --format's choices: the writer registry's names
CompensateFormat = Enum("CompensateFormat", {name: name for name in WRITERS}, type=str)  # type: ignore[misc]  # (members from the registry: mypy reads literal members only)
_FORMAT_HELP = ("File to write: " + "; ".join(f"{w.name}: {w.summary}" for w in WRITERS.values())
                + ". Default: from the -o file's ending ("
                + ", ".join(f"{' or '.join(w.extensions)} {w.name}" for w in WRITERS.values()) + ").")

DataArgument = Annotated[Path, typer.Argument(
    help="Measurement CSV: an ISO 230-2 test or scan of a rotary axis (angle_deg, error_arcsec, direction, run), "
    "a mount's tracking record (angle: RA axis, error: actual - ideal, time_s), or a PHD2 guide log as it is.",
    show_default=False, metavar="DATA.csv")]


@app.command(cls=HelpCommand)
def compensate(
    data: DataArgument,
    format: Annotated[CompensateFormat | None, typer.Option(
        "--format", "-f", metavar=FORMATS, help=_FORMAT_HELP, case_sensitive=False, show_default=False)] = None,
    output: OutputOption = None,
    drive: Annotated[Path | None, typer.Option(
        "--drive", "-d", help="Drive spec (TOML): of its shafts and meshes, those that stand out of the noise are "
        "fitted; for a mount, its worm gives the worm period.", show_default=False)] = None,
    orders: Annotated[str | None, typer.Option(
        "--orders", help="Orders to fit [cycles per output revolution], comma-separated, e.g. 1,2,9 (default: "
        "the drive's with --drive, else the strongest orders found).", show_default=False)] = None,
    harmonics: Annotated[int | None, typer.Option(
        "--harmonics", help="With --drive: harmonics of each shaft and mesh order; for a mount: harmonics of "
        "the worm order in the PEC curve (default: 3).", show_default=False,
        click_type=count_type(1, 10))] = None,
    points: Annotated[int | None, typer.Option(
        "--points", help="Table points, evenly spaced over --range, both ends included (default: 256 for "
        "linuxcnc, its most; 361 for csv).", show_default=False, click_type=count_type(2))] = None,
    range_deg: Annotated[str | None, typer.Option(
        "--range", metavar="START:END", help="Angles the table spans [deg] (default: 0:360 for data over a "
        "full turn, both ends covered as LinuxCNC holds the end values and does not wrap; the measured arc "
        "rounded out to whole degrees for a partial one).", show_default=False)] = None,
    file_type: Annotated[int | None, typer.Option(
        "--type", help="LinuxCNC COMP_FILE_TYPE: 1 = nominal, correction forward, correction reverse "
        "(correction = -error); 0 = nominal, position reached forward, reverse.  [default: 1]",
        show_default=False)] = None,
    unit: UnitOption = AngleUnit.arcsec,
    max_correction: Annotated[float | None, typer.Option(
        "--max-correction", help="Largest correction allowed, in --unit: a larger one is a warning and exit "
        "code 1 (the file is still written).", show_default=False)] = None,
    worm_period: Annotated[float | None, typer.Option(
        "--worm-period", help="Mount: the worm period [s] (default: from --drive's worm, else the strongest "
        "period in the record).", show_default=False)] = None,
    steps_per_worm: Annotated[int | None, typer.Option(
        "--steps-per-worm", help="Mount: RA motor steps per worm turn, written as !StepsPerWorm and used for "
        "the motor column that phases the curve.", show_default=False, click_type=count_type(1))] = None,
    report_path: Annotated[Path | None, typer.Option(
        "--report", help="Also write what the file is made from and what it will leave as JSON to FILE.",
        show_default=False, click_type=output_path_type("--report", "report.json"))] = None,
    column_map: MapOption = None,
    error_unit: ErrorUnitOption = None,
    angle_unit: AngleUnitOption = None,
    input_format: InputFormatOption = "auto",
    session: SessionOption = None,
    pixel_scale: PixelScaleOption = None,
    dec_deg: DecDegOption = None,
    guide_rate: GuideRateOption = None,
):
    """Correction table for a controller (LinuxCNC, CSV) or PEC curve for a mount (EQMOD).

    Fits the orders (from --orders, the drive's shafts and meshes, or the
    strongest found) per direction and evaluates them at the table's points,
    so the table corrects between the measured targets too; adds per-target
    means where the orders leave a residual above the noise; leaves out
    orders the table spacing cannot carry.  Before anything is loaded it
    says what will be left: the ISO 230-2 E, B and A of a repeat test
    (cross-validated over the runs) or a mount's PE peak-to-peak
    (cross-validated over worm cycles), with the largest orders left.  The
    file goes to -o (or stdout); the summary and how to load the file to
    stderr.

    Example: wormgear compensate test.csv --orders 1,2,9 -o table.comp

    Example: wormgear compensate PHD2_GuideLog.txt --drive mount.toml --steps-per-worm 50133 -o mount.pec
    """
    # lazy: keeps compensation.table, workflows.compensate, workflows.measure off `--help`'s start-up
    from wormgear_cli.compensation.table import parse_range
    from wormgear_cli.workflows.compensate import CompensateOptions, report, summary
    from wormgear_cli.workflows.compensate import compensate as run
    from wormgear_cli.workflows.measure import parse_orders

    unit = getattr(unit, "value", unit)
    fmt = output_format(format, output)
    inputs = [data] + ([drive] if drive is not None else [])

    check_outputs([(output, "-o"), (report_path, "--report")], inputs)  # before any work
    is_file = output is not None and str(output) != "-"
    options = CompensateOptions(
        format=fmt, drive=drive,
        orders=tuple(parse_orders(orders)) if orders is not None else None, harmonics=harmonics, points=points,
        range_deg=parse_range(range_deg) if range_deg is not None else None, file_type=file_type, unit=unit,
        max_correction=from_unit(max_correction, unit) if max_correction is not None else None,
        worm_period_s=worm_period, steps_per_worm=steps_per_worm, output=str(output) if is_file else None)
    result = run(data, options, read_options(column_map, error_unit, angle_unit, input_format, session, pixel_scale,
                                             dec_deg, guide_rate))
    for line in summary(result, unit):
        say(line)
    for w in result.warnings:
        say(f"warning: {w}")
    for n in result.notes:
        say(f"note: {n}")
    emit(result.text, output, inputs)
    if report_path is not None:
        emit(json_text(report(result, unit)), report_path, inputs)
    if result.exceeded:
        raise typer.Exit(1)
