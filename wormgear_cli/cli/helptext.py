"""How every command's ``--help`` is laid out: no line break inside a word, examples whole.

click wraps help text at hyphens, so an example such as ``--face-width-mm 20`` could come
out as ``--face-`` / ``width-mm 20`` and could not be copied.  :class:`HelpCommand` (the
class of every ``wormgear`` command) wraps at spaces only, and sets each ``Example:``
paragraph on lines of its own, never re-wrapped: the command on one line, or, when it is
wider than the help text, continued with `` \\`` before an option, so that the lines paste
into a shell as one command.
"""

from __future__ import annotations

import re

from typer.core import TyperCommand

#: stands in for "-" while click wraps (it is no break point for a wrapper), restored after
_NO_BREAK_HYPHEN = "\u2011"
#: what starts an example paragraph, and the indent of its continuation lines
EXAMPLE, CONTINUATION_INDENT = "Example: ", "    "
#: a shell word: runs of plain characters and quoted strings (a quoted string may hold spaces)
_WORD = re.compile(r"""(?:[^\s"']+|"[^"]*"|'[^']*')+""")


def example_lines(command: str, width: int) -> list[str]:
    """``Example: COMMAND`` as shell lines of at most ``width`` characters where possible:
    broken only between whole words, never between an option and its value (nor between the
    program and the command's name), each line but the last ending in `` \\``.  A unit
    longer than ``width`` stays whole on its line."""
    units: list[str] = []
    for word in _WORD.findall(command):
        joins = units and " " not in units[-1] and (units[-1].startswith("-") or units[-1] == "wormgear")
        if joins and not word.startswith("-") and word not in ("&&", "|", "||"):
            units[-1] += " " + word
        else:
            units.append(word)
    lines = [EXAMPLE + (units[0] if units else "")]
    for unit in units[1:]:
        if len(lines[-1]) + 1 + len(unit) + 2 <= width:
            lines[-1] += " " + unit
        else:
            lines[-1] += " \\"
            lines.append(CONTINUATION_INDENT + unit)
    return [EXAMPLE + command] if len(EXAMPLE) + len(command) <= width else lines


def layout(text: str, width: int) -> str:
    """Help text with each ``Example: COMMAND`` paragraph made a block click does not re-wrap
    (its ``\\b`` marker), laid out by :func:`example_lines`."""
    out = []
    for paragraph in text.split("\n\n"):
        head, sep, command = paragraph.strip().partition(EXAMPLE)
        if head or not sep:
            out.append(paragraph)
            continue
        out.append("\n".join(["\b", *example_lines(" ".join(command.split()), width)]))
    return "\n\n".join(out)


def _protected(text: str) -> str:
    return text.replace("-", _NO_BREAK_HYPHEN)


class HelpCommand(TyperCommand):
    """A typer command whose help wraps at spaces only and keeps examples whole (see the module)."""

    def format_help(self, ctx, formatter) -> None:
        write_text, write_dl = formatter.write_text, formatter.write_dl

        def text(t: str) -> None:
            write_text(_protected(layout(t, formatter.width - formatter.current_indent)))

        def dl(rows, *args, **kwargs) -> None:
            write_dl([(_protected(a), _protected(b)) for a, b in rows], *args, **kwargs)

        formatter.write_text, formatter.write_dl = text, dl  # this formatter only, for this help
        try:
            super().format_help(ctx, formatter)
        finally:
            del formatter.write_text, formatter.write_dl
        formatter.buffer[:] = [s.replace(_NO_BREAK_HYPHEN, "-") for s in formatter.buffer]
