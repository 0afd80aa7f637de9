"""Start-up cost: `wormgear analyze configs/mch50.toml --format json` vs `python -c "import numpy, typer"`.

The issue's bar: analyze costs at most 1.2x the bare imports in wall time.
Runs each command N times alternately (after one warm-up each) and prints the
medians and their ratio.  Usage: python bench/bench_startup.py [N]
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
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)
    return time.perf_counter() - t0


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
    wall(analyze), wall(baseline)  # warm the file cache
    a, b = [], []
    for _ in range(n):
        a.append(wall(analyze))
        b.append(wall(baseline))
    ma, mb = statistics.median(a), statistics.median(b)
    print(f"runs: {n} each, alternating; {analyze[0]}")
    print(f"import numpy, typer         median {mb * 1000:7.1f} ms  (min {min(b) * 1000:.1f})")
    print(f"wormgear analyze --format json median {ma * 1000:7.1f} ms  (min {min(a) * 1000:.1f})")
    print(f"ratio (median): {ma / mb:.3f}   (bar: <= 1.2)")
    print(f"ratio (min):    {min(a) / min(b):.3f}   (the least disturbed runs; use it on a busy machine)")


if __name__ == "__main__":
    main()
