"""The CLI runs numpy's BLAS on one thread unless the user set a thread count (cli.one_blas_thread)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from wormgear_cli.cli import BLAS_THREAD_VARIABLES, one_blas_thread


def test_none_set_all_set_to_one():
    env: dict[str, str] = {"PATH": "/bin"}
    assert one_blas_thread(env) is True
    assert {k: env[k] for k in BLAS_THREAD_VARIABLES} == dict.fromkeys(BLAS_THREAD_VARIABLES, "1")
    assert env["PATH"] == "/bin"


@pytest.mark.parametrize("name", ["OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"])
def test_a_users_choice_is_kept(name):
    env = {name: "4"}
    assert one_blas_thread(env) is False
    assert env == {name: "4"}


def test_an_empty_variable_is_no_choice():
    env = {"OMP_NUM_THREADS": ""}
    assert one_blas_thread(env) is True
    assert env["OPENBLAS_NUM_THREADS"] == "1"


def test_the_command_sets_them_before_numpy_loads():
    # a command run with no thread variable sees OPENBLAS_NUM_THREADS=1 once numpy is loaded
    env = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}
    code = ("import os, sys, atexit\n"
            "atexit.register(lambda: print('numpy' in sys.modules, os.environ.get('OPENBLAS_NUM_THREADS')))\n"
            "sys.argv = ['wormgear', 'analyze', 'configs/mch50.toml', '--format', 'json', '-o', os.devnull]\n"
            "from wormgear_cli.cli import main\nmain()\n")
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    out = subprocess.run([sys.executable, "-c", code], cwd=root, env=env, capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True", "1"]
