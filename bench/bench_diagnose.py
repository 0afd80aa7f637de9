"""Speed of `wormgear diagnose` on 100 000 measured rows (the issue's bar: under 5 s).

Makes a dense MCH50 measurement with synth (10 000 angles per pass, 5 runs
forward and back = 100 000 rows, random phases, a warm-up with
thermal_backlash, white and run noise), writes it to a temporary CSV, then
times (a) the core stages in-process: reading the CSV, ``diagnose`` and the
report, and (b) the whole command `wormgear diagnose DRIVE DATA --format
json` as a subprocess (start-up included).  Prints the median of N repeats.
Usage: python bench/bench_diagnose.py [N]
"""

from __future__ import annotations

import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    from wormgear_cli.diagnosis import diagnose, report
    from wormgear_cli.measurement import read_measurement
    from wormgear_cli.spec import load_spec
    from wormgear_cli.synth import Noise, Plan, Programme, format_csv, synthesize

    n = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    spec = load_spec(ROOT / "configs" / "mch50.toml")
    syn = synthesize(spec, Plan(kind="dense", points=10_000, runs=5, dwell_s=0.1),
                     effects={"thermal_backlash": {}}, noise=Noise(0.3, 0.2), seed=1, random_phases=True,
                     temperature=Programme("warmup", (20.0, 32.0, 3000.0)))
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "dense.csv"
        data.write_text(format_csv(syn))
        stages = {"read": [], "diagnose": [], "report": [], "core total": []}
        for _ in range(n):
            t0 = time.perf_counter()
            meas = read_measurement(data)
            t1 = time.perf_counter()
            diag = diagnose(spec, meas)
            t2 = time.perf_counter()
            doc = report(diag)
            t3 = time.perf_counter()
            for key, v in (("read", t1 - t0), ("diagnose", t2 - t1), ("report", t3 - t2), ("core total", t3 - t0)):
                stages[key].append(v)
        exe = shutil.which("wormgear")
        cmd = ([exe] if exe else [sys.executable, "-m", "wormgear_cli"]) + [
            "diagnose", str(ROOT / "configs" / "mch50.toml"), str(data), "--format", "json"]
        walls = []
        for _ in range(n):
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)
            walls.append(time.perf_counter() - t0)
    print(f"rows: {len(meas)}, repeats: {n} (median)")
    for key, values in stages.items():
        print(f"{key:<11} {statistics.median(values):6.2f} s")
    print(f"wormgear diagnose --format json (subprocess, start-up included) {statistics.median(walls):6.2f} s")
    print(f"verdict: {doc['verdict']}; RMS gap {doc['gap_before']['rms_arcsec']:.3f} -> "
          f"{doc['gap_after']['rms_arcsec']:.3f} arcsec")


if __name__ == "__main__":
    main()
