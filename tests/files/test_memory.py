"""Issue 23, item 7 (and the long-run notes): sizes are checked against the memory a run may
use before the work starts, in one line naming the sizes, the limit and the options; a
MemoryError all the same is exit 2 with one line, never a traceback or exit 1 ("check
failed"); a line of endless length is refused after 1 MiB; a very long tolerance run says
its expected time."""

from __future__ import annotations

import resource
import subprocess

import pytest

from tests.support.paths import CONFIGS, MCH50
from tests.support.processes import default_signals, env, run
from wormgear_cli import files
from wormgear_cli.cli import app
from wormgear_cli.errors import UsageError


def test_the_issues_synth_is_refused_before_any_work(tmp_path):
    """``synth --plan dense --points 10000000 --runs 20``: every option within its range, 4e8
    rows, about 280 GiB; refused at once with the sizes and the options to lower."""
    r = run(["synth", MCH50, "--plan", "dense", "--points", "10000000", "--runs", "20", "-o", "d.csv"], tmp_path,
            env=env(WORMGEAR_MEMORY="64G"))
    assert r.returncode == 2
    assert r.stderr.decode() == (
        "error: synth: --points 10000000 x --runs 20 x 2 directions (400,000,000 rows): about 279 GiB of memory "
        "needed, more than the 64 GiB set by WORMGEAR_MEMORY=64G; lower --points, --runs or --cycles (or set "
        "WORMGEAR_MEMORY=SIZE if the machine can give more)\n")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("command", "args"), [
    ("measure", []),
    ("diagnose", [str(MCH50)]),
])
def test_a_measurement_with_more_rows_than_memory_is_refused_naming_them(tmp_path, runner, monkeypatch, command,
                                                                         args):
    """A variant: the rows of a measurement file are counted before it is parsed (here against a
    limit of 100 KiB: the shipped 725-line file needs more in either command)."""
    monkeypatch.setenv("WORMGEAR_MEMORY", "100K")
    data = CONFIGS / "mch50-warm.csv"
    r = runner.invoke(app, [command, *args, str(data)])
    assert r.exit_code == 2
    assert r.stderr.startswith(f"error: {command}: {data} (725 lines): about ")
    assert r.stderr.endswith("more than the 100 KiB set by WORMGEAR_MEMORY=100K; split the recording (by run or by "
                             "time) and read the parts one by one (or set WORMGEAR_MEMORY=SIZE if the machine can "
                             "give more)\n")


def test_simulate_at_counts_the_rows_of_its_file(runner, monkeypatch):
    monkeypatch.setenv("WORMGEAR_MEMORY", "100K")
    data = CONFIGS / "mch50-warm.csv"
    r = runner.invoke(app, ["simulate", str(MCH50), "--at", str(data)])
    assert r.exit_code == 2
    assert r.stderr.startswith(f"error: simulate --at: {data} (725 lines): about 460 KiB of memory needed")


def test_the_sweep_grid_is_checked_too(runner, monkeypatch):
    monkeypatch.setenv("WORMGEAR_MEMORY", "10M")
    r = runner.invoke(app, ["sweep", str(MCH50), "--i", "2:10:300", "--l-mm", "100:300:300", "-f", "json"])
    assert r.exit_code == 2
    assert r.stderr.startswith("error: sweep: 90,000 grid points held for --format json: about 257 MiB")


def _address_space(limit: int):
    def child():
        default_signals()
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    return child


def test_a_memory_error_is_one_line_and_exit_2(tmp_path):
    """Under ``ulimit -v`` (700 MiB) with the estimate overridden (WORMGEAR_MEMORY), numpy runs
    out of memory: one line, exit 2, no file."""
    r = run(["synth", MCH50, "--plan", "dense", "--points", "2000000", "--runs", "2", "-o", "d.csv"], tmp_path,
            env=env(WORMGEAR_MEMORY="1T"), preexec_fn=_address_space(700 * 1024 * 1024))
    assert r.returncode == 2, r.stderr.decode()[-2000:]
    assert r.stderr.decode() == f"error: {files.OUT_OF_MEMORY}\n"
    assert list(tmp_path.iterdir()) == []


def test_the_address_space_limit_is_seen_and_named(tmp_path):
    """A variant: without the override, the same run under ``ulimit -v`` is refused before the
    work, naming that limit."""
    r = run(["synth", MCH50, "--plan", "dense", "--points", "2000000", "--runs", "2", "-o", "d.csv"], tmp_path,
            preexec_fn=_address_space(700 * 1024 * 1024))
    assert r.returncode == 2
    err = r.stderr.decode()
    assert err.startswith("error: synth: --points 2000000 x --runs 2 x 2 directions (8,000,000 rows): about 5.6 GiB")
    assert "allowed by ulimit -v" in err and len(err.splitlines()) == 1


def test_a_memory_error_inside_any_command_is_one_line(runner, monkeypatch):
    """In process: a MemoryError from the core (here the analysis) is exit 2 and the one line."""
    from wormgear_cli.analysis import accuracy

    def exhausted(spec):
        raise MemoryError()

    monkeypatch.setattr(accuracy, "analyze", exhausted)
    r = runner.invoke(app, ["analyze", str(MCH50)])
    assert r.exit_code == 2
    assert r.stderr == f"error: {files.OUT_OF_MEMORY}\n"


@pytest.mark.parametrize(("text", "expected"), [
    ("123", 123), ("8G", 8 << 30), ("512m", 512 << 20), ("1.5T", int(1.5 * (1 << 40))), ("64KiB", 64 << 10),
])
def test_memory_sizes_are_read_in_binary_units(text, expected):
    assert files.parse_size(text) == expected


def test_a_bad_memory_size_is_one_line(runner, monkeypatch):
    monkeypatch.setenv("WORMGEAR_MEMORY", "lots")
    r = runner.invoke(app, ["synth", str(MCH50)])
    assert r.exit_code == 2
    assert r.stderr == "error: WORMGEAR_MEMORY='lots': expected a size such as 8G, 512M or a number of bytes\n"


def test_check_memory_compares_against_what_is_available(monkeypatch):
    monkeypatch.setattr(files, "available_memory", lambda: (1000, "free on this machine"))
    files.check_memory(1000, "x", "y")  # exactly what is there: allowed
    with pytest.raises(UsageError, match=r"^x: about 1001 bytes of memory needed, more than the 1000 bytes free on this machine; y "):
        files.check_memory(1001, "x", "y")


def test_an_endless_line_is_refused_after_one_mebibyte(tmp_path):
    """The issue's 200 MB header-only line, as an endless one on a pipe: refused once 1 MiB has
    gone by without a line end (what was read is bounded), not parsed for a minute."""
    producer = subprocess.Popen(["sh", "-c", "yes angle_deg | tr -d '\\n'"], stdout=subprocess.PIPE)
    try:
        r = run(["measure", "/dev/stdin"], tmp_path, stdin=producer.stdout, timeout=120)
    finally:
        producer.kill()
        producer.wait()
    assert r.returncode == 2
    assert r.stderr.decode() == "error: /dev/stdin:1: a line longer than 1 MiB; expected a CSV file\n"


def test_a_long_line_in_a_file_is_refused_with_its_line_number(tmp_path):
    from wormgear_cli.errors import DataError
    from wormgear_cli.measurement.reader import read_bytes_bounded

    path = tmp_path / "wide.csv"
    path.write_bytes(b"angle_deg,error_arcsec\n1,2\n" + b"9" * (1024 * 1024 + 1) + b"\n")
    with pytest.raises(DataError) as exc:
        read_bytes_bounded(path)
    assert exc.value.problems == [f"{path}:3: a line longer than 1 MiB; expected a CSV file"]
    path.write_bytes(b"angle_deg,error_arcsec\n" + b"1," + b"0" * (1024 * 1024 - 3) + b"\n")  # exactly 1 MiB: read
    assert read_bytes_bounded(path).startswith("angle_deg")


def test_a_tolerance_run_of_more_than_1e8_samples_says_its_time_first(runner, monkeypatch):
    """Also noted in the issue: ``--samples 1e9`` ran for hours without a word.  The note comes
    before the sampling starts (which is stopped here at once)."""
    from wormgear_cli.tolerance import engine

    def stop_here(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(engine, "run", stop_here)
    r = runner.invoke(app, ["tolerance", str(MCH50), "-n", "1000000000", "-f", "json"])
    assert r.exit_code == 130
    assert r.stderr.splitlines()[0] == (
        "note: 1000000000 samples are expected to take about 3 h 53 min (14 us each with --metrics all on a "
        "2-core machine); --samples sets the count, --shard K/N splits the run")
    r = runner.invoke(app, ["tolerance", str(MCH50), "-n", "100000000", "-f", "json"])
    assert r.stderr == "interrupted; no output written\n"  # 1e8 itself: no note
