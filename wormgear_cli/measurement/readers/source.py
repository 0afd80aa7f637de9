"""The text of a measurement file, read in blocks of whole lines: a big file is never held whole.

A source gives the text every input format reads, normalised (byte-order mark removed, ``\\r\\n``
and ``\\r`` read as ``\\n``, so line numbers are an editor's): its lines from the start (headers,
preambles, metadata: read lazily, only as far as a reader looks) and blocks of whole lines from any
line on (the data rows).  Each block carries a mark from which the same block is read again:
:attr:`~wormgear_cli.measurement.reader.Measurement.rows` reads the original cells back from the
file when they are asked for (``simulate --at``), and messages quote a cell by reading its line.

* :class:`FileSource`: a regular file, checked whole once without being kept (binary, line length,
  UTF-8: :func:`wormgear_cli.files.check_text_file`), then read block by block; a file that changed
  since it was checked is refused, never read half old and half new.
* :class:`TextSource`: text in memory (a pipe, which cannot be read twice; ``parse_measurement``).
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import NamedTuple

from wormgear_cli.errors import DataError
from wormgear_cli.files import check_text_file, read_text_file
from wormgear_cli.measurement.reader import BLOCK_CHARS

_CHANGED = "{}: the file changed while it was read; read it again when it is complete"


class Block(NamedTuple):
    """Whole lines of a source: ``text`` (``\\n`` line ends; the last block of a file may end without
    one) starting at file line ``line``; ``mark``: where to start reading to get this block again
    (``(position, line)``, the position in the source's own unit)."""

    mark: tuple
    line: int
    text: str


def normalised(text: str) -> str:
    """``text`` without a leading byte-order mark, ``\\r\\n`` and ``\\r`` made ``\\n``."""
    if text.startswith("\ufeff"):
        text = text[1:]
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    return text


class _Source:
    """What both sources share: lines and cut blocks from the raw blocks of a subclass."""

    name: str
    size: int
    block_chars: int
    first_line: int = 1
    line_count: int = 0

    def _raw(self, mark: tuple | None) -> Iterator[Block]:  # pragma: no cover - abstract
        raise NotImplementedError

    def blocks(self, line: int = 1, mark: tuple | None = None) -> Iterator[Block]:
        """Blocks of whole lines from file line ``line`` to the end; ``mark``: a block's mark at or
        before that line to start from (None: the start of the file)."""
        for b in self._raw(mark):
            if b.line >= line:
                yield b
                continue
            if b.line + b.text.count("\n") < line:
                continue
            cut, at = 0, b.line
            while at < line:
                nxt = b.text.find("\n", cut)
                if nxt < 0:
                    cut = len(b.text)
                    break
                cut, at = nxt + 1, at + 1
            if at == line and cut < len(b.text):
                yield Block(b.mark, line, b.text[cut:])

    def lines(self, line: int = 1) -> Iterator[tuple[int, str]]:
        """(file line number, text) of every line from ``line`` on, read lazily (a final line end
        starts no line of its own)."""
        for b in self.blocks(line):
            parts = b.text.split("\n")
            if parts[-1] == "":
                parts.pop()
            for k, text in enumerate(parts):
                yield b.line + k, text

    def head(self, chars: int) -> str:
        """The first ``chars`` characters of the text (or all of it)."""
        out, got = [], 0
        for b in self._raw(None):
            out.append(b.text[:chars - got])
            got += len(out[-1])
            if got >= chars:
                break
        return "".join(out)

    def text(self) -> str:
        """The whole text (for a format that has no block reader)."""
        return "".join(b.text for b in self._raw(None))


class TextSource(_Source):
    """Normalised text in memory, as a source whose first line is file line ``first_line``."""

    def __init__(self, text: str, name: str = "<data>", block_chars: int = BLOCK_CHARS, first_line: int = 1):
        self._text, self.name, self.block_chars, self.first_line = text, name, max(1, int(block_chars)), first_line
        self.size = len(text)
        self.line_count = text.count("\n") + 1

    def _raw(self, mark: tuple | None) -> Iterator[Block]:
        text, size = self._text, len(self._text)
        pos, line = mark if mark is not None else (0, self.first_line)
        while pos < size:
            end = text.find("\n", pos + self.block_chars - 1)
            end = size if end < 0 else end + 1
            piece = text[pos:end]
            yield Block((pos, line), line, piece)
            line += piece.count("\n")
            pos = end

    def text(self) -> str:
        return self._text


class FileSource(_Source):
    """A regular file checked by :func:`~wormgear_cli.files.check_text_file` (``status``: its
    ``os.stat_result`` then), read in blocks of about ``block_chars`` bytes cut after a line end."""

    def __init__(self, path: str | Path, status: os.stat_result, name: str, block_chars: int = BLOCK_CHARS,
                 line_count: int = 0):
        self.path, self.name, self.block_chars = str(path), name, max(1, int(block_chars))
        self._id = _identity(status)
        self.size = status.st_size
        self.line_count = line_count

    def _raw(self, mark: tuple | None) -> Iterator[Block]:
        pos, line = mark if mark is not None else (0, 1)
        try:
            with open(self.path, "rb", buffering=0) as fh:
                if _identity(os.fstat(fh.fileno())) != self._id:
                    raise DataError(_CHANGED.format(self.name))
                fh.seek(pos)
                carry = b""
                while True:
                    chunk = fh.read(self.block_chars)
                    if not chunk:
                        if carry:
                            yield Block((pos, line), line, self._decode(carry, pos == 0))
                        return
                    data = carry + chunk if carry else chunk
                    cut = data.rfind(b"\n") + 1
                    if cut == 0:  # a line longer than a block: read on to its end
                        carry = data
                        continue
                    piece, carry = data[:cut], data[cut:]
                    text = self._decode(piece, pos == 0)
                    yield Block((pos, line), line, text)
                    line += text.count("\n")
                    pos += cut
        except OSError as exc:
            raise DataError(f"{self.name}: cannot read ({exc.strerror})") from None

    def _decode(self, piece: bytes, first: bool) -> str:
        try:
            text = piece.decode("utf-8")
        except UnicodeDecodeError:  # it was UTF-8 when checked
            raise DataError(_CHANGED.format(self.name)) from None
        if first and text.startswith("\ufeff"):
            text = text[1:]
        if "\r" in text:
            text = text.replace("\r\n", "\n").replace("\r", "\n")
        return text


def _identity(st: os.stat_result) -> tuple:
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


def open_source(path: str | Path, expected: str, max_bytes: int, max_line_bytes: int,
                block_chars: int = BLOCK_CHARS) -> _Source:
    """The source of a user-named measurement file: a regular file checked whole and read in
    blocks; anything else (a pipe, a device) read whole, bounded (it cannot be read twice).

    Raises
    ------
    DataError
        As :func:`wormgear_cli.files.read_text_file` (missing, a directory, binary, too large, a
        line too long, not UTF-8).
    """
    name = str(path)
    try:
        regular = stat.S_ISREG(os.stat(path).st_mode)
    except OSError:
        regular = False  # read_text_file says why
    if not regular:
        text = read_text_file(path, expected, DataError, encoding="utf-8-sig", max_bytes=max_bytes,
                              max_line_bytes=max_line_bytes)
        return TextSource(normalised(text), name, block_chars)
    status, lines = check_text_file(path, expected, DataError, max_bytes, max_line_bytes)
    return FileSource(path, status, name, block_chars, lines)
