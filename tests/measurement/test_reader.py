"""The measurement CSV reader: good files, and every bad file exits 2 naming file, line and column."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wormgear_cli.cli import app
from wormgear_cli.errors import DataError
from wormgear_cli.measurement.readers import parse_measurement, read_measurement


def write(tmp_path, text, name="data.csv", newline="\n"):
    path = tmp_path / name
    path.write_bytes(text.replace("\n", newline).encode("utf-8"))
    return path


def run_measure(runner, path):
    return runner.invoke(app, ["measure", str(path), "--format", "json"])


# --- good files ----------------------------------------------------------------------------------------------


def test_reads_required_and_optional_columns(tmp_path):
    path = write(tmp_path, "# rotary table test\n# laser calibrator\n"
                           "angle_deg,error_arcsec,direction,run,note,temperature_C\n"
                           "0,1.5,1,0,first,20.5\n"
                           "90,-2.25,-1,1,,21\n")
    m = read_measurement(path)
    assert len(m) == 2
    assert m.angle == pytest.approx([0.0, math.pi / 2])
    # 1 arcsec = pi / 648000 rad
    assert m.error == pytest.approx([1.5 * math.pi / 648000, -2.25 * math.pi / 648000])
    assert m.error_arcsec == pytest.approx([1.5, -2.25])
    assert list(m.direction) == [1.0, -1.0]
    assert list(m.run) == [0, 1]
    assert list(m.temperature) == [20.5, 21.0]
    assert m.present == frozenset({"direction", "run", "temperature_C"})
    assert m.comments == ("# rotary table test", "# laser calibrator")
    assert m.header[4] == "note" and m.rows[0][4] == "first"  # unknown columns kept


def test_defaults_for_absent_optional_columns(tmp_path):
    m = read_measurement(write(tmp_path, "angle_deg,error_arcsec\n0,1\n10,2\n"))
    assert list(m.direction) == [1.0, 1.0]
    assert list(m.run) == [0, 0]
    assert list(m.load) == [0.0, 0.0]
    assert list(m.temperature) == [20.0, 20.0]


def test_bom_crlf_spaces_and_blank_lines(tmp_path):
    path = tmp_path / "bom.csv"
    path.write_bytes(b"\xef\xbb\xbf angle_deg , error_arcsec \r\n\r\n 0 , 1 \r\n10,2\r\n\r\n")
    m = read_measurement(path)
    assert m.error_arcsec == pytest.approx([1.0, 2.0])


def test_rows_with_every_cell_empty_are_counted_in_a_note(tmp_path):
    # lines 3, 5 and 7 are rows of empty cells (spreadsheet exports write them); line 6 is a blank line
    text = "angle_deg,error_arcsec,direction\n0,1,1\n,,\n10,2,1\n , ,\n\n,,\n20,3,-1\n"
    m = read_measurement(write(tmp_path, text))
    assert m.error_arcsec == pytest.approx([1.0, 2.0, 3.0])
    assert m.rows == (("0", "1", "1"), ("10", "2", "1"), ("20", "3", "-1"))
    assert [n for n in m.notes if "every cell empty" in n] == ["3 rows with every cell empty left out (lines 3, 5, 7)"]


def test_many_empty_rows_note_names_the_first_three(tmp_path):
    text = "angle_deg,error_arcsec\n0,1\n" + ",\n" * 5 + "10,2\n"
    m = read_measurement(write(tmp_path, text))
    assert len(m) == 2
    assert "5 rows with every cell empty left out (lines 3, 4, 5 and 2 more)" in m.notes


def test_blank_lines_alone_give_no_empty_row_note(tmp_path):
    m = read_measurement(write(tmp_path, "angle_deg,error_arcsec\n0,1\n\n10,2\n"))
    assert not any("every cell empty" in n for n in m.notes)


def test_error_column_optional_when_not_required(tmp_path):
    m = read_measurement(write(tmp_path, "angle_deg,direction\n0,1\n5,-1\n"), require_error=False)
    assert np.all(np.isnan(m.error))


# --- bad files: exact messages through the CLI (exit 2, one stderr line) ----------------------------------------

BAD = [
    # (name, file text, expected message after "error: <path>")
    ("missing_one", "angle_deg,err\n0,1\n10,2\n",
     ":1: missing required column error_arcsec (header has: angle_deg, err); try --map error_arcsec=err"),
    ("missing_both", "# c\nangle,error\n0,1\n10,2\n",
     ":2: missing required columns angle_deg, error_arcsec (header has: angle, error); try --map angle_deg=angle "
     "--map error_arcsec=error"),
    ("non_numeric", "angle_deg,error_arcsec\n0,1\n10,2\n20,abc\n",
     ":4: column error_arcsec: expected a number, got 'abc'"),
    ("empty_cell", "angle_deg,error_arcsec\n0,1\n,2\n",
     ":3: column angle_deg: expected a number, got ''"),
    ("nan", "angle_deg,error_arcsec\n0,1\n10,NaN\n",
     ":3: column error_arcsec: expected a finite number, got 'NaN'"),
    ("inf", "angle_deg,error_arcsec\n0,inf\n10,2\n",
     ":2: column error_arcsec: expected a finite number, got 'inf'"),
    ("empty", "", ":1: empty file, expected a CSV header with angle_deg, error_arcsec"),
    ("blank", "\n\n  \n", ":1: empty file, expected a CSV header with angle_deg, error_arcsec"),
    ("comments_only", "# a\n# b\n",
     ":3: no CSV header after the comment lines, expected one with angle_deg, error_arcsec"),
    ("header_only", "angle_deg,error_arcsec\n", ":1: no data rows after the header"),
    ("single_row", "# one\nangle_deg,error_arcsec\n0,1\n", ":3: only one data row; at least two are needed"),
    ("cell_count", "angle_deg,error_arcsec\n0,1\n10,2,3\n", ":3: expected 2 cells as in the header, got 3"),
    ("direction", "angle_deg,error_arcsec,direction\n0,1,1\n10,2,0\n",
     ":3: column direction: expected +1 or -1 or a direction word (up/down, forward/reverse, fwd/rev, +/-, "
     "pos/neg, CW/CCW), got '0'"),
    ("run", "angle_deg,error_arcsec,run\n0,1,1\n10,2,1.5\n", ":3: column run: expected an integer, got '1.5'"),
    ("duplicate", "angle_deg,error_arcsec,angle_deg\n0,1,0\n10,2,10\n", ":1: column angle_deg appears twice"),
    # comment and blank lines count: the bad cell is on line 6 of the file
    ("line_numbers", "# a\n\nangle_deg,error_arcsec\n0,1\n\n5,x\n", ":6: column error_arcsec: expected a number, got 'x'"),
]


@pytest.mark.parametrize("name,text,message", BAD, ids=[b[0] for b in BAD])
def test_bad_csv_exits_2_naming_file_line_and_column(runner, tmp_path, name, text, message):
    path = write(tmp_path, text, f"{name}.csv")
    result = run_measure(runner, path)
    assert result.exit_code == 2
    assert result.stdout == ""
    assert result.stderr == f"error: {path}{message}\n"


def test_crlf_line_numbers(runner, tmp_path):
    path = write(tmp_path, "# c\nangle_deg,error_arcsec\n0,1\n10,oops\n", newline="\r\n")
    result = run_measure(runner, path)
    assert result.exit_code == 2
    assert result.stderr == f"error: {path}:4: column error_arcsec: expected a number, got 'oops'\n"


def test_missing_file_and_binary_file(runner, tmp_path):
    result = run_measure(runner, tmp_path / "nope.csv")
    assert result.exit_code == 2
    assert result.stderr == f"error: {tmp_path / 'nope.csv'}: file not found\n"
    binary = tmp_path / "b.csv"
    binary.write_bytes(b"angle_deg,error_arcsec\n\x00\x01\n")
    result = run_measure(runner, binary)
    assert result.exit_code == 2
    assert result.stderr == f"error: {binary}: binary file, expected a CSV file\n"


def test_unterminated_quote_is_a_data_error():
    with pytest.raises(DataError) as exc:
        parse_measurement('angle_deg,error_arcsec\n0,1\n10,"2\n', "q.csv")
    assert exc.value.problems[0].startswith("q.csv:3: a quoted cell runs over a line break")


@pytest.mark.parametrize("cell, column, message", [
    ("1_0", "run", "expected a number, got '1_0'"),
    ("99999999999999999999999", "run", "expected a number in [-1e+09, 1e+09], got '99999999999999999999999'"),
    ("1e6", "temperature_C", "expected a number in [-100, 300], got '1e6'"),
    ("1e300", "error_arcsec", "expected a number in [-1e+07, 1e+07], got '1e300'"),
    ("\uff11", "error_arcsec", "expected a number, got '\uff11'"),
])
def test_implausible_or_exotic_numbers_are_rejected_with_line_and_column(tmp_path, cell, column, message):
    from wormgear_cli.errors import DataError
    from wormgear_cli.measurement.readers import read_measurement

    cols = ["angle_deg", "error_arcsec", "run", "temperature_C"]
    row = {"angle_deg": "0", "error_arcsec": "1", "run": "1", "temperature_C": "20"}
    row[column] = cell
    path = tmp_path / "m.csv"
    path.write_text(",".join(cols) + "\n" + ",".join(row[c] for c in cols) + "\n10,2,1,20\n", encoding="utf-8")
    with pytest.raises(DataError) as info:
        read_measurement(path)
    assert info.value.problems == [f"{path}:2: column {column}: {message}"]
