"""TOML drive files parsed within bounds: refuse what no drive file can be, before parsing.

The standard parser (:mod:`tomllib`) is unbounded in three ways a hostile or
corrupted file can reach: a dotted key of many parts costs memory growing
with the square of the part count (20 000 parts: 1.6 GB), arrays or inline
tables nested a few hundred deep exhaust the recursion limit, and an integer
of more than 4 300 digits raises ValueError.  :func:`parse_toml` scans the raw
text once (a linear regular-expression pass that knows strings and comments)
and refuses, with the file and line, anything beyond these limits, then
parses and turns every parser exception into a :class:`SpecError` naming the
file and, where the parser says it, the line and column.

The limits are far above any drive file (the shipped ones are 2-5 kB, keys
have at most 3 parts, arrays are at most 2 deep) and are documented in
docs/reliability.md.
"""

from __future__ import annotations

import re

from wormgear_cli.errors import SpecError

#: largest drive file [bytes] (the shipped drive files are 2-5 kB)
MAX_SPEC_BYTES = 1024 * 1024
#: deepest nesting of arrays and inline tables (``[`` and ``{``, table headers included)
MAX_NESTING = 32
#: most parts in one dotted key (``a.b.c`` has 3), in a table header or before ``=``
MAX_KEY_PARTS = 32
#: longest key part, and longest bare token (a number, date or boolean) [characters]
MAX_TOKEN_CHARS = 128

_TOKEN = re.compile(
    r'''
      (?P<nl>\n)
    | (?P<ws>[ \t\r]+)
    | (?P<comment>\#[^\n]*)
    | (?P<mlbasic>"""(?:[^"\\]|\\.|"(?!""))*"""(?:"{1,2}(?!"))?)
    | (?P<mlliteral>\'\'\'(?:[^']|'(?!''))*\'\'\'(?:'{1,2}(?!'))?)
    | (?P<basic>"(?:[^"\\\n]|\\.)*")
    | (?P<literal>'[^'\n]*')
    | (?P<bare>[A-Za-z0-9_+\-:]+)
    | (?P<other>.)
    ''',
    re.S | re.X,
)


def check_toml_text(text: str, source: str = "<spec>") -> None:
    """Refuse TOML text that no drive file can be, before it is parsed.

    Parameters
    ----------
    text : str
        The whole file.
    source : str
        The file name, for messages.

    Raises
    ------
    SpecError
        ``FILE:LINE: ...`` for the first of: more than :data:`MAX_SPEC_BYTES`
        (UTF-8), nesting deeper than :data:`MAX_NESTING`, a dotted key of more
        than :data:`MAX_KEY_PARTS` parts, a key part or bare value longer than
        :data:`MAX_TOKEN_CHARS` characters.
    """
    size = len(text.encode("utf-8", "surrogatepass"))
    if size > MAX_SPEC_BYTES:
        raise SpecError(f"{source}: {size} bytes, larger than the {MAX_SPEC_BYTES // 1024} KiB a drive file "
                        f"may have")
    line = 1
    depth = 0
    parts = 0  # parts of the dotted key being read (0: not in a key)
    after_dot = False
    pending_len = 0  # length of the last quoted string, a key part if "." or "=" follows
    for m in _TOKEN.finditer(text):
        kind = m.lastgroup
        if kind == "ws":
            continue
        if kind == "nl":
            line += 1
            parts, after_dot, pending_len = 0, False, 0
            continue
        if kind == "comment":
            continue
        if kind in ("mlbasic", "mlliteral"):
            line += m.group().count("\n")
            parts, after_dot, pending_len = 0, False, 0
            continue
        if kind in ("basic", "literal", "bare"):
            length = len(m.group()) - (2 if kind != "bare" else 0)
            if kind == "bare" and length > MAX_TOKEN_CHARS:
                raise SpecError(f"{source}:{line}: a key or value of {length} characters, more than the "
                                f"{MAX_TOKEN_CHARS} a drive file may have")
            parts = parts + 1 if after_dot else 1
            after_dot = False
            pending_len = length if kind != "bare" else 0
            if parts > MAX_KEY_PARTS:
                raise SpecError(f"{source}:{line}: a dotted key of more than {MAX_KEY_PARTS} parts; a drive "
                                f"file's keys have a few")
            continue
        ch = m.group()
        if ch in "\"'":  # a string that does not end on its line: the parser reports it there
            return
        if ch in ".=" and pending_len > MAX_TOKEN_CHARS:
            raise SpecError(f"{source}:{line}: a key of {pending_len} characters, more than the "
                            f"{MAX_TOKEN_CHARS} a drive file may have")
        pending_len = 0
        if ch == "." and parts:
            after_dot = True
            continue
        parts, after_dot = 0, False
        if ch in "[{":
            depth += 1
            if depth > MAX_NESTING:
                raise SpecError(f"{source}:{line}: arrays or tables nested more than {MAX_NESTING} deep; a "
                                f"drive file needs 2 or 3")
        elif ch in "]}":
            depth = max(0, depth - 1)


def parse_toml(text: str, source: str = "<spec>") -> dict:
    """Parse drive-file TOML text after :func:`check_toml_text`.

    Returns
    -------
    dict
        The document, as :func:`tomllib.loads` gives it.

    Raises
    ------
    SpecError
        One line: ``FILE:LINE:COL: TOML syntax error: WHAT`` for a syntax
        error, ``FILE: ...`` for what the checks refuse or any other failure
        of the parser (a number out of range, exhausted recursion or memory).
    """
    import tomllib  # lazy: keeps tomllib off `analyze`'s start-up

    check_toml_text(text, source)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(syntax_message(str(exc), text, source)) from None
    except (ValueError, OverflowError) as exc:
        raise SpecError(f"{source}: TOML value cannot be read ({exc})") from None
    except RecursionError:
        raise SpecError(f"{source}: TOML nested too deeply to read") from None
    except MemoryError:
        raise SpecError(f"{source}: TOML too large to read in the memory available") from None


def syntax_message(msg: str, text: str, source: str) -> str:
    """``FILE:LINE:COL: TOML syntax error: WHAT`` from tomllib's message."""
    m = re.search(r"\s*\(at line (\d+), column (\d+)\)\s*$", msg)
    if m:
        return f"{source}:{m.group(1)}:{m.group(2)}: TOML syntax error: {msg[:m.start()]}"
    m = re.search(r"\s*\(at end of document\)\s*$", msg)
    if m:
        lines = text.splitlines() or [""]
        return (f"{source}:{len(lines)}:{len(lines[-1]) + 1}: TOML syntax error: "
                f"{msg[:m.start()]} (at end of file)")
    return f"{source}: TOML syntax error: {msg}"
