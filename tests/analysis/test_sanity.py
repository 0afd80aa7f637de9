"""Issue 23, item 11 (this issue's part): no NaN, no overflow, no absurd number without a word.

Legal inputs at the edges of their ranges (the issue's: a 0.05 mm module, one-tooth gears, a
10 mm centre-distance error) take the small-angle models to tens of thousands of degrees of
backlash.  Such inputs are now refused at load (issue 19: spec.plausibility); behind that, the guard
stops a nominal result beyond a full turn or not finite (exit 2, one line) and names an
ensemble's in one warning line."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from tests.support.paths import MCH50
from wormgear_cli.analysis.sanity import FULL_TURN, check_angles
from wormgear_cli.cli import app
from wormgear_cli.errors import SpecError


@pytest.fixture
def absurd(tmp_path):
    """The issue's drive: module 0.05 mm, one-tooth gears, a 10 mm centre-distance error."""
    text = MCH50.read_text().replace("module_mm = 2.5                 # Table 1\n", "module_mm = 0.05\n", 1)
    text = re.sub(r"^teeth = (144|18) ", "teeth = 1 ", text, flags=re.M)
    text = text.replace("gear_centre_distance_error_mm = 0.030", "gear_centre_distance_error_mm = 10.0")
    path = tmp_path / "absurd.toml"
    path.write_text(text)
    return path


def test_the_issues_drive_is_refused_at_load_one_line_per_impossible_value(runner, absurd):
    """Issue 19 item 4: a 10 mm centre-distance error on a 0.05 mm module and one-tooth gears cannot be
    built: exit 2 before any analysis, each impossible value in one line (spec.plausibility)."""
    r = runner.invoke(app, ["analyze", str(absurd), "-f", "json"])
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr.splitlines() == [
        f"error: {absurd}: assembly.gear_centre_distance_error_mm = 10 mm: more than the teeth's working depth "
        "2 m (0.1 mm), which no built drive can have; micrometres typed as millimetres? (10 um is 0.01 mm)",
        f"error: {absurd}: gear_pair.pinion.teeth = 1: a gear of 1 tooth cannot mesh continuously (its teeth "
        "would be pointed and undercut away); check the tooth counts",
        f"error: {absurd}: gear_pair.output_gear.teeth = 1: a gear of 1 tooth cannot mesh continuously (its "
        "teeth would be pointed and undercut away); check the tooth counts"]


@pytest.mark.parametrize("args", [["simulate", "--points", "100"], ["check"], ["synth", "--seed", "1"]])
def test_other_commands_refuse_it_too(runner, absurd, args):
    r = runner.invoke(app, [args[0], str(absurd), *args[1:]])
    assert r.exit_code == 2
    assert sum("teeth = 1: a gear of 1 tooth cannot mesh" in ln for ln in r.stderr.splitlines()) == 2


def test_a_nominal_result_beyond_a_full_turn_is_an_error_an_ensembles_a_warning(runner, monkeypatch):
    """The guard behind the plausibility checks: analyze's own figures beyond a full turn stop the run
    (exit 2, one line); in an ensemble (check_angles without strict) it is one warning line."""
    from wormgear_cli.analysis import accuracy

    real = accuracy.analyze

    def beyond(spec):
        result = real(spec)
        result.angles["total_backlash"] = 3 * FULL_TURN
        return result

    monkeypatch.setattr(accuracy, "analyze", beyond)
    r = runner.invoke(app, ["analyze", str(MCH50), "-f", "json"])
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr == (f"error: {MCH50}: total_backlash 1080 deg: more than a full turn, which no drive can have: "
                        "the inputs lie far outside what the model describes; check modules, teeth, centre distances "
                        "and loads\n")
    assert check_angles({"total_backlash": 3 * FULL_TURN}).startswith("total_backlash 1080 deg: more than a full turn")


def test_the_shipped_drive_has_nothing_to_say(runner):
    r = runner.invoke(app, ["analyze", str(MCH50), "-f", "json"])
    assert r.exit_code == 0 and r.stderr == ""


def test_a_value_that_is_not_finite_is_one_error_line(runner, monkeypatch):
    """A result that overflowed (inf) or is NaN never leaves as a number or a JSON null."""
    from wormgear_cli.analysis import accuracy

    real = accuracy.analyze

    def overflowing(spec):
        result = real(spec)
        result.angles["total_backlash"] = math.inf
        return result

    monkeypatch.setattr(accuracy, "analyze", overflowing)
    r = runner.invoke(app, ["analyze", str(MCH50), "-f", "json"])
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr == (f"error: {MCH50}: the model gives no finite total_backlash for these inputs: they lie "
                        "outside what it describes; check modules, teeth, centre distances and loads\n")


def test_check_angles_counts_bad_values_and_ranks_the_largest():
    with pytest.raises(SpecError, match=r"no finite curve \(2 of 4 values\)"):
        check_angles({"curve": np.array([0.0, np.nan, np.inf, 1.0])})
    assert check_angles({"a": FULL_TURN, "b": -FULL_TURN}) is None  # a full turn itself: still a value
    line = check_angles({"a": 2 * FULL_TURN, "b": -3 * FULL_TURN, "c": 0.1})
    assert line.startswith("b 1080 deg, a 720 deg: more than a full turn")
    assert check_angles({"none": np.array([])}) is None


def test_check_angles_message_edges():
    """The edges of the message: three names shown, the rest counted; a quantity after an empty
    one still checked; a pair with one bad value counted; a missing value (None) is not finite."""
    five = {name: (k + 2) * FULL_TURN for k, name in enumerate("abcde")}
    assert check_angles(five).startswith("e 2160 deg, d 1800 deg, c 1440 deg and 2 more: ")
    four = {name: (k + 2) * FULL_TURN for k, name in enumerate("abcd")}
    assert check_angles(four).startswith("d 1800 deg, c 1440 deg, b 1080 deg and 1 more: ")
    three = {name: (k + 2) * FULL_TURN for k, name in enumerate("abc")}
    assert check_angles(three).startswith("c 1440 deg, b 1080 deg, a 720 deg: ")
    assert check_angles({"empty": [], "big": [2 * FULL_TURN]}).startswith("big 720 deg: ")
    with pytest.raises(SpecError, match=r"no finite pair \(1 of 2 values\) for"):
        check_angles({"pair": [1.0, np.nan]})
    with pytest.raises(SpecError, match=r"no finite one for"):
        check_angles({"one": [np.nan]})
    with pytest.raises(SpecError, match="no finite missing"):
        check_angles({"missing": [1.0, None]})


@pytest.fixture(params=["gear", "both"])
def overloaded(request, tmp_path):
    """The breaker's drives: a 0.1 mm face width under 10^8 N, and both normal forces at 10^8 N.  Each key
    is in its range; the nominal lost motion is tens of thousands of degrees."""
    text = MCH50.read_text()
    text = text.replace("gear_normal_force_N = 666.0", "gear_normal_force_N = 1e8")
    if request.param == "gear":
        text = text.replace("face_width_mm = 50.0", "face_width_mm = 0.1", 1)
    else:
        text = text.replace("worm_normal_force_N = 85.0", "worm_normal_force_N = 1e8")
    path = tmp_path / "overloaded.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("args", [
    ["analyze"], ["check"], ["simulate", "--points", "100"], ["synth", "--seed", "1"],
    ["tolerance", "--samples", "200", "-u", "deg"], ["tolerance", "--samples", "200", "--metrics", "budget"],
    ["sweep", "--param", "worm_pair.lead_error_mm=0:0.05:3", "-f", "csv"], ["sweep", "--i", "2:10:3", "-f", "csv"],
    ["compare", str(MCH50)], ["diagnose", str(MCH50.parent / "mch50-warm.csv")],
])
def test_every_command_evaluating_a_drive_refuses_what_analyze_refuses(runner, overloaded, args):
    """One check (analysis.sanity.check_drive): tolerance and simulate had printed a backlash of 44 223 deg
    for the drive analyze and check refuse."""
    reference = runner.invoke(app, ["analyze", str(overloaded)])
    error = reference.stderr.splitlines()[-1]
    assert reference.exit_code == 2 and "more than a full turn, which no drive can have" in error
    if overloaded.read_text().count("face_width_mm = 0.1\n"):  # the breaker's figures
        assert error == (f"error: {overloaded}: total_backlash 4.422e+04 deg, gear_backlash 4.422e+04 deg, "
                         "gear_backlash_deformation 4.422e+04 deg and 3 more: more than a full turn, which no drive "
                         "can have: the inputs lie far outside what the model describes; check modules, teeth, "
                         "centre distances and loads")
    r = runner.invoke(app, [args[0], str(overloaded), *args[1:]])
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr.splitlines()[-1] == error


def test_the_api_refuses_it_with_the_same_words(overloaded):
    import wormgear_cli.api as wg

    messages = set()
    for call in (wg.analyze, wg.simulate, lambda s: wg.tolerance(s, samples=200), lambda s: wg.sweep(s, i="2:10:3")):
        with pytest.raises(SpecError) as e:
            call(overloaded)
        messages.add(str(e.value))
    assert len(messages) == 1 and "more than a full turn, which no drive can have" in messages.pop()
