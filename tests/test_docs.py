"""The README documents every command, option, spec key and catalogue effect."""

from __future__ import annotations

import re

import pytest
from typer.main import get_command

from wormgear_cli.cli import app
from wormgear_cli.models.effects import EFFECTS
from wormgear_cli.spec import FIELDS

from tests.conftest import ROOT

README = (ROOT / "README.md").read_text(encoding="utf-8")
COMMANDS = get_command(app).commands


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_command_has_a_readme_section(name):
    assert re.search(rf"^#+ `wormgear {name}\b", README, flags=re.M), f"no README heading for {name}"


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_option_is_mentioned(name):
    for param in COMMANDS[name].params:
        opts = [o for o in getattr(param, "opts", []) if o.startswith("--")]
        if not opts or opts[0] == "--help":
            continue
        assert any(o in README for o in opts), f"{name}: {opts[0]} is not documented in README.md"


@pytest.mark.parametrize("field", FIELDS, ids=lambda f: f.path)
def test_every_spec_key_is_in_the_reference(field):
    assert f"`{field.key}`" in README and f"[{field.section}]" in README


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_every_effect_is_documented_with_its_keys(name):
    assert f"`{name}`" in README
    for p in EFFECTS[name].params:
        assert p.key in README, f"{name}.{p.key}"


def test_readme_commands_for_setup_match_ci():
    ci = (ROOT / ".ci" / "run").read_text()
    assert "pip install -e '.[test,plot,docs]' && python -m pytest" in README
    assert "-e '.[test,plot,docs]'" in ci and "pytest" in ci
