"""Delimited text: the dialect (delimiter, decimal comma), the data lines after a header, cells.

Shared by every input format written as delimited text (plain CSV, TwinCAT Scope exports).
A row is one line: a quoted cell that runs over a line break is refused with its line number,
never joined (``90,"1<newline>2"`` is not the number 12).  The data lines are read block by block
from a source (:mod:`~.source`: the file, or text in memory) into typed columns; nothing here opens
a file itself.
"""

from __future__ import annotations

import bisect
import csv
import io
import re
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from wormgear_cli.errors import DataError
from wormgear_cli.measurement.readers.source import TextSource
from wormgear_cli.measurement.readers.values import direction_cells, lenient_floats

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


class Columns(NamedTuple):
    """The columns a table reads from its data lines (:meth:`DelimitedBody.read`).

    ``n``: data rows; ``values``: one float array (n,) per column asked for, NaN where a cell is not a
    number; the direction's holds +1, -1, or NaN where a cell is no direction; ``rotation``: (n,) bool,
    True where the direction is a rotation word (CW/CCW), or None when no cell is one; ``odd`` and
    ``bad``: per column, the first row of a cell with a digit separator or a non-ASCII character, and
    of another cell that is not a number (None: none), the two kinds a message names in this order;
    ``plain``: whether every direction cell reads as a number (the column is numbers, else words)."""

    n: int
    values: list
    rotation: np.ndarray | None
    odd: list
    bad: list
    plain: bool


class _Collected:
    """The columns of a table, filled block by block into arrays allocated once (no object per row)."""

    rotation: np.ndarray | None

    def __init__(self, k: int, direction: int | None, capacity: int):
        self.values = [np.empty(capacity) for _ in range(k)]
        self.direction, self.n, self.rotation, self.plain = direction, 0, None, True
        self.odd: list = [None] * k
        self.bad: list = [None] * k

    def room(self, m: int) -> None:
        """Room for ``m`` more rows (lone ``\\r`` line ends make more lines than a file's ``\\n``)."""
        size = self.values[0].shape[0] if self.values else 0
        if self.n + m <= size:
            return
        size = max(self.n + m, 2 * size)
        for i, arr in enumerate(self.values):
            self.values[i] = np.concatenate([arr[:self.n], np.empty(size - self.n)])
        if self.rotation is not None:
            self.rotation = np.concatenate([self.rotation[:self.n], np.zeros(size - self.n, dtype=bool)])

    def numbers(self, i: int, arr: np.ndarray, odd: int | None = None, bad: int | None = None) -> None:
        """Column ``i`` of the next rows, and where its first cells that are not numbers are."""
        self.values[i][self.n:self.n + arr.shape[0]] = arr
        if odd is not None and self.odd[i] is None:
            self.odd[i] = self.n + odd
        if bad is not None and self.bad[i] is None:
            self.bad[i] = self.n + bad

    def directions(self, cells, decimal_comma: bool) -> None:
        """The direction column's cells of the next rows as written (numbers or words)."""
        value, rotation, plain, odd, bad = direction_cells(cells, decimal_comma)
        assert self.direction is not None  # (direction cells are read for a table with a direction column)
        self.numbers(self.direction, value, odd, bad)
        self.plain = self.plain and plain
        if np.any(rotation):
            if self.rotation is None:
                self.rotation = np.zeros(self.values[0].shape[0], dtype=bool)
            self.rotation[self.n:self.n + rotation.shape[0]] = rotation

    def result(self) -> Columns:
        n = self.n
        return Columns(n, [v[:n] for v in self.values], None if self.rotation is None else self.rotation[:n],
                       self.odd, self.bad, self.plain)


def _strip_tag(text: str, tag: str) -> str:
    """``text`` without a last line ``tag`` (and the blank lines after it), as an export closes a file."""
    end = text.rstrip("\n")
    return end[:-len(tag)] if end.endswith("\n" + tag) else text


def _runs_on(line: str) -> bool:
    """Whether a line that ends inside a quoted cell would take the next line with it."""
    reader = csv.reader([line, ""], strict=True)
    try:
        next(reader)
    except (csv.Error, StopIteration):
        pass
    return reader.line_num > 1


#: a line of whitespace only (the csv module's idea of an empty row; ASCII)
_BLANK_LINE = re.compile(r"(?m)^[\t\x0b\x0c\x1c-\x1f ]*$")


class DelimitedBody:
    """The data lines after a header, read block by block: typed columns, exact messages.

    ``body``: a source (:mod:`~.source`) or the text after the header (``\\n`` line ends);
    ``first_line``: the file line of its first line; ``delim``: the delimiter; ``ncols``: the cells of
    the header; ``end_tag``: a last line an export closes the file with (``EOF``), not a row.

    :meth:`read` converts a block whose lines are all plain numbers with ``np.loadtxt`` (the fast
    path) and any other block cell by cell with the csv module (quotes, comments, blank lines, words,
    bad cells), with the same values either way; what a row is and every message is the csv module's.
    After it, :meth:`line_of`, :meth:`cell_of` and :meth:`rows` find rows again from a small index of
    the blocks (the text itself is not kept)."""

    def __init__(self, body, first_line: int, delim: str, ncols: int, name: str, end_tag: str | None = None):
        self.source = TextSource(body, name, first_line=first_line) if isinstance(body, str) else body
        self.first_line, self.delim, self.ncols, self.name, self.end_tag = first_line, delim, ncols, name, end_tag
        self.blank_rows: list[int] = []  # first three lines of rows whose every cell is empty (",,,"), left out
        self.blank_count = 0
        self.count = 0  # data rows read
        self._skipped = np.empty(0, dtype=np.int64)  # lines of the body that are no row (comments, blank), sorted
        self._index: list[tuple] = []  # (mark, line, first row) of every block read

    def blocks(self, mark: tuple | None = None, line: int | None = None):
        """(block, whether it is the last) of the body from ``line`` (default: its first line), the
        end tag taken off the last block."""
        pend: list = []
        for b in self.source.blocks(self.first_line if line is None else line, mark):
            pend.append(b)
            if len(pend) == 3:
                yield pend.pop(0), False
        if self.end_tag is not None and len(pend) == 2 and "\n" not in pend[1].text.rstrip("\n"):
            pend = [pend[0]._replace(text=pend[0].text + pend[1].text)]  # the tag may not start a block alone
        for i, b in enumerate(pend):
            last = i == len(pend) - 1
            if last and self.end_tag is not None:
                b = b._replace(text=_strip_tag(b.text, self.end_tag))
            if b.text:
                yield b, last

    def head_lines(self, count: int) -> list[str]:
        """The first ``count`` lines of the body."""
        out: list[str] = []
        for b, _ in self.blocks():
            parts = b.text.split("\n", count - len(out))
            if parts and parts[-1] == "" and b.text.endswith("\n") and len(parts) <= count - len(out):
                parts.pop()
            out += parts[:count - len(out)]
            if len(out) >= count:
                break
        return out

    def read(self, cols: list[int], decimal_comma: bool, direction: int | None = None) -> Columns:
        """Columns ``cols`` (file column indices) of every data row as numbers; ``direction``: the
        position in ``cols`` of a direction column (numbers or words).  DataError at the first line
        that is not one row of ``ncols`` cells (a quoted cell left open, a cell count off); cells that
        are not numbers are NaN and said in the result, so the caller names them in its order."""
        last = self.source.first_line + self.source.line_count - 1
        got = _Collected(len(cols), direction, max(0, last - self.first_line + 1))
        words, skipped = False, []
        for block, final in self.blocks():
            self._index.append((block.mark, block.line, got.n))
            fast = self._fast_text(block.text)
            arrays = self._fast(block.text, cols, decimal_comma, direction, words) if fast else None
            if arrays is None and fast and direction is not None and not words:
                arrays = self._fast(block.text, cols, decimal_comma, direction, True)
                words = arrays is not None
            if arrays is not None:
                matrix, numeric, cells = arrays
                got.room(matrix.shape[0])
                for k, i in enumerate(numeric):
                    got.numbers(i, matrix[:, k])
                if cells is not None:
                    got.directions(cells, decimal_comma)
                elif direction is not None:  # numbers: +1 and -1 are directions, anything else is not
                    v = got.values[direction][got.n:got.n + matrix.shape[0]]
                    v[(v != 1.0) & (v != -1.0)] = np.nan
                got.n += matrix.shape[0]
                continue
            rows, lines = self._exact(block, final)
            skipped.append(lines)
            got.room(len(rows))
            for i, j in enumerate(cols):
                cells = [r[j] for r in rows]
                if i == direction:
                    got.directions(cells, decimal_comma)
                else:
                    got.numbers(i, *lenient_floats(cells, decimal_comma))
            got.n += len(rows)
        self.count = got.n
        if skipped:
            self._skipped = np.asarray([x for part in skipped for x in part], dtype=np.int64)
        return got.result()

    def _fast_text(self, text: str) -> bool:
        """Whether every line of ``text`` may be a row of plain cells: ASCII, no quote, comment or digit
        separator, no blank line, exactly ``ncols - 1`` delimiters on each line."""
        if not text.isascii() or '"' in text or "#" in text or "_" in text:
            return False
        if "\n\n" in text or text.startswith("\n"):
            return False
        nlines = text.count("\n") + (0 if text.endswith("\n") else 1)
        if self.ncols == 1:
            return not _BLANK_LINE.search(text[:-1] if text.endswith("\n") else text)
        if text.count(self.delim) != (self.ncols - 1) * nlines:
            return False
        b = np.frombuffer(text.encode("ascii"), dtype=np.uint8)
        ends = np.flatnonzero(b == 10)
        if ends.shape[0] < nlines:
            ends = np.append(ends, b.shape[0])
        starts = np.empty(nlines, dtype=np.intp)
        starts[0], starts[1:] = -1, ends[:-1]
        at = np.flatnonzero(b == ord(self.delim)).reshape(nlines, self.ncols - 1)
        return bool(np.all(at[:, 0] > starts) and np.all(at[:, -1] < ends))

    def _fast(self, text: str, cols: list[int], decimal_comma: bool, direction: int | None, words: bool):
        """(float matrix of the numeric columns, their positions in ``cols``, the direction's cells as
        strings when ``words``) of a block, or None when a cell is not a plain number."""
        if decimal_comma:
            text = text.replace(",", ".")
        numeric = [i for i in range(len(cols)) if not (words and i == direction)]
        try:
            matrix = np.loadtxt(io.StringIO(text), delimiter=self.delim, dtype=float, ndmin=2,
                                usecols=[cols[i] for i in numeric], comments=None, quotechar=None)
            cells = None
            if words:
                assert direction is not None  # (words: the direction column's cells)
                cells = np.loadtxt(io.StringIO(text), delimiter=self.delim, dtype=str, ndmin=1,
                                   usecols=[cols[direction]], comments=None, quotechar=None)
        except ValueError:
            return None
        return matrix, numeric, cells

    def _exact(self, block, final: bool) -> tuple[list, list]:
        """(rows of cells, lines that are no row) of a block by the csv module; DataError at the first
        line that is not one row of ``ncols`` cells."""
        lines_in = block.text.split("\n")
        if lines_in and lines_in[-1] == "":
            lines_in.pop()
        reader = csv.reader(lines_in, delimiter=self.delim, strict=True)
        rows, skipped = [], []
        consumed = 0
        while True:
            try:
                row = next(reader)
            except StopIteration:
                break
            except csv.Error as exc:
                line_no = block.line + consumed
                at_end = consumed == len(lines_in) - 1 and not final and _runs_on(lines_in[consumed])
                if reader.line_num > consumed + 1 or at_end or lines_in[consumed].count('"') % 2:
                    raise DataError(open_quote(self.name, line_no)) from None
                raise DataError(f"{self.name}:{block.line - 1 + reader.line_num}: unreadable CSV line "
                                f"({exc})") from None
            line_no = block.line + consumed
            if reader.line_num > consumed + 1:  # a quoted cell took the next line(s) with it
                raise DataError(open_quote(self.name, line_no))
            consumed = reader.line_num
            if not row or all(not c.strip() for c in row) or row[0].lstrip().startswith("#"):
                skipped.append(line_no)
                if len(row) > 1 and all(not c.strip() for c in row):  # delimiters and nothing else: said in the notes
                    self.blank_count += 1
                    if len(self.blank_rows) < 3:
                        self.blank_rows.append(line_no)
                continue
            if len(row) != self.ncols:
                raise DataError(f"{self.name}:{line_no}: expected {self.ncols} cells as in the header, got {len(row)}")
            rows.append(row)
        return rows, skipped

    def line_of(self, k: int) -> int:
        """File line number of data row ``k``."""
        skipped, line = self._skipped, self.first_line + k
        while True:  # the k-th line that is no skipped line
            nxt = self.first_line + k + int(np.searchsorted(skipped, line, side="right"))
            if nxt == line:
                return line
            line = nxt

    def _mark_of(self, line: int):
        """The mark of the last block read that starts at or before ``line``."""
        at = bisect.bisect_right([entry[1] for entry in self._index], line) - 1
        return self._index[at][0] if at >= 0 else None

    def cell_of(self, k: int, j: int) -> str:
        """The text of cell ``j`` of data row ``k``, stripped (read again from the source)."""
        line = self.line_of(k)
        for b, _ in self.blocks(self._mark_of(line), line):
            return next(csv.reader([b.text.split("\n", 1)[0]], delimiter=self.delim))[j].strip()
        raise IndexError(k)

    def sample_cells(self, j: int, most: int = 20) -> list[str]:
        """Up to ``most`` cells of column ``j`` from the first data lines (for hints; never raises)."""
        out = []
        for line in self.head_lines(most * 2):
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

    def rows(self, kept=None) -> Rows:
        """The text cells of the data rows (``kept``: the indices of the rows to give, None: all), read
        again from the source when they are asked for."""
        return Rows(self, None if kept is None else np.asarray(kept))

    def row_cells(self, first: int, stop: int):
        """Tuples of the cells of data rows ``first`` to ``stop - 1``, read block by block."""
        if first >= stop:
            return
        starts = [entry[2] for entry in self._index]
        at = max(bisect.bisect_right(starts, first) - 1, 0)
        mark, line, row = self._index[at] if self._index else (None, None, 0)
        for b, _ in self.blocks(mark, line):
            lines_in = b.text.split("\n")
            if lines_in and lines_in[-1] == "":
                lines_in.pop()
            for r in csv.reader(lines_in, delimiter=self.delim, strict=True):
                if not r or all(not c.strip() for c in r) or r[0].lstrip().startswith("#"):
                    continue
                if row >= first:
                    yield tuple(r)
                row += 1
                if row >= stop:
                    return


class Rows(Sequence):
    """The text cells of a measurement's rows (tuples of str), read from the file when asked for: a
    sequence that holds no row (``rows[a:b]`` reads the blocks of those rows only)."""

    def __init__(self, body: DelimitedBody, kept: np.ndarray | None):
        self._body, self._kept = body, kept

    def __len__(self) -> int:
        return self._body.count if self._kept is None else int(self._kept.shape[0])

    def _span(self, a: int, b: int) -> list[tuple]:
        if a >= b:
            return []
        if self._kept is None:
            return list(self._body.row_cells(a, b))
        want = self._kept[a:b]
        first = int(want[0])
        got = list(self._body.row_cells(first, int(want[-1]) + 1))
        return [got[int(k) - first] for k in want]

    def __getitem__(self, i):
        if isinstance(i, slice):
            a, b, step = i.indices(len(self))
            return self._span(a, b) if step == 1 else [self[k] for k in range(a, b, step)]
        n = len(self)
        if i < 0:
            i += n
        if not 0 <= i < n:
            raise IndexError(i)
        return self._span(i, i + 1)[0]

    def __iter__(self):
        if self._kept is None:
            yield from self._body.row_cells(0, self._body.count)
            return
        keep = iter(self._kept.tolist())
        nxt = next(keep, None)
        for k, row in enumerate(self._body.row_cells(0, int(self._kept[-1]) + 1 if self._kept.size else 0)):
            if k == nxt:
                yield row
                nxt = next(keep, None)

    def __eq__(self, other) -> bool:
        if not isinstance(other, Sequence) or isinstance(other, str):
            return NotImplemented
        return len(self) == len(other) and all(a == tuple(b) for a, b in zip(self, other))

    __hash__ = None  # type: ignore[assignment]  # (unhashable as a list is: it defines __eq__)

def split_lines(text: str) -> list[str]:
    r"""Lines as an editor counts them (split at \n, \r\n or \r only), so line numbers match."""
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
