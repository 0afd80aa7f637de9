"""What a user's file holds, told from its first lines: a TOML drive spec or a table of data.

A measurement CSV given where a drive is expected (or a drive where a measurement is, or the
two arguments of ``diagnose`` swapped) would otherwise meet the other parser and get its error
("TOML syntax error: Expected '=' after a key", "missing required columns").  These checks run
before parsing and are cheap (the first lines only); they never raise: a file that cannot be
read is left to the reader, which says why.
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path

#: a TOML table header: [name], [a.b], [[name]]
_SECTION = re.compile(r"^\s*\[\[?\s*[A-Za-z0-9_\-\". ]+\]\]?\s*(#.*)?$")
#: a TOML key/value line
_KEY_VALUE = re.compile(r"^\s*[A-Za-z0-9_\-\".]+\s*=\s*\S")
#: top-level tables only a drive spec has
DRIVE_SECTIONS = ("drive", "gear_pair", "worm_pair", "assembly", "loads", "requirements", "materials")
#: cell separators of a table of data
_SEPARATORS = (",", ";", "\t")
#: bytes read from a file by :func:`kind_of_file`
_HEAD_BYTES = 64 * 1024


def _content_lines(text: str, most: int) -> list[str]:
    """Up to ``most`` lines that are neither blank nor ``#`` comments."""
    out = []
    for line in text.lstrip("\ufeff").splitlines():
        if line.strip() and not line.lstrip().startswith("#"):
            out.append(line)
            if len(out) == most:
                break
    return out


def looks_like_drive(text: str) -> bool:
    """True when ``text`` reads as a TOML drive spec: a ``[drive]``, ``[gear_pair]``... table
    header and a ``key = value`` line among its first lines."""
    return _drive_lines(_content_lines(text, 60))


def looks_like_drive_lines(lines) -> bool:
    """:func:`looks_like_drive` of the text that ``lines`` (an iterable of its lines, without line
    ends, read only as far as needed) make: a big file is not read whole to say what it is."""
    out: list[str] = []
    for line in lines:
        for piece in line.splitlines():
            if piece.strip() and not piece.lstrip().startswith("#"):
                out.append(piece)
        if len(out) >= 60:
            break
    return _drive_lines(out[:60])


def _drive_lines(lines: list[str]) -> bool:
    sections = {m.group(0).strip(" []").split(".")[0] for m in map(_SECTION.match, lines) if m}
    return bool(sections & set(DRIVE_SECTIONS)) and any(_KEY_VALUE.match(line) for line in lines)


def looks_like_table(text: str) -> bool:
    """True when ``text`` reads as a table of data (CSV, ';' or tab separated): its first line
    is a header of separated cells, neither a TOML table header nor a ``key = value`` line (so
    it cannot be TOML)."""
    lines = _content_lines(text, 1)
    if not lines:
        return False
    head = lines[0]
    if "=" in head or _SECTION.match(head):
        return False
    return any(sep in head for sep in _SEPARATORS)


def first_line(text: str, most: int = 60) -> str:
    """The first content line of ``text``, cut to ``most`` characters (for messages)."""
    lines = _content_lines(text, 1)
    line = lines[0].strip() if lines else ""
    return line if len(line) <= most else line[:most - 3] + "..."


def kind_of_file(path) -> str | None:
    """"drive" (a TOML drive spec), "table" (a table of data) or None (neither, or unreadable),
    from the first :data:`_HEAD_BYTES` of ``path``; only a regular file is looked at."""
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):  # a pipe read here would be lost to the reader
            return None
        with open(Path(path), "rb") as fh:
            head = fh.read(_HEAD_BYTES).decode("utf-8", errors="replace")
    except (OSError, ValueError):
        return None
    if looks_like_drive(head):
        return "drive"
    if looks_like_table(head):
        return "table"
    return None
