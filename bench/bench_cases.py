"""CPU time of the whole command on the slow cases users met (issue 24 trials), before and after.

Cases (``--cases``, comma-separated; default all):

* ``tel``: ``diagnose configs/eq6-belt-worm.toml`` on the 19-session EQ6 guide log
  (tests/data/telescope/eq6-ppec-19-sessions.guidelog.txt, 2305 frames);
* ``field``: ``diagnose configs/mch50.toml`` on tests/data/field/partial-span-order144.csv
  (2364 rows, one pass);
* ``measure190``: ``measure`` (orders scanned, drift fitted per session) on a 190-session guide
  log made here from the EQ6 log (its sessions repeated ten times).

Each case runs as a user runs it, ``python -m wormgear_cli ... --format json -o FILE`` in a fresh
process, on this tree and (``--before REV``) on a checkout of REV (``git worktree add`` in a
temporary directory, removed afterwards): the plain alternative is the code as it was.  The CPU
time (user + system of the child, resource.getrusage) is the figure to compare -- the machine may
be shared, wall time is printed too.  ``--env`` picks the environment: ``one`` (default) sets
OPENBLAS/OMP/MKL_NUM_THREADS=1, as the tests and bench/compare_outputs.py do; ``default`` removes
every BLAS thread variable, as a user's shell has it (there the code before the one-thread default
of the CLI ran OpenBLAS on every core: slow, and the EQ6 report differed in the 5th digit).
The JSON outputs of the two trees are compared byte for byte: ``identical`` or ``OUTPUTS DIFFER``.

Usage: python bench/bench_cases.py [--before REV] [--cases tel,field,measure190] [--env one|default] [--repeat N]
"""

from __future__ import annotations

import argparse
import filecmp
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

TEL = Path("tests/data/telescope/eq6-ppec-19-sessions.guidelog.txt")
BLAS = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS",
        "VECLIB_MAXIMUM_THREADS")


def repeated_log(path: Path, copies: int = 10) -> None:
    """The EQ6 log with its sessions (from the first ``Guiding Begins`` on) written ``copies`` times."""
    text = (ROOT / TEL).read_text()
    start = text.index("Guiding Begins")
    path.write_text(text[:start] + text[start:] * copies)


def cases(tmp: Path) -> dict[str, list[str]]:
    log190 = tmp / "eq6-190-sessions.guidelog.txt"
    repeated_log(log190)
    return {
        "tel": ["diagnose", "configs/eq6-belt-worm.toml", str(TEL)],
        "field": ["diagnose", "configs/mch50.toml", "tests/data/field/partial-span-order144.csv"],
        "measure190": ["measure", str(log190)],
    }


def run(tree: Path, args: list[str], out: Path, env_kind: str, repeat: int) -> dict:
    """Median CPU and wall [s] of ``repeat`` runs of the command on ``tree``; writes its JSON to ``out``."""
    env = {k: v for k, v in os.environ.items() if k not in BLAS}
    env["PYTHONPATH"] = str(tree)
    if env_kind == "one":
        env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    cpus, walls = [], []
    for _ in range(repeat):
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "wormgear_cli", *args, "--format", "json", "-o", str(out)],
                       check=True, env=env, cwd=tree, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        walls.append(time.perf_counter() - t0)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append((r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime))
    return {"cpu_s": statistics.median(cpus), "wall_s": statistics.median(walls)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", default=None, help="git revision to compare against (checked out in a temp dir)")
    ap.add_argument("--cases", default="tel,field,measure190", help="comma-separated: tel, field, measure190")
    ap.add_argument("--env", choices=("one", "default"), default="one",
                    help="one: one BLAS thread set in the environment; default: no BLAS thread variable")
    ap.add_argument("--repeat", type=int, default=1, help="runs per case and tree (median)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        table = cases(tmp)
        with checkout(args.before, tmp / "before") as before:
            print(f"environment: {'one BLAS thread' if args.env == 'one' else 'no BLAS thread variable'}; "
                  f"CPU = user + system of the command's process")
            for name in args.cases.split(","):
                now = run(ROOT, table[name], tmp / f"{name}.now.json", args.env, args.repeat)
                text = f"{name:<11} now {now['cpu_s']:7.2f} s CPU ({now['wall_s']:6.1f} s wall)"
                if before is not None:
                    old = run(before, table[name], tmp / f"{name}.before.json", args.env, args.repeat)
                    same = filecmp.cmp(tmp / f"{name}.now.json", tmp / f"{name}.before.json", shallow=False)
                    text += (f" | {args.before[:7]} {old['cpu_s']:7.2f} s CPU ({old['wall_s']:6.1f} s wall)"
                             f" | before/now CPU {old['cpu_s'] / now['cpu_s']:5.2f}x | "
                             + ("identical" if same else "OUTPUTS DIFFER"))
                print(text, flush=True)


if __name__ == "__main__":
    main()
