"""Issue 23, items 3 and 5, and fsync: all outputs of a run are committed together.

* Item 3: every staged file is ready (complete, synced, still there) before the first rename;
  a rename that fails puts back the files already replaced (from kept copies), or the one
  error line names exactly the files that could not be put back.
* Item 5: a signal that lands after the commit (while "wrote FILE" waits on a slow stderr)
  does not turn the committed run into a failed one: the run's exit code, no "no output written".
"""

from __future__ import annotations

import errno
import fcntl
import os
import shutil
import signal
from pathlib import Path

import pytest

from tests.support.paths import MCH50
from tests.support.processes import catches, start, wait_for
from wormgear_cli import files
from wormgear_cli.errors import UsageError
from wormgear_cli.files import atomic_write, output_transaction


def _names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_a_folder_removed_mid_run_replaces_nothing(tmp_path):
    """The issue's case: synth -o ... --truth B/t.json --plot A/p.png, B removed while the run is
    held at its commit (its -o is a FIFO that waits for a reader): exit 2 naming B/t.json, and
    A/p.png is still the old file."""
    pytest.importorskip("matplotlib")
    a, b = tmp_path / "A", tmp_path / "B"
    a.mkdir()
    b.mkdir()
    (a / "p.png").write_bytes(b"old plot")
    fifo = tmp_path / "data.fifo"
    os.mkfifo(fifo)
    proc = start(["synth", MCH50, "--seed", "1", "-o", fifo, "--truth", b / "t.json", "--plot", a / "p.png"],
                 tmp_path)
    wait_for(lambda: any(n.endswith(".tmp") for n in os.listdir(a)) and os.listdir(b), proc)
    shutil.rmtree(b)
    data = fifo.read_bytes()  # the reader arrives: the commit goes on
    _, err = proc.communicate(timeout=120)
    assert data.startswith(b"#")  # the FIFO, written in place first, got the data
    assert proc.returncode == 2
    assert err.decode() == f"error: {b / 't.json'}: cannot write (No such file or directory)\n"
    assert (a / "p.png").read_bytes() == b"old plot" and _names(a) == ["p.png"]


class _FailingReplace:
    """os.replace that fails (EIO) at call number ``at`` (1-based) and works otherwise."""

    def __init__(self, at: int):
        self.at, self.calls, self.real = at, 0, os.replace

    def __call__(self, src, dst):
        self.calls += 1
        if self.calls == self.at:
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        return self.real(src, dst)


def test_a_failed_rename_puts_back_the_files_already_replaced(tmp_path, monkeypatch):
    first, second, new = tmp_path / "first.csv", tmp_path / "second.csv", tmp_path / "new.csv"
    first.write_text("old first\n")
    second.write_text("old second\n")
    fail = _FailingReplace(at=3)
    with pytest.raises(UsageError) as exc:
        with output_transaction():
            atomic_write(new, "new\n")  # did not exist: put back = removed
            atomic_write(first, "new first\n")
            atomic_write(second, "new second\n")
            monkeypatch.setattr(os, "replace", fail)
    monkeypatch.undo()
    assert exc.value.problems == [f"{second}: cannot write (Input/output error); no output written ({new}, {first} "
                                  "restored)"]
    assert first.read_text() == "old first\n" and second.read_text() == "old second\n"
    assert _names(tmp_path) == ["first.csv", "second.csv"]  # no staged file, no kept copy left


def test_a_file_that_cannot_be_put_back_is_named(tmp_path, monkeypatch):
    """A variant: where no copy can be kept (no hard links), such files go last, and a failure
    among them names exactly the files already replaced."""
    one, two = tmp_path / "one.csv", tmp_path / "two.csv"
    one.write_text("old one\n")
    two.write_text("old two\n")

    def no_links(src, dst, **kw):
        raise OSError(errno.EPERM, os.strerror(errno.EPERM))

    with pytest.raises(UsageError) as exc:
        with output_transaction():
            atomic_write(one, "new one\n")
            atomic_write(two, "new two\n")
            monkeypatch.setattr(os, "link", no_links)
            monkeypatch.setattr(os, "replace", _FailingReplace(at=2))
    monkeypatch.undo()
    assert exc.value.problems == [f"{two}: cannot write (Input/output error); already replaced, could not be put "
                                  f"back: {one}"]
    assert one.read_text() == "new one\n" and two.read_text() == "old two\n"
    assert _names(tmp_path) == ["one.csv", "two.csv"]


def test_every_staged_file_is_synced_before_the_first_rename_and_its_folder_after(tmp_path, monkeypatch):
    events = []
    real_fsync, real_replace = os.fsync, os.replace

    def fsync(fd):
        events.append("fsync-folder" if os.path.isdir(f"/proc/self/fd/{fd}") else "fsync-file")
        return real_fsync(fd)

    def replace(src, dst):
        events.append("rename")
        return real_replace(src, dst)

    monkeypatch.setattr(os, "fsync", fsync)
    monkeypatch.setattr(os, "replace", replace)
    with output_transaction():
        atomic_write(tmp_path / "a.csv", "a\n")
        atomic_write(tmp_path / "b.csv", "b\n")
    assert events == ["fsync-file", "fsync-file", "rename", "rename", "fsync-folder"]


def _fill(fd: int) -> None:
    """Fill a pipe to its capacity (no write to it can proceed until it is read)."""
    size = fcntl.fcntl(fd, getattr(fcntl, "F_GETPIPE_SZ", 1032))
    os.write(fd, b"x" * size)


@pytest.mark.parametrize(("args", "code", "sig"), [
    (["analyze", str(MCH50), "-f", "csv", "-o", "out.csv"], 0, signal.SIGTERM),  # the case
    (["check", "tight.toml", "-o", "out.txt"], 1, signal.SIGINT),  # a check that failed and committed its report
])
def test_a_signal_after_the_commit_keeps_the_runs_exit_code(tmp_path, args, code, sig):
    """stderr is a full pipe, so "wrote FILE" waits after the commit; the signal lands there."""
    if not os.path.exists("/proc/self/status"):
        pytest.skip("needs /proc")
    (tmp_path / "tight.toml").write_text(MCH50.read_text().replace("max_transmission_error_arcsec = 72.0",
                                                                   "max_transmission_error_arcsec = 1.0"))
    r, w = os.pipe()
    _fill(w)
    proc = start(args, tmp_path, stderr=w, stdout=open(os.devnull, "wb"))
    os.close(w)
    out = tmp_path / args[-1]
    wait_for(lambda: out.exists() and catches(proc.pid, signal.SIGTERM), proc)
    proc.send_signal(sig)
    proc.wait(timeout=60)
    os.set_blocking(r, False)
    err = b""
    while True:
        try:
            chunk = os.read(r, 1 << 16)
        except BlockingIOError:
            break
        if not chunk:
            break
        err += chunk
    os.close(r)
    assert proc.returncode == code
    assert b"no output written" not in err and b"Traceback" not in err
    assert out.stat().st_size > 0 and not any(n.endswith(".tmp") for n in os.listdir(tmp_path))


def test_settle_makes_a_late_signal_end_the_process_with_the_outcome(monkeypatch):
    """The mechanism under the test above, in process: before settle a signal raises, after it
    the handler ends the process with the settled code (os._exit, observed here)."""
    exits = []
    monkeypatch.setattr(files, "_PROCESS_WIDE", True)
    monkeypatch.setattr(os, "_exit", lambda code: exits.append(code))
    files.settle(None)
    with pytest.raises(files.RunStopped):
        files._stop(signal.SIGTERM, None)
    files.settle(1)
    files._stop(signal.SIGTERM, None)
    files.settle(None)
    assert exits == [1]


def test_an_exclusive_output_never_replaces_a_file_that_appeared_meanwhile(tmp_path):
    """``wormgear new`` never overwrites: a file created between its check and its commit stays."""
    path = tmp_path / "new.toml"
    with pytest.raises(UsageError) as exc:
        with output_transaction():
            atomic_write(path, "template\n", exclusive=True)
            path.write_text("someone else's\n")  # appears while the run goes on
    assert exc.value.problems == [f"{path}: cannot write (File exists)"]
    assert path.read_text() == "someone else's\n" and _names(tmp_path) == ["new.toml"]
    atomic_write(tmp_path / "other.toml", "template\n", exclusive=True)  # alone, a new name: written
    assert (tmp_path / "other.toml").read_text() == "template\n"


def test_a_file_committed_alone_survives_a_later_failure_of_the_run(tmp_path):
    """For resumable runs: a finished part is committed at once (still staged, synced and
    renamed) and stays when the run fails afterwards; the run's other outputs do not."""
    with pytest.raises(RuntimeError):
        with output_transaction():
            atomic_write(tmp_path / "part-1.csv", "1\n", alone=True)
            assert (tmp_path / "part-1.csv").read_text() == "1\n"  # in place before the run ends
            atomic_write(tmp_path / "summary.json", "{}\n")
            raise RuntimeError("the run fails later")
    assert _names(tmp_path) == ["part-1.csv"]


def test_a_signal_between_the_block_and_the_commit_leaves_nothing(tmp_path, monkeypatch):
    """A signal after the run's block ends and before the commit guards itself (a SIGHUP landed
    there once in the suite: the run said "no output written" and left its staged plot): here the
    handler's RunStopped raised as the commit starts."""
    out = tmp_path / "out.csv"

    def stopped(self, exit_code=0):
        raise files.RunStopped(signal.SIGHUP)

    monkeypatch.setattr(files._Transaction, "commit", stopped)
    with pytest.raises(files.RunStopped):
        with output_transaction():
            atomic_write(out, "a,b\n")
            assert len(_names(tmp_path)) == 1  # staged
    assert _names(tmp_path) == [] and files._CURRENT is None
