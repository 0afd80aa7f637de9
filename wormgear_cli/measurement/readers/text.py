"""Delimited text: the dialect (delimiter, decimal comma), the data lines after a header, cells.

Shared by every input format written as delimited text (plain CSV, TwinCAT Scope exports).
A row is one line: a quoted cell that runs over a line break is refused with its line number,
never joined (``90,"1<newline>2"`` is not the number 12).  Pure text and numpy, no I/O.
"""

from __future__ import annotations

import csv
import re

import numpy as np

from wormgear_cli.errors import DataError
from wormgear_cli.measurement.reader import BLOCK_CHARS

_DELIMS = ("\t", ";", ",")
_COMMA_NUMBER = re.compile(r"^\s*[-+]?\d*,\d+([eE][-+]?\d+)?\s*$")
#: a number as spreadsheets and instruments write it (decimal point or comma, exponent)
NUMBER = re.compile(r"^\s*[-+]?(\d+([.,]\d*)?|[.,]\d+)([eE][-+]?\d+)?\s*$")


def detect_dialect(header_line: str, sample: list[str]) -> tuple[str, bool, str]:
    """(delimiter, decimal comma, how it was found) from the header line and sampled data lines.

    :class:`csv.Sniffer` restricted to tab, ``;`` and ``,`` is asked first;
    its answer is kept when it splits the header and every sampled line into
    the same number (>= 2) of cells.  Otherwise the candidate that does so
    (tab, ``;``, ``,`` in that order) is taken ("rule"); a one-column file
    falls back to ``,``.
    """
    lines = [header_line] + [s for s in sample if s.strip() and not s.lstrip().startswith("#")]

    def consistent(d: str) -> bool:
        counts = {len(next(csv.reader([s], delimiter=d))) for s in lines}
        return len(counts) == 1 and counts.pop() >= 2

    how = "sniffer"
    try:
        delim = csv.Sniffer().sniff("\n".join(lines), delimiters="".join(_DELIMS)).delimiter
    except csv.Error:
        delim = None
    if delim is None or not consistent(delim):
        how = "rule"
        delim = next((d for d in _DELIMS if consistent(d)), None)
        if delim is None:
            delim = max(_DELIMS, key=lambda d: header_line.count(d)) if any(d in header_line for d in _DELIMS) else ","
    return delim, decimal_comma(lines[1:], delim), how


def decimal_comma(lines: list[str], delim: str) -> bool:
    """Whether numbers are written with a decimal comma: the delimiter is not ``,``, a sampled cell
    reads ``12,5`` and none mixes ``,`` and ``.``."""
    if delim == ",":
        return False
    cells = [c for s in lines for c in s.split(delim)]
    return any(_COMMA_NUMBER.match(c) for c in cells) and not any("," in c and "." in c for c in cells)


def split_cells(line: str, delim: str, name: str, line_no: int, what: str = "line") -> list[str]:
    """The cells of one line (stdlib csv, strict); DataError naming the line when a quoted cell is
    left open (it would run over a line break) or the line is not CSV."""
    try:
        return next(csv.reader([line], delimiter=delim, strict=True))
    except csv.Error as exc:
        if line.count('"') % 2:
            raise DataError(open_quote(name, line_no)) from None
        raise DataError(f"{name}:{line_no}: unreadable CSV {what} ({exc})") from None
    except StopIteration:
        return []


def open_quote(name: str, line_no: int) -> str:
    """The message for a quoted cell that runs over a line break (the same in every reader)."""
    return (f"{name}:{line_no}: a quoted cell runs over a line break; each row must be one line (a cell "
            "split over lines would be joined into another value): put the cell on one line")


class DelimitedBody:
    """The data lines after a header: fast block conversion, exact messages on the slow path.

    ``body``: the text after the header line (``\\n`` line ends); ``first_line``: the file line of
    its first line; ``delim``: the delimiter; ``ncols``: the cells of the header."""

    def __init__(self, body: str, first_line: int, delim: str, ncols: int, name: str):
        self.body, self.first_line, self.delim, self.ncols, self.name = body, first_line, delim, ncols, name
        self._rows = None  # (rows, line numbers) of the slow path
        self.blank_rows: list[int] = []  # line numbers of rows whose every cell is empty (",,,"), left out

    def slow(self):
        """(rows of cells, file line of each row); DataError at the first row that is not one line of
        ``ncols`` cells."""
        if self._rows is None:
            lines_in = self.body.split("\n")
            if lines_in and lines_in[-1] == "":
                lines_in.pop()
            reader = csv.reader(lines_in, delimiter=self.delim, strict=True)
            rows, lines = [], []
            consumed = 0
            while True:
                try:
                    row = next(reader)
                except StopIteration:
                    break
                except csv.Error as exc:
                    line_no = self.first_line + consumed
                    if reader.line_num > consumed + 1 or lines_in[consumed].count('"') % 2:
                        raise DataError(open_quote(self.name, line_no)) from None
                    raise DataError(f"{self.name}:{self.first_line - 1 + reader.line_num}: unreadable CSV line "
                                    f"({exc})") from None
                line_no = self.first_line + consumed
                if reader.line_num > consumed + 1:  # a quoted cell took the next line(s) with it
                    raise DataError(open_quote(self.name, line_no))
                consumed = reader.line_num
                if not row or all(not c.strip() for c in row) or row[0].lstrip().startswith("#"):
                    if len(row) > 1 and all(not c.strip() for c in row):
                        self.blank_rows.append(line_no)  # delimiters and nothing else: said in the notes
                    continue
                if len(row) != self.ncols:
                    raise DataError(f"{self.name}:{line_no}: expected {self.ncols} cells as in the header, got "
                                    f"{len(row)}")
                rows.append(row)
                lines.append(line_no)
            self._rows = (rows, lines)
        return self._rows

    def _block_arrays(self, cols: list[int], decimal_comma: bool, text: tuple) -> list[np.ndarray] | None:
        """``cols`` of every row, numbers as float (``text``: positions in ``cols`` read as stripped
        strings), or None when the slow path must decide."""
        body = self.body
        groups = [[i for i in range(len(cols)) if i not in text], [i for i in range(len(cols)) if i in text]]
        parts: dict[int, list[np.ndarray]] = {i: [] for i in range(len(cols))}
        pos, size = 0, len(body)
        try:
            while pos < size:
                end = body.find("\n", pos + BLOCK_CHARS)
                end = size if end < 0 else end + 1
                block = body[pos:end]
                if decimal_comma:
                    block = block.replace(",", ".")
                lines = block.splitlines()
                for group, dtype in zip(groups, (float, str)):
                    if not group:
                        continue
                    arr = np.loadtxt(lines, delimiter=self.delim, dtype=dtype, ndmin=2,
                                     usecols=[cols[i] for i in group], comments=None, quotechar=None)
                    for k, i in enumerate(group):
                        parts[i].append(arr[:, k] if dtype is float else np.char.strip(arr[:, k]))
                pos = end
        except ValueError:
            return None
        return [np.concatenate(parts[i]) if parts[i] else np.empty(0) for i in range(len(cols))]

    def fast(self, cols: list[int], decimal_comma: bool, words: tuple = ()) -> list[np.ndarray] | None:
        """Every row of ``cols`` as arrays (float; the positions in ``words`` as strings when they do not
        read as numbers), or None when the slow path must decide (quotes, comments, blank lines, a cell
        count off somewhere, a cell that is not a number)."""
        body = self.body
        if not body.isascii() or any(ch in body for ch in ('"', "#", "_")):
            return None
        lines_est = body.count("\n") + (0 if body.endswith("\n") else 1)
        blank = body.count("\n\n") + body.startswith("\n")
        if blank or body.count(self.delim) != (self.ncols - 1) * lines_est:
            return None  # blank lines or a cell count off somewhere: let the slow path decide (and say where)
        got = self._block_arrays(cols, decimal_comma, ())
        if got is None and words:
            got = self._block_arrays(cols, decimal_comma, tuple(words))
        return got

    def line_of(self, k: int) -> int:
        """File line number of data row ``k``."""
        if self._rows is None and "\n\n" not in self.body and not self.body.startswith("\n"):
            return self.first_line + k
        return self.slow()[1][k]

    def cell_of(self, k: int, j: int) -> str:
        """The text of cell ``j`` of data row ``k``, stripped."""
        line = self.body.split("\n")[self.line_of(k) - self.first_line]
        return next(csv.reader([line], delimiter=self.delim))[j].strip()

    def column_cells(self, j: int) -> tuple[list[str], list[int]]:
        """The cells of column ``j`` of every row (slow path) and their file lines."""
        rows, lines = self.slow()
        return [r[j] for r in rows], lines

    def sample_cells(self, j: int, most: int = 20) -> list[str]:
        """Up to ``most`` cells of column ``j`` from the first data lines (for hints; never raises)."""
        out = []
        for line in self.body.split("\n", most * 2)[: most * 2]:
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            try:
                cells = next(csv.reader([line], delimiter=self.delim))
            except (csv.Error, StopIteration):
                continue
            if len(cells) == self.ncols:
                out.append(cells[j].strip())
            if len(out) >= most:
                break
        return out


def split_lines(text: str) -> list[str]:
    r"""Lines as an editor counts them (split at \n, \r\n or \r only), so line numbers match."""
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
