"""-o FILE without --format writes the format the file name asks for (.json, .csv, .txt); a
.json or .csv name that contradicts an explicit --format is an error before any work."""

from __future__ import annotations

import csv
import io
import json

import pytest

from tests.support.commands import click_group
from tests.support.paths import CONFIGS, MCH50
from wormgear_cli.cli import app

WARM = CONFIGS / "mch50-warm.csv"
PASSING = CONFIGS / "eq6-belt-worm.toml"
GRADE = ["grade", "--grade", "6", "--module-mm", "2", "--diameter-mm", "100", "--face-width-mm", "20"]
#: one cheap invocation per command with --format (the -o file is appended)
COMMANDS = {
    "analyze": ["analyze", str(MCH50)],
    "check": ["check", str(PASSING)],  # a drive that meets its limits (the MCH50 fails its own: issue 19)
    "grade": GRADE,
    "tolerance": ["tolerance", str(MCH50), "--samples", "200", "--metrics", "paper"],
    "sweep": ["sweep", str(MCH50), "--i", "2:10:3", "--l-mm", "100:300:3"],
    "simulate": ["simulate", str(MCH50), "--points", "8"],
}
FORMATS = {"analyze": {"table", "json", "csv"}, "check": {"text", "json"}, "grade": {"table", "json"},
           "tolerance": {"table", "json", "csv"}, "sweep": {"table", "json", "csv"}, "simulate": {"csv", "json"}}


def _kind(text: str) -> str:
    """What a file holds, judged by parsing it (not by how the tool names it)."""
    try:
        json.loads(text)
        return "json"
    except ValueError:
        pass
    rows = list(csv.reader(io.StringIO(text)))
    if len(rows) >= 2 and len(rows[0]) >= 2 and all(len(r) == len(rows[0]) for r in rows if r):
        return "csv"
    return "text"


@pytest.mark.parametrize("name", sorted(COMMANDS))
@pytest.mark.parametrize("suffix", [".json", ".csv"])
def test_the_file_name_chooses_the_format(runner, tmp_path, name, suffix):
    out = tmp_path / f"result{suffix}"
    r = runner.invoke(app, [*COMMANDS[name], "-o", str(out)])
    wanted = suffix[1:]
    if wanted in FORMATS[name]:
        assert r.exit_code == 0, r.stderr
        assert _kind(out.read_text()) == wanted
    else:  # the command has no such format: an error naming what it writes, and no file
        assert r.exit_code == 2
        assert not out.exists()
        assert r.stderr.startswith(f"error: -o {out}: wormgear {name} writes ")
        assert f"not {wanted}; name the file" in r.stderr


@pytest.mark.parametrize("name", ["analyze", "grade", "check"])
def test_a_text_name_gets_the_table_and_an_unknown_one_the_default(runner, tmp_path, name):
    for file in ("report.txt", "report.out", "report"):
        out = tmp_path / file
        r = runner.invoke(app, [*COMMANDS[name], "-o", str(out)])
        assert r.exit_code == 0, r.stderr
        assert _kind(out.read_text()) == "text"


def test_simulate_has_no_table_so_a_txt_name_keeps_its_csv(runner, tmp_path):
    out = tmp_path / "curve.txt"
    assert runner.invoke(app, [*COMMANDS["simulate"], "-o", str(out)]).exit_code == 0
    assert _kind(out.read_text()) == "csv"


def test_analyze_json_by_name_is_the_same_bytes_as_with_format(runner, tmp_path):
    named = tmp_path / "a.json"
    runner.invoke(app, ["analyze", str(MCH50), "-o", str(named)])
    stdout = runner.invoke(app, ["analyze", str(MCH50), "--format", "json"]).stdout
    assert named.read_text() == stdout


@pytest.mark.parametrize("fmt,file", [("csv", "out.json"), ("table", "out.json"), ("json", "out.csv"),
                                      ("table", "out.csv")])
def test_a_name_that_contradicts_the_format_is_an_error(runner, tmp_path, fmt, file):
    out = tmp_path / file
    r = runner.invoke(app, ["analyze", str(MCH50), "--format", fmt, "-o", str(out)])
    assert r.exit_code == 2 and r.stdout == ""
    assert not out.exists()
    named = file.rsplit(".", 1)[1]
    assert r.stderr == (f"error: -o {out}: the file name says {named}, but --format {fmt} was given; drop --format "
                        f"or name the file {'.txt' if fmt == 'table' else '.' + fmt}\n")


@pytest.mark.parametrize("fmt,file", [("json", "out.JSON"), ("json", "out.txt"), ("csv", "out.dat")])
def test_an_explicit_format_is_kept_where_the_name_does_not_contradict_it(runner, tmp_path, fmt, file):
    out = tmp_path / file
    r = runner.invoke(app, ["analyze", str(MCH50), "--format", fmt, "-o", str(out)])
    assert r.exit_code == 0, r.stderr
    assert _kind(out.read_text()) == fmt


def test_stdout_keeps_the_default(runner):
    r = runner.invoke(app, ["analyze", str(MCH50), "-o", "-"])
    assert r.exit_code == 0 and _kind(r.stdout) == "text"


#: the least arguments of each command with --format (its inputs are not read before the check)
LEAST_ARGS = {**COMMANDS, "measure": ["measure", str(WARM)],
              "diagnose": ["diagnose", str(MCH50), str(WARM)], "compare": ["compare", str(MCH50), str(MCH50)],
              "merge": ["merge", str(MCH50)], "compensate": ["compensate", str(WARM)]}


def test_every_command_with_format_follows_the_rule_before_any_work(runner, tmp_path):
    commands = click_group(app).commands
    with_format = {name for name, cmd in commands.items() if any(p.name == "format" for p in cmd.params)}
    assert with_format == set(LEAST_ARGS), "a command with --format is missing from LEAST_ARGS"
    for name in sorted(with_format):
        param = next(p for p in commands[name].params if p.name == "format")
        choices = [getattr(c, "value", c) for c in param.type.choices]
        other = next(c for c in choices if c != "json")
        out = tmp_path / f"{name}.json"
        r = runner.invoke(app, [*LEAST_ARGS[name], "--format", other, "-o", str(out)])
        assert r.exit_code == 2, name
        assert r.stderr.startswith(f"error: -o {out}: the file name says json, but --format {other} was given"), name
