"""The readers as a registry, and files as instruments and spreadsheets write them: headers in any case,
direction words, preambles without '#', target and actual positions, TwinCAT Scope exports, time units,
velocity, encoder counts, quoted line breaks.

The constructed cases write the hand-worked ISO 230-2 example (tests/support/iso230_hand.py: A 14, B 4,
E 5, M 1.5, R 14 arcsec, worked out by hand) in each of these ways; each must give those figures.
"""

from __future__ import annotations

import json
import math
import sys
import types

import numpy as np
import pytest

from tests.support.iso230_hand import HAND
from tests.support.paths import ROOT
from wormgear_cli.cli import app
from wormgear_cli.errors import DataError
from wormgear_cli.measurement import readers
from wormgear_cli.measurement.reader import ReadOptions
from wormgear_cli.measurement.readers import FORMATS, InputFormat, detect_format, parse_measurement, read_measurement

FIELD = ROOT / "tests" / "data" / "field"
HAND_FIGURES = {"A": 14.0, "B": 4.0, "E": 5.0, "M": 1.5, "R": 14.0}


def hand_rows():
    """(angle_deg, error_arcsec, direction, run) of the hand example, in the order of an ISO cycle."""
    rows = []
    for run in range(3):
        for d in (1, -1):
            for target in (0.0, 120.0, 240.0) if d > 0 else (240.0, 120.0, 0.0):
                rows.append((target, HAND[(target, d)][run], d, run))
    return rows


def figures(runner, path, *args):
    result = runner.invoke(app, ["measure", str(path), "-f", "json", "--orders", "1", *args])
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    return {k: doc["iso230_2"][k] for k in HAND_FIGURES}, doc, result.stderr


# --- the registry ------------------------------------------------------------------------------------------------


def test_every_registered_format_resolves_and_csv_comes_last():
    assert FORMATS[-1].name == "csv"
    for f in FORMATS:
        assert callable(f.function("detect")) and callable(f.function("read"))
    assert readers.format_names() == tuple(f.name for f in FORMATS)


def test_the_format_is_detected_from_the_content_not_the_name(tmp_path):
    scope = (FIELD / "twincat-scope-resolver.csv").read_text(encoding="utf-8")
    assert detect_format(scope.replace("\r\n", "\n")).name == "twincat-scope"
    assert detect_format((FIELD / "resolver-cyclic-error-deg.csv").read_text()).name == "csv"
    renamed = tmp_path / "export.txt"
    renamed.write_bytes((FIELD / "twincat-scope-resolver.csv").read_bytes())
    assert read_measurement(renamed).input_format == "twincat-scope"


def test_a_new_format_is_one_registration_line(monkeypatch):
    # a toy format: "ANGLES" then one angle per line, error 0; registered the way the guide-log reader will be
    module = types.ModuleType("toy_format")

    def looks_like(head):
        return head.startswith("ANGLES\n")

    def read(text, name, options):
        body = "angle_deg,error_arcsec\n" + "".join(f"{a},0\n" for a in text.split("\n")[1:] if a)
        return parse_measurement(body, name, options.require_error, ReadOptions())

    module.looks_like, module.read = looks_like, read
    monkeypatch.setitem(sys.modules, "toy_format", module)
    monkeypatch.setattr(readers, "FORMATS", (InputFormat("toy", "a toy", "toy_format", "looks_like", "read"),
                                             *FORMATS))
    m = parse_measurement("ANGLES\n10\n20\n30\n", "t.txt")
    assert m.angle_deg == pytest.approx([10.0, 20.0, 30.0])
    assert parse_measurement("angle_deg,error_arcsec\n0,1\n1,2\n", "c.csv").input_format == "csv"


def test_an_explicit_input_format_is_used_and_checked(runner, tmp_path):
    path = FIELD / "twincat-scope-resolver.csv"
    result = runner.invoke(app, ["measure", str(path), "--input-format", "bogus"])
    assert result.exit_code == 2
    assert result.stderr == "error: --input-format bogus: expected one of auto, phd2, twincat-scope, csv\n"
    # read as a plain table, the metadata is no header: refused, and no metadata value proposed as a column
    result = runner.invoke(app, ["measure", str(path), "--input-format", "csv"])
    assert result.exit_code == 2
    assert "--map" not in result.stderr.split("(header has:", 1)[1].split(")", 1)[1].replace(
        "name the columns with --map CANONICAL=HEADER", "")


# --- headers in any case, direction words ------------------------------------------------------------------------


def test_headers_in_another_case_are_read_not_ignored(runner, tmp_path):
    text = "Angle_Deg,ERROR_ARCSEC,Direction,Run\n" + "".join(f"{a:g},{e},{d},{r}\n" for a, e, d, r in hand_rows())
    path = tmp_path / "case.csv"
    path.write_text(text)
    got, doc, err = figures(runner, path)
    assert got == pytest.approx(HAND_FIGURES)
    assert doc["columns"] == {"angle_deg": "Angle_Deg", "error_arcsec": "ERROR_ARCSEC", "direction": "Direction",
                              "run": "Run"}
    assert err == ""


@pytest.mark.parametrize("up, down", [("up", "down"), ("+", "-"), ("fwd", "rev"), ("Forward", "Reverse"),
                                      ("POS", "NEG"), ("+1", "-1")])
def test_direction_words_give_the_figures_of_plus_and_minus_one(runner, tmp_path, up, down):
    text = "angle (deg);error (arcsec);direction;run\n" + "".join(
        f"{a:g};{e};{up if d > 0 else down};{r}\n" for a, e, d, r in hand_rows())
    path = tmp_path / "words.csv"
    path.write_text(text)
    got, _, _ = figures(runner, path)
    assert got == pytest.approx(HAND_FIGURES)
    assert read_measurement(path).direction.tolist() == [float(d) for _, _, d, _ in hand_rows()]


def test_numbers_and_words_mixed_in_one_direction_column():
    text = "angle_deg;error_arcsec;direction\n0;1;up\n10;2;-1,0\n20;3;+1\n30;4;Down\n"
    assert parse_measurement(text, "mixed.csv").direction.tolist() == [1.0, -1.0, 1.0, -1.0]
    with pytest.raises(DataError, match="got '2'"):
        parse_measurement("angle_deg,error_arcsec,direction\n0,1,up\n10,2,2\n", "two.csv")


def test_clockwise_words_take_forward_from_the_data(tmp_path):
    # forward runs visit 0, 120, 240 (angles rising): whichever word is written on those rows is forward
    for fwd_word, rev_word in (("CW", "CCW"), ("CCW", "CW")):
        text = "angle_deg,error_arcsec,direction,run\n" + "".join(
            f"{a:g},{e},{fwd_word if d > 0 else rev_word},{r}\n" for a, e, d, r in hand_rows())
        m = parse_measurement(text, "cw.csv")
        assert list(m.direction) == [d for _, _, d, _ in hand_rows()]
        assert m.notes == (f"direction words CW/CCW: the {fwd_word} rows move to larger angles, so {fwd_word} is "
                           "forward (+1)",)


def test_clockwise_rows_alone_can_orient_the_words():
    # the CW rows climb 0 -> 20 -> 40; the CCW rows all sit at 50 (a one-position return): CW is forward
    text = "angle_deg,error_arcsec,direction\n0,1,CW\n20,2,CW\n40,3,CW\n50,4,CCW\n50,5,CCW\n"
    assert parse_measurement(text, "cw1.csv").direction.tolist() == [1.0, 1.0, 1.0, -1.0, -1.0]
    # the CCW rows climb, the CW rows sit at one angle: CCW is forward
    text = "angle_deg,error_arcsec,direction\n50,4,CW\n50,5,CW\n0,1,CCW\n20,2,CCW\n40,3,CCW\n"
    assert parse_measurement(text, "ccw.csv").direction.tolist() == [-1.0, -1.0, 1.0, 1.0, 1.0]
    # both words climb: the data contradict each other, so they do not orient the words
    text = "angle_deg,error_arcsec,direction\n0,1,CW\n20,2,CW\n0,3,CCW\n20,4,CCW\n"
    assert "the rows do not show which one moves to larger angles" in parse_measurement(text, "both.csv").notes[0]
    # falling CW rows in one run, but two runs each of one CW row: only rows of one run are compared
    text = "angle_deg,error_arcsec,direction,run\n40,1,CW,0\n0,2,CW,1\n0,3,CCW,1\n"
    m = parse_measurement(text, "cw2.csv")
    assert m.direction.tolist() == [-1.0, -1.0, 1.0]  # the rows cannot tell: CCW forward, said


def test_clockwise_words_the_data_cannot_orient_are_said(tmp_path):
    text = "angle_deg,error_arcsec,direction\n0,1,CW\n0,2,CCW\n0,1.5,CW\n0,2.5,CCW\n"
    m = parse_measurement(text, "one.csv")
    assert list(m.direction) == [-1.0, 1.0, -1.0, 1.0]
    assert m.notes == ("direction words CW/CCW: the rows do not show which one moves to larger angles; CCW is taken "
                       "as forward (+1, the right-hand rule about the axis): if CW is your forward direction, write "
                       "+1/-1 instead",)


def test_a_cell_that_is_no_direction_is_named(tmp_path):
    with pytest.raises(DataError) as info:
        parse_measurement("angle_deg,error_arcsec,direction\n0,1,up\n10,2,sideways\n", "d.csv")
    assert info.value.problems == ["d.csv:3: column direction: expected +1 or -1 or a direction word (up/down, "
                                   "forward/reverse, fwd/rev, +/-, pos/neg, CW/CCW), got 'sideways'"]


# --- preamble without '#' --------------------------------------------------------------------------------------


def test_a_preamble_without_hash_is_skipped_and_said(runner, tmp_path):
    text = ("Rotary table test report;;;\nOperator;Hans;;\nDate;2024-03-01;;\nSerial number;1234;;\n\n"
            "angle (deg);error (arcsec);direction;run\n"
            + "".join(f"{a:g};{e};{d};{r}\n" for a, e, d, r in hand_rows()))
    path = tmp_path / "preamble.csv"
    path.write_text(text)
    got, doc, err = figures(runner, path)
    assert got == pytest.approx(HAND_FIGURES)
    assert ("4 lines before the header skipped as a preamble (metadata without '#', up to line 5): "
            "'Rotary table test report;;;'; 'Operator;Hans;;'; ...") in doc["notes"]
    m = read_measurement(path)
    assert m.preamble == ("Rotary table test report;;;", "Operator;Hans;;", "Date;2024-03-01;;",
                          "Serial number;1234;;")


def test_a_header_directly_followed_by_data_is_never_taken_for_a_preamble():
    m = parse_measurement("angle_deg,error_arcsec\n0,1\n10,2\n", "p.csv")
    assert m.preamble == () and m.notes == ()


# --- target and actual positions instead of a deviation ----------------------------------------------------------


def test_target_and_actual_positions_give_the_deviation_wrapped(runner, tmp_path):
    # a laser-style export: targets and actual positions in degrees; the actual at 0 deg reads 359.99x
    lines = ["Target (deg),Actual (deg),Direction,Run"]
    for a, e, d, r in hand_rows():
        lines.append(f"{a:g},{(a + e / 3600.0 - 3 / 3600.0) % 360.0:.9f},{d},{r}")
    path = tmp_path / "laser.csv"
    path.write_text("\n".join(lines) + "\n")
    got, doc, err = figures(runner, path)
    assert got == pytest.approx(HAND_FIGURES, abs=1e-5)
    assert doc["iso230_2"]["E_forward"] == pytest.approx(5.0, abs=1e-5)
    assert doc["input_units"] == {"angle": "deg", "error": "deg"}
    notes = "\n".join(doc["notes"])
    assert "error formed as actual - target: 'Actual (deg)' - 'Target (deg)', in deg, wrapped to +/-180 deg" in notes
    assert "rows across 0/360 deg" in notes  # those at the 0 deg target that read below 0
    assert err == ""


def test_an_error_column_wins_over_an_actual_position(tmp_path):
    m = parse_measurement("angle_deg,actual_deg,error_arcsec\n0,0.1,1\n10,10.1,2\n", "both.csv")
    assert m.error_arcsec == pytest.approx([1.0, 2.0])
    assert "column 'actual_deg' (actual position) not used: the file has an error column" in m.notes


# --- velocity, time units --------------------------------------------------------------------------------------------


def test_direction_from_velocity_with_standstill_rows_left_out_and_kept_out_of_the_rows():
    text = ("angle_deg,actual_deg,velocity,time (ms)\n0,0,0,0\n0,0.001,5,10\n10,10.002,5,20\n10,10,0,30\n"
            "10,9.999,-5,40\n0,0.0005,-5,50\n0,0,0,60\n")
    m = parse_measurement(text, "v.csv")
    assert list(m.direction) == [1.0, 1.0, -1.0, -1.0]
    assert m.time == pytest.approx([0.01, 0.02, 0.04, 0.05])
    assert m.error_arcsec == pytest.approx([3.6, 7.2, -3.6, 1.8])
    assert "direction" in m.derived
    assert ("direction from the sign of 'velocity'; 3 standstill rows (velocity 0) left out (lines 2, 5, 8)"
            in m.notes)
    assert [r[3] for r in m.rows] == ["10", "20", "40", "50"]  # simulate --at writes back only these


# --- encoder counts --------------------------------------------------------------------------------------------------


#: (error column, its length unit); the first three beside an angle column named with its unit in brackets
_LENGTH_HEADERS = [("error (mm)", "mm"), ("error (µm)", "µm"), ("error (um)", "um"), ("error_mm", "mm"), ("error / mm", "mm"), ("error / µm", "µm"), ("error (cm)", "cm"),
                   ("error (m)", "m"), ("error in mm", "mm"), ("error_microns", "microns"), ("error (thou)", "thou"),
                   ("error (mils)", "mils"), ("Error [inch]", "inch"), ("error in µm", "µm")]


@pytest.mark.parametrize(("cell", "unit"), _LENGTH_HEADERS)
def test_a_length_in_any_spelling_is_never_proposed_nor_read_as_an_error(runner, tmp_path, cell, unit):
    """An error column in a length (a linear axis's, or a rotary one's measured at a radius) read as
    arcseconds gives numbers that are all wrong.  The unit in brackets, after a slash, after ' in ' or
    as a last '_' suffix: the hint no longer proposes it, a --map naming it is refused (it had been read
    as arcsec without a word, and proposed by the hint outside brackets)."""
    angle = "angle (deg)" if cell in [c for c, _ in _LENGTH_HEADERS[:3]] else "angle_deg"
    path = tmp_path / "lengths.csv"
    path.write_text(f"{angle},{cell}\n" + "".join(f"{a},{k % 3}\n" for k, a in enumerate(range(0, 360, 30))))
    result = runner.invoke(app, ["measure", str(path)])
    assert result.exit_code == 2
    q = cell if cell.replace("_", "").isalnum() else f'"{cell}"'
    assert result.stderr == (f"error: {path}:1: missing required column error_arcsec (header has: {angle}, "
                             f"{cell}); name the columns with --map CANONICAL=HEADER ({q} states a length, not an "
                             "angle: convert it to one, arc length / the radius it was measured at, in a column of "
                             "its own)\n")
    result = runner.invoke(app, ["measure", str(path), "--map", f"error_arcsec={cell}"])
    assert result.exit_code == 2
    assert result.stderr == (f"error: {path}:1: column {cell!r} states a length ({unit}), not an angle: a rotary "
                             "axis's error is read as an angle; convert it (angle = arc length / the radius it was "
                             "measured at) in a column of its own and read that as error_arcsec\n")


def test_a_position_in_mm_named_with_map_is_refused(runner, tmp_path):
    path = tmp_path / "linear.csv"
    path.write_text("Position_mm,error_arcsec\n" + "".join(f"{a},{k % 3}\n" for k, a in enumerate(range(0, 360, 30))))
    result = runner.invoke(app, ["measure", str(path), "--map", "angle_deg=Position_mm"])
    assert result.exit_code == 2
    assert result.stderr == (f"error: {path}:1: column 'Position_mm' states a length (mm), not an angle: a rotary "
                             "axis's position is read as an angle; convert it (angle = arc length / the radius it "
                             "was measured at) in a column of its own and read that as angle_deg\n")


#: arcseconds in one of each unit, from the definitions (1 rad = 648000/pi arcsec), not from units.py
_ARCSEC_IN = {"deg": 3600.0, "arcmin": 60.0, "rad": 648000.0 / math.pi, "mrad": 648.0 / math.pi,
              "urad": 0.648 / math.pi, "arcsec": 1.0}


@pytest.mark.parametrize(("cell", "unit"), [
    ("error_deg", "deg"), ("error (deg)", "deg"), ("error / deg", "deg"), ("error in deg", "deg"),
    ("error (mrad)", "mrad"), ("error_mrad", "mrad"), ("error / mrad", "mrad"), ("error (rad)", "rad"),
    ("error in rad", "rad"), ("error_arcmin", "arcmin"), ("error in µrad", "urad"), ("Deviation_arcsec", "arcsec"),
    ("error_arcsec", "arcsec")])
def test_an_angular_error_unit_is_read_in_every_spelling(cell, unit):
    m = parse_measurement(f"angle_deg,{cell}\n0,0.002\n90,-0.001\n180,0.0005\n", "u.csv")
    assert m.error_arcsec == pytest.approx([v * _ARCSEC_IN[unit] for v in (0.002, -0.001, 0.0005)], rel=1e-12)


def test_canonical_and_unit_free_names_keep_their_meaning_beside_the_underscore_unit():
    m = parse_measurement("angle_deg,error_arcsec,time_ms,load_Nm,temperature_C,run_1\n0,1,500,2,20,0\n"
                          "90,2,1500,2,20,0\n", "c.csv")
    assert m.time == pytest.approx([0.5, 1.5])
    assert m.error_arcsec == pytest.approx([1.0, 2.0])
    assert readers.header.split_unit("run_1") == ("run 1", None)
    assert readers.header.split_unit("Position_mm") == ("position", "mm")



def test_counts_are_never_suggested_as_an_angle_nor_accepted_as_degrees(runner, tmp_path):
    path = tmp_path / "counts.csv"
    # 'Pos' is a position by its name, but its cells are whole numbers up to 4098: counts, not degrees
    path.write_text("Position (counts),Pos,Deviation (arcsec)\n" + "".join(
        f"{c},{c + 3},{k % 3}\n" for k, c in enumerate(range(0, 4096, 455))))
    result = runner.invoke(app, ["measure", str(path)])
    assert result.exit_code == 2
    assert result.stderr == (f"error: {path}:1: missing required column angle_deg (header has: Position (counts), "
                             "Pos, Deviation (arcsec)); name the columns with --map CANONICAL=HEADER\n")
    result = runner.invoke(app, ["measure", str(path), "--map", "angle_deg=Position (counts)"])
    assert result.exit_code == 2
    assert result.stderr == (f"error: {path}:1: column 'Position (counts)' holds encoder counts, not an angle: "
                             "convert it to degrees (counts x 360 / counts per turn) in a column of its own and read "
                             "that as angle_deg\n")
    # counts under a name that does not say so are read as asked, with a warning
    result = runner.invoke(app, ["measure", str(path), "--map", "angle_deg=Pos", "--orders", "1"])
    assert result.exit_code == 0
    assert "warning: the angles are whole numbers from 3 to 4098 read as degrees: if they are encoder counts" \
        in result.stderr


# --- quoted line breaks: refused by every reader, written by no writer ---------------------------------------------


QUOTED = 'angle_deg,error_arcsec,note\n0,1,a\n90,"1\n2",b\n180,3,c\n'


@pytest.mark.parametrize("command", ["measure", "diagnose", "simulate"])
def test_a_quoted_line_break_is_refused_with_its_line_in_every_command(runner, tmp_path, command):
    path = tmp_path / "q.csv"
    path.write_text(QUOTED)
    spec = ROOT / "configs" / "mch50.toml"
    args = {"measure": ["measure", str(path)], "diagnose": ["diagnose", str(spec), str(path)],
            "simulate": ["simulate", str(spec), "--at", str(path)]}[command]
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    assert result.stdout == ""  # never 12, never written back joined
    assert result.stderr == (f"error: {path}:3: a quoted cell runs over a line break; each row must be one line (a "
                             "cell split over lines would be joined into another value): put the cell on one line\n")


def test_a_quoted_line_break_in_a_header_or_an_instrument_export_is_refused():
    with pytest.raises(DataError) as info:
        parse_measurement('angle_deg,"error\narcsec"\n0,1\n1,2\n', "h.csv")
    assert info.value.problems[0].startswith("h.csv:1: a quoted cell runs over a line break")
    scope = (FIELD / "twincat-scope-resolver.csv").read_text().replace("\r\n", "\n").split("\n")
    scope[40] = scope[40].replace(";0;0;", ';"0\n0";0;')
    with pytest.raises(DataError) as info:
        parse_measurement("\n".join(scope), "s.csv")
    assert info.value.problems[0].startswith("s.csv:41: a quoted cell runs over a line break")


def test_writers_never_write_a_cell_holding_a_line_break():
    from wormgear_cli.output.formats import csv_text, one_row_per_line

    assert csv_text(["a", "b"], [[1, "x,y"]]) == 'a,b\n1,"x,y"\n'  # quoted cells without a break are fine
    # a text cell's control characters are escaped (errors.csv_cell): the row stays one line
    assert csv_text(["a"], [["x\ny"]]) == "a\nx\\ny\n"
    with pytest.raises(DataError, match="a cell would hold a line break"):  # the last guard of every writer
        one_row_per_line('a\n"x\ny"\n')


# --- plots follow the arc --------------------------------------------------------------------------------------------


def test_an_arc_through_zero_is_plotted_as_one_arc():
    pytest.importorskip("matplotlib")
    from wormgear_cli.measurement.iso230 import measurement_figures
    from wormgear_cli.plots import pyplot
    from wormgear_cli.plots.measure import deviation_figure

    targets = (330, 345, 0, 15, 30, 200, 215, 230)  # two arcs: 330 .. 30 through 0, and 200 .. 230
    text = "angle_deg,error_arcsec,direction,run\n" + "".join(
        f"{t},{math.sin(math.radians(t)) + r},{d},{r}\n" for r in range(2) for d in (1, -1) for t in targets)
    m = parse_measurement(text, "arc.csv")
    fig = deviation_figure(measurement_figures(m), m, "arcsec")
    try:
        ax = fig.axes[0]
        for line in ax.get_lines():
            x = np.asarray(line.get_xdata(), dtype=float)
            if line.get_linestyle() in ("-", "--") and x.size > 1:
                steps = np.diff(x[np.isfinite(x)])
                assert np.all(steps >= 0)
                # no line across an unmeasured gap: consecutive drawn points at most 15 deg apart
                finite_pairs = np.isfinite(x[1:]) & np.isfinite(x[:-1])
                assert np.all(np.diff(x)[finite_pairs] <= 15.0 + 1e-9)
        assert "along the arc, through 0" in ax.get_xlabel()
        lo, hi = ax.get_xlim()
        assert lo < -25 and hi < 260  # 330 deg drawn as -30 deg, before 0
    finally:
        pyplot().close(fig)


# --- TwinCAT Scope exports: a constructed one ------------------------------------------------------------------------


def scope_export(channels, rows, sep=";", comma=False):
    """A TwinCAT Scope export as the instrument writes it (metadata block, channel properties, rows, EOF)."""
    def num(x):
        text = repr(float(x))
        return text.replace(".", ",") if comma else text

    lines = [f"Name{sep}constructed export{sep}", f"File{sep}C:\\\\scope\\\\test.csv{sep}",
             f"Starttime of export{sep}133000000000000000{sep}Monday{sep}12:00:00.000", "", "",
             sep.join(["Name", *channels]), sep.join(["SymbolComment", *(["x"] * len(channels))]),
             sep.join(["Data-Type", *(["REAL64"] * len(channels))]), sep.join(["SampleTime", *(["10"] * len(channels))]),
             sep.join(["SymbolName", *(f"MAIN.{c}" for c in channels)]), sep.join(["Unit", *(["°"] * len(channels))]),
             "", ""]
    lines += [sep.join([str(t), *(num(v) for v in r)]) for t, *r in rows]
    return "\r\n".join(lines + ["EOF", ""])


def test_a_constructed_scope_export_with_ms_time_and_decimal_comma():
    # an axis from 350 deg through 0 to 10 deg and back; actual = set point + 20" sin(2 theta) + 5" lag
    theta = np.concatenate([np.linspace(350, 370, 41), np.linspace(370, 350, 41)])
    vel = np.concatenate([[0.0], np.full(39, 2.0), [0.0], [0.0], np.full(39, -2.0), [0.0]])
    setp = np.mod(theta, 360.0)
    err = 20 * np.sin(np.radians(2 * theta)) + 5 * np.sign(vel)
    act = np.mod(theta + err / 3600, 360.0)
    rows = [(10 * k, s, v, a) for k, (s, v, a) in enumerate(zip(setp, vel, act))]
    text = scope_export(["fSetPos", "fActVelo", "fEncPos"], rows, comma=True)
    m = parse_measurement(text, "scope.csv")
    moving = vel != 0
    assert m.input_format == "twincat-scope" and len(m) == int(moving.sum()) == 78
    assert m.error_arcsec == pytest.approx(err[moving], abs=1e-6)
    assert list(m.direction) == list(np.sign(vel[moving]))
    assert m.time == pytest.approx(0.01 * np.flatnonzero(moving))  # ms from the first sample
    assert dict(m.units) == {"angle": "deg", "error": "deg"}
    assert m.stated_units == {"angle", "error"}  # the Unit line says degrees
    assert "'fSetPos' as the target, 'fEncPos' as the actual position" in m.notes[0]
    assert "wrapped to +/-180 deg (1 row across 0/360 deg)" in "\n".join(m.notes)


def test_scope_channels_that_do_not_say_their_role_get_a_map_to_fill_in():
    rows = [(k, 10.0 * k, 10.0 * k + 0.001, 1.0) for k in range(5)]
    text = scope_export(["Axis1.fPos", "Axis2.fPos", "fActVelocity"], rows)
    with pytest.raises(DataError) as info:
        parse_measurement(text, "amb.csv")
    assert info.value.problems[0].endswith(
        "the channel names do not say which position is the target (a set point or counter) and which the actual "
        "(a resolver or encoder): name them, e.g. --map angle_deg=Axis1.fPos --map actual_deg=Axis2.fPos")
    m = parse_measurement(text, "amb.csv", options=ReadOptions(column_map=(("angle_deg", "Axis1.fPos"),
                                                                           ("actual_deg", "Axis2.fPos"))))
    assert m.error_arcsec == pytest.approx([3.6] * 5)


def test_a_map_names_its_column_in_any_case_when_only_one_fits(runner, tmp_path):
    path = tmp_path / "de.csv"
    path.write_text("Position (deg);Abweichung (arcsec);Richtung;Lauf\n" + "".join(
        f"{a:g};{e};{d};{r}\n" for a, e, d, r in hand_rows()))
    got, doc, _ = figures(runner, path, "--map", "error_arcsec=abweichung (ARCSEC)", "--map", "direction=richtung",
                          "--map", "run=LAUF")
    assert got == pytest.approx(HAND_FIGURES)
    assert doc["columns"]["direction"] == "Richtung"


def test_the_api_reads_files_as_they_are():
    import wormgear_cli as wg

    m = wg.read_measurement(FIELD / "twincat-scope-resolver.csv")
    assert len(m) == 2108 and m.columns["actual_deg"] == "fActPosition (Resolver)"
    r = wg.measure(FIELD / "twincat-scope-resolver.csv", orders=[4])
    assert r.iso230_2["E"].arcsec == pytest.approx(68943.70, abs=0.01)
    from wormgear_cli.errors import UsageError

    with pytest.raises(UsageError, match="--input-format nope: expected one of auto, phd2, twincat-scope, csv"):
        wg.read_measurement(FIELD / "servo-quantised-backlash.csv", input_format="nope")


# --- numbers: the slow path, ranges in the canonical unit ----------------------------------------------------------


def test_decimal_commas_on_the_slow_path_and_their_messages():
    # a '#' line between rows sends the file down the cell-by-cell path
    m = parse_measurement("angle;error (arcsec)\n0;1,5\n# pause\n10;2,5\n", "dc.csv",
                          options=ReadOptions(column_map=(("angle_deg", "angle"),)))
    assert m.error_arcsec == pytest.approx([1.5, 2.5])
    with pytest.raises(DataError) as info:
        parse_measurement("angle_deg;error_arcsec\n0;1,5\n# pause\n10;1_0\n", "u.csv")
    assert info.value.problems == ["u.csv:4: column error_arcsec: expected a number, got '1_0'"]
    long = "x" * 60
    with pytest.raises(DataError) as info:
        parse_measurement(f"angle_deg;error_arcsec\n0;1,5\n# pause\n10;{long}\n", "l.csv")
    assert info.value.problems == [f"l.csv:4: column error_arcsec: expected a number, got '{'x' * 40}'... (60 "
                                   "characters)"]


def test_ranges_are_judged_in_the_canonical_unit():
    # 3000 deg of error is 1.08e7 arcsec: beyond the 1e7 arcsec an error column may hold, said in arcsec
    with pytest.raises(DataError) as info:
        parse_measurement("angle_deg,error (deg)\n0,1\n10,3000\n", "r.csv")
    assert info.value.problems == ["r.csv:3: column error_arcsec ('error (deg)'): expected a number in [-1e+07, "
                                   "1e+07] (arcsec), got '3000'"]
    ok = parse_measurement("angle_deg,error (deg)\n0,1\n10,2700\n", "r.csv")  # 9.72e6 arcsec: inside
    assert ok.error_arcsec[1] == pytest.approx(2700 * 3600)
    edge = parse_measurement("angle_deg,error_arcsec,temperature_C\n0,1,-100\n10,2,300\n", "t.csv")
    assert edge.temperature.tolist() == [-100.0, 300.0]  # the range is inclusive


@pytest.mark.parametrize("header, factor", [("time (min)", 60.0), ("time (h)", 3600.0), ("time (ms)", 1e-3),
                                            ("time_s", 1.0)])
def test_a_time_column_in_minutes_hours_or_ms_is_read_in_seconds(header, factor):
    """1 min = 60 s, 1 h = 3600 s, 1 ms = 1e-3 s: the stated unit multiplies the cells."""
    from wormgear_cli.measurement.readers import parse_measurement

    cells = np.array([0.5, 1.5, 2.0, 3.25])
    text = f"angle_deg,error_arcsec,{header}\n" + "".join(f"{a},1,{t}\n" for a, t in zip((0, 90, 180, 270), cells))
    m = parse_measurement(text, "<t>")
    np.testing.assert_allclose(m.time, cells * factor, rtol=1e-15)


def test_a_stated_unit_the_mapped_column_cannot_take_is_refused_and_input_is_not_inches(runner, tmp_path):
    """Breaker trial: --map angle_deg=angle_mrad read milliradians as degrees, error (nm) (a load's
    N m) as arcsec; angle_in (the input side) was refused as inches even when mapped."""
    rows = "".join(f"{a},{k % 3}\n" for k, a in enumerate(range(0, 360, 30)))
    path = tmp_path / "mrad.csv"
    path.write_text("angle_mrad,error_arcsec\n" + rows)
    r = runner.invoke(app, ["measure", str(path), "--map", "angle_deg=angle_mrad"])
    assert r.exit_code == 2
    assert r.stderr == (f"error: {path}:1: column 'angle_mrad' states mrad, a unit angle_deg is not read in (it takes "
                        "deg, rad): convert it in a column of its own, or map the column it belongs to\n")
    path = tmp_path / "in.csv"
    path.write_text("angle_in,error_arcsec\n" + rows)
    r = runner.invoke(app, ["measure", str(path), "--map", "angle_deg=angle_in", "--orders", "1", "-f", "json"])
    assert r.exit_code == 0, r.stderr


def test_the_error_unit_the_warning_proposes_is_accepted(runner, tmp_path):
    """The plausibility warning may propose --error-unit rad; --error-unit rad (and mrad) is taken."""
    path = tmp_path / "rad.csv"
    path.write_text("angle_deg,deviation\n" + "".join(f"{a},{1e-5 * (k % 3)}\n" for k, a in enumerate(range(0, 360, 30))))
    for unit in ("rad", "mrad"):
        r = runner.invoke(app, ["measure", str(path), "--map", "error_arcsec=deviation", "--error-unit", unit,
                                "--orders", "3", "-f", "json"])
        assert r.exit_code == 0, r.stderr
        assert json.loads(r.stdout)["input_units"] == {"angle": "deg", "error": unit}
