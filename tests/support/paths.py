"""Paths of the repository the tests read (the shipped configs, the test data)."""

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
CONFIGS = ROOT / "configs"
MCH50 = CONFIGS / "mch50.toml"
DATA = ROOT / "tests" / "data"
