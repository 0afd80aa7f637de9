"""Shared fixtures: paths to the shipped configs and a CLI runner."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

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
    from wormgear_cli.spec import load_spec

    return load_spec(MCH50)
