"""analyze, check, new and grade keep their fast start: they never import scipy, matplotlib or
the statistics packages (the start-up budget, <= 1.2x ``import numpy, typer``, is measured by
bench/bench_startup.py; here only what is imported is checked, never the time)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from tests.support.paths import MCH50, ROOT

HEAVY = ("scipy", "matplotlib", "wormgear_cli.diagnosis", "wormgear_cli.tolerance", "statsmodels",
         "wormgear_cli.measurement.reader", "wormgear_cli.measurement.readers.", "wormgear_cli.api")
# (the registry wormgear_cli.measurement.readers itself is names only: --help lists its formats)

PROBE = f"""
import json, sys
from wormgear_cli.cli import main
sys.argv = ["wormgear", *json.loads(sys.argv[1])]
try:
    main()
except SystemExit:
    pass
heavy = sorted({{m.split(".")[0] if m.startswith(("scipy", "matplotlib", "statsmodels")) else m
                for m in sys.modules if m.startswith({HEAVY!r})
                and m != "wormgear_cli.measurement.readers"}})
sys.stderr.write("LOADED " + json.dumps(heavy) + "\\n")
"""


@pytest.mark.parametrize("args", [
    ["analyze", str(MCH50)],
    ["analyze", str(MCH50), "--format", "json"],
    ["check", str(MCH50)],
    ["analyze", str(ROOT / "configs" / "rotary-table-precision.toml")],
    ["grade", "--grade", "6", "--module-mm", "2", "--diameter-mm", "100", "--face-width-mm", "20"],
    ["--help"],
])
def test_fast_commands_load_no_heavy_module(args, tmp_path):
    proc = subprocess.run([sys.executable, "-c", PROBE, json.dumps(args)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=120)
    line = [ln for ln in proc.stderr.splitlines() if ln.startswith("LOADED ")][-1]
    assert json.loads(line[len("LOADED "):]) == []


def test_the_probe_sees_a_heavy_import(tmp_path):
    """The check can fail: a command that does need scipy (tolerance) shows it."""
    args = ["tolerance", str(MCH50), "--samples", "10", "--metrics", "paper", "--format", "json"]
    proc = subprocess.run([sys.executable, "-c", PROBE, json.dumps(args)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=300)
    line = [ln for ln in proc.stderr.splitlines() if ln.startswith("LOADED ")][-1]
    assert "scipy" in json.loads(line[len("LOADED "):])
