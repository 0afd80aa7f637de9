"""Shared fixtures: paths to the shipped configs and a CLI runner."""

from __future__ import annotations

import gc
import os
from pathlib import Path

import pytest
import typer.testing
from hypothesis import settings
from typer.testing import CliRunner

from tests.support.commands import click_group
from tests.support.paths import CONFIGS, MCH50, ROOT  # noqa: F401  (the shared paths)

# No per-example deadline (a loaded 2-core machine must not turn a slow example into a
# failure).  Under CI (CI=true) the examples are derandomised, so a run is reproducible;
# locally they stay random, to keep finding new cases.
settings.register_profile("dev", deadline=None)
settings.register_profile("ci", deadline=None, derandomize=True, database=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")


def pytest_configure(config):
    """The costly property tests draw their full count of examples in CI and in any run of the slow
    set, a quarter in the everyday run (tests/support/examples.py)."""
    from tests.support import examples

    examples.FULL = (bool(os.environ.get("CI")) or os.environ.get("WORMGEAR_TEST_EXAMPLES") == "full"
                     or (config.getoption("markexpr") or "").strip() != "not slow")


def pytest_collection_finish(session):
    """What collecting made (the imported modules, the test items: most of the process's objects) stays
    for the whole run: gc.freeze moves it out of the collector's generations, so that the full
    collections during the tests and at the end do not walk it again (about half a second of CPU)."""
    gc.freeze()


# typer's CliRunner.invoke turns the Typer app into a click command on every call
# (typer.main.get_command: every command's signature and annotations read again, about 0.05 s of
# CPU, a call of any test that runs the CLI in process).  The program does that once per process;
# the runners here do it once per app (tests/support/commands.py) and invoke that same command.
typer.testing._get_command = click_group


@pytest.fixture
def runner() -> CliRunner:
    return CliRunner()


@pytest.fixture
def mch50_path() -> Path:
    return MCH50


@pytest.fixture
def mch50_spec():
    from wormgear_cli.spec.loader import load_spec

    return load_spec(MCH50)


def _slow_set() -> tuple[frozenset, tuple]:
    """The node ids of tests/slow_set.txt: exact ids, and ids cut short (no closing "]") as prefixes."""
    exact, prefixes = set(), []
    for line in (Path(__file__).parent / "slow_set.txt").read_text(encoding="utf-8").splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        (prefixes.append(line) if "[" in line and not line.endswith("]") else exact.add(line))
    return frozenset(exact), tuple(prefixes)


@pytest.hookimpl(tryfirst=True)  # before pytest's own -m selection reads the marks
def pytest_collection_modifyitems(config, items):
    exact, prefixes = _slow_set()
    for item in items:
        if item.nodeid in exact or item.nodeid.startswith(prefixes):
            item.add_marker(pytest.mark.slow)
