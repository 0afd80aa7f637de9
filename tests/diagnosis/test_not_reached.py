"""A significant candidate the selection never took (it stopped at another one, or at --max-effects)
is reported as ``not_reached`` and named in the verdict -- never as ``not_significant``."""

from __future__ import annotations

import json

from tests.support.paths import CONFIGS, MCH50, ROOT
from wormgear_cli.cli import app

WARM = CONFIGS / "mch50-warm.csv"
#: the warm-up recording as a spreadsheet saves it (field case); against MCH50 the selection stops at
#: an unphysical bearing_clearance before it reaches the (significant) thermal_backlash
SPREADSHEET = ROOT / "tests" / "data" / "field" / "spreadsheet-export.plain.csv"


def _run(runner, *args):
    r = runner.invoke(app, ["diagnose", str(MCH50), *map(str, args), "--format", "json"])
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


def _candidates(doc):
    return {c["name"]: c for c in doc["candidates"]}


def test_a_candidate_behind_an_unphysical_stop_is_not_reached_and_in_the_verdict(runner):
    doc = _run(runner, SPREADSHEET)
    c = _candidates(doc)
    assert c["bearing_clearance"]["status"] == "unphysical"
    tb = c["thermal_backlash"]
    assert tb["status"] == "not_reached"
    assert tb["p_adjusted"] < 0.01  # significant at the default level
    assert tb["reason"] == (f"significant (adjusted p = {tb['p_adjusted']:.2g}) but not taken: the selection "
                            "stopped at bearing_clearance (unphysical)")
    assert (f"significant but not taken (the selection stopped at bearing_clearance): thermal_backlash "
            f"(adjusted p = {tb['p_adjusted']:.2g})") in doc["verdict"]
    assert all(x["status"] != "not_significant" or x.get("p_adjusted", 1.0) >= 0.01 for x in doc["candidates"])


def test_max_effects_zero_names_nothing_and_lists_what_it_did_not_take(runner):
    doc = _run(runner, WARM, "--max-effects", "0")
    assert doc["effects_found"] == []
    assert doc["verdict"].startswith("no effect named (--max-effects reached); significant but not taken "
                                     "(--max-effects reached): thermal_backlash")
    tb = _candidates(doc)["thermal_backlash"]
    assert tb["status"] == "not_reached" and "--max-effects was reached" in tb["reason"]
    assert tb["remedy"] == "rerun with a larger --max-effects"
    assert "short of the level" not in doc["verdict"]


def test_rows_with_every_cell_empty_are_said_in_both_verdict_lines(runner, tmp_path):
    # the reader's note reaches the verdict of diagnose (text and JSON) and of measure, not only a note
    lines = WARM.read_text().splitlines()
    path = tmp_path / "blank.csv"
    path.write_text("\n".join(lines[:201] + [",,,,,", ",,,,,"] + lines[201:]) + "\n")
    doc = _run(runner, path)
    assert "; 2 rows with every cell empty left out" in doc["verdict"]
    r = runner.invoke(app, ["measure", str(path), "--format", "json"])
    assert r.exit_code == 0, r.output
    assert "2 rows with every cell empty left out" in json.loads(r.stdout)["verdict"]
