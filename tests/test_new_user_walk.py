"""What a new user does first works as written: the README's set-up makes a virtual environment
before installing, and its quick start and the tutorial can be followed one after the other in
one directory (neither stops with 'already exists' because the other wrote the file)."""

from __future__ import annotations

import contextlib
import re
import shlex
import shutil

import pytest

from tests.support.paths import ROOT
from wormgear_cli import _docgen

README = (ROOT / "README.md").read_text(encoding="utf-8")
TUTORIAL = (ROOT / "docs" / "tutorial.md").read_text(encoding="utf-8")


def readme_commands() -> list[tuple[str, int]]:
    """The quick start's wormgear commands (continuation lines joined, comments dropped) with the
    exit code each is shown to give: 0, or N where its comment starts "exit N"."""
    section = README[README.index("## Quick start"):]
    block = re.search(r"```sh\n(.*?)```", section, flags=re.S).group(1)
    commands = []
    for line in block.replace("\\\n", " ").splitlines():
        line, _, comment = line.partition("  #")
        line = line.strip()
        if line.startswith("wormgear "):
            code = re.match(r"\s*exit (\d+)", comment)
            commands.append((line[len("wormgear "):], int(code.group(1)) if code else 0))
    return commands


def tutorial_steps() -> list[tuple[str, str, str]]:
    """(kind, argument, block) of the tutorial's run/write steps, in page order."""
    return [(m.group(1), m.group(3), m.group(5)) for m in _docgen._DIRECTIVE.finditer(TUTORIAL)
            if m.group(1) in ("run", "write")]


def _new_targets(commands) -> set[str]:
    return {shlex.split(c)[1] for c in commands if c.startswith("new ")}


@pytest.mark.parametrize("page", ["README.md", "docs/index.md"])
def test_the_set_up_makes_a_virtual_environment_before_installing(page):
    text = (ROOT / page).read_text(encoding="utf-8")
    setup = text[text.index("## Set-up"):]
    setup = setup[:setup.index("\n## ")]
    assert "python3 -m venv .venv" in setup and ". .venv/bin/activate" in setup
    assert setup.index("python3 -m venv") < setup.index("pip install")


def test_the_readme_and_the_tutorial_write_different_templates():
    readme = _new_targets(c for c, _ in readme_commands())
    tutorial = _new_targets(arg for kind, arg, _ in tutorial_steps() if kind == "run")
    assert readme and tutorial
    assert not readme & tutorial, f"both write {readme & tutorial}: the second stops with 'already exists'"


@pytest.mark.slow
def test_the_tutorial_then_the_readme_run_in_one_directory(tmp_path, runner):
    from wormgear_cli.cli import app

    shutil.copytree(ROOT / "configs", tmp_path / "configs")
    env = {"COLUMNS": "80", "NO_COLOR": "1"}
    with contextlib.chdir(tmp_path):
        for kind, arg, block in tutorial_steps():
            if kind == "write":
                (tmp_path / arg).write_text(block, encoding="utf-8")
                continue
            shown = re.search(r"\[exit code (\d+)\]", block)
            r = runner.invoke(app, shlex.split(arg), env=env)
            assert r.exit_code == (int(shown.group(1)) if shown else 0), f"tutorial: wormgear {arg}\n{r.output}"
        for command, code in readme_commands():
            r = runner.invoke(app, shlex.split(command), env=env)
            assert r.exit_code == code, f"README: wormgear {command}\n{r.output}"
            assert "already exists" not in r.output
