"""The recipes of docs/scaling.md, run as written with small sizes: a Slurm array (its
environment simulated, 0-based), GNU parallel (or xargs, which takes the same line) and
make -j.  Each merged result must equal the unsharded run byte for byte."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys

import pytest

from tests.support.paths import MCH50, ROOT

SMALL = {"SAMPLES": "3000", "PARTS": "3", "I": "2:10:5", "L": "100:300:7"}


def recipe(name: str) -> str:
    text = (ROOT / "docs" / "scaling.md").read_text()
    m = re.search(rf"<!-- recipe: {name} -->\n```\w*\n(.*?)```", text, re.S)
    assert m, f"recipe {name} not found in docs/scaling.md"
    return m.group(1)


@pytest.fixture
def workdir(tmp_path):
    """A folder with the drive, and `wormgear` on the PATH running this tree."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    shim = bin_dir / "wormgear"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m wormgear_cli "$@"\n')
    shim.chmod(0o755)
    work = tmp_path / "work"
    work.mkdir()
    shutil.copy(MCH50, work / "drive.toml")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("SLURM_", "SGE_", "PBS_"))}
    env.update(SMALL, DRIVE="drive.toml", PATH=f"{bin_dir}{os.pathsep}{env.get('PATH', '')}",
               PYTHONPATH=str(ROOT))
    return work, env


def unsharded(work, env) -> tuple[bytes, bytes]:
    def out(*args):
        return subprocess.run(["wormgear", *args], cwd=work, env=env, capture_output=True, check=True).stdout

    return (out("tolerance", "drive.toml", "--samples", SMALL["SAMPLES"], "--seed", "1", "--format", "json"),
            out("sweep", "drive.toml", "--i", SMALL["I"], "--l-mm", SMALL["L"], "--format", "csv"))


def check_merged(work, env) -> None:
    tolerance, sweep = unsharded(work, env)
    assert (work / "tolerance.json").read_bytes() == tolerance
    assert (work / "sweep.csv").read_bytes() == sweep


def bash(script: str, work, env, **extra):
    r = subprocess.run(["bash", "-euo", "pipefail", "-c", script], cwd=work, env={**env, **extra},
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r


def test_slurm_array_0_based_then_merge(workdir):
    work, env = workdir
    script = recipe("slurm")
    assert "#SBATCH --array=0-99" in script
    array = {"SLURM_ARRAY_TASK_MIN": "0", "SLURM_ARRAY_TASK_MAX": "2", "SLURM_ARRAY_TASK_STEP": "1",
             "SLURM_ARRAY_TASK_COUNT": "3", "SLURM_CPUS_PER_TASK": "2"}
    for task in (2, 0, 1):
        r = bash(script, work, env, SLURM_ARRAY_TASK_ID=str(task), **array)
        assert f"shard {task + 1}/3 (--shard auto) from Slurm: SLURM_ARRAY_TASK_ID={task}," in r.stderr
    again = bash(script, work, env, SLURM_ARRAY_TASK_ID="1", **array)  # a re-submitted task: skipped
    assert again.stderr.count("is complete and its manifest matches this run; skipped") == 2
    wrapped = re.search(r"--wrap \\\n\s*'(.*)'", recipe("slurm-merge")).group(1)
    bash(wrapped, work, env)
    check_merged(work, env)


@pytest.mark.parametrize("runner", ["parallel", "xargs"])
def test_gnu_parallel_or_xargs_then_merge(workdir, runner):
    if runner == "parallel" and shutil.which("parallel") is None:
        pytest.skip("GNU parallel is not installed")
    work, env = workdir
    script = recipe("parallel")
    if runner == "xargs":
        script = script.replace("parallel --jobs 2", "xargs -P 2 -I{}")
    bash(script, work, env)
    check_merged(work, env)


@pytest.mark.skipif(shutil.which("make") is None, reason="make is not installed")
def test_make_j_then_merge(workdir):
    work, env = workdir
    (work / "Makefile").write_text(recipe("make"))
    args = ["make", "-j", "2", *(f"{k}={v}" for k, v in SMALL.items())]
    r = subprocess.run(args, cwd=work, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    check_merged(work, env)
    r = subprocess.run(args, cwd=work, env=env, capture_output=True, text=True)
    assert "Nothing to be done" in r.stdout or "up to date" in r.stdout
