"""Speed-up of --jobs: the same command at --jobs 1 and --jobs 2 (or --jobs N), side by side.

Run: python bench/bench_jobs.py [--repeat R] [--jobs N] [--quick]
Cases (configs/mch50.toml):
  * tolerance, 10^6 samples, every metric (--format json);
  * tolerance, 10^6 samples, the paper's metrics, the samples CSV (--format csv, 0.5 GB);
  * sweep, 10^7 points (--i 2:10:1000 --l-mm 100:300:10000 --format csv, 1.1 GB);
  * simulate --at a 10^6-row measurement (made by synth first).
Each run is a new process with stdout read through a pipe and hashed (the outputs of all job
counts must be identical: the script says so).  Wall time and CPU time (user + system of the
process and its worker processes) per run, the best of R runs, and the load average before
each case: the machine is shared, so CPU time is the steadier figure and the speed-up in wall
time depends on what else runs.  --quick: 10x smaller sizes.
No assertions: this is a measurement, not a test.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DRIVE = str(ROOT / "configs" / "mch50.toml")


def command(*args):
    exe = shutil.which("wormgear")
    return [exe, *args] if exe else [sys.executable, "-m", "wormgear_cli", *args]


def timed(args) -> tuple[float, float, str, int]:
    """(wall s, CPU s of the process and its workers, SHA-256 of stdout, bytes) of one run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.Popen(command(*args), stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    h, n = hashlib.sha256(), 0
    while piece := p.stdout.read(1 << 20):
        h.update(piece)
        n += len(piece)
    if p.wait() != 0:
        raise SystemExit(f"failed: {' '.join(args)}")
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, h.hexdigest(), n


def case(name: str, args: list, jobs: list[int], repeat: int) -> None:
    load = os.getloadavg()
    print(f"{name}\n  load average before: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} (2 cores: {os.cpu_count()})")
    best, digests = {}, set()
    for _ in range(repeat):
        for j in jobs:  # alternated, so that a change of machine load hits every job count
            wall, cpu, digest, size = timed([*args, "--jobs", str(j)])
            digests.add(digest)
            w, c = best.get(j, (float("inf"), float("inf")))
            best[j] = (min(w, wall), min(c, cpu))
    for j in jobs:
        print(f"  --jobs {j}: {best[j][0]:7.2f} s wall, {best[j][1]:7.2f} s CPU (best of {repeat})")
    base = best[jobs[0]][0]
    for j in jobs[1:]:
        print(f"  speed-up --jobs {j} / --jobs {jobs[0]}: {base / best[j][0]:.2f}x wall; CPU ratio "
              f"{best[j][1] / best[jobs[0]][1]:.2f}")
    print(f"  outputs identical: {len(digests) == 1} ({size / 1e6:.1f} MB)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--jobs", type=int, default=2, help="the job count compared with 1 (default 2)")
    ap.add_argument("--quick", action="store_true", help="10x smaller sizes")
    ap.add_argument("--only", default="", help="run only the cases whose name contains this")
    a = ap.parse_args()
    k = 10 if a.quick else 1
    jobs = [1, a.jobs]
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "at.csv"
        cases = [
            (f"tolerance, {10**6 // k} samples, every metric, --format json",
             ["tolerance", DRIVE, "-n", str(10**6 // k), "--format", "json"]),
            (f"tolerance, {10**6 // k} samples, the paper's metrics, --format csv",
             ["tolerance", DRIVE, "-n", str(10**6 // k), "--metrics", "paper", "--format", "csv"]),
            (f"sweep, {10**7 // k} points, --format csv",
             ["sweep", DRIVE, "--i", "2:10:1000", "--l-mm", f"100:300:{10**4 // k}", "--format", "csv"]),
            (f"simulate --at, {10**6 // k} rows", ["simulate", DRIVE, "--at", str(data)]),
        ]
        for name, args in cases:
            if a.only and a.only not in name:
                continue
            if args[0] == "simulate" and not data.exists():
                subprocess.run(command("synth", DRIVE, "--plan", "dense", "--points", str(10**5 // k), "--runs",
                                       "5", "-o", str(data)), check=True, stderr=subprocess.DEVNULL)
            case(name, args, jobs, a.repeat)


if __name__ == "__main__":
    main()
