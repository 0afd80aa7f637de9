"""Files as they come: delimiters, decimal commas, BOM, CRLF, units in headers, other languages, --map,
unit options, the missing-column hint, and plausibility warnings.

The constructed cases reuse the hand-worked ISO 230-2 example of test_measure_cli.py (figures worked
out by hand there: A 14, B 4, E 5, M 1.5, R 14 arcsec), written in other formats and units.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.support.iso230_hand import HAND
from wormgear_cli.cli import app
from wormgear_cli.errors import DataError, UsageError
from wormgear_cli.measurement.reader import ReadOptions
from wormgear_cli.measurement.readers import parse_measurement, read_measurement
from wormgear_cli.measurement.readers.text import detect_dialect

HAND_FIGURES = {"A": 14.0, "B": 4.0, "E": 5.0, "M": 1.5, "R": 14.0}
URAD_PER_ARCSEC = math.pi / 648000.0 * 1e6  # 4.8481 urad


def hand_rows():
    """(angle_deg, error_arcsec, direction, run) of the hand example."""
    rows = []
    for run in range(3):
        for d in (1, -1):
            for target in (0.0, 120.0, 240.0) if d > 0 else (240.0, 120.0, 0.0):
                rows.append((target, HAND[(target, d)][run], d, run))
    return rows


def write_bytes(path, text, bom=False, crlf=False):
    data = text.replace("\n", "\r\n") if crlf else text
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + data.encode("utf-8"))
    return path


def figures(runner, path, *args):
    result = runner.invoke(app, ["measure", str(path), "-f", "json", *args])
    assert result.exit_code == 0, result.stderr
    return json.loads(result.stdout), result.stderr


def test_tab_decimal_comma_french_header_in_arcmin_bom_crlf(runner, tmp_path):
    lines = ["Position (°)\tÉcart (arcmin)\tSens\tSérie"]
    for a, e, d, r in hand_rows():
        lines.append(f"{a:g}\t{e / 60.0:.9f}".replace(".", ",") + f"\t{d}\t{r}")
    path = write_bytes(tmp_path / "fr.csv", "\n".join(lines) + "\n", bom=True, crlf=True)
    # without a map: the header found and a map that fits (units suffix and keywords)
    result = runner.invoke(app, ["measure", str(path)])
    assert result.exit_code == 2
    # ('Position (°)' is recognised: an English base name with a unit)
    assert result.stderr == (f"error: {path}:1: missing required column error_arcsec (header has: "
                             "Position (°), Écart (arcmin), Sens, Série); try "
                             "--map error_arcsec=\"Écart (arcmin)\" --map direction=Sens --map run=Série\n")
    doc, err = figures(runner, path, "--map", "angle_deg=Position (°)", "--map", "error_arcsec=Écart (arcmin)",
                       "--map", "direction=Sens", "--map", "run=Série")
    for key, value in HAND_FIGURES.items():
        assert doc["iso230_2"][key] == pytest.approx(value, abs=1e-6), key
    assert doc["input_units"] == {"angle": "deg", "error": "arcmin"}  # taken from the header
    assert err == ""


def test_semicolon_and_english_headers_with_units_need_no_map(tmp_path):
    text = "angle (deg);error [arcsec];direction;run\n" + "".join(
        f"{a:g};{e:g};{d};{r}\n" for a, e, d, r in hand_rows())
    m = read_measurement(write_bytes(tmp_path / "en.csv", text))
    assert dict(m.columns) == {"angle_deg": "angle (deg)", "error_arcsec": "error [arcsec]", "direction": "direction",
                               "run": "run"}
    assert m.error_arcsec[:3] == pytest.approx([1.0, 4.0, -3.0])


@pytest.mark.parametrize("delim", [",", ";", "\t"])
def test_delimiter_detected(delim):
    text = delim.join(["angle_deg", "error_arcsec", "run"]) + "\n" + "\n".join(
        delim.join([str(a), str(e), "0"]) for a, e in ((0, 1.5), (10, 2.5), (20, -1.25))) + "\n"
    m = parse_measurement(text, "x.csv")
    assert m.error_arcsec == pytest.approx([1.5, 2.5, -1.25])


def test_sniffer_and_rule_are_named():
    # the Sniffer finds ';' on a regular file
    assert detect_dialect("a;b;c", ["1,5;2;3", "2,5;3;4"]) == (";", True, "sniffer")
    # a single data line whose ',' count matches the header: decided by the rule (tab, ';', ',' in turn)
    delim, comma, how = detect_dialect("angle_deg,error_arcsec", ["0,1"])
    assert delim == "," and comma is False


def test_error_unit_urad_and_angle_unit_rad(runner, tmp_path):
    lines = ["angle_deg,error_arcsec,direction,run"]
    for a, e, d, r in hand_rows():
        lines.append(f"{math.radians(a)!r},{e * URAD_PER_ARCSEC!r},{d},{r}")
    path = tmp_path / "si.csv"
    path.write_text("\n".join(lines) + "\n")
    doc, _ = figures(runner, path, "--error-unit", "urad", "--angle-unit", "rad")
    for key, value in HAND_FIGURES.items():
        assert doc["iso230_2"][key] == pytest.approx(value, abs=1e-6), key
    assert [t["target_deg"] for t in doc["per_target"]] == pytest.approx([0.0, 120.0, 240.0])


def test_map_errors_are_one_line_each(runner, tmp_path):
    path = tmp_path / "a.csv"
    path.write_text("Pos,Dev\n0,1\n10,2\n")
    result = runner.invoke(app, ["measure", str(path), "--map", "angle_deg=Pos", "--map", "error_arcsec=Nope"])
    assert result.exit_code == 2
    assert result.stderr == f"error: {path}:1: --map error_arcsec=Nope: no such column (header has: Pos, Dev)\n"
    result = runner.invoke(app, ["measure", str(path), "--map", "angle=Pos", "--map", "error_arcsec"])
    assert result.exit_code == 2
    assert result.stderr == "error: --map error_arcsec: expected CANONICAL=HEADER, e.g. --map angle_deg=Position\n"
    with pytest.raises(UsageError) as info:
        ReadOptions(column_map=(("angle", "Pos"),))
    assert info.value.problems == ["--map angle=...: unknown column name 'angle', expected one of angle_deg, "
                                   "error_arcsec, direction, run, load_Nm, temperature_C, time_s, actual_deg, velocity"]


def test_errors_in_degrees_read_as_arcsec_are_flagged(runner, tmp_path):
    # a 20 arcsec peak-to-peak error written in degrees (20 / 3600 = 0.00556 deg)
    theta = np.arange(0, 360, 15)
    err_deg = 10.0 / 3600.0 * np.sin(np.radians(theta))
    path = tmp_path / "deg.csv"
    path.write_text("angle_deg,error_arcsec\n" + "".join(f"{a},{float(e)!r}\n" for a, e in zip(theta, err_deg)))
    doc, err = figures(runner, path)
    assert "if the column is in deg, use --error-unit deg" in err
    assert any("--error-unit deg" in w for w in doc["warnings"])
    doc, err = figures(runner, path, "--error-unit", "deg")
    assert "warning" not in err
    assert doc["iso230_2"]["E_forward"] == pytest.approx(20.0, rel=1e-3)


def test_angles_in_radians_read_as_degrees_are_flagged(tmp_path):
    rad = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    path = tmp_path / "rad.csv"
    path.write_text("angle_deg,error_arcsec\n" + "".join(f"{float(a)!r},{math.sin(a)}\n" for a in rad))
    m = read_measurement(path)
    assert any("--angle-unit rad" in w for w in m.warnings)
    assert not read_measurement(path, options=ReadOptions(angle_unit="rad")).warnings


def test_header_unit_against_explicit_option_is_flagged(tmp_path):
    path = tmp_path / "u.csv"
    path.write_text("angle (deg),error (arcmin)\n0,1\n10,2\n20,3\n")
    m = read_measurement(path, options=ReadOptions(error_unit="arcsec"))
    assert m.warnings[0] == ("column 'error (arcmin)' says arcmin but is read as arcsec (--error-unit arcsec); if "
                             "the header is right, use --error-unit arcmin")
    assert read_measurement(path).error_arcsec == pytest.approx([60.0, 120.0, 180.0])


def test_two_columns_for_one_name_are_refused(tmp_path):
    path = tmp_path / "two.csv"
    path.write_text("position (deg),angle [deg],error_arcsec\n0,0,1\n10,10,2\n")
    with pytest.raises(DataError) as info:
        read_measurement(path)
    assert info.value.problems == [f"{path}:1: columns 'position (deg)' and 'angle [deg]' both give angle_deg; "
                                   "choose one with --map angle_deg=..."]


@pytest.mark.parametrize("header", ["angle_deg,angle_rad,error_arcsec,error_urad", "angle_rad,angle_deg,error_urad,error_arcsec",
                                    "angle (deg),angle_deg,error_arcsec,error (mrad)"])
def test_the_canonical_name_wins_over_another_spelling_of_its_column(tmp_path, header):
    """Breaker trial: once '_rad' was read as a unit, a file holding angle_deg beside angle_rad was
    refused as two columns for one name; the canonical names are the reader's own contract."""
    path = tmp_path / "both.csv"
    cols = header.split(",")
    values = {"angle_deg": "10", "angle_rad": "0.5", "angle (deg)": "20", "error_arcsec": "1", "error_urad": "99",
              "error (mrad)": "7"}
    row = ",".join(values[c] for c in cols) + "\n"
    path.write_text(header + "\n" + row + row)
    m = read_measurement(path)
    assert float(m.angle[0]) == pytest.approx(np.radians(10.0)) and float(m.error[0]) == pytest.approx(np.radians(1 / 3600))


def test_rows_are_kept_for_writing_back_in_the_file_delimiter(tmp_path):
    path = tmp_path / "s.csv"
    path.write_text("angle_deg;error_arcsec;note\n0;1;a,b\n10;2;c\n")
    m = read_measurement(path)
    assert m.rows == (("0", "1", "a,b"), ("10", "2", "c"))


def test_time_restarts_make_passes_constructed(tmp_path):
    # three sessions of 4 rows; time starts again at 0, 0.5 in sessions 2 and 3
    times = [0, 1, 2, 3, 0, 1, 2, 3, 0.5, 1.5, 2.5, 3.5]
    path = tmp_path / "t.csv"
    path.write_text("angle_deg,error_arcsec,time_s\n" + "".join(f"{10 * i},{i % 3},{t}\n" for i, t in enumerate(times)))
    m = read_measurement(path)
    assert m.run.tolist() == [0] * 4 + [1] * 4 + [2] * 4
    assert m.derived == frozenset({"run"})
    assert m.notes == ("no run column: time_s goes backwards at lines 6, 10, taken as the start of a new pass (3 "
                       "passes); add a run column to say so explicitly",)
    # with a run column nothing is derived
    path.write_text("angle_deg,error_arcsec,time_s,run\n" + "".join(
        f"{10 * i},{i % 3},{t},7\n" for i, t in enumerate(times)))
    m = read_measurement(path)
    assert m.derived == frozenset() and set(m.run.tolist()) == {7}


def test_an_option_reading_a_canonical_column_in_another_unit_is_noted(tmp_path):
    # the header's canonical name states a unit too: reading it in another is said (a note), not silent
    from wormgear_cli.measurement.reader import ReadOptions
    from wormgear_cli.measurement.readers import read_measurement

    path = tmp_path / "d.csv"
    path.write_text("angle_deg,error_arcsec\n0,1\n90,2\n180,3\n270,4\n")
    m = read_measurement(path, options=ReadOptions(error_unit="urad"))
    assert "column 'error_arcsec' read in urad (--error-unit urad), not in the arcsec its name says" in m.notes
    assert m.error[1] == pytest.approx(2e-6, rel=1e-12)  # read as the option says
    m = read_measurement(path, options=ReadOptions(angle_unit="rad"))
    assert "column 'angle_deg' read in rad (--angle-unit rad), not in the deg its name says" in m.notes
    assert not any("read in" in n for n in read_measurement(path).notes)
