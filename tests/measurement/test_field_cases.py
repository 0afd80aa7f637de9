"""Each field case of tests/data/field/README.md with the right value it names.

Values (arcsec) are the README's, which come from the recordings' known truth (an exact
10 sin(144 theta) signal; the directions of an ISO 230-2 cycle; ISO 230-2 arithmetic on
the shipped configs/mch50-warm.csv), not from this code's output.
"""

from __future__ import annotations

import json
import shlex

import numpy as np
import pytest

from tests.support.paths import ROOT
from wormgear_cli.cli import app

FIELD = ROOT / "tests" / "data" / "field"


def measure_json(runner, *args):
    result = runner.invoke(app, ["measure", *map(str, args), "-f", "json"])
    assert result.exit_code == 0, result.stderr
    return json.loads(result.stdout), result.stderr


def by_order(doc):
    return {it["order"]: it for it in doc["orders"]["items"]}


@pytest.mark.parametrize("orders", ["144", "1,144", "144,1"])
def test_partial_span_order144_whatever_the_order_list(runner, orders):
    doc, _ = measure_json(runner, FIELD / "partial-span-order144.csv", "--orders", orders)
    items = by_order(doc)
    assert items[144.0]["status"] == "fitted"
    assert items[144.0]["common"]["amplitude"] == pytest.approx(10.0, abs=0.01)  # README: 10.000 +/- 0.01
    if "1" in orders.split(","):
        assert items[1.0]["status"] == "beyond span"
        assert items[1.0]["common"]["amplitude"] is None
        assert "11.07 deg" in items[1.0]["reason"]
    assert doc["coverage"]["full_turn"] is False
    assert doc["coverage"]["span_deg"] == pytest.approx(11.07, abs=0.01)  # -10.64 .. +0.43 deg in the file


def test_partial_span_note_names_the_span(runner):
    doc, _ = measure_json(runner, FIELD / "partial-span-order144.csv", "--orders", "1,144")
    notes = "\n".join(doc["notes"])
    assert "order 1 not fitted: beyond span: one period is longer than the 11.07 deg the data cover" in notes
    assert "partial span 11.07 deg" in doc["verdict"]


def test_no_direction_column_warns_and_withholds_forward_repeatability(runner):
    doc, err = measure_json(runner, FIELD / "no-direction-column.csv")
    assert "warning: no direction column: every row is taken as forward, yet one run visits the same target" in err
    iso = doc["iso230_2"]
    assert iso["R_forward"] is None  # not the 138.44 computed from mixed directions
    assert iso["A_forward"] is None
    assert all(t["s_forward"] is None for t in doc["per_target"])
    assert "one-direction figures withheld" in doc["verdict"]


def test_no_direction_column_with_the_directions_restored(runner, tmp_path):
    # put the directions back by the visiting order (first visit of a target in a run: up, second: down)
    lines = (FIELD / "no-direction-column.csv").read_text().splitlines()
    header = lines[1].split(",")
    out = [lines[1] + ",direction"]
    seen = set()
    for line in lines[2:]:
        cells = dict(zip(header, line.split(",")))
        key = (cells["run"], cells["angle_deg"])
        out.append(line + ("," + ("-1" if key in seen else "1")))
        seen.add(key)
    path = tmp_path / "restored.csv"
    path.write_text("\n".join(out) + "\n")
    doc, err = measure_json(runner, path)
    assert doc["iso230_2"]["R_forward"] == pytest.approx(18.30, abs=0.005)  # README
    assert doc["iso230_2"]["R_reverse"] == pytest.approx(204.75, abs=0.005)
    assert "warning" not in err


def test_time_restarts_give_the_passes_of_the_run_column():
    from wormgear_cli.measurement.readers import read_measurement

    without = read_measurement(FIELD / "time-restarts-no-run.csv")
    with_run = read_measurement(FIELD / "time-restarts-with-run.csv")
    assert "run" in without.derived and "run" in without.present
    assert np.array_equal(without.run, with_run.run)  # README: two sessions joined end to end
    assert np.unique(without.run).tolist() == [0, 1]
    assert any("time_s goes backwards at line 303" in n for n in without.notes)  # 2 comment/header + 300 rows


def test_one_position_backlash_per_target_values(runner):
    doc, _ = measure_json(runner, FIELD / "one-position-backlash.csv")
    t = doc["per_target"]
    assert len(t) == 1
    # README: B = -15.13 (mean forward - mean reverse), s up 7.25, s down 7.10, R up 28.99, R down 28.40, R 43.82
    assert t[0]["reversal"] == pytest.approx(-15.13, abs=0.005)
    assert t[0]["s_forward"] == pytest.approx(7.25, abs=0.005)
    assert t[0]["s_reverse"] == pytest.approx(7.10, abs=0.005)
    iso = doc["iso230_2"]
    assert iso["B_signed"] == pytest.approx(-15.13, abs=0.005)
    assert iso["R_forward"] == pytest.approx(28.99, abs=0.005)
    assert iso["R_reverse"] == pytest.approx(28.40, abs=0.005)
    assert iso["R"] == pytest.approx(43.82, abs=0.005)
    # figures that compare targets are not applicable, not refused
    assert iso["A"] is None and iso["E"] is None and iso["M"] is None
    assert "one target (one-position test)" in doc["verdict"]


SPREADSHEET_MAP = ('--map angle_deg="Position (deg)" --map error_arcsec="Abweichung (arcsec)" --map direction=Richtung '
                   '--map run=Lauf --map temperature_C="Temperatur (°C)"')


def test_spreadsheet_export_gives_the_figures_of_the_shipped_file(runner):
    doc, _ = measure_json(runner, FIELD / "spreadsheet-export.csv", *shlex.split(SPREADSHEET_MAP))
    iso = doc["iso230_2"]
    # README: A 182.86, B 158.26, E 180.77, M 71.90, R 160.10 (those of the plain CSV it was exported from,
    # the demo measurement shipped before the demo was rebuilt: spreadsheet-export.plain.csv)
    for key, value in {"A": 182.86, "B": 158.26, "E": 180.77, "M": 71.90, "R": 160.10}.items():
        assert iso[key] == pytest.approx(value, abs=0.005), key
    shipped, _ = measure_json(runner, FIELD / "spreadsheet-export.plain.csv")
    assert iso == pytest.approx(shipped["iso230_2"])


def test_spreadsheet_export_without_map_shows_the_header_and_a_map_that_fits(runner):
    path = FIELD / "spreadsheet-export.csv"
    result = runner.invoke(app, ["measure", str(path)])
    assert result.exit_code == 2
    assert result.stderr == (
        f"error: {path}:1: missing required column error_arcsec (header has: Position (deg), Abweichung (arcsec), "
        'Richtung, Lauf, Temperatur (°C)); try --map error_arcsec="Abweichung (arcsec)" --map direction=Richtung '
        '--map run=Lauf --map temperature_C="Temperatur (°C)"\n')
    # and the suggestion works as given (with the recognised 'Position (deg)')
    hint = result.stderr.split("; try ", 1)[1].strip()
    doc, _ = measure_json(runner, path, *shlex.split(hint))
    assert doc["iso230_2"]["A"] == pytest.approx(182.86, abs=0.005)


# --- third round ------------------------------------------------------------------------------------------------


def test_servo_quantised_backlash_says_below_resolution_not_zero(runner):
    doc, err = measure_json(runner, FIELD / "servo-quantised-backlash.csv")
    iso = doc["iso230_2"]
    assert iso["B_signed"] == pytest.approx(-2223.63, abs=0.005)  # README: 7.03 counts = 0.618 deg
    # every reverse reading is the same encoder count: no s = 0.00, R = 0.00 as if perfectly repeatable
    assert iso["R_reverse"] is None
    assert doc["per_target"][0]["s_reverse"] is None and doc["per_target"][0]["below_resolution"] == "reverse"
    res = doc["resolution"]
    assert res["step"] == pytest.approx(1296000 / 4096, rel=1e-9)  # README: one step 316.4 arcsec (12-bit)
    assert res["quantised"] is True and res["below"] == ["R_reverse"]
    assert res["basis"] == "whole counts of an encoder with 4096 counts per turn"
    # R as computed: 2 s_up + 2 s_down + |B| with the forward scatter (five readings on one count, one off it)
    assert iso["R"] == pytest.approx(2 * doc["per_target"][0]["s_forward"] + 2223.633, abs=1e-6)
    assert ("all 6 reverse readings are equal: their s and R are below the resolution of the data (one step = "
            "316.406 arcsec: whole counts of an encoder with 4096 counts per turn), not zero") in doc["notes"]


def test_servo_quantised_backlash_table_shows_below_one_step(runner):
    result = runner.invoke(app, ["measure", str(FIELD / "servo-quantised-backlash.csv")])
    assert result.exit_code == 0
    line = next(ln for ln in result.stdout.splitlines() if ln.lstrip().startswith("repeatability R"))
    assert line.split()[-1] == "step" and "<1 step" in line and "0.00" not in line
    assert "179.9121       6    -958.01   21.53       6    1265.62   <1 step" in result.stdout


def test_twincat_scope_export_read_as_it_is_equals_the_converted_file(runner):
    scope, err = measure_json(runner, FIELD / "twincat-scope-resolver.csv")
    converted, _ = measure_json(runner, FIELD / "resolver-cyclic-error-deg.csv")
    assert err == ""
    assert scope["rows"] == converted["rows"] == 2108 and scope["targets"] == converted["targets"]
    assert (scope["rows_forward"], scope["rows_reverse"]) == (1054, 1054)
    # the converted file rounds the error to 1e-6 deg (0.0036 arcsec)
    assert scope["iso230_2"] == pytest.approx(converted["iso230_2"], abs=0.004)
    for a, b in zip(scope["orders"]["items"], converted["orders"]["items"]):
        assert a["common"]["amplitude"] == pytest.approx(b["common"]["amplitude"], abs=0.004)
    assert scope["iso230_2"]["E"] == pytest.approx(68943.70, abs=0.01)  # README
    assert by_order(scope)[4.0]["common"]["amplitude"] == pytest.approx(29220.0, abs=0.05)
    assert scope["orders"]["differential_offset"] == pytest.approx(-4351.0, abs=0.05)
    assert scope["columns"] == {"angle_deg": "fActPosition (Internal Counter)", "time_s": "time (FILETIME)",
                                "actual_deg": "fActPosition (Resolver)", "velocity": "fActVelocity"}
    notes = "\n".join(scope["notes"])
    assert "metadata block skipped (lines 1-27)" in notes
    assert "2427 standstill rows (velocity 0) left out (lines 28, 29, 30 and 2424 more)" in notes
    assert "error formed as actual - target: 'fActPosition (Resolver)' - 'fActPosition (Internal Counter)'" in notes
    assert "counted from the first row (2022-02-22 12:55:48 UTC)" in notes  # the export's 13:55:48 CET
    assert scope["warnings"] == []


def test_resolver_error_in_degrees_gets_no_advice_against_its_header(runner):
    doc, err = measure_json(runner, FIELD / "resolver-cyclic-error-deg.csv")
    assert doc["iso230_2"]["E"] == pytest.approx(68943.70, abs=0.005)  # README
    assert by_order(doc)[4.0]["common"]["amplitude"] == pytest.approx(29220.0, abs=0.05)
    assert doc["orders"]["differential_offset"] == pytest.approx(-4351.0, abs=0.05)
    assert err == "" and doc["warnings"] == [] and "check the units" not in doc["verdict"]
    assert not any("--error-unit" in n for n in doc["notes"])
    assert ("the errors span 68943.7 arcsec (19.15 deg) peak to peak, far beyond a positioning error's usual size; "
            "read in deg as the header states") in "\n".join(doc["notes"])


@pytest.mark.parametrize("p2p_deg", [3.0, 6.0, 19.0, 40.0])
def test_large_errors_stated_in_degrees_get_the_same_kind_of_message_whatever_their_size(tmp_path, p2p_deg):
    from wormgear_cli.measurement.readers import read_measurement

    theta = np.arange(0.0, 360.0, 7.5)
    path = tmp_path / "deg.csv"
    path.write_text("angle (deg),error (deg)\n" + "".join(
        f"{a:g},{p2p_deg / 2 * np.sin(np.radians(a)):.6f}\n" for a in theta))
    m = read_measurement(path)
    assert m.warnings == ()
    said = [n for n in m.notes if n.startswith("the errors span")]
    assert len(said) == 1
    assert said[0].endswith("far beyond a positioning error's usual size; read in deg as the header states (a "
                            "faulty encoder or resolver, or a reading lag, can be off by degrees)")
    assert f"({p2p_deg:.4g} deg)" in said[0]
    # the degree values written under the canonical error_arcsec are read as arcsec, the unit assumed: a few
    # arcsec is a plausible error, so nothing is said about the size (the note belongs to a stated unit)
    path.write_text(path.read_text().replace("angle (deg),error (deg)", "angle_deg,error_arcsec"))
    assumed = read_measurement(path)
    assert not any(n.startswith("the errors span") for n in assumed.notes) and assumed.warnings == ()


def test_quantised_readings_keep_their_numbers_where_they_scatter(runner):
    # the one-position test was read off a dial indicator (0.01 mm at 150 mm: 13.751 arcsec a division):
    # quantised, yet no cell has all its readings equal, so every s and R stays a number (README values)
    doc, _ = measure_json(runner, FIELD / "one-position-backlash.csv")
    res = doc["resolution"]
    assert res["quantised"] is True and res["step"] == pytest.approx(0.01 / 150 * 206264.806, abs=0.001)
    assert res["below"] == [] and res["cells_below"] == {"forward": 0, "reverse": 0}
    assert doc["iso230_2"]["R"] == pytest.approx(43.82, abs=0.005)
    assert doc["per_target"][0]["below_resolution"] is None
