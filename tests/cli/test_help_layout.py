"""--help never breaks a line inside a word, and every example can be copied into a shell whole,
at any terminal width (click wraps at hyphens: --face- / width-mm)."""

from __future__ import annotations

import re
import shlex

import pytest
from typer.main import get_command

from wormgear_cli.cli import app
from wormgear_cli.cli.helptext import HelpCommand, example_lines

COMMANDS = get_command(app).commands
WIDTHS = (40, 60, 72, 80, 100, 120)


def _help(runner, name: str, width: int) -> str:
    r = runner.invoke(app, [name, "--help"], env={"COLUMNS": str(width)})
    assert r.exit_code == 0
    return r.stdout


def _examples(text: str) -> list[str]:
    """Each ``Example:`` of a help text as one command line (continuation lines joined)."""
    out, lines = [], text.splitlines()
    for k, line in enumerate(lines):
        if line.strip().startswith("Example: "):
            command = line.strip()[len("Example: "):]
            while command.endswith(" \\"):
                k += 1
                command = command[:-2] + " " + lines[k].strip()
            out.append(command)
    return out


def _docstring_examples(name: str) -> list[str]:
    doc = COMMANDS[name].help
    return [" ".join(p.strip()[len("Example: "):].split()) for p in doc.split("\n\n")
            if p.strip().startswith("Example: ")]


def test_every_command_lays_out_its_help_this_way():
    for name, cmd in COMMANDS.items():
        assert isinstance(cmd, HelpCommand), f"{name}: register it with @app.command(cls=HelpCommand)"


@pytest.mark.parametrize("name", sorted(COMMANDS))
@pytest.mark.parametrize("width", WIDTHS)
def test_examples_come_out_whole_at_every_width(runner, name, width):
    text = _help(runner, name, width)
    wanted = _docstring_examples(name)
    assert wanted, f"{name}: no example in its help"
    assert _examples(text) == wanted
    for command in wanted:
        words = shlex.split(command)
        assert words[:2] == ["wormgear", name]
        options = {o for p in COMMANDS[name].params for o in getattr(p, "opts", [])}
        for w in words:  # every option of the example is one of the command's, whole
            if w.startswith("--") and w != "--help":
                assert w.split("=")[0] in options, f"{name}: {w} in the example is not an option"


@pytest.mark.parametrize("name", sorted(COMMANDS))
@pytest.mark.parametrize("width", WIDTHS)
def test_no_line_ends_inside_a_hyphenated_word(runner, name, width):
    for line in _help(runner, name, width).splitlines():
        assert not re.search(r"\w-$", line), f"{name} at {width} columns: {line!r}"


def test_example_lines_break_only_before_options_and_fit():
    cmd = "wormgear grade --grade 6 --module-mm 2 --diameter-mm 100 --face-width-mm 20"
    for width in range(30, 100):
        lines = example_lines(cmd, width)
        assert " ".join(ln.strip().removesuffix(" \\").strip() for ln in lines) == "Example: " + cmd
        for ln in lines[1:]:
            assert ln.strip().startswith("--")
        assert all(ln.endswith(" \\") for ln in lines[:-1])
        longest_unit = len("    --face-width-mm 20")
        assert all(len(ln) <= max(width, longest_unit + 2, len("Example: wormgear grade --grade 6 \\")) for ln in lines)
    quoted = 'wormgear measure x.csv --map angle_deg="Position (deg)" --map error_arcsec=Deviation'
    lines = example_lines(quoted, 50)
    assert shlex.split(" ".join(ln.removesuffix(" \\") for ln in lines))[1:] == shlex.split(quoted)
