"""Issue 23, item 11 (this issue's part): no NaN, no overflow, no absurd number without a word.

Legal inputs at the edges of their ranges (the issue's: a 0.05 mm module, one-tooth gears, a
10 mm centre-distance error) take the small-angle models to tens of thousands of degrees of
backlash.  The guard names such results in one warning line; a value that is not finite
stops the run (exit 2, one line).  Which inputs are implausible is the plausibility checks'
business (another issue)."""

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


def test_the_issues_drive_says_its_backlash_is_beyond_a_full_turn(runner, absurd):
    r = runner.invoke(app, ["analyze", str(absurd), "-f", "json"])
    assert r.exit_code == 0
    (line,) = r.stderr.splitlines()
    assert line.startswith(f"warning: {absurd}: total_backlash 1.674e+04 deg, ")
    assert line.endswith("more than a full turn, so the inputs lie far outside what the model describes; check "
                         "modules, teeth, centre distances and loads")
    assert '"backlash": 60265626.' in r.stdout  # the numbers themselves are still reported (1.674e4 deg)


@pytest.mark.parametrize("args", [["simulate", "--points", "100"], ["check"], ["synth", "--seed", "1"]])
def test_other_commands_say_it_too(runner, absurd, args):
    """A variant: the curve of simulate and synth, and check's verdict, carry the same word."""
    r = runner.invoke(app, [args[0], str(absurd), *args[1:]])
    assert r.exit_code in (0, 1), r.stderr
    warnings = [ln for ln in r.stderr.splitlines() if ln.startswith("warning: ")]
    assert len(warnings) == 1 and "more than a full turn" in warnings[0]


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
