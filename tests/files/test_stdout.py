"""Every write to stdout is checked and completed; a closed pipe is a quiet stop; one run's
outputs are committed together."""

from __future__ import annotations

import errno
import os
import subprocess
import sys

import pytest

from tests.support.paths import MCH50, ROOT
from wormgear_cli import files as wio
from wormgear_cli.errors import UsageError

FULL = "/dev/full"
needs_full = pytest.mark.skipif(not os.path.exists(FULL), reason="needs /dev/full")


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _run(args, stdout, cwd, timeout=300):
    return subprocess.run([sys.executable, "-m", "wormgear_cli", *args], stdout=stdout, stderr=subprocess.PIPE,
                          cwd=cwd, env=_env(), timeout=timeout)


@needs_full
@pytest.mark.parametrize("args", [
    ["analyze", str(MCH50)],                                  # a table
    ["analyze", str(MCH50), "-f", "json"],
    ["simulate", str(MCH50), "--points", "200000", "-f", "csv"],  # several MB
    ["sweep", str(MCH50), "--i", "2:10:50", "--l-mm", "100:300:50", "-f", "csv"],  # streamed rows
    ["--version"],
    ["analyze", "--help"],
])
def test_stdout_to_a_full_device_is_exit_2_with_one_line(tmp_path, args):
    with open(FULL, "wb") as full:
        r = _run(args, full, tmp_path)
    err = r.stderr.decode()
    assert r.returncode == 2, err
    assert len(err.splitlines()) == 1 and err.startswith("error: ") and "No space left on device" in err
    assert "Traceback" not in err


@needs_full
def test_full_stdout_commits_no_other_output(tmp_path):
    """sweep to a full stdout with --plot: no plot is left behind."""
    with open(FULL, "wb") as full:
        r = _run(["sweep", str(MCH50), "--i", "2:10:3", "--l-mm", "100:300:3", "-f", "csv", "--plot", "p.png"],
                 full, tmp_path)
    assert r.returncode == 2, r.stderr.decode()
    assert list(tmp_path.iterdir()) == []


@needs_full
def test_full_output_file_commits_no_other_output(tmp_path):
    """-o onto a full device and --plot: exit 2, and the plot is not committed either."""
    r = _run(["sweep", str(MCH50), "--i", "2:10:3", "--l-mm", "100:300:3", "-o", FULL, "--plot", "p.png"],
             subprocess.DEVNULL, tmp_path)
    assert r.returncode == 2
    assert r.stderr.decode() == f"error: {FULL}: cannot write (No space left on device)\n"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args", [
    ["sweep", str(MCH50), "--i", "2:10:300", "--l-mm", "100:300:300", "-f", "csv"],
    ["simulate", str(MCH50), "--points", "400000", "-f", "csv"],
    ["analyze", str(MCH50), "-f", "json"],
])
def test_reader_closing_the_pipe_early_is_a_quiet_stop(tmp_path, args):
    """``wormgear ... | head -c 10``: no message, exit 0 (normal use), never 1."""
    proc = subprocess.Popen([sys.executable, "-m", "wormgear_cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, cwd=tmp_path, env=_env())
    first = proc.stdout.read(10)
    proc.stdout.close()  # the reader goes away
    err = proc.stderr.read()
    proc.wait(timeout=300)
    assert len(first) == 10
    assert proc.returncode == wio.BROKEN_PIPE_EXIT == 0
    assert err == b""


class _ShortWrites:
    """os.write that writes at most ``step`` bytes, and fails with ``fail`` after ``limit`` bytes."""

    def __init__(self, real, step, limit=None, fail=errno.ENOSPC):
        self.real, self.step, self.limit, self.fail, self.done, self.calls = real, step, limit, fail, 0, 0

    def __call__(self, fd, data):
        self.calls += 1
        if self.limit is not None and self.done >= self.limit:
            raise OSError(self.fail, os.strerror(self.fail))
        n = self.real(fd, bytes(data[:self.step]))
        self.done += n
        return n


@pytest.fixture
def stdout_file(tmp_path):
    """A real file to stand in for stdout; the test puts it in place (pytest's capture resets
    sys.stdout between set-up and the test)."""
    path = tmp_path / "stdout.txt"
    fh = open(path, "w", encoding="utf-8")
    yield path, fh
    fh.close()


def test_short_writes_are_resumed_until_everything_is_written(stdout_file, monkeypatch):
    path, fh = stdout_file
    monkeypatch.setattr(sys, "stdout", fh)
    text = "".join(f"{k},{k * 0.5}\n" for k in range(5000)) + "Ω end\n"
    fake = _ShortWrites(os.write, step=7)
    monkeypatch.setattr(os, "write", fake)
    fh.write("before\n")  # buffered text goes first
    wio.write_stdout(text)
    monkeypatch.setattr(os, "write", fake.real)
    fh.flush()
    assert path.read_bytes() == ("before\n" + text).encode("utf-8")
    assert fake.calls > len(text.encode()) // 7  # it really was written in pieces


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EIO])
def test_a_write_error_midway_is_one_usage_error(stdout_file, monkeypatch, code):
    monkeypatch.setattr(sys, "stdout", stdout_file[1])
    fake = _ShortWrites(os.write, step=100, limit=300, fail=code)
    monkeypatch.setattr(os, "write", fake)
    dup = os.dup(1)
    try:
        with pytest.raises(UsageError) as exc:
            wio.write_stdout(b"x" * 10_000)
    finally:
        monkeypatch.setattr(os, "write", fake.real)
        os.dup2(dup, 1)  # write_stdout points fd 1 at /dev/null after a failure; restore it
        os.close(dup)
    assert exc.value.problems == [f"stdout: cannot write ({os.strerror(code)}); is the disk full or the output "
                                  f"closed?"]


def test_a_write_that_makes_no_progress_is_an_error_not_a_loop(stdout_file, monkeypatch):
    monkeypatch.setattr(sys, "stdout", stdout_file[1])
    monkeypatch.setattr(os, "write", lambda fd, data: 0)
    dup = os.dup(1)
    try:
        with pytest.raises(UsageError, match="stdout: cannot write"):
            wio.write_stdout("abc")
    finally:
        monkeypatch.undo()
        os.dup2(dup, 1)
        os.close(dup)


def test_staged_file_writes_are_completed_too(tmp_path, monkeypatch):
    fake = _ShortWrites(os.write, step=3)
    monkeypatch.setattr(os, "write", fake)
    data = bytes(range(256)) * 50
    wio.atomic_write(tmp_path / "o.bin", data)
    monkeypatch.undo()
    assert (tmp_path / "o.bin").read_bytes() == data and fake.calls >= len(data) // 3


def test_a_failing_staged_write_leaves_no_file(tmp_path, monkeypatch):
    monkeypatch.setattr(os, "write", _ShortWrites(os.write, step=10, limit=20))
    with pytest.raises(UsageError, match=r"o\.csv: cannot write \(No space left on device\)"):
        wio.atomic_write(tmp_path / "o.csv", "y" * 1000)
    monkeypatch.undo()
    assert list(tmp_path.iterdir()) == []


def _small_file_limit():
    """A file-size limit of 12 kB (as a nearly full disk): the kernel writes up to the limit
    (a short write), then fails with EFBIG.  SIGXFSZ ignored so the failure is an error code."""
    import resource
    import signal

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (12 * 1024, 12 * 1024))


@pytest.mark.parametrize("where", ["redirect", "-o"])
def test_real_short_write_on_a_regular_file_is_exit_2_and_leaves_no_result(tmp_path, where):
    out = tmp_path / "o.csv"
    args = [sys.executable, "-m", "wormgear_cli", "simulate", str(MCH50), "--points", "200000", "-f", "csv"]
    if where == "-o":
        args += ["-o", str(out)]
    with open(tmp_path / "stdout.txt" if where == "-o" else out, "wb") as fh:
        r = subprocess.run(args, stdout=fh, stderr=subprocess.PIPE, env=_env(), timeout=300,
                           preexec_fn=_small_file_limit)
    err = r.stderr.decode()
    assert r.returncode == 2, err
    assert len(err.splitlines()) == 1 and "File too large" in err, err
    if where == "-o":
        assert sorted(p.name for p in tmp_path.iterdir()) == ["stdout.txt"]  # no o.csv, no staged file
        assert err == f"error: {out}: cannot write (File too large)\n"
    else:
        assert err.startswith("error: stdout: cannot write (File too large)")
