"""The input formats of measurements, as a registry: a file is read as it is, its format detected from
its content (or named with ``--input-format``).

An input format is a module with two pure functions, registered by one line in :data:`FORMATS`:

* ``detect(head: str) -> bool``: whether the first :data:`HEAD_CHARS` characters of the text (BOM
  removed, ``\\n`` line ends) are this format;
* ``read(text: str, name: str, options: ReadOptions) -> Measurement``: the whole text (the same
  normalisation) read into the record every command uses; ``name`` is the file's name for messages
  (``name:line: ...``), ``options`` the column map, units and ``require_error``.

and, optionally, a third that reads big files in bounded memory (the sixth field of
:class:`InputFormat`, the function's name; None: the format has none):

* ``read_source(source, name: str, options: ReadOptions) -> Measurement``: the same record from a
  :mod:`~.source` (the file read block by block: ``source.lines()`` for a header or metadata,
  ``source.blocks(line)`` for the data lines; delimited data goes through
  :class:`~.text.DelimitedBody`, which converts a block at a time into typed columns).  A format
  without it gets ``read(source.text(), ...)``: the whole text in memory, as before.

The first format whose ``detect`` accepts the head reads the file; the delimited table (``csv``)
accepts any text and comes last.  Adding a format touches only this list and its own module.
Modules are imported when a file is read (a registry of names keeps start-up free of them).
"""

from __future__ import annotations

import dataclasses
import importlib
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

from wormgear_cli.errors import DataError, UsageError

if TYPE_CHECKING:  # the record module loads numpy and the effect catalogue: only when a file is read
    from wormgear_cli.measurement.reader import Measurement, ReadOptions

#: characters of the text given to each format's ``detect``
HEAD_CHARS = 65536


class InputFormat(NamedTuple):
    """One input format: ``name`` (as ``--input-format`` takes it), ``title`` (for help and messages),
    ``module`` (dotted path), and the names of its ``detect`` and ``read`` functions in that module.
    (A named tuple: ``--help`` builds the option's help from this list, and a named tuple costs a
    sixth of a frozen dataclass to create.)"""

    name: str
    title: str
    module: str
    detect: str
    read: str
    read_source: str | None = None

    def function(self, which: str):
        """The module's ``detect``, ``read`` or ``read_source`` function (the module imported on first use)."""
        return getattr(importlib.import_module(self.module), getattr(self, which))


#: the input formats, most specific first (the first whose detect accepts the file reads it)
FORMATS = (
    InputFormat("phd2", "a PHD2 guide log", "wormgear_cli.measurement.guidelog", "looks_like_guidelog",
                "read_phd2"),
    InputFormat("twincat-scope", "a TwinCAT Scope CSV export", "wormgear_cli.measurement.readers.twincat",
                "looks_like_twincat_scope", "read_twincat_scope", "read_twincat_source"),
    InputFormat("csv", "a delimited table with a header line", "wormgear_cli.measurement.readers.delimited",
                "looks_like_table", "read_table", "read_table_source"),
)


def format_names() -> tuple[str, ...]:
    """The names ``--input-format`` accepts."""
    return tuple(f.name for f in FORMATS)


def find_format(name: str) -> InputFormat:
    """The registered format called ``name``; UsageError naming the known ones otherwise."""
    for f in FORMATS:
        if f.name == name:
            return f

    raise UsageError(f"--input-format {name}: expected one of auto, {', '.join(format_names())}")


def detect_format(text: str) -> InputFormat:
    """The first registered format whose ``detect`` accepts the head of ``text``."""
    head = text[:HEAD_CHARS]
    for f in FORMATS:
        if f.function("detect")(head):
            return f
    return FORMATS[-1]


def read_source(source, name: str, options: ReadOptions) -> Measurement:
    """A :mod:`~.source`'s measurement in its format (named in ``options`` or detected from its head)."""
    fmt = find_format(options.input_format) if options.input_format else detect_format(source.head(HEAD_CHARS))
    if options.guidelog.given and fmt.name != "phd2":
        raise UsageError(f"{', '.join(options.guidelog.given)}: only for a PHD2 guide log; {name} is read as "
                         f"{fmt.title} (--input-format phd2 if it is a guide log)")
    if fmt.read_source:
        return fmt.function("read_source")(source, name, options)
    return fmt.function("read")(source.text(), name, options)


def _asked(options: ReadOptions | None, require_error: bool) -> ReadOptions:
    """``options`` (default: canonical names and units, format detected) with ``require_error``."""
    from wormgear_cli.measurement.reader import ReadOptions  # lazy: keeps measurement.reader off `--help`'s start-up

    options = options or ReadOptions()
    if options.require_error != require_error:
        options = dataclasses.replace(options, require_error=require_error)
    return options


def parse_measurement(text: str, name: str = "<data>", require_error: bool = True,
                      options: ReadOptions | None = None) -> Measurement:
    """Read measurement text in any registered format (see the module doc).

    Parameters
    ----------
    text : str
        The file's text.
    name : str
        The file's name, for messages.
    require_error : bool
        Whether the error (or the actual position) is required.
    options : ReadOptions or None
        Column map, units, input format (None: canonical names and units, format detected).

    Raises
    ------
    DataError
        One line per problem, naming file, line and column.
    """
    # lazy: keeps measurement.readers.source off `--help`'s start-up
    from wormgear_cli.measurement.readers.source import TextSource, normalised

    options = _asked(options, require_error)
    return read_source(TextSource(normalised(text), name, options.block_chars), name, options)


def read_measurement(path: str | Path, require_error: bool = True, options: ReadOptions | None = None) -> Measurement:
    """Read and validate a measurement file in any registered format (see the module doc).

    A regular file is checked whole (size, binary, line length, UTF-8) without being kept, then read
    block by block: the memory is the typed columns', not the text's.

    Parameters
    ----------
    path : str or Path
        The file.
    require_error : bool
        Whether the error column (or the actual position) is required.
    options : ReadOptions or None
        Column map, units, input format (None: canonical names and units, format detected).

    Raises
    ------
    DataError
        One line per problem, naming file, line and column.
    """
    # lazy: keeps measurement.reader, measurement.readers.source, spec.filekind off `--help`'s start-up
    from wormgear_cli.measurement.reader import MAX_LINE_BYTES
    from wormgear_cli.measurement.readers.source import open_source
    from wormgear_cli.spec.filekind import looks_like_drive_lines

    options = _asked(options, require_error)
    source = open_source(path, "a CSV file", options.max_bytes, MAX_LINE_BYTES, options.block_chars)
    if looks_like_drive_lines(line for _, line in source.lines()):  # a drive spec where the data belong: say so
        raise DataError(f"{path}: a TOML drive spec, not a measurement; expected a CSV file with a header "
                        "line such as angle_deg,error_arcsec")
    return read_source(source, str(path), options)
