"""Peak memory per row of ``wormgear measure`` on big files, before and after (prints figures; not a test).

Two files are written to a scratch folder (``--keep DIR`` keeps them there for a re-run):

* short: ``--short`` rows (default 13 000 000) of ``angle_deg,direction,error_arcsec``, e.g.
  ``350.000,-1,-2.53`` (17 bytes a row): 36 targets 10 deg apart, forward then reverse, an ISO 230-2
  test repeated until the file is full (few targets, very many repeats);
* dense: ``--dense`` rows (default 2 000 000) of ``angle_deg,error_arcsec,direction,run``: a forward and
  a reverse scan at distinct angles (a tracking log: every row its own target, so the JSON's
  per-target part has a line a row).

Each file is measured end to end in a fresh process (``wormgear measure FILE --drive
configs/mch50.toml``, in the table format and with ``--format json``; the result goes to a pipe that is
read and dropped): peak resident memory of the command (``ru_maxrss`` of the child, Python start-up and
imports included, about 60 MB) per row, wall and CPU time (user + system: the steadier figure on a
shared machine).  ``--before TREE`` runs the same commands with
an earlier source tree's ``wormgear_cli`` (a checkout of main: ``git archive main | tar -x -C DIR``) and
prints the ratio before / after.

Targets (issue 24): within 100 B a row on short rows and 300 B a row on dense scans.

Run: python bench/bench_memory.py [--before DIR] [--short 13e6] [--dense 2e6] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_measure import DRIVE, ROOT, WRAPPER, write_dense

#: rows written at a time
_BLOCK = 1_000_000
#: bytes a row allowed (issue 24)
TARGET = {"short": 100, "dense": 300}


def write_short(path: Path, rows: int, rng) -> None:
    """``rows`` rows of an ISO 230-2 test at 36 targets, forward then reverse, repeated."""
    with open(path, "w") as fh:
        fh.write("angle_deg,direction,error_arcsec\n")
        for a in range(0, rows, _BLOCK):
            k = np.arange(a, min(rows, a + _BLOCK))
            pos = k % 72
            forward = pos < 36
            target = np.where(forward, pos, 71 - pos) * 10.0
            d = np.where(forward, 1, -1)
            err = 3.0 * np.sin(np.radians(target)) + 2.0 * d + rng.normal(0.0, 0.8, k.size)
            np.savetxt(fh, np.column_stack([target, d, err]), fmt=["%.3f", "%d", "%.2f"], delimiter=",")


def run_once(tree: Path, path: Path, fmt: str) -> dict:
    """One ``measure`` in a fresh process: exit code, wall and CPU time [s], peak RSS [kB]."""
    env = {**os.environ, "PYTHONPATH": str(tree), "OPENBLAS_NUM_THREADS": "1"}
    cmd = [sys.executable, "-c", WRAPPER, sys.executable, "-m", "wormgear_cli", "measure", str(path), "--drive",
           str(DRIVE), "--format", fmt]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True, cwd=tree).stdout
    res = json.loads(out)
    if res["rc"] != 0:
        raise SystemExit(f"measure failed ({tree}, {path.name}, {fmt}): {res['err']}")
    return res


def line(name: str, rows: int, fmt: str, after: dict, before: dict | None) -> str:
    per = after["rss_kb"] * 1024.0 / rows
    out = (f"{name:5s} {rows / 1e6:5.1f} M rows {fmt:5s}: peak {after['rss_kb'] / 1024:6.0f} MiB = {per:5.0f} B/row "
           f"({'within' if per <= TARGET[name] else 'OVER'} {TARGET[name]}), {after['s']:5.1f} s "
           f"(CPU {after['cpu']:.1f} s)")
    if before is not None:
        per_b = before["rss_kb"] * 1024.0 / rows
        out += (f"; before {before['rss_kb'] / 1024:6.0f} MiB = {per_b:5.0f} B/row, {before['s']:5.1f} s "
                f"(CPU {before['cpu']:.1f} s): memory x{per_b / per:.1f} less, "
                f"CPU time x{before['cpu'] / after['cpu']:.2f}")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--short", type=float, default=13e6, help="rows of the short-row file")
    ap.add_argument("--dense", type=float, default=2e6, help="rows of the dense scan")
    ap.add_argument("--before", type=Path, default=None, help="source tree of the version to compare with")
    ap.add_argument("--keep", type=Path, default=None, help="folder to write the files to and keep them in")
    ap.add_argument("--formats", default="table,json")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.keep or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        for name, rows, writer in (("short", int(args.short), write_short), ("dense", int(args.dense), write_dense)):
            path = folder / f"{name}-{rows}.csv"
            if not path.exists():
                writer(path, rows, np.random.default_rng(1))
            print(f"{name}: {path.stat().st_size / 2**20:.0f} MiB, {path.stat().st_size / rows:.1f} bytes a row",
                  flush=True)
            for fmt in args.formats.split(","):
                after = run_once(ROOT, path, fmt)
                before = run_once(args.before, path, fmt) if args.before is not None else None
                print(line(name, rows, fmt, after, before), flush=True)


if __name__ == "__main__":
    main()
