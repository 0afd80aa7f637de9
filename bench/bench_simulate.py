"""Speed of ``wormgear simulate`` on 100 000 rows (target: under 2 s each).

Run: python bench/bench_simulate.py
Generates a 100 000-row measurement with the synthesis core in a temporary
folder, then times (wall clock, best of 3):
  * the core simulate() on 100 000 samples (in process);
  * ``wormgear simulate DRIVE --at big.csv -o out.csv`` (a new process, start-up included);
  * ``wormgear simulate DRIVE --points 100000 -o dense.csv`` (a new process);
  * ``wormgear synth DRIVE --plan dense --points 10000 --runs 5`` (100 000 rows, a new process).
Prints one line per figure.  No assertions: this is a measurement, not a test.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from _timing import best_of

ROOT = Path(__file__).resolve().parent.parent
DRIVE = ROOT / "configs" / "mch50.toml"


def command(*args):
    exe = shutil.which("wormgear")
    cmd = [exe, *args] if exe else [sys.executable, "-m", "wormgear_cli", *args]
    return lambda: subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def main() -> None:
    import numpy as np

    from wormgear_cli.analysis.simulate import simulate
    from wormgear_cli.analysis.synth import Noise, Plan, format_csv, parse_temperature, synthesize
    from wormgear_cli.physics.effects import Signals
    from wormgear_cli.spec.loader import load_spec

    spec = load_spec(DRIVE)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        big = tmp / "big.csv"
        result = synthesize(spec, plan=Plan(kind="dense", points=10_000, runs=5), noise=Noise(0.5, 1.0), seed=1,
                            temperature=parse_temperature("warmup:20:30:3600"),
                            effects={"thermal_drift": {"arcsec_per_K": 0.4}})
        big.write_text(format_csv(result))
        rows = len(result.columns["angle_deg"])
        print(f"rows in the generated file: {rows} ({big.stat().st_size / 1e6:.1f} MB)")

        theta = np.linspace(0.0, 2.0 * np.pi, 100_000, endpoint=False)
        signals = Signals.make(theta, np.where(np.arange(theta.size) % 2, 1.0, -1.0), 10.0, 25.0, 0.0)
        print(f"core simulate(), 100000 samples:                 {best_of(lambda: simulate(spec, signals)):.3f} s")
        t_noop = best_of(command("--help"))
        print(f"wormgear --help (process start-up):              {t_noop:.3f} s")
        t_at = best_of(command("simulate", str(DRIVE), "--at", str(big), "-o", str(tmp / "out.csv")))
        print(f"wormgear simulate --at (100000 rows):            {t_at:.3f} s")
        t_dense = best_of(command("simulate", str(DRIVE), "--points", "100000", "-o", str(tmp / "dense.csv")))
        print(f"wormgear simulate --points 100000:               {t_dense:.3f} s")
        t_dense_json = best_of(command("simulate", str(DRIVE), "--points", "100000", "-f", "json", "-o",
                                       str(tmp / "dense.json")))
        print(f"wormgear simulate --points 100000 --format json: {t_dense_json:.3f} s")
        t_synth = best_of(command("synth", str(DRIVE), "--plan", "dense", "--points", "10000", "--runs", "5",
                                  "--noise-arcsec", "0.5", "-o", str(tmp / "synth.csv")))
        print(f"wormgear synth, 100000 rows:                     {t_synth:.3f} s")


if __name__ == "__main__":
    main()
