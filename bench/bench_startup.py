"""Start-up cost: `wormgear analyze configs/mch50.toml --format json` vs `python -c "import numpy, typer"`.

The issue's bar: analyze costs at most 1.2x the bare imports in wall time.
Runs each command N times alternately (after one warm-up each) and prints the
medians and their ratio, in wall time and in CPU time of the child process (user + system:
the steadier figure on a shared, loaded machine), and the same for a drive of three stages
(configs/radar-pedestal-2start.toml).  Usage: python bench/bench_startup.py [N]
"""

from __future__ import annotations

import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def wall(cmd: list[str]) -> float:
    return timed(cmd)[0]


def timed(cmd: list[str]) -> tuple[float, float]:
    """(wall, cpu) seconds of one run of ``cmd``; cpu = the child's user + system time."""
    import os

    before = os.times()
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)
    w = time.perf_counter() - t0
    after = os.times()
    return w, (after.children_user - before.children_user) + (after.children_system - before.children_system)


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 30
    # the console script of this interpreter's environment, not the first one on PATH: a
    # version manager's shim (pyenv's is a shell script running `pyenv exec`) adds ~25 ms
    # that is not the program's
    here = Path(sys.executable).parent / "wormgear"
    exe = str(here) if here.exists() else shutil.which("wormgear")
    analyze = ([exe] if exe else [sys.executable, "-m", "wormgear_cli"]) + [
        "analyze", "configs/mch50.toml", "--format", "json"]
    baseline = [sys.executable, "-c", "import numpy, typer"]
    # byte-compile the package as a wheel install does: with PYTHONDONTWRITEBYTECODE set (or an
    # edited source), every run would otherwise compile the modules again (~+10 ms)
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(ROOT / "wormgear_cli")], check=True)
    train = analyze[:-3] + ["configs/radar-pedestal-2start.toml", "--format", "json"]
    wall(analyze), wall(baseline), wall(train)  # warm the file cache
    a, b, c = [], [], []
    for _ in range(n):
        a.append(timed(analyze))
        b.append(timed(baseline))
        c.append(timed(train))
    print(f"runs: {n} each, alternating; {analyze[0]}")
    for k, what in ((0, "wall"), (1, "cpu")):
        ma, mb, mc = (statistics.median(x[k] for x in runs) for runs in (a, b, c))
        lo_a, lo_b, lo_c = (min(x[k] for x in runs) for runs in (a, b, c))
        print(f"[{what}] import numpy, typer            median {mb * 1000:7.1f} ms  (min {lo_b * 1000:.1f})")
        print(f"[{what}] analyze mch50 --format json    median {ma * 1000:7.1f} ms  (min {lo_a * 1000:.1f})")
        print(f"[{what}] analyze radar (3 stages)       median {mc * 1000:7.1f} ms  (min {lo_c * 1000:.1f})")
        print(f"[{what}] ratio (median): {ma / mb:.3f}, 3 stages {mc / mb:.3f}   (bar: <= 1.2)")
        print(f"[{what}] ratio (min):    {lo_a / lo_b:.3f}, 3 stages {lo_c / lo_b:.3f}   (the least disturbed runs)")


if __name__ == "__main__":
    main()
