"""What every command shares: output options, writing results, rendering.

One set of options (``--format``, ``--unit``, ``-o``) defined once, as sqlite-utils does.
Every byte a command puts on stdout goes through :func:`write_stdout`; every file it writes
is announced on stderr by :func:`announce_written`.  Text formats (numbers, CSV, JSON,
tables as data) are the core's (:mod:`wormgear_cli.output.formats`); here they are only drawn.
rich is imported only when a table is drawn.

Tables follow one rule (:func:`render`): they fit the width (80 columns at COLUMNS=80)
without cutting a word or a number.  Text wraps at spaces; a table too wide for its
numbers is split into parts that repeat its first column.  Colour and styles (bold,
italic, dim) only on a terminal without NO_COLOR.
"""

from __future__ import annotations

import io
import math
import os
import re
import sys
from collections import Counter
from collections.abc import Iterable
from enum import Enum
from functools import lru_cache
from pathlib import Path
from typing import Annotated, Any

import typer
from typer._click.globals import get_current_context
from typer._click.types import IntParamType, IntRange, ParamType

from wormgear_cli import __version__
from wormgear_cli.errors import UsageError, escape, quote
from wormgear_cli.errors import escape as printable
from wormgear_cli.files import (
    after_commit,
    atomic_stream,
    atomic_write,
    check_output_path,
    descriptor_of,
    names_a_descriptor,
)
from wormgear_cli.files import write_stdout as checked_write
from wormgear_cli.output.formats import csv_text, fmt_angle, fmt_number, json_text  # noqa: F401  (re-exported)
from wormgear_cli.units import RAD_PER_UNIT


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
#: the folder ending of a path's raw text: "/", "/." or "/.." (pathlib drops the first two, so
#: ``-o out/`` and ``-o out/.`` had written a file named ``out``)
_FOLDER_ENDING = re.compile(r"(?<=.)/(\.{0,2}/*)?$")


def output_path_type(option: str, example: str = "result.json") -> ParamType:
    """The click type of every option or argument naming a file to write (-o, --plot, --truth,
    --report, --write-spec, ``new FILE``): a path, refused at once (UsageError, exit 2) when its
    raw text is empty or ends with "/", "/." or "/..", which name a folder.  ``example``: the file name the
    message proposes in that folder."""
    class OutputPath(ParamType):
        name = "path"

        def convert(self, value, param, ctx):
            text = os.fspath(value)
            if not text:  # pathlib reads "" as "." (the current folder)
                raise UsageError(f"{option}: the file name is empty; expected a file name (e.g. {quote(example)})")
            ending = _FOLDER_ENDING.search(text)
            if ending is not None:
                folder = text.rstrip("/").removesuffix("/.") + "/"  # out/. is out/; out/.. is out/../
                raise UsageError(f"{quote(text)}: ends with {ending.group(0)}, which names a folder; expected a "
                                 f"file name for {option} (e.g. {quote(folder + example)})")
            return Path(text)

    return OutputPath()


def _check_output(value: Path | None) -> Path | None:
    """-o: a directory or a missing folder is the project's one-line error, before any work."""
    check_output_path(value, "-o")
    return value


OutputOption = Annotated[Path | None, typer.Option("--output", "-o", help="Write the result to FILE "
                                                      "(atomically) instead of stdout; - is stdout.",
                                                      callback=_check_output, click_type=output_path_type("-o"))]


# --- the format a file name asks for -----------------------------------------------------------

#: file-name suffix -> the format a file of that name holds.  ``-o out.json`` without
#: ``--format`` writes JSON; an explicit ``--format`` that contradicts it is an error.
SUFFIX_FORMATS = {".json": "json", ".csv": "csv", ".npy": "npy"}
#: suffixes of plain text: ``-o report.txt`` without ``--format`` writes the table (or text)
#: format where the command has one, else its default; they never contradict a ``--format``
TEXT_SUFFIXES = (".txt", ".text", ".log")


def _suffix_formats() -> dict[str, str]:
    """File-name suffix -> format: the documents' (.json, .csv, .npy) and the writer registry's
    (.comp, .tbl, .pec: files other programs load)."""
    from wormgear_cli.output.writers import extensions  # lazy: keeps output.writers off `analyze`'s start-up

    return {**extensions(), **SUFFIX_FORMATS}


def _suffix_for(fmt: str) -> str:
    """The file-name suffix of a format: .json, .csv, a writer's own (.comp, .pec), else .txt
    (tables and text)."""
    return next((k for k, v in _suffix_formats().items() if v == fmt), TEXT_SUFFIXES[0])


def _format_param(ctx):
    """(the command's --format parameter, whether the user gave it) in the running command."""
    for param in ctx.command.params:
        if param.name == "format":
            source = ctx.get_parameter_source("format")
            return param, source is not None and source.name not in ("DEFAULT", "DEFAULT_MAP")
    return None, True


def output_format(format, output: Path | None) -> str:
    """The output format of a command: ``--format`` when given, else the one the ``-o`` file's
    name asks for (``.json``, ``.csv``; ``.txt`` the table or text), else the default.

    One rule for every command with ``--format``, decided before any work: a ``.json`` or
    ``.csv`` name holds that format, so ``-o out.json`` with ``--format csv``, or a ``.csv``
    name for a command without CSV, is an error (UsageError, exit 2) naming both.
    """
    fmt = getattr(format, "value", format)
    ctx = get_current_context(silent=True)
    file = output_file(output)
    if ctx is None or file is None:
        return fmt
    param, explicit = _format_param(ctx)
    if param is None:
        return fmt
    choices = [getattr(c, "value", c) for c in getattr(param.type, "choices", ())]
    suffix = Path(file).suffix.lower()
    named = (_suffix_formats() if "table" not in choices and "text" not in choices else SUFFIX_FORMATS).get(suffix)
    command = ctx.command_path
    if named is not None and named != fmt and explicit:
        raise UsageError(f"-o {output}: the file name says {named}, but --format {fmt} was given; drop "
                         f"--format or name the file {_suffix_for(fmt)}")
    if explicit:
        return fmt
    if named is not None:
        if named not in choices:
            names = " or ".join(f"{_suffix_for(c)} ({c})" for c in choices)
            raise UsageError(f"-o {output}: {command} writes {' or '.join(choices)}, not {named}; name the "
                             f"file {names}")
        return named
    if suffix in TEXT_SUFFIXES:
        return next((c for c in ("table", "text") if c in choices), fmt)
    return fmt


# --- counts ------------------------------------------------------------------------------------


def parse_count(text: str) -> int:
    """A whole number as engineers type it: ``100000``, ``100_000``, ``1e5``, ``2.5e3``.

    Raises ValueError (its text says what was expected) for a fraction (``1.5``, ``1e-3``),
    a non-finite value or anything that is not a number."""
    text = str(text).strip()
    try:
        return int(text)
    except ValueError:
        pass
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"expected a whole number (e.g. 100000, 100_000 or 1e5), got {text!r}") from None
    if not math.isfinite(value) or not value.is_integer():
        raise ValueError(f"expected a whole number (e.g. 100000, 100_000 or 1e5), got {text}")
    return int(value)


@lru_cache(maxsize=1)
def _count_types():
    """The click types of counts (built on first use: typer's click is imported with typer)."""
    class _Parse(ParamType):  # (before the integer type in the method order: parses, then hands on)
        def convert(self, value, param, ctx):
            if isinstance(value, str):
                try:
                    value = parse_count(value)
                except ValueError as exc:
                    self.fail(str(exc), param, ctx)
            return super().convert(value, param, ctx)

    class Count(_Parse, IntParamType):
        """An integer option that also takes 1e6 and 1_000_000."""

    class CountRange(_Parse, IntRange):
        """A bounded integer option that also takes 1e6 and 1_000_000."""

    return Count, CountRange


def count_type(min: int | None = None, max: int | None = None):
    """The click type of an integer count option (``--samples``, ``--points``, ``--runs`` ...):
    :func:`parse_count`, within ``[min, max]`` when given (help and messages as click's
    integer types).  Use as ``typer.Option("--samples", click_type=count_type(1))``."""
    count, count_range = _count_types()
    return count() if min is None and max is None else count_range(min=min, max=max)


JobsOption = Annotated[int, typer.Option(
    "--jobs", "-j", metavar="N", click_type=count_type(0),
    help="Worker processes (0: every core). The output is the same, byte for byte, whatever N.")]
ShardOption = Annotated[str | None, typer.Option(
    "--shard", metavar="K/N|auto", help="Compute only part K of N contiguous parts of the run; auto: the part "
    "from a Slurm, Grid Engine or PBS job array (auto:FIRST-LAST[:STEP] gives the array's range). With -o, a "
    "manifest is written beside the part, a complete part is skipped on a re-run, and wormgear merge joins "
    "the parts.", show_default=False)]
DriveArgument = Annotated[Path, typer.Argument(help="Drive spec (TOML).", show_default=False,
                                                               metavar="DRIVE.toml")]


# --- writing ---------------------------------------------------------------------------------


def write_stdout(data: str | bytes) -> None:
    """Write ``data`` (text, or bytes of ASCII/UTF-8 text) to stdout and flush.

    The one place a command's result reaches stdout: :func:`wormgear_cli.files.write_stdout`
    checks and completes every write (a full disk is exit 2, a closed pipe a quiet stop)."""
    checked_write(data)


def is_stdout(output: Path | None) -> bool:
    """True when ``-o`` means stdout: not given, ``-``, or a path naming descriptor 1
    (``/dev/stdout``, ``/proc/self/fd/1``: written exactly like ``-``, streamed where ``-`` is)."""
    if output is None or str(output) == "-":
        return True

    return descriptor_of(output) == 1


def output_file(output: Path | None) -> Path | None:
    """The file ``-o`` names, or None when it means stdout (:func:`is_stdout`)."""
    return None if output is None or is_stdout(output) else output


def announce_written(path: str | Path) -> None:
    """Say on stderr that the command wrote ``path``: ``wrote PATH``.  Every command that
    writes a file (``-o``, ``--plot``, ``--truth``, ...) says so this way, once per file,
    and only once the run's outputs are committed (a failed run claims no file).  A path
    naming a descriptor (``-o /dev/stdout``) is written like ``-``: nothing to announce."""
    if names_a_descriptor(path):
        return
    after_commit(lambda: say(f"wrote {quote(path)}"))


def say(line: str) -> None:
    """One message line on stderr, control characters written out
    (:func:`wormgear_cli.errors.escape`); a stderr that is gone is not an error of its own."""
    try:
        typer.echo(escape(line), err=True)
    except (OSError, ValueError):
        pass


def load_drive(path):
    """Load a drive spec and say its plausibility warnings on stderr, one ``warning:`` line each
    (:mod:`wormgear_cli.spec.plausibility`); an impossible value is the loader's SpecError (exit 2),
    and so is a drive whose own figures no drive can have, beyond a full turn
    (:func:`wormgear_cli.analysis.sanity.check_drive`: every command that evaluates a drive loads
    it here, so they all refuse the same specs)."""
    from wormgear_cli.analysis.sanity import check_drive  # lazy: keeps analysis off `analyze`'s start-up
    from wormgear_cli.spec.loader import load_spec  # lazy: keeps spec.loader off `analyze`'s start-up

    spec = load_spec(path)
    for w in spec.warnings:
        say(f"warning: {w}")
    check_drive(spec, str(path))
    return spec


def warn_if_absurd(angles: dict, source, unit: str = "rad", strict: bool = False) -> None:
    """The guard on every result: angles (name -> value or array, in ``unit``) that are not
    finite stop the run (one error line, exit 2); magnitudes beyond a full turn are one
    warning line, or with ``strict`` (the nominal drive's own figures) an error
    (:func:`wormgear_cli.analysis.sanity.check_angles`)."""
    from wormgear_cli.analysis.sanity import check_angles  # lazy: keeps analysis.sanity off `analyze`'s start-up

    scale = RAD_PER_UNIT[unit]
    warning = check_angles({k: v if scale == 1.0 else _scaled(v, scale) for k, v in angles.items()}, str(source),
                           strict)
    if warning is not None:
        say(f"warning: {warning}")


def _scaled(v, scale: float):
    import numpy as np  # lazy: keeps numpy off `analyze`'s start-up

    return np.asarray(v, dtype=float) * scale


def emit(data: str | bytes, output: Path | None, inputs: Iterable = ()) -> None:
    """Send a result to stdout (``output`` None or ``-``), or atomically to ``output``
    (refusing to overwrite any of ``inputs``) and announce it."""
    file = output_file(output)
    if file is None:
        write_stdout(data)
        return

    atomic_write(file, data, tuple(inputs))
    announce_written(file)


def emit_stream(chunks: Iterable, output: Path | None, inputs: Iterable = ()) -> None:
    """:func:`emit` of a result given in pieces (str or bytes), each written as it comes: to stdout,
    or to a staged file renamed over ``output`` at the end (:func:`wormgear_cli.files.atomic_stream`);
    a big result is never held whole."""
    file = output_file(output)
    if file is None:
        for data in chunks:
            write_stdout(data)
        return

    with atomic_stream(file, tuple(inputs)) as write:
        for data in chunks:
            write(data)
    announce_written(file)


# --- --jobs and --shard ------------------------------------------------------------------


def jobs_count(jobs: int) -> int:
    """``--jobs`` as a number of worker processes (0: every core this process may use)."""
    from wormgear_cli.batch.pool import resolve_jobs  # lazy: keeps batch.pool off `analyze`'s start-up

    return resolve_jobs(jobs)


def shard_part(text: str | None):
    """``--shard`` as a :class:`~wormgear_cli.batch.shards.Part` (None without the option); for
    ``auto`` says on stderr which part it took and from which variables."""
    if text is None:
        return None
    from wormgear_cli.batch import shards  # lazy: keeps batch.shards off `analyze`'s start-up

    part = shards.parse(text, os.environ)
    if part.source:
        typer.echo(f"shard {part.label} (--shard {text}) from {part.source}", err=True)
    return part


class PartOutput:
    """The manifest of a part written with ``--shard`` and ``-o`` (nothing for other runs).

    ``key`` identifies the run (:func:`~wormgear_cli.batch.manifest.run_key`); :meth:`done`
    says on stderr and returns True when the part is already complete (skip the work);
    :meth:`hashing` wraps the output's writes; :meth:`finish` stages the manifest beside the
    output (after it, in the same transaction)."""

    def __init__(self, command: str, drive: Path, output: Path | None, part, parameters: dict, first: int,
                 stop: int, total: int):
        from wormgear_cli.batch import manifest  # lazy: keeps batch.manifest off `analyze`'s start-up

        special = output is not None and Path(output).exists() and not Path(output).is_file()
        file = output_file(output)
        self.active = part is not None and file is not None and not special  # /dev/null: no manifest
        self.output, self.drive = output, drive
        self.file = file if self.active else None  # the part's file, beside which its manifest goes
        self.hash = manifest.Hashing()
        if self.active:
            part_info = {"k": part.k, "n": part.n, "first": int(first), "stop": int(stop), "total": int(total)}
            self.key = manifest.run_key(command, __version__, manifest.file_sha256(drive), parameters, part_info)
            from wormgear_cli.workflows.merge import MERGEABLE  # lazy: keeps workflows.merge off `analyze`'s start-up

            fmt, mergeable = parameters.get("format"), MERGEABLE.get(command, ())
            if fmt not in mergeable:  # said before the part runs, not when the parts are merged
                say(f"warning: {command} parts in {fmt} cannot be joined by wormgear merge; for a run in parts "
                    f"use --format {' or '.join(mergeable)}")

    def done(self) -> bool:
        if self.file is None:  # (not active)
            return False
        from wormgear_cli.batch.manifest import resume_note  # lazy: keeps batch.manifest off `analyze`'s start-up

        note = resume_note(self.file, self.key)
        if note is not None:
            typer.echo(f"part {self.key['part']['k']}/{self.key['part']['n']}: {note}", err=True)
        return note is not None

    def emit(self, data: str | bytes, inputs: Iterable = ()) -> None:
        """:func:`emit` of the whole output, hashed for the manifest, then the manifest."""
        emit(self.hash.add(data) if self.active else data, self.output, inputs)
        self.finish(inputs)

    def finish(self, inputs: Iterable = ()) -> None:
        if self.file is None:  # (not active)
            return
        from wormgear_cli.batch import manifest  # lazy: keeps batch.manifest off `analyze`'s start-up

        text = manifest.document(self.key, self.drive, self.hash.file, Path(self.file).name)
        atomic_write(manifest.manifest_path(self.file), text, tuple(inputs))


# --- terminals -------------------------------------------------------------------------------


def text_width() -> int:
    """Width for tables written to a file or a pipe: $COLUMNS when it is a sane
    number (40..1000), else 100."""
    try:
        width = int(os.environ.get("COLUMNS", "100"))
    except ValueError:
        return 100
    return width if 40 <= width <= 1000 else 100


def stdout_is_terminal() -> bool:
    return sys.stdout.isatty()


def stderr_is_terminal() -> bool:
    return sys.stderr.isatty()


def no_color() -> bool:
    """NO_COLOR set to a non-empty value (https://no-color.org): no colour and no other styles either."""
    return bool(os.environ.get("NO_COLOR"))


_SAFE_CONSOLE = None


def console(**kwargs):
    """A rich Console (same arguments) that never sends a control character of its text: every
    text segment passes :func:`wormgear_cli.errors.escape` (line ends kept), so a name holding
    an escape sequence shows as ``\\u001B[31m`` instead of recolouring or retitling the
    terminal; rich's own styles (its segments' styles) are drawn as usual."""
    global _SAFE_CONSOLE
    if _SAFE_CONSOLE is None:
        # lazy: keeps rich.console, rich.segment off `analyze`'s start-up
        from rich.console import Console
        from rich.segment import Segment


        class SafeConsole(Console):
            def _render_buffer(self, buffer):
                return super()._render_buffer(s if s.control else Segment(escape(s.text, "\n"), s.style, s.control)
                                              for s in buffer)

        _SAFE_CONSOLE = SafeConsole
    return _SAFE_CONSOLE(**kwargs)


def terminal_console(stderr: bool = False, width: int | None = None):
    """A rich console for a terminal: styled unless NO_COLOR is set, in which case it writes
    no escape code at all (``color_system=None`` drops bold, italic and dim too)."""
    if no_color():
        return console(stderr=stderr, highlight=False, width=width, color_system=None, no_color=True)
    return console(stderr=stderr, highlight=False, width=width)


class Progress:
    """A rich progress bar on stderr when it is a terminal and the work may take > 1 s
    (none under NO_COLOR: a live bar cannot be drawn without escape codes)."""

    def __init__(self, total: int, seconds: float, label: str):
        self.bar = None
        if total > 0 and seconds > 1.0 and stderr_is_terminal() and not no_color():
            # lazy: keeps rich.progress off `analyze`'s start-up
            from rich.progress import BarColumn, MofNCompleteColumn, TimeRemainingColumn
            from rich.progress import Progress as Bar

            self.bar = Bar("[progress.description]{task.description}", BarColumn(), MofNCompleteColumn(),
                           TimeRemainingColumn(), console=terminal_console(stderr=True), transient=True)
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


class Stages:
    """A spinner on stderr with the text of the stage the work is in (``update(text)``), for work
    whose length is not known up front (e.g. diagnose: a few thousand rows can take a minute);
    only on a terminal (not under NO_COLOR), and only once the work has run ``after`` seconds:
    a short run shows nothing.  Use as a context manager."""

    def __init__(self, text: str, after: float = 1.0):
        import threading  # lazy: only diagnose shows stages

        self.text = text
        self.status: Any = None
        self.lock = threading.Lock()
        self.timer = threading.Timer(after, self._show) if stderr_is_terminal() and not no_color() else None
        if self.timer is not None:
            self.timer.daemon = True

    def _show(self) -> None:
        with self.lock:
            if self.timer is None:  # the work ended first
                return
            status = terminal_console(stderr=True).status(self.text)
            status.start()
            self.status = status

    def update(self, text: str) -> None:
        with self.lock:
            self.text = text
            if self.status is not None:
                self.status.update(text)

    def __enter__(self):
        if self.timer is not None:
            self.timer.start()
        return self

    def __exit__(self, *exc):
        with self.lock:
            if self.timer is not None:
                self.timer.cancel()
                self.timer = None
            if self.status is not None:
                self.status.stop()
                self.status = None


# --- tables ----------------------------------------------------------------------------------


def _rich_table(t):
    """A :class:`wormgear_cli.output.tables.Table` as a rich Table (text is never read as markup)."""
    # lazy: keeps rich.box, rich.markup, rich.table, rich.text off `analyze`'s start-up
    from rich import box
    from rich.markup import escape as markup
    from rich.table import Table
    from rich.text import Text

    from wormgear_cli.output.tables import Cell  # lazy: keeps output.tables off `analyze`'s start-up

    def escape(text):  # rich markup escaped, control characters written out (before the layout)
        return markup(printable(text, "\n"))

    out = Table(title=escape(t.title), title_justify="left", show_header=t.show_header,
                box=getattr(box, t.box.upper()), padding=(0, t.padding))
    for c in t.columns:
        out.add_column(escape(c.header), justify=c.justify, min_width=c.min_width)
    for row in t.rows:
        out.add_row(*(Text(printable(c.text, "\n"), style=c.style or "") if isinstance(c, Cell) else escape(str(c))
                      for c in row))
    if t.caption:
        out.caption = escape(t.caption)
        out.caption_justify = "left"
    return out


def _words(table) -> Counter:
    """Every word and number of a rich table's header and body cells, with its count."""
    from rich.text import Text  # lazy: keeps rich.text off `analyze`'s start-up

    words: Counter = Counter()
    for column in table.columns:
        for cell in [column.header, *column.cells]:
            text = cell.plain if isinstance(cell, Text) else Text.from_markup(str(cell)).plain
            words.update(text.split())
    return words


_RULES = re.compile("[\u2500-\u257f]")  # box-drawing characters: the table's rules and edges
#: a width no table reaches: measuring at it gives a table's natural width
_UNBOUNDED = 1_000_000


def _fits(table, console, width: int) -> bool:
    """True when rich lays ``table`` out in ``width`` columns without breaking a word or
    number: the table is drawn (without its title and caption) and every word of its cells
    must come out whole.  Only rich's public drawing is used, so the answer does not depend
    on how a rich version computes its column widths or paddings."""
    from rich.console import Console  # lazy: keeps rich.console off `analyze`'s start-up
    from rich.measure import Measurement  # lazy: as rich.console

    drawing = io.StringIO()
    probe = Console(file=drawing, width=width, no_color=True, color_system=None, highlight=False,
                    force_terminal=False, soft_wrap=False, legacy_windows=False)
    title, caption = table.title, table.caption
    table.title = table.caption = None
    try:
        # every column at its natural width (no cell wrapped) within ``width``: it fits as drawn, without
        # drawing it (most tables; the drawing below is for those rich would have to wrap)
        if Measurement.get(probe, probe.options.update_width(_UNBOUNDED), table).maximum <= width:
            return True
        probe.print(table)
    finally:
        table.title, table.caption = title, caption
    drawn = drawing.getvalue()
    if any(len(line.rstrip()) > width for line in drawn.splitlines()):
        return False
    return not (_words(table) - Counter(_RULES.sub(" ", drawn).split()))


def _part(table, columns: list, title, caption):
    from dataclasses import replace  # lazy: keeps dataclasses off `analyze`'s start-up

    from rich.table import Table  # lazy: keeps rich.table off `analyze`'s start-up

    part = Table(title=title, title_justify=table.title_justify, caption=caption,
                 caption_justify=table.caption_justify, show_header=table.show_header, box=table.box,
                 show_edge=table.show_edge, padding=table.padding, show_lines=table.show_lines)
    part.columns = [replace(c, _index=k, _cells=list(c._cells)) for k, c in enumerate(columns)]
    part.rows = list(table.rows)
    return part


def fit_table(table, console, width: int) -> list:
    """``table`` as one or more rich Tables that each fit ``width`` without cutting a word or
    number: columns wrap at spaces (overflow 'fold', never '...'); when the numbers alone
    are too wide, the columns are split into consecutive parts, each repeating the first
    (label) column, titled "(continued)" after the first and captioned on the last."""
    for c in table.columns:
        c.overflow = "fold"
        c.no_wrap = False
    if _fits(table, console, width) or len(table.columns) <= 2:
        return [table]
    key, rest = table.columns[0], table.columns[1:]
    for n_parts in range(2, len(rest) + 1):  # the fewest parts of balanced size that all fit
        size = -(-len(rest) // n_parts)
        groups = [rest[k:k + size] for k in range(0, len(rest), size)]
        if all(_fits(_part(table, [key, *g], None, None), console, width) for g in groups):
            break
    parts = []
    for n, g in enumerate(groups):
        title = table.title if n == 0 else (f"{table.title} (continued)" if table.title else None)
        parts.append(_part(table, [key, *g], title, table.caption if n == len(groups) - 1 else None))
    return parts


def _draw(console, renderables: list, width: int) -> None:
    from rich.table import Table as RichTable  # lazy: keeps rich.table off `analyze`'s start-up

    from wormgear_cli.output.tables import Table  # lazy: keeps output.tables off `analyze`'s start-up

    for r in renderables:
        if isinstance(r, Table):
            r = _rich_table(r)
        for part in fit_table(r, console, width) if isinstance(r, RichTable) else [r]:
            console.print(part)


def render(renderables: list, output: Path | None, inputs: Iterable = ()) -> None:
    """Draw tables (:class:`wormgear_cli.output.tables.Table` or rich renderables) to stdout
    (styled only on a terminal without NO_COLOR) or, as plain text, to ``output``."""
    if output is None and stdout_is_terminal():
        probe = terminal_console(width=text_width() if "COLUMNS" in os.environ else None)
        buf = io.StringIO()
        out = console(file=buf, width=probe.width, force_terminal=True, highlight=False,
                      color_system=None if no_color() else probe.color_system, no_color=no_color())
        _draw(out, renderables, out.width)
        write_stdout(buf.getvalue())
        return
    buf = io.StringIO()
    width = text_width()
    out = console(file=buf, width=width, no_color=True, color_system=None,
                  highlight=False, force_terminal=False, soft_wrap=False)
    _draw(out, renderables, width)
    text = "\n".join(line.rstrip() for line in buf.getvalue().splitlines()) + "\n"  # no padding spaces
    emit(text, output, inputs)
