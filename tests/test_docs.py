"""The documentation agrees with the code.

* The generated reference pages (``docs/reference/``) are what
  ``python -m wormgear_cli._docgen`` writes now: a help text, spec key or
  effect changed without regenerating them fails here.
* Every command has a page under ``docs/commands/`` that mentions each of its
  options; every spec key and catalogue effect is in its reference page.
* The README's set-up commands are the ones CI runs; CI builds the docs strictly.
* Every page is reachable from the nav, every nav entry and README link exists,
  and no page points outside the project.
"""

from __future__ import annotations

import re

import pytest

from tests.support.commands import click_group
from tests.support.paths import ROOT
from wormgear_cli import _docgen
from wormgear_cli.cli import app
from wormgear_cli.physics.effects import EFFECTS
from wormgear_cli.spec.loader import FIELDS

DOCS = ROOT / "docs"
README = (ROOT / "README.md").read_text(encoding="utf-8")
MKDOCS = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
COMMANDS = click_group(app).commands
SETUP = ("pip install . && wormgear analyze configs/mch50.toml",
         "pip install -e '.[test,plot,docs]' && python -m pytest")


def page(path: str) -> str:
    return (DOCS / path).read_text(encoding="utf-8")


def pages():
    return sorted(p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md"))


# --- generated pages ------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def generated():
    return _docgen.generate()


@pytest.mark.pinned  # the help text as the current typer renders it
@pytest.mark.parametrize("path", sorted(_docgen.PAGES))
def test_generated_page_is_fresh(generated, path):
    assert (DOCS / path).is_file(), f"docs/{path} is missing: run python -m wormgear_cli._docgen"
    assert page(path) == generated[path], f"docs/{path} is stale: run python -m wormgear_cli._docgen"


def test_generation_is_deterministic(generated):
    assert _docgen.generate() == generated


def test_cli_reference_holds_each_commands_help_at_80_columns():
    text = page("reference/cli.md")
    for name in COMMANDS:
        assert f"## `wormgear {name}`" in text
        assert f"Usage: wormgear {name} [OPTIONS]" in text
    blocks = re.findall(r"^```text\n(.*?)^```$", text, flags=re.M | re.S)
    assert len(blocks) == len(COMMANDS) + 1
    assert max(len(line) for block in blocks for line in block.splitlines()) <= 80
    assert "\x1b[" not in text, "colour codes in the CLI reference"


def test_the_grade_example_of_the_cli_reference_pastes_whole():
    """The example is one shell command over lines continued with ' \\', no option cut in two."""
    text = page("reference/cli.md")
    grade = text[text.index("## `wormgear grade`"):]
    lines = grade[grade.index("Example: "):].splitlines()
    command = lines[0].strip()
    k = 0
    while command.endswith(" \\"):
        k += 1
        command = command[:-2] + " " + lines[k].strip()
    assert command == "Example: wormgear grade --grade 6 --module-mm 2 --diameter-mm 100 --face-width-mm 20"
    assert "--face-\n" not in text


@pytest.mark.slow
def test_tutorial_outputs_are_fresh():
    """The tutorial's outputs are what its commands print now (re-runs the whole session)."""
    for name in _docgen.SESSION_PAGES:
        text = page(name)
        assert _docgen.refresh_session(text, ROOT) == text, \
            f"docs/{name} is stale: run python -m wormgear_cli._docgen --session"


# --- hand-written pages cover the code ------------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_command_has_a_page(name):
    path = DOCS / "commands" / f"{name}.md"
    assert path.is_file(), f"no page docs/commands/{name}.md"
    assert re.match(rf"# `wormgear {name}`", path.read_text(encoding="utf-8")), \
        f"docs/commands/{name}.md must start with the heading # `wormgear {name}`"
    assert f"commands/{name}.md" in MKDOCS, f"docs/commands/{name}.md is not in the nav of mkdocs.yml"


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_option_is_documented_on_its_page(name):
    path = DOCS / "commands" / f"{name}.md"
    text = path.read_text(encoding="utf-8") if path.is_file() else ""
    for param in COMMANDS[name].params:
        opts = [o for o in getattr(param, "opts", []) if o.startswith("--")]
        if not opts or opts[0] == "--help":
            continue
        assert any(o in text for o in opts), f"{name}: {opts[0]} is not documented in docs/commands/{name}.md"


def _section_table(text: str, section: str) -> str:
    start = text.index(f"## `[{section}]`")
    end = text.find("\n## ", start + 1)
    return text[start:end if end > 0 else len(text)]


@pytest.mark.parametrize("field", FIELDS, ids=lambda f: f.path)
def test_every_spec_key_is_in_the_reference(field):
    table = _section_table(page("reference/spec.md"), field.section)
    assert f"| `{field.key}` |" in table


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_every_effect_is_documented_with_its_keys(name):
    text = page("reference/effects.md")
    start = text.index(f"## `{name}`")
    end = text.find("\n## ", start + 1)
    section = text[start:end if end > 0 else len(text)]
    for p in EFFECTS[name].params:
        assert f"| `{p.key}` |" in section, f"{name}.{p.key}"
    assert f"`{name}`" in page("models.md"), f"{name} has no formula in docs/models.md"


# --- README, CI, site -----------------------------------------------------------------------------------------------


def test_readme_commands_for_setup_match_ci():
    ci = (ROOT / ".ci" / "run").read_text()
    for command in SETUP:
        assert command in README and command in page("index.md")
    assert "-e '.[test,plot,docs]'" in ci and "pytest" in ci


def test_ci_builds_the_docs_strictly_outside_the_tree():
    ci = (ROOT / ".ci" / "run").read_text()
    assert re.search(r"mkdocs build --strict --site-dir \"\$\(mktemp -d\)\"", ci)
    assert ci.index("pytest") < ci.index("mkdocs build")


def test_readme_stays_short():
    assert len(README.splitlines()) <= 200, "README.md is over 200 lines: move the detail to docs/"


def test_readme_links_exist():
    for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", README):
        assert (ROOT / target).exists(), f"README.md links to {target}, which does not exist"


def test_every_nav_entry_exists_and_every_page_is_in_the_nav():
    nav = set(re.findall(r"^\s*- (?:[^:\n]+: )?(\S+\.md)\s*$", MKDOCS, flags=re.M))
    assert nav, "no nav in mkdocs.yml"
    for path in sorted(nav):
        assert (DOCS / path).is_file(), f"mkdocs.yml: nav entry {path} does not exist"
    for path in pages():
        if not path.endswith("-notes.md"):
            assert path in nav, f"docs/{path} is not in the nav of mkdocs.yml: add one line for it"


@pytest.mark.parametrize("path", pages())
def test_pages_stay_inside_the_project(path):
    text = page(path)
    assert "../shared" not in text and "/work/" not in text, f"docs/{path} points outside the project"
