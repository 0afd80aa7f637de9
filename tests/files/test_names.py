"""Issue 23, items 9 and 10 (and formula cells): every name from outside reaches a terminal, a
pipe or a file's comment through one quoting function (:func:`wormgear_cli.errors.quote`,
with :func:`~wormgear_cli.errors.escape` as the guard of whole lines); no escape sequence, no
OSC title, no line break that starts a TOML line; no spreadsheet formula in a CSV text cell."""

from __future__ import annotations

import os
import pty
import shutil
import subprocess
import tomllib

import pytest

from tests.support.paths import CONFIGS, MCH50
from tests.support.processes import command, env
from wormgear_cli.cli import app

#: an OSC title, a colour and a bell, written as TOML escapes inside a quoted key
HOSTILE_TOML = "\\u001b]0;PWNED\\u0007\\u001b[31m"
HOSTILE = "\x1b]0;PWNED\x07\x1b[31m"


def _controls(data: bytes) -> list[int]:
    """Control bytes other than line ends in ``data`` (ESC, BEL, C1 as UTF-8 ...)."""
    text = data.decode("utf-8", "replace")
    return sorted({ord(c) for c in text if not c.isprintable() and c not in "\n"})


@pytest.mark.parametrize(("table", "command_"), [
    (f'\n[effects."x{HOSTILE_TOML}"]\namplitude_arcsec = 1\n', "analyze"),  # the issue's [effects."..."]
    (f'\n[statistics]\n"a{HOSTILE_TOML}" = "normal"\n', "tolerance"),  # and a [statistics] key
    (f'\n[statistics."b{HOSTILE_TOML}"]\nlaw = "normal"\n', "check"),  # a variant: a [statistics] table name
])
def test_hostile_keys_reach_stderr_written_out(tmp_path, runner, table, command_):
    spec = tmp_path / "drive.toml"
    spec.write_text(MCH50.read_text() + table)
    r = runner.invoke(app, [command_, str(spec)] + (["-n", "10"] if command_ == "tolerance" else []),
                      env={"NO_COLOR": "1"})
    assert r.exit_code == 2
    assert _controls(r.stderr.encode()) == []
    assert "\\u001B]0;PWNED\\u0007\\u001B[31m" in r.stderr and len(r.stderr.splitlines()) == 1


@pytest.fixture
def hostile_drive(tmp_path):
    """The shipped drive, without its name, in a file whose name holds an OSC title and a colour."""
    path = tmp_path / f"t{HOSTILE}.toml"
    path.write_text("\n".join(ln for ln in MCH50.read_text().splitlines() if not ln.startswith("name =")) + "\n")
    return path


@pytest.mark.parametrize("fmt", ["table", "csv", "json"])
def test_a_drive_named_by_a_hostile_file_name_reaches_a_pipe_written_out(tmp_path, hostile_drive, fmt):
    r = subprocess.run(command("analyze", hostile_drive, "-f", fmt), capture_output=True, cwd=tmp_path,
                       env=env(NO_COLOR="1"), timeout=120)
    assert r.returncode == 0, r.stderr.decode()
    assert _controls(r.stdout) == [] and _controls(r.stderr) == []
    assert "u001B]0;PWNED" in r.stdout.decode()  # the name is shown, written out


def test_a_drive_named_by_a_hostile_file_name_on_a_terminal_sends_no_osc(tmp_path, hostile_drive):
    """A variant on a real terminal (a pty), colours on: rich's own styles (CSI ... m) are the
    only escapes; no OSC (ESC ]), no bell, nothing from the name."""
    main, secondary = pty.openpty()
    proc = subprocess.Popen(command("analyze", hostile_drive), stdout=secondary, stderr=subprocess.PIPE, cwd=tmp_path,
                            env=env(TERM="xterm-256color", COLUMNS="100"))
    os.close(secondary)
    out = b""
    while True:
        try:
            chunk = os.read(main, 1 << 16)
        except OSError:
            break
        if not chunk:
            break
        out += chunk
    proc.wait(timeout=120)
    os.close(main)
    assert proc.returncode == 0
    assert b"\x1b]" not in out and b"\x07" not in out
    assert b"\\u001B]0;PWNED" in out


def test_check_lines_name_a_hostile_file_written_out(tmp_path, runner, hostile_drive):
    r = runner.invoke(app, ["check", str(hostile_drive)])
    assert r.exit_code == 1  # the MCH50's restated TE limit fails (issue 19): its line names the file too
    assert _controls(r.stdout.encode()) == [] and "\\u001B]0;PWNED" in r.stdout


def test_a_formula_drive_name_is_not_a_formula_in_csv(tmp_path, runner):
    """Also noted: a drive named ``=HYPERLINK(...)`` became a live spreadsheet formula."""
    spec = tmp_path / "d.toml"
    spec.write_text(MCH50.read_text().replace('name = "MCH50 rotary table"', 'name = "=HYPERLINK(\\"x\\")"'))
    r = runner.invoke(app, ["analyze", str(spec), "-f", "csv"])
    assert r.exit_code == 0
    assert r.stdout.splitlines()[1].startswith("\"'=HYPERLINK(\"\"x\"\")\",arcsec,")
    r = runner.invoke(app, ["analyze", str(spec), "-f", "json"])
    assert '"drive": "=HYPERLINK(\\"x\\")"' in r.stdout  # JSON is data, not a spreadsheet: kept as it is


def test_write_spec_header_cannot_carry_toml(tmp_path, runner):
    """Item 10: a data file named ``d⏎[effects.output_gear_runout]⏎eccentricity_um = 400⏎#.csv``
    (and a drive file named likewise) put a live effect into the augmented spec through its
    header comment.  Now the names stay on their comment line: the TOML parses to exactly the
    spec written from plain names, and ``check`` reads it."""
    injected = "\n[effects.output_gear_runout]\neccentricity_um = 400\n#"
    data = tmp_path / f"d{injected}.csv"
    shutil.copy(CONFIGS / "mch50-warm.csv", data)
    drive = tmp_path / f"m{injected}.toml"
    shutil.copy(MCH50, drive)
    plain_data, plain_drive = tmp_path / "d.csv", tmp_path / "m.toml"
    shutil.copy(CONFIGS / "mch50-warm.csv", plain_data)
    shutil.copy(MCH50, plain_drive)
    out = {}
    for name, (d, m) in {"hostile": (data, drive), "plain": (plain_data, plain_drive)}.items():
        spec_out = tmp_path / f"{name}-augmented.toml"
        r = runner.invoke(app, ["diagnose", str(m), str(d), "--resamples", "0", "-f", "json", "-o", os.devnull,
                                "--write-spec", str(spec_out)])
        assert r.exit_code == 0, r.stderr
        out[name] = spec_out.read_text()
    header = [ln for ln in out["hostile"].splitlines() if ln.startswith("#")]
    assert len(header) == len([ln for ln in out["plain"].splitlines() if ln.startswith("#")])
    assert header[0].endswith('/d\\n[effects.output_gear_runout]\\neccentricity_um = 400\\n#.csv"')
    assert tomllib.loads(out["hostile"]) == tomllib.loads(out["plain"])
    body = {k: [ln for ln in v.splitlines() if not ln.startswith("#")] for k, v in out.items()}
    assert body["hostile"] == body["plain"]  # nothing but comments differs
    r = runner.invoke(app, ["check", str(tmp_path / "hostile-augmented.toml")])
    assert r.exit_code in (0, 1), r.stderr
