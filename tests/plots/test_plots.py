"""Same input, same bytes: every plotting command writes identical PNG, SVG and PDF files on
every run (one shared set-up in wormgear_cli.plots)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

pytest.importorskip("matplotlib")

from tests.support.paths import CONFIGS, MCH50, ROOT
from wormgear_cli.cli import app

DATA = CONFIGS / "mch50-warm.csv"

COMMANDS = {
    "simulate": ["simulate", str(MCH50), "--points", "500"],
    "synth": ["synth", str(MCH50), "--seed", "3", "-o", "{dir}/synth.csv"],
    "measure": ["measure", str(DATA), "--drive", str(MCH50)],
    "diagnose": ["diagnose", str(MCH50), str(DATA), "--resamples", "0"],
    "sweep": ["sweep", str(MCH50), "--i", "2:10:4", "--l-mm", "100:300:5", "-f", "csv"],
    "sweep-param": ["sweep", str(MCH50), "--param", "worm_pair.lead_error_mm=0:0.05:4", "-f", "csv"],
}


def _plot(runner, tmp_path, command, name):
    out = tmp_path / name
    args = [a.replace("{dir}", str(tmp_path)) for a in COMMANDS[command]] + ["--plot", str(out)]
    r = runner.invoke(app, args)
    assert r.exit_code in (0, 1), r.stderr  # diagnose/measure may report a failed check; the plot is written
    return out.read_bytes()


@pytest.mark.parametrize("fmt", ["svg", "png"])
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_two_runs_give_the_same_plot_bytes(runner, tmp_path, command, fmt):
    first = _plot(runner, tmp_path, command, f"a.{fmt}")
    second = _plot(runner, tmp_path, command, f"b.{fmt}")
    assert len(first) > 1000
    assert first == second


def test_pdf_is_reproducible_and_undated(runner, tmp_path):
    first = _plot(runner, tmp_path, "simulate", "a.pdf")
    second = _plot(runner, tmp_path, "simulate", "b.pdf")
    assert first == second
    assert b"/CreationDate" not in first and b"/Producer" not in first


def test_svg_has_no_date_and_no_random_ids_across_processes(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    outs = []
    for k in range(2):
        out = tmp_path / f"p{k}.svg"
        r = subprocess.run([sys.executable, "-m", "wormgear_cli", *COMMANDS["simulate"], "--plot", str(out),
                            "-o", str(tmp_path / f"s{k}.csv")], env=env, stderr=subprocess.PIPE, timeout=300)
        assert r.returncode == 0, r.stderr.decode()
        outs.append(out.read_bytes())
    assert outs[0] == outs[1]
    assert b"<dc:date>" not in outs[0]
