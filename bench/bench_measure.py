"""Speed of ``wormgear measure`` on 100 000 rows (prints figures; not a test).

Two synthetic files are written to a temporary folder:

* iso:   500 irregular targets x 100 runs x 2 directions (few targets, many repeats)
* dense: 50 000 forward + 50 000 reverse rows at distinct angles (a dense scan)

Each is measured end to end as a subprocess (`wormgear measure FILE
--drive configs/mch50.toml -f json`, Python start-up included) and in
process (read + ISO 230-2 + order fit), best of 3.

Run: python bench/bench_measure.py
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from _timing import best_of

ROOT = Path(__file__).resolve().parent.parent
DRIVE = ROOT / "configs" / "mch50.toml"
ROWS = 100_000


def write_iso(path: Path, rng) -> None:
    targets = np.sort(rng.uniform(0.0, 360.0, 500))
    ang = np.tile(np.repeat(targets, 100), 2)
    d = np.repeat([1, -1], 50_000)
    run = np.tile(np.tile(np.arange(100), 500), 2)
    _write(path, ang, d, run, rng)


def write_dense(path: Path, rng) -> None:
    ang = np.concatenate([np.linspace(0, 360, 50_000, endpoint=False),
                          np.linspace(0, 360, 50_000, endpoint=False) + 0.0036])
    d = np.repeat([1, -1], 50_000)
    run = np.zeros(ROWS, dtype=int)
    _write(path, ang, d, run, rng)


def _write(path: Path, ang, d, run, rng) -> None:
    th = np.radians(ang)
    err = 6 * np.sin(th + 0.5) + 2 * np.sin(8 * th) + np.sin(240 * th) - 4 * d + rng.normal(0, 0.5, ang.size)
    lines = ["angle_deg,error_arcsec,direction,run"]
    lines += [f"{a:.6f},{e:.4f},{int(s)},{int(r)}" for a, e, s, r in zip(ang, err, d, run)]
    path.write_text("\n".join(lines) + "\n")


def main() -> None:
    from wormgear_cli.analysis import geometry
    from wormgear_cli.harmonics import analyse_orders, physical_orders, physical_priority
    from wormgear_cli.iso230 import measurement_figures
    from wormgear_cli.measurement import read_measurement
    from wormgear_cli.spec import load_spec

    rng = np.random.default_rng(1)
    geo = geometry(load_spec(DRIVE))
    orders = [k for k, _ in physical_orders(geo)]
    prio = physical_priority(geo)
    with tempfile.TemporaryDirectory() as tmp:
        for name, writer in (("iso", write_iso), ("dense", write_dense)):
            path = Path(tmp) / f"{name}.csv"
            writer(path, rng)
            m = read_measurement(path)
            t_read = best_of(lambda: read_measurement(path))
            t_iso = best_of(lambda: measurement_figures(m))
            t_ord = best_of(lambda: analyse_orders(m.angle, m.error, m.direction, orders, None, prio))
            cmd = [sys.executable, "-m", "wormgear_cli", "measure", str(path), "--drive", str(DRIVE), "-f", "json",
                   "-o", str(Path(tmp) / f"{name}.json")]
            t_cli = best_of(lambda: subprocess.run(cmd, check=True, capture_output=True))
            print(f"{name:5s} {len(m):6d} rows: read {t_read:.3f} s, ISO 230-2 {t_iso:.3f} s, "
                  f"orders ({len(orders)}) {t_ord:.3f} s, whole command {t_cli:.3f} s "
                  f"({'under' if t_cli < 2 else 'OVER'} 2 s)")


if __name__ == "__main__":
    main()
