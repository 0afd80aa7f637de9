"""Real processes for the fault tests: the command line as a subprocess, and code run as
another user (a forked child that drops root; the interpreter lives where that user cannot
read, so the child runs the already-imported program in process)."""

from __future__ import annotations

import os
import pickle
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from tests.support.paths import ROOT

#: the unprivileged user of the tests that need another owner than root
NOBODY = 65534

needs_root = pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0 or not hasattr(os, "fork"),
                                reason="needs root, to act as (or own files of) another user")


def shell_status(returncode: int) -> int:
    """The exit status a shell (and a script's ``$?``) reports for a child that ended with
    ``returncode``: 128 + N for one ended by signal N (subprocess's -N), else the code itself.

    The tests of stop signals hold the command to what its user sees: one line on stderr and the
    status 128 + N.  A process may reach that status either way: by ``exit(128 + N)``, or by ending
    itself with the signal once it has said its line (the interpreter does so for an interrupt on
    some paths of its shutdown, as programs should for SIGINT: Cracauer, "Proper handling of SIGINT/
    SIGQUIT"); both read 130 after Ctrl-C in a shell."""
    return 128 - returncode if returncode < 0 else returncode


def env(**extra) -> dict:
    """The environment of a subprocess running this checkout's ``wormgear_cli``."""
    out = dict(os.environ)
    out["PYTHONPATH"] = str(ROOT) + os.pathsep + out.get("PYTHONPATH", "")
    out.pop("WORMGEAR_MEMORY", None)
    out.update(extra)
    return out


def command(*args) -> list[str]:
    return [sys.executable, "-m", "wormgear_cli", *map(str, args)]


def default_signals():
    """In a child before exec: SIGHUP and SIGINT as a terminal session has them, whatever the
    test run inherited (under ``nohup`` SIGHUP is ignored, and an ignored signal stays so)."""
    signal.signal(signal.SIGHUP, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def run(args, cwd, timeout=300, preexec_fn=default_signals, **kw) -> subprocess.CompletedProcess:
    kw.setdefault("stdout", subprocess.PIPE)
    kw.setdefault("stderr", subprocess.PIPE)
    kw.setdefault("env", env())
    return subprocess.run(command(*args), cwd=cwd, timeout=timeout, preexec_fn=preexec_fn, **kw)


def shell(script: str, cwd, timeout=300, **extra_env) -> subprocess.CompletedProcess:
    """``sh -c script`` with ``wormgear`` meaning this checkout's command line."""
    wormgear = " ".join(command())
    return subprocess.run(["sh", "-c", f'wormgear() {{ {wormgear} "$@"; }}\n{script}'], cwd=cwd, timeout=timeout,
                          env=env(**extra_env), capture_output=True, preexec_fn=default_signals)


def start(args, cwd, **kw) -> subprocess.Popen:
    kw.setdefault("stdout", subprocess.PIPE)
    kw.setdefault("stderr", subprocess.PIPE)
    kw.setdefault("env", env())
    kw.setdefault("preexec_fn", default_signals)
    return subprocess.Popen(command(*args), cwd=cwd, **kw)


def wait_for(predicate, proc, limit_s=60.0) -> None:
    """Poll until predicate() (the test runner's own bound: limit_s, not a timing assertion)."""
    deadline = time.monotonic() + limit_s
    while not predicate():
        if proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"command ended early with {proc.returncode}: {(err or b'').decode()[-2000:]}")
        if time.monotonic() > deadline:
            proc.kill()
            pytest.fail("command did not reach the expected point")
        time.sleep(0.005)


def catches(pid: int, sig: int) -> bool:
    """The process has its own handler for ``sig`` (Linux: SigCgt in /proc/PID/status)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    mask = next(int(line.split()[1], 16) for line in status.splitlines() if line.startswith("SigCgt:"))
    return bool(mask >> (sig - 1) & 1)


def as_user(uid: int, fn, *args):
    """``fn(*args)`` in a forked child running as ``uid`` (its group too, no supplementary
    groups); its return value (picklable) comes back, an exception becomes a test failure."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        try:
            os.close(r)
            os.setgroups([])
            os.setgid(uid)
            os.setuid(uid)
            result = ("ok", fn(*args))
        except BaseException as exc:
            result = ("error", f"{type(exc).__name__}: {exc}")
        try:
            os.write(w, pickle.dumps(result))
        finally:
            os._exit(0)
    os.close(w)
    chunks = []
    while chunk := os.read(r, 1 << 16):
        chunks.append(chunk)
    os.close(r)
    os.waitpid(pid, 0)
    kind, value = pickle.loads(b"".join(chunks))
    if kind == "error":
        pytest.fail(f"as uid {uid}: {value}")
    return value


def open_folder(mode: int, owner: int = 0) -> Path:
    """A new folder under /tmp (pytest's own are private to root) with ``mode`` and ``owner``."""
    path = Path(tempfile.mkdtemp(prefix="wormgear-faults-", dir="/tmp"))
    os.chown(path, owner, owner)
    path.chmod(mode)
    return path
