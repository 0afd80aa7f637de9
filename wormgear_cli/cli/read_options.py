"""Options for reading a measurement file, shared by ``measure`` and ``diagnose``.

Use in a command::

    def measure(data: DataArgument, column_map: MapOption = None, error_unit: ErrorUnitOption = None,
                angle_unit: AngleUnitOption = None, ..., session: SessionOption = None, ...):
        options = read_options(column_map, error_unit, angle_unit, input_format, session, pixel_scale,
                               dec_deg, guide_rate)
        m = read_measurement(data, options=options)
"""

from __future__ import annotations

from enum import Enum
from typing import Annotated

import typer

from wormgear_cli.errors import UsageError, quote
from wormgear_cli.files import check_memory, count_lines
from wormgear_cli.measurement.readers import FORMATS, find_format


class ErrorUnit(str, Enum):
    arcsec = "arcsec"
    arcmin = "arcmin"
    deg = "deg"
    urad = "urad"
    mrad = "mrad"
    rad = "rad"


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
    return ("Format of the data file: auto (detected from its content) or one of "
            + ", ".join(f"{f.name} ({f.title})" for f in FORMATS) + ".")


InputFormatOption = Annotated[str, typer.Option(
    "--input-format", help=_format_help(), show_default=True, metavar="NAME")]


SessionOption = Annotated[list[str] | None, typer.Option(
    "--session", metavar="N", help="PHD2 guide log: read only session N (1 for the first 'Guiding Begins'; "
    "repeatable, or a list such as 2,3 or 5-7). Default: every session, each a run.", show_default=False)]
PixelScaleOption = Annotated[float | None, typer.Option(
    "--pixel-scale", metavar="ARCSEC_PER_PX", help="PHD2 guide log: the guide camera's pixel scale [arcsec/px] "
    "(206.265 x pixel size [um] x binning / focal length [mm]); wins over the log's.", show_default=False)]
DecDegOption = Annotated[float | None, typer.Option(
    "--dec-deg", metavar="DEG", help="PHD2 guide log: the declination guided on [deg]; wins over the log's.",
    show_default=False)]
GuideRateOption = Annotated[float | None, typer.Option(
    "--guide-rate", metavar="ARCSEC_PER_S", help="PHD2 guide log: the RA guide rate [arcsec/s at the equator, "
    "e.g. 7.52 for 0.5x sidereal]; wins over the log's calibration.", show_default=False)]


def parse_sessions(items: list[str] | None) -> tuple[int, ...]:
    """``--session`` values (each a number, a comma list or a range A-B) as session numbers; UsageError
    naming the item otherwise."""
    out: list[int] = []
    for item in items or ():
        for part in str(item).split(","):
            lo, dash, hi = part.strip().partition("-")
            try:
                first, last = int(lo), int(hi) if dash else int(lo)
            except ValueError:
                raise UsageError(f"--session {item}: expected a session number (1 for the first), a list such as "
                                 "2,3 or a range such as 5-7") from None
            if first < 1 or last < first:
                raise UsageError(f"--session {item}: expected session numbers from 1 up, a range low-high")
            out += [k for k in range(first, last + 1) if k not in out]
    return tuple(out)


def read_options(column_map: list[str] | None, error_unit=None, angle_unit=None, input_format: str = "auto",
                 session: list[str] | None = None, pixel_scale: float | None = None, dec_deg: float | None = None,
                 guide_rate: float | None = None):
    """:class:`~wormgear_cli.measurement.reader.ReadOptions` from the option values; UsageError (one line
    per bad ``--map``, or naming the guide-log option) otherwise.  (The measurement module is imported
    here, not at start-up.)"""
    # lazy: keeps measurement.guidelog_options, measurement.reader off `--help`'s start-up
    from wormgear_cli.measurement.guidelog_options import GuideLogOptions
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
        find_format(input_format)
    return ReadOptions(column_map=tuple(pairs), error_unit=getattr(error_unit, "value", error_unit),
                       angle_unit=getattr(angle_unit, "value", angle_unit),
                       input_format=None if input_format == "auto" else input_format,
                       guidelog=GuideLogOptions(parse_sessions(session), pixel_scale, dec_deg, guide_rate))


def check_rows_memory(data, bytes_per_row: int, command: str) -> None:
    """Refuse, before it is parsed, a measurement file whose rows the machine cannot hold: its
    line ends are counted in one fast pass (a regular file; a pipe is bounded by the size limit
    alone) and priced at ``bytes_per_row`` (:func:`wormgear_cli.files.check_memory`)."""
    from wormgear_cli.measurement.reader import MAX_FILE_BYTES  # lazy: keeps measurement.reader off `--help`'s start-up

    rows = count_lines(data, MAX_FILE_BYTES)
    if rows:
        check_memory(rows * bytes_per_row, f"{command}: {quote(data)} ({rows:,} lines)",
                     "split the recording (by run or by time) and read the parts one by one")
