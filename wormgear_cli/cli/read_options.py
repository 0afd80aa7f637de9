"""Options for reading a measurement file, shared by ``measure`` and ``diagnose``.

Use in a command::

    def measure(data: DataArgument, column_map: MapOption = None, error_unit: ErrorUnitOption = None,
                angle_unit: AngleUnitOption = None, ...):
        options = read_options(column_map, error_unit, angle_unit)
        m = read_measurement(data, options=options)
"""

from __future__ import annotations

from enum import Enum
from typing import Annotated

import typer


class ErrorUnit(str, Enum):
    arcsec = "arcsec"
    arcmin = "arcmin"
    deg = "deg"
    urad = "urad"


class InputAngleUnit(str, Enum):
    deg = "deg"
    rad = "rad"


MapOption = Annotated[list[str] | None, typer.Option(
    "--map", help="Column of the file to read as a canonical column, CANONICAL=HEADER (repeatable), e.g. "
    "--map angle_deg=Position --map error_arcsec=Deviation. Canonical names: angle_deg, error_arcsec, "
    "direction, run, load_Nm, temperature_C, time_s; actual_deg (an actual position: the error is actual - "
    "angle_deg) and velocity (its sign gives the direction).", show_default=False)]
ErrorUnitOption = Annotated[ErrorUnit | None, typer.Option(
    "--error-unit", help="Unit of the error column (default: the unit in its header, e.g. 'error (arcmin)', "
    "else arcsec).", case_sensitive=False, show_default=False)]
AngleUnitOption = Annotated[InputAngleUnit | None, typer.Option(
    "--angle-unit", help="Unit of the angle column (default: the unit in its header, else deg).",
    case_sensitive=False, show_default=False)]


def _format_help() -> str:
    from wormgear_cli.measurement.readers import FORMATS

    return ("Format of the data file: auto (detected from its content) or one of "
            + ", ".join(f"{f.name} ({f.title})" for f in FORMATS) + ".")


InputFormatOption = Annotated[str, typer.Option(
    "--input-format", help=_format_help(), show_default=True, metavar="NAME")]


def read_options(column_map: list[str] | None, error_unit=None, angle_unit=None, input_format: str = "auto"):
    """:class:`~wormgear_cli.measurement.reader.ReadOptions` from the option values; UsageError (one line
    per bad ``--map``) otherwise.  (The measurement module is imported here, not at start-up.)"""
    from wormgear_cli.errors import UsageError
    from wormgear_cli.measurement.reader import ReadOptions

    pairs = []
    problems = []
    for item in column_map or ():
        canon, sep, header = item.partition("=")
        if not sep or not canon.strip() or not header.strip():
            problems.append(f"--map {item}: expected CANONICAL=HEADER, e.g. --map angle_deg=Position")
            continue
        pairs.append((canon.strip(), header.strip()))
    if problems:
        raise UsageError(problems)
    if input_format != "auto":
        from wormgear_cli.measurement.readers import find_format

        find_format(input_format)
    return ReadOptions(column_map=tuple(pairs), error_unit=getattr(error_unit, "value", error_unit),
                       angle_unit=getattr(angle_unit, "value", angle_unit),
                       input_format=None if input_format == "auto" else input_format)


def check_rows_memory(data, bytes_per_row: int, command: str) -> None:
    """Refuse, before it is parsed, a measurement file whose rows the machine cannot hold: its
    line ends are counted in one fast pass (a regular file; a pipe is bounded by the size limit
    alone) and priced at ``bytes_per_row`` (:func:`wormgear_cli.files.check_memory`)."""
    from wormgear_cli.errors import quote
    from wormgear_cli.files import check_memory, count_lines
    from wormgear_cli.measurement.reader import MAX_FILE_BYTES

    rows = count_lines(data, MAX_FILE_BYTES)
    if rows:
        check_memory(rows * bytes_per_row, f"{command}: {quote(data)} ({rows:,} lines)",
                     "split the recording (by run or by time) and read the parts one by one")
