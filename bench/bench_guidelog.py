"""Time to read a 10 MB PHD2 guide log (prints figures; not a test).

The log is the test data's real logs joined end to end until it reaches ``--mb`` megabytes (a
night's log of a one-second guide camera is about that size): sessions, INFO lines, DROP and
dead-reckoning rows as PHD2 writes them.  Timed, best of ``--repeat``:

* ``read_guidelog``: the whole reader (sections, headers, frames, dithers, pulses, the sign check,
  angles, notes) on the text already in memory;
* a plain parse of the same frame rows with the csv module (every line that starts with a digit,
  Time, RARawDistance and RADuration converted): the least any reader must do.

Wall time and CPU time of this process are printed (the CPU time is steadier when the machine is
shared).

Target (issue 20): under 2 s for 10 MB.

Run: python bench/bench_guidelog.py [--mb 10] [--repeat 3]
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from _timing import best_of  # noqa: E402

from wormgear_cli.measurement.guidelog import read_guidelog  # noqa: E402

LOGS = [ROOT / "tests" / "data" / "telescope" / name
        for name in ("cge-pro-180.guidelog.txt", "eq6-ppec-19-sessions.guidelog.txt")]


def best_cpu(fn, repeat: int) -> float:
    """Least CPU time [s] of this process over ``repeat`` calls of ``fn``."""
    times = []
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return min(times)


def big_log(mb: float) -> str:
    parts = [p.read_text().replace("\r\n", "\n") for p in LOGS]
    out, size, k = [], 0, 0
    while size < mb * 1e6:
        out.append(parts[k % len(parts)])
        size += len(out[-1])
        k += 1
    return "\n".join(out)


def plain_csv(text: str) -> int:
    n = 0
    for row in csv.reader(line for line in text.split("\n") if line[:1].isdigit()):
        float(row[1])
        if row[2] == '"Mount"' or row[2] == "Mount":
            float(row[5])
            int(row[9] or 0)
        n += 1
    return n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mb", type=float, default=10.0)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    text = big_log(args.mb)
    m = read_guidelog(text, "bench")
    rows = plain_csv(text)
    t_reader = best_of(lambda: read_guidelog(text, "bench"), args.repeat)
    t_csv = best_of(lambda: plain_csv(text), args.repeat)
    c_reader = best_cpu(lambda: read_guidelog(text, "bench"), args.repeat)
    c_csv = best_cpu(lambda: plain_csv(text), args.repeat)
    print(f"log: {len(text) / 1e6:.1f} MB, {rows} frame rows, {len(m)} frames with a star, "
          f"{len(set(m.run.tolist()))} sessions")
    print(f"                          wall      CPU   (best of {args.repeat}; CPU is steadier on a shared machine)")
    print(f"read_guidelog:          {t_reader:6.3f} s  {c_reader:6.3f} s   (target < 2 s)")
    print(f"plain csv-module parse: {t_csv:6.3f} s  {c_csv:6.3f} s")
    print(f"ratio reader / csv:     {t_reader / t_csv:6.2f}    {c_reader / c_csv:6.2f}")


if __name__ == "__main__":
    main()
