"""Benchmark of ``wormgear sweep``: the exact vectorised (i, l) sweep against a plain numpy
script that samples 3600 pinion angles per design, plus the whole CLI path.

Run:  python bench/bench_sweep.py [--n 1000] [--naive-designs 20000]

Prints, for an n x n grid of the MCH50 (i = 2..10, l = 100..300 mm):
* fast core: wall time and peak memory (ru_maxrss of a fresh subprocess that imports the
  package and computes the grid; the import baseline is printed too);
* naive: 3600 samples of the paper's Delta phi_cc per design, vectorised over blocks of
  designs, timed on a random subset of ``--naive-designs`` designs and scaled to n^2 (said so);
  its largest error against the exact maximum on that subset;
* the ratio naive / fast;
* the CLI path ``wormgear sweep ... --format csv > /dev/null``: wall time and peak memory.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DRIVE = ROOT / "configs" / "mch50.toml"
#: a train of three stages (spur gearmotor, two-start worm, bull gear): its last spur stage is swept,
#: the worm and the gearmotor carried through the ratios
TRAIN = ROOT / "configs" / "radar-pedestal-2start.toml"

_FAST = r"""
import json, resource, sys, time
import numpy as np
from wormgear_cli.spec.loader import load_spec
from wormgear_cli.analysis.sweep import RatioDistanceSweep
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
n = int(sys.argv[1])
spec = load_spec(sys.argv[2])
t0, c0 = time.perf_counter(), time.process_time()
sw = RatioDistanceSweep(spec, np.linspace(2, 10, n), np.linspace(100, 300, n))
data = sw.collect()
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"wall": wall, "cpu": cpu, "peak_kb": peak, "import_kb": base, "points": int(data["i"].size)}))
"""


_MEASURE = r"""
import json, os, resource, subprocess, sys, time
cmd = json.loads(sys.argv[1])
t0 = time.perf_counter()
proc = subprocess.Popen(cmd, stdout=subprocess.PIPE)
size = 0
while True:
    chunk = proc.stdout.read(1 << 20)
    if not chunk:
        break
    size += len(chunk)
proc.wait()
wall = time.perf_counter() - t0
print(json.dumps({"wall": wall, "bytes": size,
                  "peak_kb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss}))
"""


def naive_max(r1, r2, de, alpha, d1, samples=3600, block=2000):
    """max over `samples` evenly spaced phi of the paper's Delta phi_cc, written directly."""
    import numpy as np

    phi = (np.arange(samples) + 0.5) * (2.0 * np.pi / samples) - np.pi  # avoids tan(pi/2)
    out = np.empty(r1.size)
    for a in range(0, r1.size, block):
        b = min(r1.size, a + block)
        R1, R2, D1 = r1[a:b, None], r2[a:b, None], d1[a:b, None]
        l = R1 + R2
        A = (l + de) / de
        kin = 2.0 * np.arctan(np.sqrt((A + 1.0) / (A - 1.0)) * np.tan(phi / 2.0)) - (
            phi - np.tan(alpha) * np.log(1.0 + 2.0 * A * (1.0 - np.cos(phi)) / (A - 1.0) ** 2))
        lam1 = np.arctan(de * np.sin(phi) / (l + de * (1.0 - np.cos(phi))))
        te = l / (2.0 * R2) * kin + D1 * np.sin(alpha + lam1) / R2
        out[a:b] = te.max(axis=1)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000, help="grid is n x n (default 1000)")
    ap.add_argument("--naive-designs", type=int, default=20000, help="designs timed for the naive script")
    args = ap.parse_args()
    n = args.n
    total = n * n

    fast = json.loads(subprocess.run([sys.executable, "-c", _FAST, str(n), str(DRIVE)], check=True,
                                     capture_output=True, text=True).stdout)
    print(f"grid: {n} x {n} = {total} designs of {DRIVE.name} (i = 2..10, l = 100..300 mm)")
    print(f"fast core   : {fast['wall']:.3f} s wall, {fast['cpu']:.3f} s cpu, peak RSS {fast['peak_kb'] / 1024:.0f} MB "
          f"(after imports {fast['import_kb'] / 1024:.0f} MB)")
    train = json.loads(subprocess.run([sys.executable, "-c", _FAST, str(n), str(TRAIN)], check=True,
                                      capture_output=True, text=True).stdout)
    print(f"fast core, {TRAIN.name} (3 stages, its bull-gear stage swept): {train['wall']:.3f} s wall, "
          f"{train['cpu']:.3f} s cpu")

    import numpy as np

    from wormgear_cli.analysis.sweep import RatioDistanceSweep
    from wormgear_cli.spec.loader import load_spec

    spec = load_spec(DRIVE)
    rng = np.random.default_rng(0)
    m = min(args.naive_designs, total)
    i = rng.uniform(2, 10, m)
    l = rng.uniform(100, 300, m)
    sw = RatioDistanceSweep(spec, np.array([8.0]), np.array([200.0]))
    exact = sw.evaluate(i, l)  # also gives delta1 per design, the naive script's input
    r1, r2 = l / (1 + i), l * i / (1 + i)
    de, alpha = spec.assembly.gear_eccentricity, spec.gear_pair.pressure_angle
    d1 = exact["gear_deflection_um"] * 1e-3
    t0 = time.perf_counter()
    te = naive_max(r1, r2, de, alpha, d1)
    # the naive script also forms the totals; the worm terms are constants per design
    w_te = exact["total_transmission_error"] - exact["gear_transmission_error"]
    _ = te + w_te
    naive_wall = time.perf_counter() - t0
    scaled = naive_wall * total / m
    err = np.max(np.abs(te / exact["gear_transmission_error"] - 1.0))
    below = bool(np.all(te <= exact["gear_transmission_error"] * (1 + 1e-12)))
    print(f"naive numpy : {naive_wall:.3f} s for {m} designs x 3600 samples -> {scaled:.1f} s scaled to "
          f"{total} designs (run on a subset and scaled)")
    print(f"naive error : sampled maxima are up to {err:.2e} relative below the exact maxima "
          f"(never above: {below})")
    print(f"ratio       : naive / fast = {scaled / fast['wall']:.0f}x")

    cmd = [sys.executable, "-m", "wormgear_cli", "sweep", str(DRIVE), "--i", f"2:10:{n}", "--l-mm", f"100:300:{n}",
           "--format", "csv"]
    cli = json.loads(subprocess.run([sys.executable, "-c", _MEASURE, json.dumps(cmd)], check=True,
                                    capture_output=True, text=True).stdout)
    print(f"CLI path    : {cli['wall']:.3f} s wall, peak RSS {cli['peak_kb'] / 1024:.0f} MB for "
          f"`wormgear sweep ... --format csv > /dev/null` ({cli['bytes'] / 1e6:.0f} MB of CSV)")

if __name__ == "__main__":
    main()
