"""Record every command's output on the shipped drives, the demo and the field cases, and
compare two recordings byte for byte.

A refactoring that moves code must not change what a user sees.  This script runs each
command of a fixed list (``CASES``) as a user would (``python -m wormgear_cli ...`` in a
scratch copy of ``configs/`` and ``tests/data/``), and stores stdout, stderr, the exit code
and every file the command wrote under ``OUT/<case>/``.  Run it on the tree before and after
a change and compare::

    python bench/compare_outputs.py record /tmp/before --tree /path/to/old/checkout
    python bench/compare_outputs.py record /tmp/after            # this tree
    python bench/compare_outputs.py diff /tmp/before /tmp/after  # exit 1 on any difference

``--tree`` names the source tree whose ``wormgear_cli`` is run (``PYTHONPATH``); its
``configs/`` and ``tests/data/`` are the inputs, so both recordings read the same files.
Cases are run with one BLAS thread, ``COLUMNS=80``, no colour and a fixed locale, so the
bytes depend on the code only.
"""

from __future__ import annotations

import argparse
import filecmp
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: case name -> arguments of ``wormgear`` (run in the scratch directory, which holds configs/
#: and field/); outputs written with -o/--truth/--plot/--write-spec land in the case folder
CASES: dict[str, list[str]] = {
    "help": ["--help"],
    **{f"help-{c}": [c, "--help"] for c in ("analyze", "check", "new", "grade", "tolerance", "sweep",
                                             "simulate", "synth", "measure", "diagnose")},
    "analyze-mch50": ["analyze", "configs/mch50.toml"],
    "analyze-mch50-json": ["analyze", "configs/mch50.toml", "--format", "json"],
    "analyze-mch50-csv-deg": ["analyze", "configs/mch50.toml", "--format", "csv", "--unit", "deg"],
    "analyze-precision": ["analyze", "configs/rotary-table-precision.toml"],
    "analyze-precision-json": ["analyze", "configs/rotary-table-precision.toml", "-f", "json"],
    "analyze-radar": ["analyze", "configs/radar-pedestal-2start.toml"],
    "analyze-radar-json": ["analyze", "configs/radar-pedestal-2start.toml", "-f", "json"],
    "check-all": ["check", "configs/mch50.toml", "configs/rotary-table-precision.toml",
                  "configs/radar-pedestal-2start.toml"],
    "check-all-json": ["check", "configs/mch50.toml", "configs/rotary-table-precision.toml",
                       "configs/radar-pedestal-2start.toml", "--format", "json"],
    "new": ["new", "OUT/new.toml"],
    "grade": ["grade", "--grade", "6", "--module-mm", "2.5", "--diameter-mm", "360", "--face-width-mm", "50"],
    "grade-json": ["grade", "-g", "5", "--module-mm", "2", "--diameter-mm", "100", "--face-width-mm", "20",
                   "-f", "json"],
    "tolerance-mch50": ["tolerance", "configs/mch50.toml", "--samples", "3000", "--seed", "1"],
    "tolerance-precision-json": ["tolerance", "configs/rotary-table-precision.toml", "--samples", "2000",
                                 "--seed", "2", "--metrics", "all", "-f", "json"],
    "tolerance-radar-csv": ["tolerance", "configs/radar-pedestal-2start.toml", "--samples", "500", "-f", "csv",
                            "-o", "OUT/samples.csv"],
    "sweep-paper": ["sweep", "configs/mch50.toml", "--i", "2:12:6", "--l-mm", "100:300:5"],
    "sweep-paper-csv": ["sweep", "configs/mch50.toml", "--i", "2:12:6", "--l-mm", "100:300:5", "-f", "csv"],
    "sweep-param-json": ["sweep", "configs/rotary-table-precision.toml", "--param",
                         "loads.gear_normal_force_N=0:2000:5", "-f", "json"],
    "simulate-mch50": ["simulate", "configs/mch50.toml", "--points", "720", "-o", "OUT/curve.csv"],
    "simulate-radar-json": ["simulate", "configs/radar-pedestal-2start.toml", "--points", "200", "-f", "json"],
    "synth-mch50": ["synth", "configs/mch50.toml", "-o", "OUT/test.csv", "--truth", "OUT/truth.json",
                    "--seed", "1"],
    "synth-radar-dense": ["synth", "configs/radar-pedestal-2start.toml", "--plan", "dense", "--points", "2000",
                          "--seed", "3", "-o", "OUT/dense.csv"],
    "measure-warm": ["measure", "configs/mch50-warm.csv", "--drive", "configs/mch50.toml"],
    "measure-warm-json": ["measure", "configs/mch50-warm.csv", "--drive", "configs/mch50.toml", "-f", "json"],
    "measure-warm-csv": ["measure", "configs/mch50-warm.csv", "-f", "csv"],
    "diagnose-warm": ["diagnose", "configs/mch50.toml", "configs/mch50-warm.csv"],
    "diagnose-warm-json": ["diagnose", "configs/mch50.toml", "configs/mch50-warm.csv", "-f", "json",
                           "-o", "OUT/report.json", "--write-spec", "OUT/warm.toml"],
    "measure-field-partial": ["measure", "field/partial-span-order144.csv", "--orders", "1,144"],
    "measure-field-nodir": ["measure", "field/no-direction-column.csv", "-f", "json"],
    "measure-field-onepos": ["measure", "field/one-position-backlash.csv"],
    "measure-field-sheet": ["measure", "field/spreadsheet-export.csv", "--map", "angle_deg=Position (deg)",
                            "--map", "error_arcsec=Abweichung (arcsec)", "--map", "direction=Richtung",
                            "--map", "run=Lauf", "--map", "temperature_C=Temperatur (°C)"],
    "measure-field-sheet-nomap": ["measure", "field/spreadsheet-export.csv"],
    "diagnose-field-restarts": ["diagnose", "field/telescope-mount.toml", "field/time-restarts-no-run.csv",
                                "-f", "json"],
    "diagnose-field-restarts-run": ["diagnose", "field/telescope-mount.toml", "field/time-restarts-with-run.csv"],
    "error-missing-file": ["analyze", "configs/nope.toml"],
    "error-bad-option": ["analyze", "configs/mch50.toml", "--formt", "json"],
}


def _env(tree: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("WORMGEAR", "PYTHON"))}
    env.update(PYTHONPATH=str(tree), COLUMNS="80", LC_ALL="C.UTF-8", LANG="C.UTF-8", NO_COLOR="1",
               TERM="dumb", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1",
               PYTHONHASHSEED="0", TZ="UTC", MPLBACKEND="Agg")
    return env


def record(out: Path, tree: Path, only: list[str] | None) -> int:
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="wormgear-compare-") as tmp:
        work = Path(tmp)
        shutil.copytree(tree / "configs", work / "configs")
        shutil.copytree(tree / "tests" / "data" / "field", work / "field")
        for name, args in CASES.items():
            if only and name not in only:
                continue
            case = out / name
            if case.exists():
                shutil.rmtree(case)
            case.mkdir()
            scratch = work / "OUT"
            scratch.mkdir()
            proc = subprocess.run([sys.executable, "-m", "wormgear_cli", *args], cwd=work, env=_env(tree),
                                  capture_output=True, timeout=600)
            (case / "stdout").write_bytes(proc.stdout)
            (case / "stderr").write_bytes(proc.stderr)
            (case / "exit").write_text(f"{proc.returncode}\n")
            for f in sorted(scratch.iterdir()):
                shutil.copy(f, case / ("file-" + f.name))
            shutil.rmtree(scratch)
            print(f"{name}: exit {proc.returncode}", file=sys.stderr)
    return 0


def diff(a: Path, b: Path) -> int:
    bad = 0
    names = sorted({p.name for p in a.iterdir()} | {p.name for p in b.iterdir()})
    for name in names:
        da, db = a / name, b / name
        if not da.is_dir() or not db.is_dir():
            print(f"{name}: only in {'before' if da.is_dir() else 'after'}")
            bad += 1
            continue
        cmp = filecmp.dircmp(da, db)
        files = sorted(set(cmp.left_list) | set(cmp.right_list))
        for f in files:
            fa, fb = da / f, db / f
            if not fa.exists() or not fb.exists() or fa.read_bytes() != fb.read_bytes():
                print(f"{name}/{f}: differs")
                bad += 1
    print(f"{len(names)} cases, {bad} differences", file=sys.stderr)
    return 1 if bad else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="cmd", required=True)
    rec = sub.add_parser("record", help="run every case and store its output")
    rec.add_argument("out", type=Path)
    rec.add_argument("--tree", type=Path, default=ROOT, help="source tree to run (default: this one)")
    rec.add_argument("--only", nargs="*", help="run only these cases")
    dif = sub.add_parser("diff", help="compare two recordings (exit 1 on any difference)")
    dif.add_argument("before", type=Path)
    dif.add_argument("after", type=Path)
    args = parser.parse_args(argv)
    if args.cmd == "record":
        return record(args.out, args.tree.resolve(), args.only)
    return diff(args.before, args.after)


if __name__ == "__main__":
    sys.exit(main())
