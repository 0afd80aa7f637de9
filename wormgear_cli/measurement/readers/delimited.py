"""The delimited-table format (``csv``): a header line and one row per line, as spreadsheets and
instruments write them.

* delimiter ``,``, ``;`` or tab, found by :class:`csv.Sniffer` on the header and the first data
  lines, else by rule (:func:`~.text.detect_dialect`); decimal comma when the delimiter is not
  ``,`` and a sampled number is written ``12,5``;
* UTF-8 with or without BOM, LF, CRLF or CR line ends (normalised by the registry);
* ``#`` lines and blank lines before the header are comments;
* a preamble without ``#`` (``Operator;Hans``, ``Date;2024-03-01``: metadata lines before the
  header) is skipped and said in the notes: the header is the first line that has as many cells as
  the data lines after it and no cell that is a number, followed by lines of numbers;
* a quoted cell that runs over a line break is refused with its line number.

The table itself (columns, units, checks, formed columns) is :mod:`~.table`'s.
"""

from __future__ import annotations

import csv
import itertools

from wormgear_cli.errors import DataError
from wormgear_cli.measurement.reader import REQUIRED, SNIFF_LINES, Measurement, ReadOptions
from wormgear_cli.measurement.readers.source import TextSource
from wormgear_cli.measurement.readers.table import TableSource, build_measurement
from wormgear_cli.measurement.readers.text import NUMBER, DelimitedBody, detect_dialect, split_cells

#: lines looked at for a header after a preamble (beyond them the first line is the header)
PREAMBLE_LINES = 200
#: data lines that must follow a header found after a preamble (fewer when the file has fewer)
DATA_AFTER_HEADER = 3


def looks_like_table(head: str) -> bool:
    """Any text: the delimited table is the format of last resort."""
    return True


def _numbers(cells: list[str]) -> int:
    return sum(1 for c in cells if NUMBER.match(c))


def _data_like(cells: list[str]) -> bool:
    """A data line: at least two cells, at least two of them numbers."""
    return len(cells) >= 2 and _numbers(cells) >= 2


def find_header(lines: list[tuple[int, str]]) -> int:
    """Index in ``lines`` ((line number, text) of the non-blank, non-``#`` lines) of the header: of the
    lines with no number among their cells, the one followed by the longest run of data lines with as
    many cells (under one of tab, ``;``, ``,``), at least :data:`DATA_AFTER_HEADER` of them (or all
    that follow); 0 when none is (the first line is the header, as without a preamble)."""
    best, best_run = 0, 0
    for d in ("\t", ";", ","):
        rows = []
        for _, text in lines:
            try:
                rows.append(next(csv.reader([text], delimiter=d)))
            except (csv.Error, StopIteration):
                rows.append([])
        data = [_data_like(r) for r in rows]
        for i, head in enumerate(rows):
            if len(head) < 2 or _numbers(head):
                continue
            run = 0
            while i + 1 + run < len(rows) and data[i + 1 + run] and len(rows[i + 1 + run]) == len(head):
                run += 1
            if run > best_run and run >= min(DATA_AFTER_HEADER, len(rows) - i - 1):
                best, best_run = i, run
    return best


def _preamble(source, name: str) -> tuple[int, list[str], list[str]]:
    """(line number of the header line, ``#`` comments, preamble lines) of a source's text (its
    first lines only are read)."""
    line_no = 0
    comments: list[str] = []
    seen: list[str] = []  # every line up to the last candidate (comments among a preamble)
    candidates: list[tuple[int, str]] = []  # (line number, text) of other lines
    for line_no, line in source.lines():
        if len(candidates) >= PREAMBLE_LINES + DATA_AFTER_HEADER + 1:
            break
        seen.append(line)
        if line.strip() and not line.lstrip().startswith("#"):
            candidates.append((line_no, line))
        elif line.strip() and not candidates:
            comments.append(line)
    else:
        line_no += 1
    if not candidates:
        if comments:
            raise DataError(f"{name}:{line_no}: no CSV header after the comment lines, expected one "
                            f"with {', '.join(REQUIRED)}")
        raise DataError(f"{name}:1: empty file, expected a CSV header with {', '.join(REQUIRED)}")
    k = find_header(candidates) if _first_is_not_header(candidates) else 0
    preamble = [t for _, t in candidates[:k]]
    header_line = candidates[k][0]
    if k:  # '#' lines between preamble lines are comments too
        comments = [line for line in seen[:header_line - 1] if line.lstrip().startswith("#")]
    return header_line, comments, preamble


def _first_is_not_header(candidates) -> bool:
    """Whether the first line cannot be the header as it stands: a next line that is not data."""
    if len(candidates) < 2:
        return False
    first, second = candidates[0][1], candidates[1][1]
    for d in ("\t", ";", ","):
        try:
            a, b = next(csv.reader([first], delimiter=d)), next(csv.reader([second], delimiter=d))
        except (csv.Error, StopIteration):
            continue
        if len(a) >= 2 and len(a) == len(b) and _numbers(a) == 0 and _data_like(b):
            return False
    return True


def read_table(text: str, name: str, options: ReadOptions) -> Measurement:
    """Read a delimited table (see the module doc); ``text`` with ``\\n`` line ends, no BOM."""
    return read_table_source(TextSource(text, name, options.block_chars), name, options)


def read_table_source(source, name: str, options: ReadOptions) -> Measurement:
    """Read a delimited table from a source (:mod:`~.source`: a file read block by block)."""
    # the csv module refuses a cell over 128 KiB with its own exception (a traceback, not a DataError);
    # a cell is at most as long as the text, so it is parsed and then judged like any other cell
    limit = csv.field_size_limit()
    csv.field_size_limit(max(limit, source.size + 1))
    try:
        return build_measurement(_source(source, name), options)
    finally:
        csv.field_size_limit(limit)


def _source(source, name: str) -> TableSource:
    """The header, the data lines and the dialect of a delimited table."""
    header_line_no, comments, preamble = _preamble(source, name)
    lines = source.lines(header_line_no)
    header_text = next(lines)[1]
    sample = [text for _, text in itertools.islice(lines, SNIFF_LINES)]
    delim, decimal_comma, _how = detect_dialect(header_text, sample)
    header = [h.strip() for h in split_cells(header_text, delim, name, header_line_no, "header")]
    notes = []
    if preamble:
        last = header_line_no - 1
        notes.append(f"{len(preamble)} line{'s' if len(preamble) != 1 else ''} before the header skipped as a "
                     f"preamble (metadata without '#', up to line {last}): "
                     + "; ".join(_clip(p) for p in preamble[:2]) + ("; ..." if len(preamble) > 2 else ""))
    return TableSource(name=name, header=header, header_line=header_line_no,
                       body=DelimitedBody(source, header_line_no + 1, delim, len(header), name),
                       decimal_comma=decimal_comma, comments=tuple(comments), preamble=tuple(preamble), notes=notes)


def _clip(line: str, most: int = 40) -> str:
    line = line.strip()
    return repr(line) if len(line) <= most else repr(line[:most]) + "..."
