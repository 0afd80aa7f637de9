"""Signals stop a run like Ctrl-C: staged outputs removed, exit 128 + signal, one stderr line.

Real subprocesses (``python -m wormgear_cli``) receive real signals.  A run is
held at a known point without timing guesses by making one output a FIFO: the
command stages its other files, then waits at commit for the FIFO's reader.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.support.paths import MCH50, ROOT
from tests.support.processes import shell_status
from wormgear_cli.files import remove_stale_staged

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="POSIX signals")


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _default_stop_signals():
    """In the child: SIGHUP and SIGINT as a terminal session has them, whatever this test run
    inherited (under ``nohup`` SIGHUP is ignored, and an ignored signal stays ignored)."""
    signal.signal(signal.SIGHUP, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(args, cwd, **kw):
    kw.setdefault("preexec_fn", _default_stop_signals)
    return subprocess.Popen([sys.executable, "-m", "wormgear_cli", *args], cwd=cwd, env=_env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kw)


def _wait_for(predicate, proc, limit_s=60.0):
    """Poll until predicate() (the test runner's own bound: limit_s, not a timing assertion)."""
    deadline = time.monotonic() + limit_s
    while not predicate():
        if proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"command ended early with {proc.returncode}: {err.decode()[-2000:]}")
        if time.monotonic() > deadline:
            proc.kill()
            pytest.fail("command did not reach the expected point")
        time.sleep(0.01)


def _catches(proc, sig) -> bool:
    """The process has its own handler for ``sig`` (Linux: SigCgt in /proc/PID/status)."""
    try:
        status = Path(f"/proc/{proc.pid}/status").read_text()
    except OSError:
        return False
    mask = next(int(line.split()[1], 16) for line in status.splitlines() if line.startswith("SigCgt:"))
    return bool(mask >> (sig - 1) & 1)


def _staged(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


def _held_run(tmp_path):
    """simulate with --plot (staged) and -o onto a FIFO nobody reads: the run waits at commit."""
    pytest.importorskip("matplotlib")  # the staged output is the plot (the `plot` extra)
    fifo = tmp_path / "out.fifo"
    os.mkfifo(fifo)
    proc = _start(["simulate", str(MCH50), "--points", "2000", "--plot", "p.png", "-o", str(fifo)], tmp_path)
    _wait_for(lambda: _staged(tmp_path), proc)
    return proc, fifo


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_signal_while_outputs_are_staged_removes_them(tmp_path, sig):
    proc, fifo = _held_run(tmp_path)
    (name,) = _staged(tmp_path)
    assert name.startswith(".p.png.wormgear-") and f"-{proc.pid}-" in name  # recognisable, with our pid
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=60)
    assert shell_status(proc.returncode) == 128 + sig
    lines = err.decode().splitlines()
    assert lines == [f"stopped by {signal.Signals(sig).name}; no output written"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.fifo"]


def test_sigterm_during_a_large_sweep_leaves_nothing(tmp_path):
    """A grid of 10^6 points (about 110 MB of CSV): SIGTERM once the command runs (its handler
    is installed) and either its staged file appears or it has computed for half a second."""
    out = tmp_path / "out.csv"
    proc = _start(["sweep", str(MCH50), "--i", "2:10:1000", "--l-mm", "100:300:1000", "-f", "csv",
                   "-o", str(out)], tmp_path)
    if not Path(f"/proc/{proc.pid}/status").exists():
        proc.kill()
        pytest.skip("needs /proc to see when the command has started")
    _wait_for(lambda: _catches(proc, signal.SIGTERM), proc)
    start = time.monotonic()
    _wait_for(lambda: _staged(tmp_path) or time.monotonic() - start > 0.5, proc)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert shell_status(proc.returncode) == 143, err.decode()[-2000:]
    assert err.decode().splitlines() == ["stopped by SIGTERM; no output written"]
    assert list(tmp_path.iterdir()) == []


def test_sigkill_leftover_is_removed_by_the_next_run_in_that_folder(tmp_path, runner):
    proc, fifo = _held_run(tmp_path)
    (leftover,) = _staged(tmp_path)
    proc.kill()
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL and _staged(tmp_path) == [leftover]
    from wormgear_cli.cli import app

    r = runner.invoke(app, ["analyze", str(MCH50), "-f", "csv", "-o", str(tmp_path / "a.csv")])
    assert r.exit_code == 0, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "out.fifo"]


def test_stale_removal_keeps_live_foreign_and_unrecognised_files(tmp_path):
    from wormgear_cli.files import _host_tag

    host = _host_tag()
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()  # a pid that existed and is gone
    names = {
        "dead": f".x.csv.wormgear-{host}-{dead.pid}-ab12cd34.tmp",
        "live": f".x.csv.wormgear-{host}-{os.getppid()}-ab12cd34.tmp",  # our parent: alive
        "other_host": f".x.csv.wormgear-{host}zz-{dead.pid}-ab12cd34.tmp",
        "not_ours": f".x.csv.{dead.pid}.tmp",
    }
    for n in names.values():
        (tmp_path / n).write_text("partial")
    removed = remove_stale_staged(tmp_path)
    assert removed == [names["dead"]]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(v for k, v in names.items() if k != "dead")


def test_ignored_sighup_stays_ignored(tmp_path):
    """nohup sets SIGHUP to ignored; the run must not turn it back into a stop."""
    pytest.importorskip("matplotlib")  # the staged output is the plot (the `plot` extra)
    fifo = tmp_path / "out.fifo"
    os.mkfifo(fifo)
    proc = _start(["simulate", str(MCH50), "--points", "2000", "--plot", "p.png", "-o", str(fifo)], tmp_path,
                  preexec_fn=lambda: signal.signal(signal.SIGHUP, signal.SIG_IGN))
    _wait_for(lambda: _staged(tmp_path), proc)
    proc.send_signal(signal.SIGHUP)
    data = fifo.read_bytes()  # the reader arrives: the run completes
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err.decode()
    assert data.startswith(b"angle_deg,")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.fifo", "p.png"]
