"""Time and peak memory of ``wormgear measure`` on long files (prints figures; not a test).

Two synthetic files of ``--rows`` rows (default 2 000 000) are written to a temporary folder:

* iso:   500 irregular targets x (rows / 1000) runs x 2 directions (few targets, many repeats)
* dense: a forward and a reverse scan at distinct angles (a tracking log: every row its own target)

Each is measured end to end as a subprocess (``wormgear measure FILE --drive configs/mch50.toml``,
table output, Python start-up included): wall time and CPU time (user + system; steadier than wall
time on a shared machine), best of ``--repeat``, and peak resident memory
of the command (``resource.getrusage(RUSAGE_CHILDREN).ru_maxrss`` in a fresh wrapper process per run),
also per row.  With ``--before PATH`` (a checkout of an earlier version, e.g. /work/main) the same
command runs against it too and the ratios before/after are printed.

Targets (issue 10): under 5 s and under 300 bytes of peak memory per row on 2 million rows.

Run: python bench/bench_measure.py [--rows 2000000] [--before /path/to/old/checkout] [--repeat 1]
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

ROOT = Path(__file__).resolve().parent.parent
DRIVE = ROOT / "configs" / "mch50.toml"

WRAPPER = r"""
import json, resource, subprocess, sys, time
t0 = time.perf_counter()
r = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
dt = time.perf_counter() - t0
u = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"rc": r.returncode, "s": dt, "cpu": u.ru_utime + u.ru_stime, "rss_kb": u.ru_maxrss,
                  "err": r.stderr.decode()[-300:]}))
"""


def write_iso(path: Path, rows: int, rng) -> None:
    runs = max(rows // 1000, 1)
    targets = np.sort(rng.uniform(0.0, 360.0, 500))
    ang = np.tile(np.concatenate([targets, targets[::-1]]), runs)
    d = np.tile(np.repeat([1, -1], 500), runs)
    run = np.repeat(np.arange(runs), 1000)
    _write(path, ang, d, run, rng)


def write_dense(path: Path, rows: int, rng) -> None:
    half = rows // 2
    ang = np.concatenate([np.linspace(0, 360, half, endpoint=False), np.linspace(360, 0, half, endpoint=False)])
    d = np.repeat([1, -1], half)
    run = np.zeros(2 * half, dtype=int)
    _write(path, ang, d, run, rng)


def _write(path: Path, ang, d, run, rng) -> None:
    th = np.radians(ang)
    err = 6 * np.sin(th + 0.5) + 2 * np.sin(8 * th) + np.sin(240 * th) - 4 * d + rng.normal(0, 0.5, ang.size)
    with open(path, "w") as fh:
        fh.write("angle_deg,error_arcsec,direction,run\n")
        np.savetxt(fh, np.column_stack([ang, err, d, run]), fmt=["%.6f", "%.4f", "%d", "%d"], delimiter=",")


def measure_once(tree: Path, path: Path) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    cmd = [sys.executable, "-c", WRAPPER, sys.executable, "-m", "wormgear_cli", "measure", str(path), "--drive",
           str(DRIVE)]
    # cwd = tree: ``python -m`` puts the working folder first on sys.path
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True, cwd=tree).stdout
    res = json.loads(out)
    if res["rc"] != 0:
        raise SystemExit(f"measure failed ({tree}): {res['err']}")
    return res


def best(tree: Path, path: Path, repeat: int) -> tuple[float, float, float]:
    """(wall time [s], CPU time [s], peak RSS [bytes]): best times, largest peak over ``repeat`` runs."""
    runs = [measure_once(tree, path) for _ in range(repeat)]
    return min(r["s"] for r in runs), min(r["cpu"] for r in runs), max(r["rss_kb"] for r in runs) * 1024.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=2_000_000)
    ap.add_argument("--before", type=Path, default=None, help="checkout of the version to compare with")
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    rng = np.random.default_rng(1)
    with tempfile.TemporaryDirectory() as tmp:
        for name, writer in (("iso", write_iso), ("dense", write_dense)):
            path = Path(tmp) / f"{name}.csv"
            writer(path, args.rows, rng)
            size = path.stat().st_size
            t_after, c_after, m_after = best(ROOT, path, args.repeat)
            line = (f"{name:5s} {args.rows:8d} rows ({size / 1e6:.0f} MB): {t_after:6.2f} s "
                    f"(CPU {c_after:.2f} s), peak "
                    f"{m_after / 1e6:7.0f} MB = {m_after / args.rows:5.0f} B/row "
                    f"({'under' if t_after < 5 else 'OVER'} 5 s, {'under' if m_after / args.rows < 300 else 'OVER'} "
                    "300 B/row)")
            if args.before is not None:
                t_before, c_before, m_before = best(args.before, path, args.repeat)
                line += (f"; before {t_before:.2f} s (CPU {c_before:.2f} s), {m_before / 1e6:.0f} MB = "
                         f"{m_before / args.rows:.0f} B/row: time x{t_before / t_after:.1f} (CPU "
                         f"x{c_before / c_after:.1f}), memory x{m_before / m_after:.1f} less")
            print(line, flush=True)


if __name__ == "__main__":
    main()
