"""``wormgear compare``: drives side by side, with their differences to the first."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    AngleUnit,
    FormatOption,
    OutputOption,
    Progress,
    TableFormat,
    UnitOption,
    count_type,
    csv_text,
    emit,
    fmt_angle,
    json_text,
    load_drive,
    output_format,
    render,
)
from wormgear_cli.cli.helptext import HelpCommand
from wormgear_cli.errors import UsageError

#: seconds per sampled drive of the yield (paper and budget metrics), for the progress bar
_SECONDS_PER_SAMPLE = 3.5e-6


@app.command(cls=HelpCommand)
def compare(
    drives: Annotated[list[Path], typer.Argument(help="Two or more drive specs (TOML); the first is the "
                                                 "baseline of the differences.", show_default=False,
                                                 metavar="DRIVE.toml...")],
    samples: Annotated[int | None, typer.Option(
        "--samples", "-n", help="Also estimate the yield of built drives against each drive's own "
        "[requirements] limits from N samples each (e.g. 20000 or 1e5), as tolerance does.",
        show_default=False, click_type=count_type(1, 10**8))] = None,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the yield's samples (same seed, same output).",
                                      min=0)] = 0,
    format: FormatOption = TableFormat.table,
    unit: UnitOption = AngleUnit.arcsec,
    output: OutputOption = None,
):
    """Drives side by side: totals, error budget and yield, and each one's difference to the first.

    For each drive the paper's total TE and backlash, the full budget's TE
    totals (linear, statistical, peak) and every budget line at the output, as
    analyze computes them; with --samples the yield of each [requirements]
    limit and of all together, as tolerance estimates it.  Differences are
    each drive minus the first (yields in percentage points).

    Example: wormgear compare configs/mch50.toml configs/rotary-table-precision.toml --samples 2e4
    """
    # lazy: keeps workflows.compare off `--help`'s start-up
    from wormgear_cli.workflows.compare import MIN_DRIVES, Options, compare, csv_rows

    fmt = output_format(format, output)
    unit = getattr(unit, "value", unit)
    if len(drives) < MIN_DRIVES:
        raise UsageError(f"compare needs at least {MIN_DRIVES} drive specs, got {len(drives)}: "
                         f"wormgear compare A.toml B.toml")
    specs = [load_drive(d) for d in drives]
    options = Options(unit=unit, samples=samples, seed=seed)
    total = (samples or 0) * len(specs)
    with Progress(total, total * _SECONDS_PER_SAMPLE, "yield") as bar:
        doc = compare(specs, [str(d) for d in drives], options, bar.advance)
    if fmt == "json":
        emit(json_text(doc), output, drives)
    elif fmt == "csv":
        emit(csv_text(*csv_rows(doc)), output, drives)
    else:
        render(_tables(doc), output, drives)


def _letters(n: int) -> list[str]:
    return [chr(ord("A") + k) if k < 26 else f"D{k + 1}" for k in range(n)]


def _tables(doc: dict) -> list:
    """The table view: which drive is which, then totals, budget lines and yields with differences
    (:class:`~wormgear_cli.output.tables.Table`)."""
    from rich.markup import escape  # lazy: keeps rich.markup off `--help`'s start-up

    from wormgear_cli.output.tables import Column, Table  # lazy: keeps output.tables off `--help`'s start-up

    unit = doc["unit"]
    names = _letters(len(doc["drives"]))
    out: list = [escape(f"{n} = {d['file']} ({d['drive']})") for n, d in zip(names, doc["drives"])]

    def angle(x):
        return "-" if x is None else fmt_angle(x, unit)

    def diff(x):
        return "-" if x is None else ("+" if x > 0 else "") + fmt_angle(x, unit)

    def table(title: str, first: str, rows, value, difference) -> Table:
        t = Table(title, [Column(first), *(Column(n, "right") for n in names),
                          *(Column(f"{n} - {names[0]}", "right") for n in names[1:])], box="simple_head")
        for label, q in rows:
            t.add_row(label, *(value(v) for v in q["values"]), *(difference(d) for d in q["differences"][1:]))
        return t

    out.append(table(f"totals at the output [{unit}]", "quantity", ((q["label"], q) for q in doc["totals"].values()),
                     angle, diff))
    out.append(table(f"error budget by source, amplitude at the output [{unit}]", "source",
                     doc["budget"].items(), angle, diff))
    y = doc["yield"]
    if y is not None:
        def pct(x):
            return "n/a" if x is None else f"{100 * x:.2f} %"

        def pp(x):
            return "-" if x is None else f"{100 * x:+.2f} pp"

        rows = ((("all limits" if k == "all" else k.replace("requirements.", "")), q)
                for k, q in y["requirements"].items())
        out.append(table(f"yield against each drive's own limits ({y['samples']} samples, seed {y['seed']})",
                         "requirement", rows, pct, pp))
        out.append("n/a: the drive has no such limit; pp: percentage points")
    out.append(escape(f"differences: each drive minus {names[0]}; the paper's totals and the budget as analyze "
                      "computes them"))
    return out
