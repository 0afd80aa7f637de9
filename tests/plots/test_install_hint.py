"""The plot install hint works where the user is: wormgear-cli is installed from a checkout, not
from the package index (where an unrelated `wormgear` lives), so no hint may tell to install it by
name; the hint installs the plot extra's own requirement."""

from __future__ import annotations

import re
import shlex
import tomllib

from tests.support.paths import ROOT
from wormgear_cli.plots import INSTALL_HINT

PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
#: a pip command that installs this project by its name from the index
BY_NAME = re.compile(r"pip install\s+['\"]?wormgear(-cli)?\b")


def _requirement_name(req: str) -> str:
    return re.split(r"[<>=!~;\[ ]", req, maxsplit=1)[0].strip().lower()


def test_the_hint_installs_what_the_plot_extra_needs():
    command = INSTALL_HINT.split(": ", 1)[1]
    words = shlex.split(command)
    assert words[:2] == ["pip", "install"]
    wanted = {_requirement_name(r) for r in PYPROJECT["project"]["optional-dependencies"]["plot"]}
    assert {_requirement_name(w) for w in words[2:]} == wanted
    assert not BY_NAME.search(INSTALL_HINT)


def test_no_page_and_no_help_installs_the_project_by_name():
    texts = {"README.md": (ROOT / "README.md").read_text(encoding="utf-8")}
    texts.update({str(p.relative_to(ROOT)): p.read_text(encoding="utf-8") for p in (ROOT / "docs").rglob("*.md")})
    texts.update({str(p.relative_to(ROOT)): p.read_text(encoding="utf-8")
                  for p in (ROOT / "wormgear_cli").rglob("*.py")})
    for name, text in texts.items():
        assert not BY_NAME.search(text), f"{name} tells to install the project from the package index"
