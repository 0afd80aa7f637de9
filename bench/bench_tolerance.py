"""Speed and memory of ``wormgear tolerance`` (targets: 10^6 samples of the paper's metrics <= 2 s,
of the ISO 230-2 figures at 24 targets <= 10 s, peak memory < 1 GB).

Run: python bench/bench_tolerance.py [N]
Prints, for N samples (default 10^6), seed 0, of configs/mch50.toml (paper kinematics) and
configs/rotary-table-precision.toml (involute kinematics, grades, the budget's pitch deviations):
  * the core run (draw, metrics, statistics; scipy imported beforehand) for --metrics paper, best of 2;
  * the same for --metrics budget (the budget's linear and rss totals), once;
  * the same for --metrics iso (24 targets of the iso plan), once;
  * (MCH50) a plain numpy script that loops analyze's model functions sample by sample (scalar calls, timed on
    2000 samples and scaled to N), and the ratio to the vectorised run;
  * the whole command in a new process (start-up included) for --metrics paper, and its peak memory
    (ru_maxrss of the child) for N and 4 N samples;
No assertions: this is a measurement, not a test.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

from _timing import best_of

ROOT = Path(__file__).resolve().parent.parent
DRIVE = ROOT / "configs" / "mch50.toml"
#: the paper's drive, the rotary table (involute kinematics, ISO 1328 grades, ten budget sources), and two
#: other trains: a belt + worm mount and the three-stage radar pedestal (spur, worm, spur)
DRIVES = (DRIVE, ROOT / "configs" / "rotary-table-precision.toml", ROOT / "configs" / "eq6-belt-worm.toml",
          ROOT / "configs" / "radar-pedestal-2start.toml")


def command(*args):
    exe = shutil.which("wormgear")
    return [exe, *args] if exe else [sys.executable, "-m", "wormgear_cli", *args]


def plain_loop(spec, draw, n: int) -> float:
    """Seconds for n samples, one scalar call of each of analyze's model functions per sample."""
    from wormgear_cli.drive.registry import deflections
    from wormgear_cli.physics import spur as gear
    from wormgear_cli.physics import worm

    gp, wp = spec.gear_pair, spec.worm_pair
    z1, z2, m, a = gp.output_gear.teeth, gp.pinion.teeth, gp.module, gp.pressure_angle
    lam, a2, m2, z3 = wp.lead_angle, wp.transverse_pressure_angle, wp.module, wp.wheel.teeth
    i_c = z1 / z2
    v = {k: x.tolist() for k, x in draw.values.items()}
    t0 = time.perf_counter()
    d_worm, d_gear = deflections(spec)
    for j in range(n):
        de = v["assembly.gear_eccentricity_mm"][j]
        te, _ = gear.gear_te_max_fast(m * z2 / 2, m * z1 / 2, de, a, d_gear)
        bl = gear.gear_backlash_max(m, z1, de, a, d_gear)
        h = worm.worm_te_halfwidth(v["worm_pair.lead_error_mm"][j], v["assembly.worm_eccentricity_mm"][j],
                                   v["assembly.worm_bearing_clearance_mm"][j],
                                   v["worm_pair.wheel.radial_composite_error_mm"][j],
                                   v["assembly.wheel_eccentricity_mm"][j], v["assembly.wheel_bearing_clearance_mm"][j],
                                   lam, a2)
        wte = worm.worm_te(d_worm, h, m2, z3)
        c = worm.worm_backlash_central(d_worm, v["worm_pair.worm.profile_error_mm"][j],
                                       v["worm_pair.wheel.profile_error_mm"][j],
                                       v["worm_pair.worm.thickness_deviation_mm"][j],
                                       v["worm_pair.wheel.thickness_deviation_mm"][j], lam)
        hj = worm.worm_backlash_halfwidth(v["worm_pair.worm.profile_error_mm"][j],
                                          v["worm_pair.wheel.profile_error_mm"][j],
                                          v["worm_pair.worm.thickness_deviation_mm"][j],
                                          v["worm_pair.wheel.thickness_deviation_mm"][j],
                                          sum(v[f"assembly.worm_pair_errors_mm[{i}]"][j] ** 2 for i in range(6)),
                                          v["worm_pair.lead_error_mm"][j],
                                          v["assembly.worm_centre_distance_error_mm"][j],
                                          v["worm_pair.wheel.radial_composite_error_mm"][j], lam, a2)
        wbl = worm.worm_backlash(sum(c), hj, m2, z3)
        _ = (te + wte / i_c, bl + wbl / i_c)
    return time.perf_counter() - t0


_WRAPPER = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL); "
            "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")


def peak_rss_mb(*args: str) -> float:
    """Peak resident memory [MB] of one ``wormgear`` process (measured by a fresh parent)."""
    out = subprocess.run([sys.executable, "-c", _WRAPPER, *command(*args)], check=True, capture_output=True,
                         text=True)
    return int(out.stdout.split()[-1]) / 1024.0  # kB -> MB


def child_cpu(*args: str) -> float:
    """CPU seconds (user + system) of one ``wormgear`` process, its start-up included."""
    before = os.times()
    subprocess.run(command(*args), check=True, stdout=subprocess.DEVNULL)
    after = os.times()
    return (after.children_user - before.children_user) + (after.children_system - before.children_system)


def timed(fn):
    """(wall, cpu) seconds of one call; cpu counts every thread of this process."""
    t0, c0 = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - t0, time.process_time() - c0


def main() -> None:
    import scipy.stats  # noqa: F401  (imported once, outside the timings)

    from wormgear_cli.spec.loader import load_spec
    from wormgear_cli.tolerance import engine, sampling
    from wormgear_cli.tolerance.quantities import varied_quantities

    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    spec = load_spec(DRIVE)
    print(f"machine load (1 min average): {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores "
          "(wall times grow with it; cpu times much less)")
    wall = None
    for drive in DRIVES:
        sp = load_spec(drive)
        print(f"{drive.name} ({' + '.join(s.kind for s in sp.stages)}):")
        paper = engine.setup(sp, engine.Options(samples=n, metrics="paper"))
        w, cpu = min(timed(lambda: engine.run(paper)) for _ in range(2))  # noqa: B023
        wall = w if wall is None else wall
        print(f"  core, {n} samples, paper metrics:            wall {w:6.2f} s, cpu {cpu:6.2f} s  (target 2 s)")
        bud = engine.setup(sp, engine.Options(samples=n, metrics="budget"))
        w_b, cpu_b = timed(lambda: engine.run(bud))  # noqa: B023
        print(f"  core, {n} samples, budget linear + rss:      wall {w_b:6.2f} s, cpu {cpu_b:6.2f} s")
        iso = engine.setup(sp, engine.Options(samples=n, metrics="iso", targets=24))
        wall_i, cpu_i = timed(lambda: engine.run(iso))  # noqa: B023
        print(f"  core, {n} samples, ISO 230-2 at 24 targets:  wall {wall_i:6.2f} s, cpu {cpu_i:6.2f} s  "
              "(target 10 s)")
    m = 2000
    draw = sampling.draw(varied_quantities(spec), 0, 0, m)
    t_loop = plain_loop(spec, draw, m) * n / m
    print(f"plain loop of analyze's functions per sample, scaled to {n}: {t_loop:.0f} s "
          f"(ratio to the vectorised paper run: {t_loop / wall:.0f}x)")
    args = ("tolerance", str(DRIVE), "-n", str(n), "--metrics", "paper", "--format", "json")
    t_cmd = best_of(lambda: subprocess.run(command(*args), check=True, stdout=subprocess.DEVNULL), repeat=1)
    print(f"wormgear {' '.join(args[:1] + args[2:])}: {t_cmd:.2f} s (new process, start-up included)")
    # the bar: 10^6 samples of the paper's metrics <= 15 x one analyze, in CPU time (steady on a
    # shared machine), each a new process with its start-up, best of 3
    for drive in (DRIVE, ROOT / "configs" / "eq6-belt-worm.toml"):
        one = min(child_cpu("analyze", str(drive), "--format", "json") for _ in range(3))
        tol = min(child_cpu("tolerance", str(drive), "-n", str(n), "--metrics", "paper", "--format", "json")
                  for _ in range(3))
        print(f"{drive.name}: tolerance -n {n} --metrics paper {tol:.2f} s cpu, one analyze {one:.3f} s cpu: "
              f"{tol / one:.1f}x (bar: <= 15x)")
    for k in (n, 4 * n):
        mb = peak_rss_mb('tolerance', str(DRIVE), '-n', str(k), '--metrics', 'paper', '--format', 'json')
        print(f"peak memory, wormgear tolerance -n {k} --metrics paper: {mb:.0f} MB")
    mb = peak_rss_mb('tolerance', str(DRIVE), '-n', str(n // 4), '--metrics', 'all', '--format', 'json')
    print(f"peak memory, wormgear tolerance -n {n // 4} --metrics all:   {mb:.0f} MB")


if __name__ == "__main__":
    main()
