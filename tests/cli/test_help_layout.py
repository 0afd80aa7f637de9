"""--help never breaks a line inside a word, and every example can be copied into a shell whole,
at any terminal width (click wraps at hyphens: --face- / width-mm)."""

from __future__ import annotations

import functools
import re
import shlex

import pytest

from tests.support.commands import click_group
from wormgear_cli.cli import app
from wormgear_cli.cli.helptext import HelpCommand, example_lines

#: the app as the click group the program builds once per process (tests/support/commands.py)
GROUP = click_group(app)
COMMANDS = GROUP.commands
WIDTHS = (40, 60, 72, 80, 100, 120)
#: a shell word, quoted parts kept whole (--map angle_deg="Position (deg)")
SHELL_WORD = re.compile(r"""(?:[^\s"']+|"[^"]*"|'[^']*')+""")


def _help(runner, name: str, width: int) -> str:
    """``COLUMNS=width wormgear NAME --help``: click draws help min(width, 80) - 2 columns wide, at
    least 50 (the test runner forces 80, so the width is given to the context, as the CLI's is)."""
    return _drawn_help(name, max(min(width, 80) - 2, 50))


@functools.cache
def _drawn_help(name: str, drawn: int) -> str:
    """A command's help drawn ``drawn`` columns wide (drawn once: several widths draw alike, and two
    tests read each)."""
    from typer._click import Context

    cmd = COMMANDS[name]
    root = Context(GROUP, info_name="wormgear", terminal_width=drawn, max_content_width=drawn)
    ctx = Context(cmd, info_name=name, parent=root, terminal_width=drawn, max_content_width=drawn)
    return cmd.get_help(ctx) + "\n"


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


@pytest.mark.parametrize("command", [
    "wormgear grade --grade 6 --module-mm 2 --diameter-mm 100 --face-width-mm 20",
    "wormgear compare configs/mch50.toml configs/rotary-table-precision.toml --samples 2e4",
    'wormgear measure export.csv --map angle_deg="Position (deg)" --map error_arcsec=Deviation',
])
def test_example_lines_are_filled_greedily_to_the_width(command):
    """Each line takes every unit that fits (with its ' \\'), no more: a line and the next line's
    first unit would not fit together; the program and the command name stay together."""
    for width in range(40, 101):
        lines = example_lines(command, width)
        if len("Example: ") + len(command) <= width:
            assert lines == ["Example: " + command]
            continue
        assert lines[0].startswith("Example: wormgear " + command.split()[1])
        for line, after in zip(lines, lines[1:]):
            body = line.removesuffix(" \\")
            words = SHELL_WORD.findall(after.strip().removesuffix(" \\"))
            first = " ".join(words[:2]) if words[0].startswith("-") and len(words) > 1 and \
                not words[1].startswith("-") else words[0]  # an option goes with its value
            assert len(body) + 1 + len(first) + 2 > width, f"{first!r} would fit on {line!r} at {width}"
            assert len(line) <= width or len(SHELL_WORD.findall(body)) <= 3


def test_positional_arguments_may_go_on_their_own_lines():
    lines = example_lines("wormgear compare configs/mch50.toml configs/rotary-table-precision.toml", 50)
    assert lines == ["Example: wormgear compare configs/mch50.toml \\", "    configs/rotary-table-precision.toml"]


def test_only_a_paragraph_that_starts_with_example_is_laid_out():
    from wormgear_cli.cli.helptext import layout

    text = "Run it as the docs do. Example: wormgear analyze x.toml --unit deg"
    assert layout(text, 40) == text


@pytest.mark.parametrize("width", [50, 60, 72, 80])
def test_example_lines_fit_the_help_width(runner, width):
    """click draws help at min(COLUMNS, 80) - 2 columns (at least 50); the examples fit it."""
    for name in COMMANDS:
        text = _help(runner, name, width)
        lines = text.splitlines()
        for k, line in enumerate(lines):
            if line.strip().startswith("Example: ") or (k and lines[k - 1].endswith(" \\")):
                assert len(line) <= max(min(width, 80) - 2, 50), f"{name} at {width} columns: {line!r}"


def test_the_program_and_the_command_stay_together_and_nothing_is_lost():
    assert example_lines("wormgear grade --grade 6", 20)[0] == "Example: wormgear grade \\"
    assert example_lines("", 40) == ["Example: "]
    lines = example_lines("wormgear compare --samples 2e4 configs/mch50.toml configs/rotary-table-precision.toml", 50)
    assert lines[-1].strip() == "configs/rotary-table-precision.toml"  # a positional after an option's value
    lines = example_lines("wormgear synth a.toml --random-phases --no-spec-effects --seed 1", 48)
    assert [ln.strip().removesuffix(" \\") for ln in lines] == \
        ["Example: wormgear synth a.toml --random-phases", "--no-spec-effects --seed 1"]


@pytest.mark.parametrize("joiner", ["&&", "|", "||"])
def test_a_shell_operator_starts_a_unit_of_its_own(joiner):
    width = len("Example: wormgear new -") + len(" " + joiner) + len(" \\") - 1  # the operator does not fit
    lines = example_lines(f"wormgear new - {joiner} wormgear check x.toml", width)
    assert lines[0] == "Example: wormgear new - \\"
    assert lines[1].strip().startswith(f"{joiner} ")
