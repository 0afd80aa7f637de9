"""Speed and peak memory of `wormgear diagnose` at 1e5 and 1e6 measured rows (issue 10:
1e5 rows under 2.5 s, peak memory under 1 KB per row).

Makes a dense MCH50 measurement with synth (``rows / 10`` angles per pass, 5
runs forward and back, random phases, a warm-up with thermal_backlash, white
and run noise), writes it to a temporary CSV, then runs each measurement in a
fresh subprocess (so the peak RSS is that run's alone) which reads the CSV and
times ``diagnose`` + ``report`` (the core; CSV reading reported apart) and
reports:

* wall time and CPU time (resource.getrusage: user + system) -- the machine
  may be shared, the CPU time is the steadier figure;
* peak RSS (ru_maxrss) of the whole process and per row, and the part above
  the RSS after the imports (numpy, scipy, the package: a fixed cost; read
  from /proc/self/status, Linux).

The whole command as a user runs it, ``python -m wormgear_cli diagnose
configs/mch50.toml DATA.csv --format json`` (start-up, imports, reading,
the JSON written), is timed too at each size up to ``--whole-max`` rows
(default 1e5): wall and CPU (of the child process) with one BLAS thread,
after one run that leaves the byte-compiled modules in place (as an
installed package has them).

With ``--before REV`` the same is run on a checkout of REV (``git worktree
add`` in a temporary directory, removed afterwards) and the ratio
before/after is printed: the plain alternative is the code as it was.  The
two reports are compared too (a SHA-256 of the JSON document, every float
at full precision): a speed-up must not change a single number, and the
bench says ``reports identical`` or ``REPORTS DIFFER``.

Usage: python bench/bench_diagnose.py [--rows 100000,1000000] [--repeat N] [--before REV] [--whole-max ROWS]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))
from _timing import checkout  # noqa: E402  (the bench scripts share it; run as python bench/NAME.py)

#: run in a fresh interpreter with PYTHONPATH at the tree under test: argv = csv path
CHILD = r"""
import hashlib, json, resource, sys, time
from pathlib import Path
def rss_kb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
def current_kb():
    with open("/proc/self/status") as f:
        return next(int(l.split()[1]) for l in f if l.startswith("VmRSS:"))
import numpy, scipy.special, scipy.linalg
from wormgear_cli.diagnosis import diagnose, report
from wormgear_cli.measurement.readers import read_measurement
from wormgear_cli.spec.loader import load_spec
base = current_kb()
spec = load_spec(Path(sys.argv[2]) / "configs" / "mch50.toml")
t0 = time.perf_counter()
meas = read_measurement(Path(sys.argv[1]))
t_read = time.perf_counter() - t0
after_read = rss_kb()
r0 = resource.getrusage(resource.RUSAGE_SELF)
t0 = time.perf_counter()
doc = report(diagnose(spec, meas))
wall = time.perf_counter() - t0
r1 = resource.getrusage(resource.RUSAGE_SELF)
cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
print(json.dumps({"rows": len(meas), "read_s": t_read, "wall_s": wall, "cpu_s": cpu, "base_kb": base,
                  "after_read_kb": after_read, "peak_kb": rss_kb(), "verdict": doc["verdict"],
                  "gap_after": doc["gap_after"]["rms_arcsec"],
                  "report_sha256": hashlib.sha256(json.dumps(doc, sort_keys=True, default=repr).encode()).hexdigest()}))
"""


def make_csv(rows: int, path: Path) -> None:
    """Write the measurement in a subprocess: this process stays small, so the children it forks
    start with a small ru_maxrss (Linux carries the high-water mark across fork and exec)."""
    subprocess.run([sys.executable, str(Path(__file__).resolve()), "--make", str(rows), str(path)], check=True,
                   cwd=ROOT)


def _make_csv(rows: int, path: Path) -> None:
    from wormgear_cli.analysis.synth import Noise, Plan, Programme, format_csv, synthesize
    from wormgear_cli.spec.loader import load_spec

    spec = load_spec(ROOT / "configs" / "mch50.toml")
    syn = synthesize(spec, Plan(kind="dense", points=rows // 10, runs=5, dwell_s=0.1),
                     effects={"thermal_backlash": {}}, noise=Noise(0.3, 0.2), seed=1, random_phases=True,
                     temperature=Programme("warmup", (20.0, 32.0, 3000.0)))
    path.write_text(format_csv(syn))


def measure(tree: Path, data: Path, repeat: int) -> dict:
    """Median wall/CPU of ``repeat`` fresh runs of the tree's diagnose on ``data``; largest peak RSS."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    runs = []
    for _ in range(repeat):
        out = subprocess.run([sys.executable, "-c", CHILD, str(data), str(tree)], check=True, env=env,
                             capture_output=True, text=True, cwd=tree).stdout
        runs.append(json.loads(out.strip().splitlines()[-1]))
    res = dict(runs[0])
    for key in ("wall_s", "cpu_s", "read_s"):
        res[key] = statistics.median(r[key] for r in runs)
    res["peak_kb"] = max(r["peak_kb"] for r in runs)
    return res


def whole_command(tree: Path, data: Path, repeat: int) -> dict:
    """Median wall and CPU [s] of ``repeat`` runs of the whole ``diagnose`` command on ``data`` (one BLAS
    thread; a first run on the demo writes the tree's byte-compiled modules)."""
    env = {**os.environ, "PYTHONPATH": str(tree), "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    warm = {k: v for k, v in env.items() if k != "PYTHONDONTWRITEBYTECODE"}
    cmd = [sys.executable, "-m", "wormgear_cli", "diagnose", str(tree / "configs" / "mch50.toml")]
    subprocess.run([*cmd, str(tree / "configs" / "mch50-warm.csv"), "--format", "json"], check=True, env=warm,
                   cwd=tree, stdout=subprocess.DEVNULL)
    walls, cpus = [], []
    for _ in range(repeat):
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run([*cmd, str(data), "--format", "json"], check=True, env=env, cwd=tree,
                       stdout=subprocess.DEVNULL)
        walls.append(time.perf_counter() - t0)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append((r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime))
    return {"wall_s": statistics.median(walls), "cpu_s": statistics.median(cpus), "best_wall_s": min(walls)}


def whole_line(label: str, w: dict) -> str:
    return (f"{label:<7} whole command    {w['wall_s']:7.2f} s wall {w['cpu_s']:7.2f} s CPU (best wall "
            f"{w['best_wall_s']:.2f} s; one BLAS thread)")


def line(label: str, r: dict) -> str:
    rows = r["rows"]
    peak = r["peak_kb"] * 1024
    extra = (r["peak_kb"] - r["base_kb"]) * 1024
    return (f"{label:<7} diagnose+report {r['wall_s']:7.2f} s wall {r['cpu_s']:7.2f} s CPU | read {r['read_s']:5.2f} s"
            f" | peak RSS {peak / 2**20:7.0f} MiB = {peak / rows:6.0f} B/row ({extra / rows:5.0f} B/row above "
            f"imports)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", default="100000,1000000", help="comma-separated row counts")
    ap.add_argument("--repeat", type=int, default=1, help="runs per size (median time, largest peak)")
    ap.add_argument("--before", default=None, help="git revision to compare against (checked out in a temp dir)")
    ap.add_argument("--whole-max", type=float, default=1e5,
                    help="time the whole command at sizes up to this many rows (0: never)")
    ap.add_argument("--make", nargs=2, metavar=("ROWS", "CSV"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.make:
        _make_csv(int(args.make[0]), Path(args.make[1]))
        return
    sizes = [int(float(s)) for s in args.rows.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        with checkout(args.before, tmp / "before") as before:
            for rows in sizes:
                data = tmp / f"dense_{rows}.csv"
                make_csv(rows, data)
                after = measure(ROOT, data, args.repeat)
                print(f"rows: {after['rows']}  (verdict: {after['verdict']}; RMS gap after "
                      f"{after['gap_after']:.3f} arcsec)")
                print(line("now", after))
                whole = rows <= args.whole_max
                if whole:
                    w_after = whole_command(ROOT, data, args.repeat)
                    print(whole_line("now", w_after))
                if before is not None:
                    old = measure(before, data, args.repeat)
                    print(line(args.before[:7], old))
                    if whole:
                        w_old = whole_command(before, data, args.repeat)
                        print(whole_line(args.before[:7], w_old))
                        print(f"ratio before/now, whole command: wall {w_old['wall_s'] / w_after['wall_s']:.2f}x, "
                              f"CPU {w_old['cpu_s'] / w_after['cpu_s']:.2f}x")
                    same = old["report_sha256"] == after["report_sha256"]
                    print(f"ratio before/now: wall {old['wall_s'] / after['wall_s']:.2f}x, CPU "
                          f"{old['cpu_s'] / after['cpu_s']:.2f}x, peak RSS {old['peak_kb'] / after['peak_kb']:.2f}x; "
                          + ("reports identical" if same else "REPORTS DIFFER")
                          + ("" if old["verdict"] == after["verdict"] else " (VERDICTS DIFFER)"))
                data.unlink()
    print("issue 10 bars: 1e5 rows under 2.5 s (the whole command); peak memory under 1024 B/row")


if __name__ == "__main__":
    main()
