"""``wormgear grade``: exit codes, JSON keys and the standard's check values."""

from __future__ import annotations

import json

import pytest

from wormgear_cli.cli import app

ARGS = ["grade", "--grade", "6", "--module-mm", "2", "--diameter-mm", "100", "--face-width-mm", "20"]


def test_json_has_the_standards_worked_example(runner):
    r = runner.invoke(app, [*ARGS, "--format", "json"])
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    # ISO 1328-1:2013 worked example: 8.5, 27, 11, 24 um
    assert (doc["f_pT_um"], doc["F_pT_um"], doc["F_alphaT_um"], doc["F_rT_um"]) == (8.5, 27.0, 11.0, 24.0)
    # ISO 1328-2 grade 6 with range means (hand, tests/physics/test_iso1328.py): 31 and 9.5 um
    assert (doc["F_i2T_um"], doc["f_i2T_um"]) == (31.0, 9.5)
    assert doc["teeth"] == 50 and r.stderr == ""


def test_second_check_value(runner):
    r = runner.invoke(app, ["grade", "-g", "6", "--module-mm", "3", "--diameter-mm", "120", "--face-width-mm",
                            "30", "-f", "json"])
    doc = json.loads(r.stdout)
    assert (doc["f_pT_um"], doc["F_pT_um"], doc["F_alphaT_um"]) == (9.0, 29.0, 12.0)


def test_table_is_deterministic_and_fits_80_columns(runner):
    a, b = runner.invoke(app, ARGS), runner.invoke(app, ARGS)
    assert a.exit_code == 0 and a.stdout_bytes == b.stdout_bytes
    assert max(len(line) for line in a.stdout.splitlines()) <= 80
    assert "F_pT" in a.stdout and " 27 " in a.stdout


@pytest.mark.parametrize("args, message", [
    (["--grade", "12"], "error: --grade: grade 12 outside ISO 1328-1:2013's range, expected an integer in [1, 11]\n"),
    (["--module-mm", "0.3"], "error: --module-mm: module 0.3 outside ISO 1328-1:2013's scope [0.5, 70] mm (its "
                             "formulas are not extrapolated)\n"),
    (["--face-width-mm", "-1"], "error: --face-width-mm: expected a finite number > 0, got -1\n"),
])
def test_bad_input_exits_2_naming_the_option_and_range(runner, args, message):
    full = list(ARGS)
    full[full.index(args[0]) + 1] = args[1]
    r = runner.invoke(app, full)
    assert r.exit_code == 2 and r.stderr == message and r.stdout == ""


def test_part2_extrapolation_warns_and_grade_3_has_no_composite(runner):
    r = runner.invoke(app, ["grade", "-g", "6", "--module-mm", "4", "--diameter-mm", "1200", "--face-width-mm",
                            "50", "-f", "json"])
    assert r.exit_code == 0
    assert r.stderr == ("warning: diameter 1200 outside ISO 1328-2:1997's scope [5, 1000] mm: the tolerance of "
                        "its nearest range is given (the formulas are not extrapolated)\n")
    r = runner.invoke(app, ["grade", "-g", "3", "--module-mm", "2", "--diameter-mm", "100", "--face-width-mm",
                            "20", "-f", "json"])
    assert r.exit_code == 0 and json.loads(r.stdout)["F_i2T_um"] is None


def test_teeth_derived_from_the_diameter_name_the_options_given(runner):
    from wormgear_cli.cli import app

    r = runner.invoke(app, ["grade", "-g", "6", "--module-mm", "2", "--diameter-mm", "8", "--face-width-mm", "20"])
    assert r.exit_code == 2
    assert r.stderr.startswith("error: --diameter-mm/--module-mm (z = d/m = 8/2 = 4): teeth 4 outside")


def test_teeth_that_contradict_the_diameter_are_warned(runner):
    from wormgear_cli.cli import app

    r = runner.invoke(app, ["grade", "-g", "6", "--module-mm", "2", "--diameter-mm", "100", "--face-width-mm", "20",
                            "--teeth", "10"])
    assert r.exit_code == 0 and "warning: --teeth 10 with --module-mm 2 gives d = z m = 20 mm" in r.stderr
