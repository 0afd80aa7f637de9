"""``wormgear merge``: join the parts of a sharded ``sweep`` or ``tolerance`` run."""

from __future__ import annotations

from enum import Enum
from pathlib import Path
from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    JobsOption,
    OutputOption,
    Progress,
    emit,
    emit_stream,
    jobs_count,
    json_text,
    output_format,
    render,
)
from wormgear_cli.cli.helptext import HelpCommand
from wormgear_cli.errors import UsageError


class MergeFormat(str, Enum):
    table = "table"
    json = "json"
    csv = "csv"


@app.command(cls=HelpCommand)
def merge(
    parts: Annotated[list[Path], typer.Argument(help="The parts (each written with --shard K/N -o FILE, its "
                                                "manifest beside it), in any order.", show_default=False,
                                                metavar="PART...")],
    drive: Annotated[Path | None, typer.Option(
        "--drive", help="The drive spec the parts were computed with (default: the path their manifests "
        "name; checked by its SHA-256).", show_default=False)] = None,
    format: Annotated[MergeFormat | None, typer.Option(
        "--format", "-f", help="tolerance: the report (table, default, or json) or the samples (csv); sweep: "
        "csv (the joined CSV).", case_sensitive=False, show_default=False)] = None,
    target_yield: Annotated[float | None, typer.Option(
        "--target-yield", help="tolerance: yield to aim at (as tolerance --target-yield; default: [requirements] "
        "min_yield).", show_default=False)] = None,
    jobs: JobsOption = 1,
    output: OutputOption = None,
):
    """Join the parts of a sharded run into the output of the unsharded run, byte for byte.

    Every part of the run must be given once, unchanged since it was written; missing,
    duplicate, changed or mismatched parts (another drive, seed, grid or version) exit 2,
    one line each.  sweep: CSV parts give the whole CSV.  tolerance: CSV or NPY parts give
    the report (or, with --format csv, the samples CSV) of the unsharded run.

    Example: wormgear merge part1.npy part2.npy part3.npy part4.npy --format json -o report.json
    """
    from wormgear_cli.workflows import merge as work  # lazy: keeps workflows.merge off `--help`'s start-up

    fmt = output_format(format, output)
    got = work.parts_of(parts)
    inputs = [Path(p["path"]) for p in got]
    if got[0]["command"] == "sweep":
        if fmt not in (None, "csv"):
            raise UsageError(f"--format {fmt}: sweep parts join into their CSV; use --format csv")
        if target_yield is not None:
            raise UsageError("--target-yield applies to tolerance parts only")
        emit_stream(work.joined_csv(got), output, inputs)
        return
    drive = drive if drive is not None else Path(got[0]["drive"])
    work.check_drive(drive, got)
    _tolerance(got, drive, fmt or "table", target_yield, jobs_count(jobs), output, inputs + [drive])


def _tolerance(parts, drive, fmt, target_yield, jobs, output, inputs) -> None:
    # lazy: the tolerance command's modules, loaded only when tolerance parts are merged
    from wormgear_cli.cli.tolerance import _tables, allocation_seconds
    from wormgear_cli.spec.loader import load_spec
    from wormgear_cli.tolerance import engine, report, study
    from wormgear_cli.workflows import merge as work

    if target_yield is not None and not 0.0 < target_yield < 1.0:
        raise UsageError(f"--target-yield: expected a number in (0, 1), got {target_yield:g}")
    spec = load_spec(drive)
    s = work.tolerance_setup(spec, parts, jobs)
    if fmt == "csv":
        if all(p["parameters"]["format"] == "csv" for p in parts):
            emit_stream(work.joined_csv(parts), output, inputs)
        else:
            header = report.csv_header(s)
            emit_stream((header if b is None else report.csv_rows(s, b)
                    for b in (None, *work.tolerance_blocks(s, parts))), output, inputs)
        return
    summary = work.tolerance_summary(s, parts)
    target = target_yield if target_yield is not None else spec.requirements.min_yield
    runs = engine.allocation_runs(s, target, s.options.samples)
    with Progress(runs[1] if runs else 0, allocation_seconds(spec, runs), "allocation") as bar:
        doc = study.finish(s, summary, target_yield, s.options.samples, None, bar.advance)
    if fmt == "json":
        emit(json_text(doc), output, inputs)
    else:
        render(_tables(doc, target), output, inputs)
