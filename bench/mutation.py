"""Mutation testing of one module at a time with mutmut (the ``mutation`` extra).

Usage (from the repository root)::

    python bench/mutation.py --list                      # the targets and their test selections
    python bench/mutation.py worm                        # one target, 1 worker, prints the score
    nohup python bench/mutation.py gear > /tmp/mut-gear.log 2>&1 &   # in the background
    python bench/mutation.py --faults                    # the hand-made faults of bench/faults.py
    python bench/mutation.py --faults --changed          # those in the files this branch changes
    python bench/mutation.py --faults iso230-ddof rank-by-F   # named ones

Each run copies ``wormgear_cli/``, ``tests/`` and ``pyproject.toml`` into a scratch directory
(``$TMPDIR/wormgear-mutation/<target>``), adds a ``[tool.mutmut]`` section there that mutates
only the target's file(s) and runs only the target's test selection, runs ``mutmut run
--max-children N`` (default 1: the machine is small and shared) and prints the score::

    target  killed  survived  timeout  no-tests  score
    worm        61         0        0         0  100.0 %

followed by the name of every surviving mutant (``--show``: with its diff).  The score counts killed + timeout
over every mutant that ran; mutants no selected test reaches ("no tests") count as survivors.  A
surviving mutant is either equivalent (state why in docs/development-testing.md) or a gap
in the tests (write the test that kills it).  The scratch copy is left in place so
``mutmut show <name>`` / ``mutmut results`` can be run there; ``--clean`` removes it first.

``--faults`` runs the hand-made faults of ``bench/faults.py`` instead (no mutmut needed): each is put
into a scratch copy (``$TMPDIR/wormgear-faults``) on its own, its test selection is run (``-x``, the
everyday set) and it is "killed" when a test fails, "survived" when all pass, "moved" when its text
is no longer found exactly once (update the entry).  One line per fault, then the score.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: target -> (files mutated, test selection, functions scored or None for all).  Selections are
#: the tests that check the target by its inputs and outputs; keep each run near 10 minutes on
#: one core.
TARGETS: dict[str, tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...] | None]] = {
    # what a new user trips on (issue 25): file kinds told apart, help examples laid out whole
    "filekind": (("wormgear_cli/spec/filekind.py", "wormgear_cli/cli/helptext.py"),
                 ("tests/cli/test_swapped_files.py", "tests/cli/test_help_layout.py"), None),
    "worm": (("wormgear_cli/physics/worm.py",),
             ("tests/physics/test_hand_worked.py", "tests/physics/test_stage_models.py"), None),
    "deformation": (("wormgear_cli/physics/deformation.py",),
                    ("tests/physics/test_hand_worked.py", "tests/physics/test_stage_models.py"), None),
    "thermal": (("wormgear_cli/physics/thermal.py",),
                ("tests/physics/test_hand_worked.py",), None),
    "gear": (("wormgear_cli/physics/spur.py",),
             ("tests/physics/test_hand_worked.py", "tests/physics/test_stage_models.py"), None),
    # the catalogue's records (_phase, _tref) are built when the module is imported, before mutmut
    # switches a mutant on, so their mutants cannot be seen in a forked worker: they are left out
    # here and checked by tests/physics/test_effects_hand.py::test_*_parameter_record and by hand
    # (docs/development-testing.md)
    "effects": (("wormgear_cli/physics/effects.py",),
                ("tests/physics/test_effects_hand.py", "tests/physics/test_effects.py"),
                ("output_gear_runout", "intermediate_shaft_runout", "worm_runout", "gear_mesh_error",
                 "thermal_backlash", "thermal_drift", "torsional_compliance", "bearing_clearance", "make",
                 "param", "effect_error", "params_from_keys", "params_to_keys")),
    # the drive layer: the train's ratios, turns and orders; the belt stage (by hand in tests/drive)
    "train": (("wormgear_cli/drive/train.py",), ("tests/drive/test_train.py",),
              ("train", "_teeth", "orders", "_of", "shaft_label")),
    "belt": (("wormgear_cli/drive/belt.py",), ("tests/drive/test_belt.py", "tests/drive/test_train.py"), None),
    "iso230": (("wormgear_cli/measurement/iso230.py",),
               ("tests/measurement/test_iso230_hand.py",), None),
    # the step of the readings (digits written, encoder grid, common step)
    "resolution": (("wormgear_cli/measurement/resolution.py",),
                   ("tests/measurement/test_resolution.py",), None),
    # cells to numbers: direction words, their orientation, the range checks
    "reader-values": (("wormgear_cli/measurement/readers/values.py",),
                      ("tests/measurement/test_readers.py", "tests/measurement/test_reader.py",
                       "tests/measurement/test_reader_formats.py"), None),
    # the aliasing decisions (correlations, groups, folding); the least-squares fits are left to
    # a later round (run them with a functions list of their own)
    "serial": (("wormgear_cli/measurement/serial.py",), ("tests/measurement/test_serial.py",), None),
    "separation": (("wormgear_cli/measurement/separation.py",), ("tests/measurement/test_separation.py",), None),
    "harmonics": (("wormgear_cli/measurement/harmonics.py",),
                  ("tests/measurement/test_aliasing.py", "tests/measurement/test_harmonics.py"),
                  ("_sampling", "_correlations", "order_correlations", "offset_correlations", "_groups",
                   "alias_groups", "folded_orders", "_folded")),
    # the diagnosis statistics: REML, GLS sufficient statistics, Wald/Satterthwaite, containment
    # df.  Mutating all of diagnose is far beyond 10 minutes; only these functions are run.
    # (Bonferroni and the interval quantile sit inside the selection loop and _final_inference,
    # whose mutants need a full diagnose per test: they are checked by the five-fault script.)
    # Only runs.py and mixed.py are mutated (generating the mutants of the whole package took
    # ~11 minutes).  The names follow the package split (pass_sums, fit_at, level_shares and
    # variance_info lost their underscore: the first round's list never ran them).
    "statistics": (("wormgear_cli/diagnosis/runs.py", "wormgear_cli/diagnosis/mixed.py"),
                   ("tests/diagnosis/test_dof.py", "tests/diagnosis/test_statistics_groups.py",
                    "tests/diagnosis/test_statistics_reml.py"),
                   ("make_groups", "pass_sums", "weighted", "_neg2_reml", "fit_at", "reml",
                    "_full_neg2_reml", "level_shares", "containment_df", "variance_info", "_df_of",
                    "wald", "contrast_df")),
    # ISO 1328 grades: pure functions of the grade and the geometry
    "iso1328": (("wormgear_cli/physics/iso1328.py",),
                ("tests/physics/test_iso1328.py",), None),
    # the error budget (lines, sums, phased peak); analysis is run for real by its tests
    "budget": (("wormgear_cli/analysis/budget.py",),
               ("tests/analysis/test_budget.py",), None),
    # tolerance analysis: the input distributions and the streaming statistics
    "tolerance-sampling": (("wormgear_cli/tolerance/sampling.py",),
                           ("tests/tolerance/test_sampling.py",), None),
    "tolerance-statistics": (("wormgear_cli/tolerance/statistics.py",),
                             ("tests/tolerance/test_statistics.py",), None),
    # --shard K/N and --shard auto (the schedulers' array variables)
    "batch-shards": (("wormgear_cli/batch/shards.py",), ("tests/batch/test_shards.py",), None),
    # compensate: the writers (checked against LinuxCNC's and EQASCOM's reading rules) and the
    # table arithmetic (points, what a table carries, how a controller applies it, noise, scans)
    "compensation-writers": (("wormgear_cli/output/writers/__init__.py", "wormgear_cli/output/writers/linuxcnc.py",
                              "wormgear_cli/output/writers/eqmod.py",
                              "wormgear_cli/output/writers/correction_csv.py"),
                             ("tests/output/test_writers.py",), None),
    "compensation-table": (("wormgear_cli/compensation/table.py", "wormgear_cli/compensation/noise.py",
                            "wormgear_cli/compensation/scan.py"),
                           ("tests/compensation/test_table.py", "tests/compensation/test_noise.py",
                            "tests/compensation/test_scan.py"), None),
    # the gear functions that compute values (the maximiser is scored with them; the location of
    # its maximum is checked against scipy's bounded minimiser in test_hand_worked.py)
    "gear-values": (("wormgear_cli/physics/spur.py",),
                    ("tests/physics/test_hand_worked.py",),
                    ("eccentricity_ratio", "contact_phase_angle", "kinematic_bracket", "gear_kinematic_te",
                     "gear_deformation_te", "gear_te", "gear_te_max", "gear_backlash", "gear_backlash_max",
                     "pitch_arc_to_angle", "_bracket_constants", "kinematic_bracket_derivatives",
                     "load_factor_derivatives", "kinematic_peak", "gear_te_max_fast", "involute_stage")),
    # the one quoting of names (issue 23, item 9): escapes, TOML quoting, CSV formula cells
    "quoting": (("wormgear_cli/errors.py",),
                ("tests/test_errors.py",),
                ("_escaped", "escape", "quote", "toml_key", "csv_cell")),
    # the guard on the model's results (issue 23, item 11)
    "sanity": (("wormgear_cli/analysis/sanity.py",),
               ("tests/analysis/test_sanity.py",), None),
    # the guide-log reader (PHD2 logs) and the periodic error of a worm, checked by their tests
    "guidelog": (("wormgear_cli/measurement/guidelog.py",),
                 ("tests/measurement/test_guidelog.py",), None),
    "periodic-error": (("wormgear_cli/measurement/periodic_error.py",),
                       ("tests/measurement/test_periodic_error.py",), None),
}


def _patterns(functions) -> list[str]:
    """mutmut name patterns of the functions' mutants (plain functions and methods)."""
    return [f"*{sep}{fn}__mutmut_*" for fn in functions for sep in ("x_", "\u01c1")]


def _copy_tree(dest: Path) -> None:
    if dest.exists():
        shutil.rmtree(dest)
    dest.mkdir(parents=True)
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "mutants", ".hypothesis")
    shutil.copytree(ROOT / "wormgear_cli", dest / "wormgear_cli", ignore=ignore)
    shutil.copytree(ROOT / "tests", dest / "tests", ignore=ignore)
    shutil.copytree(ROOT / "configs", dest / "configs", ignore=ignore)
    shutil.copy2(ROOT / "pyproject.toml", dest / "pyproject.toml")


def _toml_list(items) -> str:
    return "[" + ", ".join(f'"{i}"' for i in items) + "]"


def _configure(dest: Path, files, tests) -> None:
    text = (dest / "pyproject.toml").read_text(encoding="utf-8")
    text += (
        "\n[tool.mutmut]\n"
        'source_paths = ["wormgear_cli"]\n'
        'also_copy = ["configs"]\n'
        f"only_mutate = {_toml_list(files)}\n"
        f"pytest_add_cli_args_test_selection = {_toml_list(tests)}\n"
        'pytest_add_cli_args = ["-p", "no:cacheprovider", "-q", "-x", "-m", "not slow"]\n'
        "use_git_change_detection = false\n"
    )
    (dest / "pyproject.toml").write_text(text, encoding="utf-8")


def _results(dest: Path, env) -> list[tuple[str, str]]:
    out = subprocess.run(["mutmut", "results", "--all", "true"], cwd=dest, env=env, capture_output=True, text=True)
    rows = []
    for line in out.stdout.splitlines():
        m = re.match(r"\s*(\S+__mutmut_\d+): (.+)$", line)
        if m:
            rows.append((m.group(1), m.group(2).strip()))
    return rows


def _fault_pytest(dest: Path, tests, timeout: int) -> tuple[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONPATH"] = str(dest)
    try:
        out = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", "-x", "-m", "not slow",
                              *tests], cwd=dest, env=env, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "timeout", ""
    failed = re.findall(r"^FAILED (\S+)", out.stdout, flags=re.M)
    if out.returncode == 0:
        return "survived", ""
    if out.returncode == 1:
        return "killed", failed[0] if failed else ""
    tail = (out.stdout.strip().splitlines() or [""])[-1]
    return f"error {out.returncode}", tail


def run_faults(names, changed: bool, timeout: int) -> int:
    """Put each hand-made fault into a scratch copy on its own and run its tests; print the score."""
    sys.path.insert(0, str(ROOT / "bench"))
    from faults import FAULTS

    chosen = names or list(FAULTS)
    unknown = [n for n in chosen if n not in FAULTS]
    if unknown:
        print(f"unknown faults: {', '.join(unknown)} (see bench/faults.py)", file=sys.stderr)
        return 2
    if changed:
        diff = subprocess.run(["git", "diff", "--name-only", "main...HEAD"], cwd=ROOT, capture_output=True,
                              text=True).stdout.split()
        touched = {d.removeprefix("wormgear_cli/") for d in diff if d.startswith("wormgear_cli/")}
        chosen = [n for n in chosen if FAULTS[n].file in touched]
    dest = Path(tempfile.gettempdir()) / "wormgear-faults"
    _copy_tree(dest)
    count: dict[str, int] = {}
    for name in chosen:
        f = FAULTS[name]
        path = dest / "wormgear_cli" / f.file
        text = path.read_text(encoding="utf-8")
        if text.count(f.old) != 1:
            status, detail = "moved", f"text found {text.count(f.old)} times in {f.file}"
        else:
            path.write_text(text.replace(f.old, f.new), encoding="utf-8")
            try:
                status, detail = _fault_pytest(dest, f.tests, timeout)
            finally:
                path.write_text(text, encoding="utf-8")
        count[status] = count.get(status, 0) + 1
        print(f"{status:9s} {name:26s} {f.why}" + (f"  [{detail}]" if detail else ""), flush=True)
    ran = sum(count.values())
    killed = count.get("killed", 0) + count.get("timeout", 0)
    print(f"\n{killed} of {ran} faults killed ({100.0 * killed / ran if ran else float('nan'):.1f} %); "
          + ", ".join(f"{k} {v}" for k, v in sorted(count.items())))
    return 0 if killed == ran else 1


def main(argv=None) -> int:
    # the property tests draw their full count of examples, as in CI (tests/support/examples.py)
    os.environ.setdefault("WORMGEAR_TEST_EXAMPLES", "full")
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("target", nargs="*", help="a mutmut target (see --list), or fault names with --faults")
    ap.add_argument("--faults", action="store_true", help="run the hand-made faults of bench/faults.py")
    ap.add_argument("--changed", action="store_true", help="with --faults: only faults in files that differ "
                    "from main")
    ap.add_argument("--timeout", type=int, default=900, help="with --faults: seconds per fault (default 900)")
    ap.add_argument("--list", action="store_true", help="print the targets and their test selections")
    ap.add_argument("--max-children", type=int, default=1, help="parallel mutant workers (default 1)")
    ap.add_argument("--workdir", type=Path, default=Path(tempfile.gettempdir()) / "wormgear-mutation")
    ap.add_argument("--clean", action="store_true", help="start from a fresh scratch copy")
    ap.add_argument("--report-only", action="store_true", help="print the score of the last run")
    ap.add_argument("--show", action="store_true", help="print each surviving mutant's diff (slow: one "
                    "mutmut call per mutant)")
    args = ap.parse_args(argv)
    if args.faults:
        return run_faults(args.target, args.changed, args.timeout)
    if len(args.target) > 1 or (args.target and args.target[0] not in TARGETS):
        ap.error(f"one target of: {', '.join(sorted(TARGETS))}")
    args.target = args.target[0] if args.target else None
    if args.list or not args.target:
        for name, (files, tests, _) in TARGETS.items():
            print(f"{name:12s} {' '.join(files)}\n{'':12s} tests: {' '.join(tests)}")
        return 0
    files, tests, functions = TARGETS[args.target]
    dest = args.workdir / args.target
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONPATH"] = str(dest)
    if not args.report_only:
        if args.clean or not dest.exists():
            _copy_tree(dest)
        else:  # refresh sources and tests, keep mutmut's cache
            for sub in ("wormgear_cli", "tests", "configs"):
                shutil.rmtree(dest / sub)
                shutil.copytree(ROOT / sub, dest / sub,
                                ignore=shutil.ignore_patterns("__pycache__", "*.pyc", ".hypothesis"))
            shutil.copy2(ROOT / "pyproject.toml", dest / "pyproject.toml")
        _configure(dest, files, tests)
        names = _patterns(functions) if functions else []
        run = subprocess.run(["mutmut", "run", "--max-children", str(args.max_children), *names], cwd=dest,
                             env=env)
        if run.returncode not in (0, None):
            print(f"mutmut run exited with {run.returncode}", file=sys.stderr)
    rows = _results(dest, env)
    if functions:
        keep = re.compile(r"(?:x_|\u01c1)(" + "|".join(functions) + r")__mutmut_\d+$")
        rows = [r for r in rows if keep.search(r[0])]
    count = dict.fromkeys(("killed", "survived", "timeout", "no tests", "suspicious", "skipped"), 0)
    for _, status in rows:
        count[status] = count.get(status, 0) + 1
    ran = count["killed"] + count["survived"] + count["timeout"] + count["no tests"] + count["suspicious"]
    score = 100.0 * (count["killed"] + count["timeout"]) / ran if ran else float("nan")
    print(f"{'target':12s} {'killed':>7s} {'survived':>9s} {'timeout':>8s} {'no-tests':>9s} {'score':>8s}")
    print(f"{args.target:12s} {count['killed']:7d} {count['survived']:9d} {count['timeout']:8d} "
          f"{count['no tests']:9d} {score:7.1f} %")
    left = [(name, status) for name, status in rows if status in ("survived", "no tests", "suspicious")]
    for name, status in left:
        print(f"{status}: {name}")
        if args.show:
            show = subprocess.run(["mutmut", "show", name], cwd=dest, env=env, capture_output=True, text=True)
            print(show.stdout.strip() + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
