"""Time and peak memory of each command on the largest legal input (prints figures; not a test).

Inputs, written to a temporary folder:

* spec at the size limit: configs/mch50.toml padded with comment lines to
  ``tomlguard.MAX_SPEC_BYTES`` (1 MiB; the shipped files are 2-5 kB);
* CSV at the size limit: a dense measurement made by ``wormgear synth`` (the
  same columns and number format as real files), repeated runs appended until
  just under ``io.MAX_INPUT_BYTES`` (16 MiB).

Each command runs as a subprocess (Python start-up included), once; wall time
and peak resident memory (``ru_maxrss`` of the child) are printed with the ratio
to the same command on the shipped input (configs/mch50.toml,
configs/mch50-warm.csv), the plain alternative a user starts from.  A command
that has not finished after ``--limit`` seconds (default 280) is stopped and
reported as ">LIMIT".  ``analyze*`` reads the slowest 1 MiB text the TOML guard
accepts (dense number arrays under unknown keys; validation then refuses it,
exit 2): the bound on parsing cost.

Run: python bench/bench_limits.py [--limit S] [--only NAME ...]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from wormgear_cli.files import MAX_INPUT_BYTES  # noqa: E402
from wormgear_cli.spec.toml import MAX_SPEC_BYTES  # noqa: E402

DRIVE = ROOT / "configs" / "mch50.toml"
DATA = ROOT / "configs" / "mch50-warm.csv"


def run(args: list[str], limit: float) -> tuple[float, float, int]:
    """(wall s, peak RSS MiB, exit code) of ``wormgear ARGS``; wall = inf past ``limit``."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "wormgear_cli", *args], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, env=env)
    deadline = t0 + limit
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            break
        if time.perf_counter() > deadline:
            proc.kill()
            _, status, usage = os.wait4(proc.pid, 0)
            return float("inf"), usage.ru_maxrss / 1024, -9
        time.sleep(0.02)
    wall = time.perf_counter() - t0
    code = os.waitstatus_to_exitcode(status)
    proc.returncode = code
    return wall, usage.ru_maxrss / 1024, code


def big_spec(folder: Path) -> Path:
    text = DRIVE.read_text()
    line = "# " + "padding to the size limit of a drive file " * 2 + "\n"
    room = MAX_SPEC_BYTES - len(text.encode())
    text += line * (room // len(line))
    path = folder / "big.toml"
    path.write_text(text)
    return path


def dense_toml(folder: Path) -> Path:
    """The slowest text the guard lets through: 1 MiB of short keys and number arrays (not a
    drive file: validation refuses the unknown keys, after parsing)."""
    line = "x{} = [" + ", ".join(["1.5"] * 100) + "]\n"
    out, k, size = [], 0, 0
    while True:
        new = line.format(k)
        if size + len(new) > MAX_SPEC_BYTES:
            break
        out.append(new)
        size += len(new)
        k += 1
    path = folder / "dense.toml"
    path.write_text("".join(out))
    return path


def big_csv(folder: Path) -> Path:
    part = folder / "part.csv"
    subprocess.run([sys.executable, "-m", "wormgear_cli", "synth", str(DRIVE), "--plan", "dense", "--points",
                    "20000", "--runs", "5", "--seed", "1", "-o", str(part)], check=True, stderr=subprocess.DEVNULL,
                   env=dict(os.environ, PYTHONPATH=str(ROOT)))
    lines = part.read_text().splitlines(keepends=True)
    head = [ln for ln in lines if ln.startswith("#")]
    header = lines[len(head)]
    rows = lines[len(head) + 1:]
    out = "".join(head) + header
    run_col = header.strip().split(",").index("run")
    k = 0
    chunks = [out]
    size = len(out.encode())
    while True:  # append copies of the runs, numbered on, until the file is at the limit
        for row in rows:
            cells = row.rstrip("\n").split(",")
            cells[run_col] = str(int(cells[run_col]) + 5 * k)
            new = ",".join(cells) + "\n"
            if size + len(new) > MAX_INPUT_BYTES:
                path = folder / "big.csv"
                path.write_text("".join(chunks))
                return path
            chunks.append(new)
            size += len(new)
        k += 1


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--limit", type=float, default=280.0)
    ap.add_argument("--only", nargs="*")
    opts = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        spec = big_spec(folder)
        data = big_csv(folder)
        print(f"spec {spec.stat().st_size} bytes (limit {MAX_SPEC_BYTES}); "
              f"CSV {data.stat().st_size} bytes (limit {MAX_INPUT_BYTES}), "
              f"{sum(1 for ln in open(data) if not ln.startswith('#')) - 1} rows")
        dense = dense_toml(folder)
        cases = {
            "analyze": (["analyze", str(spec)], ["analyze", str(DRIVE)]),
            "analyze*": (["analyze", str(dense)], ["analyze", str(DRIVE)]),
            "check": (["check", str(spec)], ["check", str(DRIVE)]),
            "simulate": (["simulate", str(spec), "-f", "csv"], ["simulate", str(DRIVE), "-f", "csv"]),
            "synth": (["synth", str(spec), "--seed", "1"], ["synth", str(DRIVE), "--seed", "1"]),
            "sweep": (["sweep", str(spec), "--i", "2:10:20", "--l-mm", "100:300:20", "-f", "csv"],
                      ["sweep", str(DRIVE), "--i", "2:10:20", "--l-mm", "100:300:20", "-f", "csv"]),
            "measure": (["measure", str(data), "--drive", str(spec), "-f", "json"],
                        ["measure", str(DATA), "--drive", str(DRIVE), "-f", "json"]),
            "diagnose": (["diagnose", str(spec), str(data), "-f", "json"],
                         ["diagnose", str(DRIVE), str(DATA), "-f", "json"]),
        }
        print(f"{'command':<10}{'limit s':>10}{'MiB':>8}{'shipped s':>11}{'MiB':>8}{'time x':>8}{'mem x':>7}  exit")
        for name, (big, small) in cases.items():
            if opts.only and name not in opts.only:
                continue
            ws, ms, _ = run(small, opts.limit)
            wb, mb, code = run(big, opts.limit)
            shown = f"{wb:10.2f}" if wb != float("inf") else f"{'>' + str(int(opts.limit)):>10}"
            print(f"{name:<10}{shown}{mb:8.0f}{ws:11.2f}{ms:8.0f}{wb / ws:8.1f}{mb / ms:7.1f}  {code}", flush=True)


if __name__ == "__main__":
    main()
