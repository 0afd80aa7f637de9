"""--jobs, --shard auto, resumable parts and wormgear merge through the CLI.

What the issue asks to hold, byte for byte: --jobs 2 gives the output of --jobs 1 (sweep,
tolerance; diagnose and simulate --at too); --shard auto under a 0-based Slurm array gives
the explicit part; an interrupted sharded run resumes, and its merged parts equal the
unsharded run.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from tests.support.paths import MCH50
from tests.support.processes import shell_status
from wormgear_cli.cli import app

GRID = ("--i", "2:10:40", "--l-mm", "100:300:3000")  # 120 000 points: two chunks per part of 3
SLURM_0_BASED = {"SLURM_ARRAY_TASK_MIN": "0", "SLURM_ARRAY_TASK_MAX": "2", "SLURM_ARRAY_TASK_STEP": "1",
                 "SLURM_ARRAY_TASK_COUNT": "3"}


def run(runner, *args, env=None):
    r = runner.invoke(app, [str(a) for a in args], env=env)
    assert r.exit_code == 0, r.output
    return r


def _slurm(task: int) -> dict:
    return {**SLURM_0_BASED, "SLURM_ARRAY_TASK_ID": str(task)}


@pytest.fixture
def no_array_env(monkeypatch):
    for name in ("SLURM_ARRAY_TASK_ID", "SGE_TASK_ID", "PBS_ARRAY_INDEX", "PBS_ARRAYID"):
        monkeypatch.delenv(name, raising=False)


# --- --jobs: the same bytes ---------------------------------------------------------------------


@pytest.mark.parametrize("fmt", ["csv", pytest.param("json", marks=pytest.mark.slow)])
def test_sweep_jobs_2_equals_jobs_1(runner, fmt):
    grid = GRID if fmt == "csv" else ("--i", "2:10:30", "--l-mm", "100:300:3000")
    one = run(runner, "sweep", MCH50, *grid, "--format", fmt, "--jobs", "1").stdout_bytes
    two = run(runner, "sweep", MCH50, *grid, "--format", fmt, "--jobs", "2").stdout_bytes
    assert one == two and len(one) > 1000


@pytest.mark.slow  # whole-command sweeps run twice; -j in the everyday set: the csv sweep and the API
def test_sweep_jobs_2_equals_jobs_1_to_a_file_snapped_and_by_param(runner, tmp_path):
    snap = ("--i", "2:10:60", "--l-mm", "100:300:2000", "--module-mm", "1.5")
    run(runner, "sweep", MCH50, *snap, "--format", "csv", "-o", tmp_path / "a.csv")
    run(runner, "sweep", MCH50, *snap, "--format", "csv", "-o", tmp_path / "b.csv", "-j", "2")
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    param = ("--param", "worm_pair.lead_error_mm=0:0.05:7", "--param", "assembly.gear_eccentricity_mm=0:0.03:31")
    one = run(runner, "sweep", MCH50, *param, "--format", "csv").stdout_bytes
    assert run(runner, "sweep", MCH50, *param, "--format", "csv", "-j", "2").stdout_bytes == one


@pytest.mark.parametrize("fmt, metrics", [pytest.param("csv", "paper", marks=pytest.mark.slow),
                                          pytest.param("json", "all", marks=pytest.mark.slow),
                                          ("table", "paper+budget")])
def test_tolerance_jobs_2_equals_jobs_1(runner, fmt, metrics):
    args = ("tolerance", MCH50, "-n", 140_000 if metrics != "all" else 70_000, "--metrics", metrics,
            "--format", fmt, "--seed", 5)
    one = run(runner, *args, "-j", "1").stdout_bytes
    assert run(runner, *args, "-j", "2").stdout_bytes == one


def test_tolerance_npy_jobs_2_equals_jobs_1(runner, tmp_path):
    args = ("tolerance", MCH50, "-n", 140_000, "--metrics", "paper", "--format", "npy")
    run(runner, *args, "-o", tmp_path / "1.npy")
    run(runner, *args, "-o", tmp_path / "2.npy", "-j", "2")
    assert (tmp_path / "1.npy").read_bytes() == (tmp_path / "2.npy").read_bytes()


@pytest.mark.slow  # two diagnose runs with 60 resamples each
def test_simulate_at_and_diagnose_jobs_2_equal_jobs_1(runner, tmp_path):
    data = tmp_path / "d.csv"
    run(runner, "synth", MCH50, "--plan", "dense", "--points", "400", "--runs", "5", "--noise-arcsec", "0.3",
        "--effect", "thermal_backlash", "--temperature", "warmup:20:30:1800", "--seed", "2", "-o", data)
    one = run(runner, "simulate", MCH50, "--at", data).stdout_bytes
    assert run(runner, "simulate", MCH50, "--at", data, "-j", "2").stdout_bytes == one
    args = ("diagnose", MCH50, data, "--format", "json", "--resamples", "60")
    one = run(runner, *args).stdout_bytes
    assert run(runner, *args, "-j", "2").stdout_bytes == one
    doc = json.loads(one)
    assert doc["effects_found"] and doc["effects_found"][0]["stability"] is not None  # the resamples ran


# --- --shard auto ---------------------------------------------------------------------------------


@pytest.mark.slow  # six sweeps of 40 000 points; the variables' reading: tests/batch/test_shards.py
def test_shard_auto_under_a_0_based_slurm_array_equals_the_explicit_part(runner, no_array_env):
    for task in range(3):
        auto = run(runner, "sweep", MCH50, *GRID, "--format", "csv", "--shard", "auto", env=_slurm(task))
        explicit = run(runner, "sweep", MCH50, *GRID, "--format", "csv", "--shard", f"{task + 1}/3")
        assert auto.stdout_bytes == explicit.stdout_bytes
        assert auto.stderr == (f"shard {task + 1}/3 (--shard auto) from Slurm: SLURM_ARRAY_TASK_ID={task}, "
                               "SLURM_ARRAY_TASK_MIN=0, SLURM_ARRAY_TASK_MAX=2, SLURM_ARRAY_TASK_STEP=1, "
                               "SLURM_ARRAY_TASK_COUNT=3\n")
    tol = ("tolerance", MCH50, "-n", 3000, "--metrics", "paper", "--format", "json")
    auto = run(runner, *tol, "--shard", "auto", env=_slurm(0)).stdout
    assert auto == run(runner, *tol, "--shard", "1/3").stdout
    assert json.loads(auto)["shard"] == {"part": "1/3", "first_sample": 0, "stop_sample": 1000}


def test_shard_auto_without_an_array_names_the_variables(runner, no_array_env):
    r = runner.invoke(app, ["tolerance", str(MCH50), "--shard", "auto"])
    assert (r.exit_code, r.stdout) == (2, "")
    assert r.stderr == ("error: --shard auto: no job-array index in the environment (SLURM_ARRAY_TASK_ID, "
                        "SGE_TASK_ID, PBS_ARRAY_INDEX, PBS_ARRAYID are unset); run it as a task of a job array, "
                        "or give --shard K/N\n")


# --- resumable parts, merge ---------------------------------------------------------------------


def _interrupt_at_block(monkeypatch, n):
    """Make the n-th tolerance block of this process raise KeyboardInterrupt (Ctrl-C mid-run)."""
    from wormgear_cli.tolerance import engine

    real, count = engine.block, [0]

    def block(s, b):
        count[0] += 1
        if count[0] == n:
            raise KeyboardInterrupt
        return real(s, b)

    monkeypatch.setattr(engine, "block", block)
    return lambda: monkeypatch.setattr(engine, "block", real)


@pytest.mark.slow  # nine tolerance runs of 50 000 to 150 000 samples; resume and merge in the everyday set:
# test_sweep_parts_resume_and_merge_to_the_unsharded_csv, test_merge_refuses_..., test_a_changed_run_...
@pytest.mark.parametrize("fmt", ["npy", "csv"])
def test_an_interrupted_sharded_tolerance_run_resumes_and_merges_to_the_unsharded_run(runner, tmp_path,
                                                                                      monkeypatch, fmt):
    n, parts = 150_000, 3  # parts end inside random-stream blocks (65 536 samples)
    base = ("tolerance", MCH50, "-n", n, "--metrics", "paper", "--seed", 3)
    paths = [tmp_path / f"part{k}.{fmt}" for k in range(1, parts + 1)]

    def part(k, **kw):
        return runner.invoke(app, [str(a) for a in (*base, "--format", fmt, "--shard", f"{k}/{parts}", "-o",
                                                    paths[k - 1])], **kw)

    assert part(1).exit_code == 0
    restore = _interrupt_at_block(monkeypatch, 1)
    stopped = part(2)
    restore()
    assert (stopped.exit_code, stopped.stderr) == (130, "interrupted; no output written\n")
    assert sorted(os.listdir(tmp_path)) == [f"part1.{fmt}", f"part1.{fmt}.manifest.json"]  # nothing of part 2
    first = paths[0].stat().st_mtime_ns
    redo = [part(k) for k in range(1, parts + 1)]  # the whole array again, as after a failed node
    assert all(r.exit_code == 0 for r in redo)
    assert redo[0].stderr == (f"part 1/3: {paths[0]} is complete and its manifest matches this run; skipped "
                              "(delete it to compute it again)\n")
    assert paths[0].stat().st_mtime_ns == first
    assert redo[1].stderr == f"wrote {paths[1]}\n"
    for report_fmt in ("json", "table"):
        unsharded = run(runner, *base, "--format", report_fmt).stdout
        assert run(runner, "merge", *reversed(paths), "--format", report_fmt).stdout == unsharded
    samples = run(runner, *base, "--format", "csv").stdout
    assert run(runner, "merge", *paths, "--format", "csv").stdout == samples


def test_npy_parts_are_compact_and_hold_the_metrics(runner, tmp_path):
    out = tmp_path / "p.npy"
    run(runner, "tolerance", MCH50, "-n", 5000, "--metrics", "paper", "--format", "npy", "--shard", "2/2",
        "-o", out)
    rec = np.load(out)
    assert rec.dtype.names == ("sample", "total_transmission_error_arcsec", "total_backlash_arcsec")
    assert rec["sample"].tolist() == list(range(2500, 5000))
    csv_text = run(runner, "tolerance", MCH50, "-n", 5000, "--metrics", "paper", "--format", "csv", "--shard",
                   "2/2").stdout
    rows = np.loadtxt(csv_text.splitlines()[1:], delimiter=",")
    assert np.array_equal(rows[:, -2:], np.column_stack([rec["total_transmission_error_arcsec"],
                                                         rec["total_backlash_arcsec"]]))
    assert out.stat().st_size < len(csv_text) / 5
    whole = tmp_path / "whole.npy"
    run(runner, "tolerance", MCH50, "-n", 5000, "--metrics", "paper", "--format", "npy", "-o", whole)
    assert not (tmp_path / "whole.npy.manifest.json").exists()  # manifests are for parts
    report = run(runner, "tolerance", MCH50, "-n", 5000, "--format", "json", "--summarize", whole).stdout
    assert report == run(runner, "tolerance", MCH50, "-n", 5000, "--metrics", "paper", "--format", "json").stdout
    r = runner.invoke(app, ["tolerance", str(MCH50), "--format", "npy"])
    assert (r.exit_code, r.stderr) == (2, "error: --format npy writes binary columns: give -o FILE.npy\n")
    manifest = json.loads((tmp_path / "p.npy.manifest.json").read_text())
    assert manifest["part"] == {"k": 2, "n": 2, "first": 2500, "stop": 5000, "total": 5000}
    assert manifest["parameters"]["seed"] == 0 and manifest["command"] == "tolerance"


def test_sweep_parts_resume_and_merge_to_the_unsharded_csv(runner, tmp_path):
    whole = run(runner, "sweep", MCH50, *GRID, "--format", "csv").stdout_bytes
    paths = [tmp_path / f"s{k}.csv" for k in (1, 2, 3)]
    for k, p in enumerate(paths, 1):
        run(runner, "sweep", MCH50, *GRID, "--format", "csv", "--shard", f"{k}/3", "-o", p, "-j", "2")
    again = run(runner, "sweep", MCH50, *GRID, "--format", "csv", "--shard", "2/3", "-o", paths[1])
    assert "is complete and its manifest matches this run; skipped" in again.stderr
    run(runner, "merge", *paths, "-o", tmp_path / "all.csv")
    assert (tmp_path / "all.csv").read_bytes() == whole


def test_a_changed_run_is_not_skipped(runner, tmp_path):
    out = tmp_path / "p.csv"
    run(runner, "sweep", MCH50, *GRID, "--format", "csv", "--shard", "1/3", "-o", out)
    r = run(runner, "sweep", MCH50, *GRID, "--format", "csv", "--unit", "deg", "--shard", "1/3", "-o", out)
    assert r.stderr == f"wrote {out}\n"
    out.write_bytes(out.read_bytes()[:-10])  # damaged since: computed again
    r = run(runner, "sweep", MCH50, *GRID, "--format", "csv", "--unit", "deg", "--shard", "1/3", "-o", out)
    assert r.stderr == f"wrote {out}\n"


def test_merge_refuses_missing_duplicate_changed_and_mismatched_parts(runner, tmp_path):
    base = ("tolerance", MCH50, "-n", 3000, "--metrics", "paper", "--format", "npy")
    p = {k: tmp_path / f"p{k}.npy" for k in (1, 2, 3)}
    for k in (1, 2, 3):
        run(runner, *base, "--shard", f"{k}/3", "-o", p[k])
    other = tmp_path / "seed1.npy"
    run(runner, *base, "--seed", 1, "--shard", "2/3", "-o", other)
    changed = tmp_path / "changed.npy"
    changed.write_bytes(p[3].read_bytes()[:-8] + b"\0" * 8)
    (tmp_path / "changed.npy.manifest.json").write_text((tmp_path / "p3.npy.manifest.json").read_text())
    bare = tmp_path / "bare.npy"
    bare.write_bytes(p[1].read_bytes())
    r = runner.invoke(app, ["merge", *map(str, (p[1], p[1], other, changed, bare))])
    assert (r.exit_code, r.stdout) == (2, "")
    assert r.stderr.splitlines() == [
        f"error: {changed}: changed since it was written (its checksum differs from its manifest); run the part "
        "again",
        f"error: {bare}: no manifest (bare.npy.manifest.json); only parts written with --shard and -o can be "
        "merged (an interrupted part has none: run it again)",
        f"error: {other}: not a part of the run of {p[1]} (seed 1 vs 0); merge parts of one run only",
        f"error: part 1/3 given twice ({p[1]}, {p[1]})",
        f"error: part 2/3 missing (given only from another run: {other}) (run it with --shard 2/3)",
        "error: part 3/3 missing (run it with --shard 3/3)",
    ]


def test_merge_checks_the_drive(runner, tmp_path):
    out = tmp_path / "p.npy"
    run(runner, "tolerance", MCH50, "-n", 1000, "--metrics", "paper", "--format", "npy", "--shard", "1/1",
        "-o", out)
    other = tmp_path / "other.toml"
    other.write_text(MCH50.read_text() + "\n# edited\n")
    r = runner.invoke(app, ["merge", str(out), "--drive", str(other)])
    assert (r.exit_code, r.stderr) == (2, f"error: {other}: not the drive the parts were computed with (its "
                                          "SHA-256 differs from their manifests'); give that file with --drive\n")


def test_api_jobs_gives_the_same_results():
    from wormgear_cli import api

    one = api.tolerance(MCH50, samples=70_000, metrics="paper", seed=2)
    two = api.tolerance(MCH50, samples=70_000, metrics="paper", seed=2, jobs=2)
    assert one.metrics["total_transmission_error"].percentiles == two.metrics["total_transmission_error"].percentiles
    assert one.metrics["total_backlash"].std == two.metrics["total_backlash"].std


@pytest.mark.skipif(not hasattr(os, "killpg"), reason="process groups (POSIX)")
def test_ctrl_c_to_the_whole_foreground_group_stops_the_workers_and_writes_nothing(tmp_path):
    """The terminal sends SIGINT to every process of the job: the workers ignore it, the command
    stops them, exits 130 and leaves no file (and no process)."""
    import signal
    import subprocess
    import time

    from tests.support.processes import start

    out = tmp_path / "big.npy"
    # SIGINT as a terminal has it, whatever this run inherited (a background job of a
    # non-interactive shell starts with SIGINT ignored, and an ignored signal stays ignored)
    p = start(["tolerance", MCH50, "-n", "5000000", "--metrics", "paper", "--format", "npy", "-j", "2",
               "-o", out], tmp_path, start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and p.poll() is None:  # until the first block is written (workers busy)
        staged = [f for f in tmp_path.iterdir() if f.name.startswith(".big.npy.wormgear-")]
        if staged and staged[0].stat().st_size > 1000:
            break
        time.sleep(0.05)
    os.killpg(p.pid, signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert (shell_status(p.returncode), err.decode()) == (130, "interrupted; no output written\n")
    assert list(tmp_path.iterdir()) == []
    left = subprocess.run(["ps", "-o", "pid=", "-g", str(p.pid)], capture_output=True, text=True).stdout.split()
    assert left == []


def test_merge_takes_the_second_pass_of_large_runs(runner, tmp_path, monkeypatch):
    """Beyond IN_MEMORY_SAMPLES the percentiles need a second pass over the samples: the merge
    reads the parts again and still gives the unsharded report."""
    from wormgear_cli.tolerance import statistics

    monkeypatch.setattr(statistics, "IN_MEMORY_SAMPLES", 50_000)
    base = ("tolerance", MCH50, "-n", 140_000, "--metrics", "paper")
    paths = [tmp_path / f"p{k}.npy" for k in (1, 2)]
    for k, p in enumerate(paths, 1):
        run(runner, *base, "--format", "npy", "--shard", f"{k}/2", "-o", p)
    assert run(runner, "merge", *paths, "--format", "json").stdout == run(runner, *base, "--format", "json").stdout


def test_a_part_in_a_format_merge_cannot_join_is_warned_about_before_it_runs(runner, tmp_path):
    r = run(runner, "tolerance", MCH50, "-n", 2000, "--metrics", "paper", "--shard", "1/2", "-f", "json", "-o",
            tmp_path / "p1.json")
    assert r.stderr.startswith("warning: tolerance parts in json cannot be joined by wormgear merge; for a run in "
                               "parts use --format csv or npy\n")
    r = run(runner, "tolerance", MCH50, "-n", 2000, "--metrics", "paper", "--shard", "1/2", "-f", "npy", "-o",
            tmp_path / "p1.npy")
    assert "warning" not in r.stderr
