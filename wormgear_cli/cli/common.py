"""What every command shares: output options, writing results, rendering.

One set of options (``--format``, ``--unit``, ``-o``) defined once, as
sqlite-utils does.  rich is imported only when a table is drawn.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import sys
from enum import Enum
from pathlib import Path
from typing import Annotated, Iterable, Optional

import typer


class TableFormat(str, Enum):
    table = "table"
    json = "json"
    csv = "csv"


class TableJsonFormat(str, Enum):
    table = "table"
    json = "json"


class TextJsonFormat(str, Enum):
    text = "text"
    json = "json"


class CsvJsonFormat(str, Enum):
    csv = "csv"
    json = "json"


class AngleUnit(str, Enum):
    deg = "deg"
    arcmin = "arcmin"
    arcsec = "arcsec"
    urad = "urad"


FormatOption = Annotated[TableFormat, typer.Option("--format", "-f", help="Output format.", case_sensitive=False)]
UnitOption = Annotated[AngleUnit, typer.Option("--unit", "-u", help="Unit of the angular errors in the "
                                               "output (positions such as target angles stay in deg).",
                                               case_sensitive=False)]
def _check_output(value: Optional[Path]) -> Optional[Path]:
    """-o: a directory or a missing folder is the project's one-line error, before any work."""
    from wormgear_cli.io import check_output_path

    check_output_path(value, "-o")
    return value


OutputOption = Annotated[Optional[Path], typer.Option("--output", "-o", help="Write the result to FILE "
                                                      "(atomically) instead of stdout; - is stdout.",
                                                      callback=_check_output)]
DriveArgument = Annotated[Path, typer.Argument(help="Drive spec (TOML).", show_default=False)]


def emit(text: str, output: Optional[Path], inputs: Iterable = ()) -> None:
    """Send a result to stdout (``output`` None or ``-``), or atomically to ``output``."""
    from wormgear_cli.io import atomic_write, write_stdout

    if output is None or str(output) == "-":
        write_stdout(text)  # checked and completed: a full disk is exit 2, a closed pipe a quiet stop
        return

    atomic_write(output, text, tuple(inputs))


def json_text(doc) -> str:
    """Deterministic JSON (key order as built, shortest round-trip floats)."""
    return json.dumps(_clean(doc), indent=2, allow_nan=False) + "\n"


def _clean(obj):
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if hasattr(obj, "item") and not isinstance(obj, (str, bytes)):
        return _clean(obj.item())
    return obj


def fmt_number(x) -> str:
    """CSV number: shortest repr that round-trips; integers as integers; None (undefined) empty."""
    if x is None:
        return ""
    if isinstance(x, bool):
        return str(int(x))
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if not math.isfinite(x):
            return ""
        return repr(x)
    if hasattr(x, "item"):
        return fmt_number(x.item())
    return str(x)


def csv_text(columns: list[str], rows: Iterable[Iterable], header: bool = True) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    if header:
        w.writerow(columns)
    for row in rows:
        w.writerow([fmt_number(v) for v in row])
    return buf.getvalue()


def text_width() -> int:
    """Width for tables written to a file or a pipe: $COLUMNS when it is a sane
    number (40..1000), else 100."""
    try:
        width = int(os.environ.get("COLUMNS", "100"))
    except ValueError:
        return 100
    return width if 40 <= width <= 1000 else 100


def render(renderables: list, output: Optional[Path], inputs: Iterable = ()) -> None:
    """Draw rich renderables to stdout (colour only on a terminal without
    NO_COLOR) or, as plain text, to ``output``."""
    from rich.console import Console

    if output is None and sys.stdout.isatty():
        console = Console(no_color="NO_COLOR" in os.environ, highlight=False,
                          width=text_width() if "COLUMNS" in os.environ else None)
        for r in renderables:
            console.print(r)
        return
    buf = io.StringIO()
    console = Console(file=buf, width=text_width(), no_color=True, color_system=None,
                      highlight=False, force_terminal=False, soft_wrap=False)
    for r in renderables:
        console.print(r)
    text = "\n".join(line.rstrip() for line in buf.getvalue().splitlines()) + "\n"  # no padding spaces
    emit(text, output, inputs)


def stderr_is_terminal() -> bool:
    return sys.stderr.isatty()


def fmt_angle(x: float, unit: str) -> str:
    """Angle for tables: 4 significant digits beyond the unit's natural scale."""
    if unit == "deg":
        return f"{x:.5f}"
    if unit == "arcmin":
        return f"{x:.3f}"
    if unit == "arcsec":
        return f"{x:.2f}"
    return f"{x:.1f}"
