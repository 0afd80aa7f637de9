"""A file of the wrong kind gets guidance, not the other parser's error: a measurement CSV where a
drive belongs, a drive where a measurement belongs, and diagnose's or measure's files swapped."""

from __future__ import annotations

import os

import pytest

from tests.support.paths import CONFIGS, MCH50
from wormgear_cli.cli import app
from wormgear_cli.spec.filekind import first_line, kind_of_file, looks_like_drive, looks_like_table

WARM = CONFIGS / "mch50-warm.csv"


def test_diagnose_with_the_arguments_swapped_says_so(runner):
    r = runner.invoke(app, ["diagnose", str(WARM), str(MCH50)])
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr == (f"error: the arguments look swapped: {WARM} is a measurement and {MCH50} a drive spec; "
                        f"diagnose takes the drive first: wormgear diagnose {MCH50} {WARM}\n")


def test_measure_given_a_drive_says_where_the_drive_goes(runner):
    r = runner.invoke(app, ["measure", str(MCH50)])
    assert r.exit_code == 2
    assert r.stderr == (f"error: {MCH50} is a drive spec, not a measurement; measure reads a measurement CSV and "
                        f"takes the drive as --drive: wormgear measure DATA.csv --drive {MCH50}\n")


def test_measure_with_the_files_swapped_says_so(runner):
    r = runner.invoke(app, ["measure", str(MCH50), "--drive", str(WARM)])
    assert r.exit_code == 2
    assert r.stderr == (f"error: the files look swapped: {MCH50} is a drive spec and {WARM} a measurement; "
                        f"wormgear measure {WARM} --drive {MCH50}\n")


@pytest.mark.parametrize("args", [["analyze", str(WARM)], ["check", str(WARM)], ["tolerance", str(WARM)],
                                  ["simulate", str(WARM)], ["diagnose", str(WARM), str(WARM)]])
def test_a_csv_where_a_drive_belongs_is_named_as_such(runner, args):
    r = runner.invoke(app, args)
    assert r.exit_code == 2
    assert (f"error: {WARM}: a table of data (first line: angle_deg,error_arcsec,direction,run,load_Nm,"
            "temperature_...), not a TOML drive file; give the drive spec here (wormgear new writes one)") in r.stderr
    assert "TOML syntax error" not in r.stderr


def test_a_drive_where_data_belong_is_named_as_such(runner):
    r = runner.invoke(app, ["simulate", str(MCH50), "--at", str(MCH50)])
    assert r.exit_code == 2
    assert r.stderr == (f"error: {MCH50}: a TOML drive spec, not a measurement; expected a CSV file with a header "
                        "line such as angle_deg,error_arcsec\n")


@pytest.mark.parametrize("path", sorted(CONFIGS.glob("*.toml")), ids=lambda p: p.name)
def test_every_shipped_drive_is_a_drive_and_no_table(path):
    text = path.read_text(encoding="utf-8")
    assert looks_like_drive(text) and not looks_like_table(text)
    assert kind_of_file(path) == "drive"


@pytest.mark.parametrize("text", [
    "angle_deg,error_arcsec\n0,1\n",
    "# a comment\n\nPosition;Deviation\n0;1,5\n",
    "\ufeffangle_deg\terror_arcsec\n0\t1\n",
])
def test_tables_are_tables_and_no_drives(text):
    assert looks_like_table(text) and not looks_like_drive(text)


@pytest.mark.parametrize("text", [
    "", "# only a comment\n", "[drive]\nname = 'x'\n",   # a drive, or nothing: not a table
    "a = [1, 2, 3]\n",                                    # valid TOML with commas
    "angle\n0\n1\n",                                      # one column, no separator: left to the reader
])
def test_what_is_not_a_table(text):
    assert not looks_like_table(text)


def test_toml_without_drive_sections_is_not_called_a_drive():
    assert not looks_like_drive("[tool.x]\na = 1\n")
    assert not looks_like_drive("angle_deg,error_arcsec\n0,1\n")


def test_a_pipe_is_not_read_ahead(tmp_path):
    fifo = tmp_path / "p"
    os.mkfifo(fifo)
    assert kind_of_file(fifo) is None  # returns at once: a read would block or take the reader's data
    assert kind_of_file(tmp_path / "missing") is None


@pytest.mark.parametrize("text", [
    "\ufeff[drive]\nname = 'x'\n",                       # a byte-order mark before the first table
    "\ufeff# a comment\n[gear_pair.pinion]\nteeth = 18\n",  # only a sub-table of a drive section
    "   # indented comment, with, commas\n[worm_pair]\nmodule_mm = 2.5\n",
])
def test_drives_are_told_by_their_sections_whatever_comes_first(text):
    assert looks_like_drive(text) and not looks_like_table(text)


def test_a_byte_order_mark_or_an_indented_comment_is_not_the_header():
    assert looks_like_table("\ufeff# exported, by, a tool\nangle_deg,error_arcsec\n0,1\n")
    assert first_line("\ufeff# note, here\n  # more = text\nangle,error\n") == "angle,error"
    assert not looks_like_table("  # a, b, c\n[drive]\nname = 'x'\n")


def test_first_line_is_cut_only_beyond_its_length():
    assert first_line("") == ""
    assert first_line("a,b\n") == "a,b"
    exact = "x" * 60
    assert first_line(exact) == exact
    assert first_line(exact + "y") == "x" * 57 + "..."


def test_a_header_starting_with_x_keeps_its_letters():
    assert first_line("XY,Z\n1,2\n") == "XY,Z"


def test_a_file_with_bytes_that_are_not_utf8_is_still_told(tmp_path):
    f = tmp_path / "export.csv"
    f.write_bytes(b"angle,error\n0,\xff\xfe1\n")  # a Latin-1 export: the header decides, not the bytes after
    assert kind_of_file(f) == "table"
