"""Command-line mistakes (unknown option, bad choice, missing argument, unknown command) give the
project's one ``error:`` line naming where to look, and exit 2 -- not click's three-line usage block."""

from __future__ import annotations

import pytest

from tests.support.paths import MCH50
from wormgear_cli.cli import app


@pytest.mark.parametrize("args,line", [
    (["analyze", str(MCH50), "-f", "xml"],
     "error: Invalid value for '--format' / '-f': 'xml' is not one of 'table', 'json', 'csv'; "
     "see 'wormgear analyze --help'"),
    (["analyze", str(MCH50), "--bogus"], "error: No such option: --bogus; see 'wormgear analyze --help'"),
    (["analyze"], "error: Missing argument 'DRIVE.toml'; see 'wormgear analyze --help'"),
    (["diagnose", str(MCH50)], "error: Missing argument 'DATA.csv'; see 'wormgear diagnose --help'"),
    (["analyze", str(MCH50), "-u", "rad"],
     "error: Invalid value for '--unit' / '-u': 'rad' is not one of 'deg', 'arcmin', 'arcsec', 'urad'; "
     "see 'wormgear analyze --help'"),
    (["bogus"], "error: No such command 'bogus'; see 'wormgear --help'"),
    (["--bogus"], "error: No such option: --bogus; see 'wormgear --help'"),
])
def test_a_usage_mistake_is_one_error_line_and_exit_2(runner, args, line):
    r = runner.invoke(app, args)
    assert r.exit_code == 2
    assert r.stdout == ""
    assert r.stderr == line + "\n"


def test_no_arguments_still_shows_the_help(runner):
    r = runner.invoke(app, [])
    assert "Usage: wormgear" in r.output and "analyze" in r.output
