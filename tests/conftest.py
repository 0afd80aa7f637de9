"""Shared fixtures: paths to the shipped configs and a CLI runner."""

from __future__ import annotations

from pathlib import Path

import os

import pytest
from hypothesis import settings
from typer.testing import CliRunner

# No per-example deadline (a loaded 2-core machine must not turn a slow example into a
# failure).  Under CI (CI=true) the examples are derandomised, so a run is reproducible;
# locally they stay random, to keep finding new cases.
settings.register_profile("dev", deadline=None)
settings.register_profile("ci", deadline=None, derandomize=True, database=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")

ROOT = Path(__file__).resolve().parent.parent
CONFIGS = ROOT / "configs"
MCH50 = CONFIGS / "mch50.toml"


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
