"""Hostile drive files stay bounded: refused before parsing, or a one-line exit 2 naming the
file and line.  Time and memory are bounded by the test runner's own limits (the child runs
under RLIMIT_AS and a timeout); there are no timing assertions."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.support.paths import CONFIGS, MCH50, ROOT
from wormgear_cli.errors import SpecError
from wormgear_cli.spec.toml import MAX_KEY_PARTS, MAX_NESTING, MAX_SPEC_BYTES, MAX_TOKEN_CHARS, parse_toml

MEMORY_LIMIT = 400 * 2**20  # analyze of a normal drive file needs < 300 MB of address space
TIME_LIMIT_S = 120  # the runner's bound on a run that must be refused within a fraction of it


def _limited():
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def _analyze(path, stdin=None):
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
               PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    return subprocess.run([sys.executable, "-m", "wormgear_cli", "analyze", str(path)], stdin=stdin,
                          capture_output=True, env=env, timeout=TIME_LIMIT_S,
                          preexec_fn=_limited)


HOSTILE = {
    # name: (text, expected message after "FILE:")
    "dotted_20k": ("a" + ".a" * 20_000 + " = 1\n", f"1: a dotted key of more than {MAX_KEY_PARTS} parts"),
    "dotted_100k": ("[drive]\n" + "a" + " . a" * 100_000 + " = 1\n", f"2: a dotted key of more than {MAX_KEY_PARTS}"),
    "quoted_dotted": ('"a"' + '."b"' * 20_000 + " = 1\n", f"1: a dotted key of more than {MAX_KEY_PARTS} parts"),
    "header_dotted": ("[" + "t." * 20_000 + "t]\n", f"1: a dotted key of more than {MAX_KEY_PARTS} parts"),
    "arrays_500": ("x = " + "[" * 500 + "]" * 500 + "\n", f"1: arrays or tables nested more than {MAX_NESTING}"),
    "inline_500": ("x = " + "{a = " * 500 + "1" + "}" * 500 + "\n", f"1: arrays or tables nested more than "
                                                                     f"{MAX_NESTING}"),
    "mixed_deep": ("# c\n\nx = [\n" + "[{a = [" * 200 + "]}]" * 200 + "]\n", "4: arrays or tables nested more"),
    "int_4301": ("[drive]\nname = \"x\"\nn = " + "7" * 4301 + "\n", "3: a key or value of 4301 characters"),
    "long_key": ("k" * 5000 + " = 1\n", "1: a key or value of 5000 characters"),
    "long_quoted_key": ('"' + "k" * 5000 + '" = 1\n', "1: a key of 5000 characters"),
    "oversized": ("# " + "x" * MAX_SPEC_BYTES + "\n", ""),
}


_CHILD = """
import json, sys
from typer.testing import CliRunner
from wormgear_cli.cli import app
runner = CliRunner()
out = {}
for path in sys.argv[1:]:
    r = runner.invoke(app, ["analyze", path])
    out[path] = [r.exit_code, r.stderr, repr(r.exception) if r.exit_code not in (0, 1, 2) else None]
print(json.dumps(out))
"""


@pytest.fixture(scope="module")
def hostile_results(tmp_path_factory):
    """Every hostile file through ``wormgear analyze`` in one child process under the memory
    and time limits (one start-up for all of them)."""
    folder = tmp_path_factory.mktemp("hostile")
    paths = {}
    for name, (text, _) in HOSTILE.items():
        paths[name] = folder / f"{name}.toml"
        paths[name].write_text(text)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
               PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    r = subprocess.run([sys.executable, "-c", _CHILD, *map(str, paths.values())], capture_output=True,
                       env=env, timeout=TIME_LIMIT_S, preexec_fn=_limited)
    assert r.returncode == 0, r.stderr.decode()[-3000:]
    import json

    got = json.loads(r.stdout)
    return {name: (path, got[str(path)]) for name, path in paths.items()}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_drive_file_is_refused_within_the_runner_limits(hostile_results, name):
    path, (code, err, exc) = hostile_results[name]
    expected = HOSTILE[name][1]
    assert code == 2, (err, exc)
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert err.startswith(f"error: {path}:{expected}")
    if name == "oversized":
        assert "larger than the 1 MiB accepted" in err


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom"])
def test_endless_binary_input_is_refused_early(device):
    if not os.path.exists(device):
        pytest.skip(f"no {device}")
    r = _analyze(device)
    assert r.returncode == 2
    assert r.stderr.decode() == f"error: {device}: binary file, expected a TOML drive file\n"


def test_endless_text_on_a_pipe_is_read_only_up_to_the_limit(tmp_path):
    """``yes 'x = 1' | wormgear analyze /dev/stdin``: refused after MAX_SPEC_BYTES, not read forever."""
    feeder = subprocess.Popen([sys.executable, "-c", "import sys\nwhile True: sys.stdout.write('x = 1\\n' * 1000)"],
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    try:
        r = _analyze("/dev/stdin", stdin=feeder.stdout)
    finally:
        feeder.kill()
        feeder.wait()
    assert r.returncode == 2
    assert r.stderr.decode() == "error: /dev/stdin: more than the 1 MiB accepted; expected a TOML drive file\n"


def test_parser_errors_name_file_line_and_column(tmp_path, runner):
    from wormgear_cli.cli import app

    path = tmp_path / "bad.toml"
    path.write_text(MCH50.read_text() + "\n[oops\n")
    r = runner.invoke(app, ["analyze", str(path)])
    n = len(path.read_text().splitlines())
    assert r.exit_code == 2
    assert r.stderr.startswith(f"error: {path}:{n}:") and "TOML syntax error" in r.stderr


def test_shipped_drive_files_and_legal_extremes_pass_the_guard():
    for path in CONFIGS.glob("*.toml"):
        parse_toml(path.read_text(), str(path))
    legal = (
        "# [[[[ { { in a comment . . . . . . . . . . . . . . . . . . . . . . . . . . . . . .\n"
        f"s = \"{'.' * 5000}[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[{{{{{{\"\n"
        f"m = '''\n{'[' * 100}\n''' \n"
        f"b = \"\"\"\n{'a.' * 1000} \\\" {{{{{{ \"\"\"\n"
        f"{'.'.join(['k'] * MAX_KEY_PARTS)} = 1\n"
        f"deep = {'[' * MAX_NESTING}{']' * MAX_NESTING}\n"
        f"f = {'1' * 60}.{'2' * 60}\n"
        f"{'q' * MAX_TOKEN_CHARS} = 2\n"
        "d = 1979-05-27T07:32:00.999999-07:00\n"
    )
    doc = parse_toml(legal)
    assert doc["s"].startswith(".....") and doc["m"] == "[" * 100 + "\n"
    depth, node = 0, doc["deep"]
    while isinstance(node, list):
        depth, node = depth + 1, (node[0] if node else None)
    assert depth == MAX_NESTING
    assert doc["f"] > 1e59


def test_a_file_just_under_the_size_limit_is_read(tmp_path):
    body = MCH50.read_text()
    pad = MAX_SPEC_BYTES - len(body.encode()) - 3
    text = body + "#" + "x" * pad + "\n"
    assert len(text.encode()) <= MAX_SPEC_BYTES
    path = tmp_path / "big.toml"
    path.write_text(text)
    from wormgear_cli.spec.loader import load_spec

    assert load_spec(path).drive.name == load_spec(MCH50).drive.name


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet=st.sampled_from(list("ab1.=[]{}\"'#\n ,x\\")), max_size=300))
def test_any_text_gives_a_spec_error_never_another_exception(text):
    try:
        parse_toml(text, "f.toml")
    except SpecError as exc:
        assert len(exc.problems) == 1 and exc.problems[0].startswith("f.toml")
