"""The one error family of the core, and the one way names appear in its messages.

Core code raises :class:`WormgearError` (or a subclass) for anything the
*user* got wrong: a bad file, a bad key, a bad option value.  Only the CLI
layer turns it into messages on stderr and exit code 2.  Anything else that
escapes is a bug and may raise normally.
"""

from __future__ import annotations

import difflib
import re
import warnings


class WormgearError(Exception):
    """A user mistake.  ``problems`` holds one line per problem."""

    exit_code = 2

    def __init__(self, problems: str | list[str]):
        if isinstance(problems, str):
            problems = [problems]
        self.problems = list(problems)
        super().__init__("\n".join(self.problems))

    def __reduce__(self):  # pickled with its problems (raised in a worker of --jobs, reported by the parent)
        return self.__class__, (self.problems,)


class SpecError(WormgearError):
    """A drive spec (TOML) that cannot be loaded or is invalid."""


class DataError(WormgearError):
    """A measurement file (CSV) that cannot be read."""


class UsageError(WormgearError):
    """An option or parameter value that makes no sense.

    ``parameter``: the API parameter (keyword) the first problem is about, that problem starting
    with it ("NAME: ..." or "NAME VALUE: ..."); the core speaks the API's words, and the command line shows its own flag
    for that parameter there instead (``alpha: ...`` from Python, ``--alpha: ...`` from the shell).
    """

    def __init__(self, problems: str | list[str], parameter: str | None = None):
        super().__init__(problems)
        self.parameter = parameter

    def __reduce__(self):
        return self.__class__, (self.problems, self.parameter)

    def in_flags(self, flags: dict[str, str]) -> list[str]:
        """The problems as the command line says them: ``flags`` maps API parameters to the command's flags."""
        flag = flags.get(self.parameter or "")
        first = self.problems[0] if self.problems else ""
        if flag is None or not first.startswith((f"{self.parameter}:", f"{self.parameter} ")):
            return self.problems
        return [flag + first[len(self.parameter or ""):], *self.problems[1:]]


def did_you_mean(word: str, choices, *, show=str, otherwise: str = "", cutoff: float = 0.6) -> str:
    """The hint of every "unknown key" message: `` (did you mean X?)`` for the closest of
    ``choices`` to ``word`` (difflib ratio >= ``cutoff``), shown through ``show`` (a prefix,
    quotes), else ``otherwise`` (e.g. the list of valid names, or nothing).  A choice that differs
    from ``word`` in case only is the closest (``max_iso230_a_arcsec`` -> ``max_iso230_A_arcsec``,
    where difflib alone finds ``_M_`` as near)."""
    choices = list(choices)
    same = [c for c in choices if c.lower() == word.lower()]
    near = same[:1] or difflib.get_close_matches(word, choices, n=1, cutoff=cutoff)
    return f" (did you mean {show(near[0])}?)" if near else otherwise


def moved(old: str, new: str, stacklevel: int = 3) -> None:
    """Warn that ``old`` is now ``new`` (a DeprecationWarning, shown once per call site)."""
    warnings.warn(f"{old} moved to {new}; the old name will be removed in wormgear-cli 0.3",
                  DeprecationWarning, stacklevel=stacklevel)


# --- names in messages ---------------------------------------------------------------------
#
# The one way a name from outside reaches a terminal, a message or a file's comment.
#
# Names come from files and options the user may not have written: TOML keys
# (``[effects."..."]``, ``[statistics]``), file names, drive names, table names.  Any of
# them may hold control characters: a line break that starts a new TOML line inside a
# comment, an escape sequence that recolours or retitles a terminal (ANSI CSI, OSC), a
# bidirectional override that shows text in another order.  Every such name is printed
# through :func:`quote`; whole message lines pass :func:`escape` as a last guard; CSV text
# cells pass :func:`csv_cell` (no spreadsheet formula either).
#
# Escapes are those of TOML basic strings and JSON (\n, \t, \", \\, \u001B), so a quoted
# name is also a valid TOML key or string.  Ordinary names (printable, no surrounding space)
# are left exactly as they are.

_SHORT = {"\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r", "\\": "\\\\", '"': '\\"'}

#: characters a spreadsheet reads as the start of a formula (OWASP "CSV injection")
FORMULA_PREFIXES = ("=", "+", "-", "@", "\t", "\r")

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?|inf|nan)", re.I)


def _escaped(c: str, quotes: bool) -> str:
    if c in ('"', "\\"):
        return _SHORT[c] if quotes else c
    if c.isprintable():
        return c
    if c in _SHORT:
        return _SHORT[c]
    n = ord(c)
    return f"\\u{n:04X}" if n <= 0xFFFF else f"\\U{n:08X}"


def escape(text: str, keep: str = "") -> str:
    """``text`` with every character that is not printable written as an escape (``\\n``,
    ``\\u001B``, ``\\u202E``); printable text, quotes and backslashes unchanged, and the
    characters of ``keep`` too (``"\\n"`` for text of several lines).  The last guard on a
    whole message line: whatever a message holds, it stays one line and sends no control
    sequence to a terminal or a log."""
    if text.isprintable():
        return text
    return "".join(c if c in keep else _escaped(c, False) for c in text)


def quote(name: object) -> str:
    """A name as it may be shown anywhere: unchanged when it is printable and has no
    leading or trailing space, else in double quotes with TOML/JSON escapes
    (``"d\\n[effects.x]"``, ``"\\u001B]0;title\\u0007"``).

    Parameters
    ----------
    name : object
        A key, file name, drive or table name (``str()`` of it is quoted).

    Returns
    -------
    str
        One line without control characters.
    """
    text = str(name)
    if text.isprintable() and text == text.strip():
        return text
    return '"' + "".join(_escaped(c, True) for c in text) + '"'


def toml_key(name: str) -> str:
    """``name`` as one part of a TOML key: bare when it may be (letters, digits, ``_``, ``-``),
    else a quoted basic string (:func:`quote`'s escapes)."""
    if _BARE_KEY.fullmatch(name):
        return name
    return '"' + "".join(_escaped(c, True) for c in name) + '"'


def csv_cell(text: str) -> str:
    """A text cell of a CSV output: control characters escaped (:func:`escape`), and a text
    that a spreadsheet would run as a formula (starting with ``= + - @``, a tab or a carriage
    return) prefixed with ``'``, as OWASP advises.  Numbers (``-3.5``, ``+1e3``) are left alone."""
    if text[:1] in FORMULA_PREFIXES and not _NUMBER.fullmatch(text):
        text = "'" + text
    return escape(text)
