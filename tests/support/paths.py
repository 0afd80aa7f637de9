"""Paths of the repository the tests read (the shipped configs, the test data)."""

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
CONFIGS = ROOT / "configs"
MCH50 = CONFIGS / "mch50.toml"
DATA = ROOT / "tests" / "data"
#: the radar pedestal as shipped until the drive trains' second milestone: a worm + spur drive in the legacy
#: two-table form (involute kinematics, ISO 1328 grades); configs/ now holds it with its spur gearmotor
LEGACY_RADAR = DATA / "legacy" / "radar-pedestal-2start.toml"
