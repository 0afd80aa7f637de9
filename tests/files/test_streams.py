"""Issue 23, items 8 and 12: the edges of a run.

* Item 8: closed standard streams (``>&-``, ``2>&-``, ``<&-``) are handled at start-up: with
  ``-o`` the file is written (exit 0), without it one error line (exit 2); never a traceback,
  and no file the run opens takes the number of a closed stream.
* Item 12: Ctrl-C is quiet from the program's first instruction to its last: while the heavy
  modules load, one line and exit 130; a second Ctrl-C while the first is handled (or while
  the interpreter shuts down) adds nothing, never "Exception ignored in threading._shutdown".
  (Python's own start-up, before the first instruction of wormgear, is the interpreter's.)
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time

import pytest

from tests.support.paths import MCH50
from tests.support.processes import catches, default_signals, run, shell_status, start, wait_for


def _closing(*fds):
    def child():
        default_signals()
        for fd in fds:
            os.close(fd)

    return child


def test_closed_stdout_with_an_output_file_writes_the_file(tmp_path):
    """The issue's command: ``wormgear analyze configs/mch50.toml -o out.txt >&-``."""
    r = run(["analyze", MCH50, "-o", "out.txt"], tmp_path, preexec_fn=_closing(1), stdout=None)
    assert r.returncode == 0, r.stderr.decode()
    assert r.stderr == b"wrote out.txt\n"
    assert "transmission error" in (tmp_path / "out.txt").read_text()


def test_closed_stdout_without_an_output_file_is_one_error_line(tmp_path):
    r = run(["analyze", MCH50, "-f", "json"], tmp_path, preexec_fn=_closing(1), stdout=None)
    assert r.returncode == 2
    assert r.stderr == (b"error: stdout: cannot write (Bad file descriptor); stdout is closed or read-only: name a "
                        b"file with -o\n")
    assert list(tmp_path.iterdir()) == []


def test_all_three_closed_and_several_outputs_go_to_their_own_files(tmp_path):
    """A variant: ``<&- >&- 2>&-`` with -o and --truth; exit 0 and each file holds its own
    content (a file opened first would otherwise have become "stdout" or "stderr")."""
    r = run(["synth", MCH50, "--seed", "2", "-o", "data.csv", "--truth", "truth.json"], tmp_path,
            preexec_fn=_closing(0, 1, 2), stdout=None, stderr=None, stdin=None)
    assert r.returncode == 0
    assert (tmp_path / "data.csv").read_text().startswith("#")
    assert (tmp_path / "truth.json").read_text().startswith("{")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data.csv", "truth.json"]


def test_version_to_a_closed_stdout_is_one_error_line(tmp_path):
    r = run(["--version"], tmp_path, preexec_fn=_closing(1), stdout=None)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1 and b"Traceback" not in r.stderr


def _interrupt_while_loading(tmp_path, args, signals, delay_s):
    """Start the command, wait until its first instruction has installed the stop handlers
    (SIGTERM caught: Python alone does not catch it), wait ``delay_s`` more, send ``signals``."""
    proc = start(args, tmp_path)
    if not os.path.exists(f"/proc/{proc.pid}/status"):
        proc.kill()
        pytest.skip("needs /proc")
    wait_for(lambda: catches(proc.pid, signal.SIGTERM), proc)
    time.sleep(delay_s)
    for sig in signals:
        try:
            proc.send_signal(sig)
        except ProcessLookupError:
            break
    out, err = proc.communicate(timeout=120)
    return shell_status(proc.returncode), err.decode()


@pytest.mark.parametrize("delay_s", [0.0, 0.01, 0.03])
def test_ctrl_c_while_the_program_loads_is_one_line(tmp_path, delay_s):
    """The issue's case: Ctrl-C in the first ~100 ms (here: from the handlers' installation on,
    while typer, numpy and the command load) is one line and exit 130, or the run finished."""
    code, err = _interrupt_while_loading(tmp_path, ["analyze", MCH50, "-f", "json"], [signal.SIGINT], delay_s)
    assert (code, err) in ((130, "interrupted; no output written\n"), (0, ""))


def test_ctrl_c_at_any_moment_never_shows_a_traceback_of_the_program(tmp_path):
    """A variant: Ctrl-C at moments spread from the launch to the end of a run.  Each is one
    line and exit 130, a finished run, or -- when it lands in Python's own start-up, before
    the first instruction of wormgear -- the interpreter's report, which has no frame of
    ``main``; a traceback through ``main`` is the program's fault."""
    t0 = time.monotonic()
    probe = start(["analyze", MCH50, "-f", "json"], tmp_path)
    probe.communicate(timeout=120)
    whole = time.monotonic() - t0
    for k in range(10):
        proc = start(["analyze", MCH50, "-f", "json"], tmp_path)
        time.sleep(whole * k / 10)
        try:
            proc.send_signal(signal.SIGINT)
        except ProcessLookupError:
            pass
        _, err = proc.communicate(timeout=120)
        err = err.decode()
        ours = re.search(r'wormgear_cli.cli.__init__\.py", line \d+, in (main|_run)', err) or "Exception ignored" in err
        assert not ours, err
        if proc.returncode in (0, 130):
            assert err in ("", "interrupted; no output written\n"), err


@pytest.mark.parametrize("second", [signal.SIGINT, signal.SIGTERM])
def test_a_second_signal_adds_nothing(tmp_path, second):
    """Double Ctrl-C (and Ctrl-C then SIGTERM): one line, the first signal's exit code, never
    "Exception ignored" from the interpreter's shutdown."""
    args = ["sweep", MCH50, "--i", "2:10:400", "--l-mm", "100:300:400", "-f", "csv", "-o", "out.csv"]
    proc = start(args, tmp_path)
    wait_for(lambda: any(n.endswith(".tmp") for n in os.listdir(tmp_path)), proc)
    proc.send_signal(signal.SIGINT)
    proc.send_signal(second)
    _, err = proc.communicate(timeout=120)
    assert shell_status(proc.returncode) == 130
    assert err.decode() == "interrupted; no output written\n"
    assert list(tmp_path.iterdir()) == []


def test_a_signal_as_the_interpreter_exits_changes_nothing(tmp_path):
    """Ctrl-C at the very end of a finished run (exit code settled): the process ends at once
    with that code, quietly.  Signals are sent as fast as possible until the process is gone."""
    proc = start(["analyze", MCH50, "-f", "json", "-o", "out.json"], tmp_path, stderr=subprocess.PIPE)
    wait_for(lambda: (tmp_path / "out.json").exists(), proc)
    while proc.poll() is None:
        try:
            proc.send_signal(signal.SIGINT)
        except ProcessLookupError:
            break
        time.sleep(0.001)
    err = proc.stderr.read().decode()
    proc.wait()
    assert proc.returncode == 0
    assert "Exception ignored" not in err and "Traceback" not in err and "no output written" not in err
