"""Issue 19, item 4 (issue 23, item 11): every length, angle and tolerance against the drive's own scale.

An implausible value is one warning line naming the key, the value, the scale it was held against
and the likely slip; an impossible one is an error at load (exit 2)."""

from __future__ import annotations

import re

import pytest

from tests.support.paths import CONFIGS, MCH50
from wormgear_cli.cli import app
from wormgear_cli.errors import SpecError
from wormgear_cli.physics.iso1328 import coarse_scale, flank_tolerances
from wormgear_cli.spec.loader import load_spec, loads_spec
from wormgear_cli.spec.plausibility import RULES
from wormgear_cli.spec.stages import STAGE_FIELDS


def _mch50(old: str, new: str) -> str:
    text = MCH50.read_text(encoding="utf-8")
    assert old in text
    return text.replace(old, new, 1)


def test_a_micrometre_value_typed_into_a_millimetre_key_is_one_warning_line(runner, tmp_path):
    """The issue's slip: lead_error_mm = 3 (meant 3 um).  Grade 12 at the wheel's size (m = 2.5, d = 75)
    allows F_pT = (0.15 + 0.55 sqrt 75 + 1.75 + 12) sqrt(2)^7 = 211 um; 3 mm is 14.2 times that."""
    path = tmp_path / "slip.toml"
    path.write_text(_mch50("lead_error_mm = 0.030 ", "lead_error_mm = 3 "), encoding="utf-8")
    r = runner.invoke(app, ["analyze", str(path), "-f", "json"])
    assert r.exit_code == 0
    assert r.stderr == (f"warning: {path}: worm_pair.lead_error_mm = 3 mm is 14.2 times the cumulative pitch "
                        "deviation of ISO 1328 grade 12 at this size (0.211 mm): micrometres typed as millimetres? "
                        "(3 um is 0.003 mm)\n")
    r = runner.invoke(app, ["check", str(path)])
    assert r.stderr.count("warning: ") == 1 and "worm_pair.lead_error_mm = 3 mm" in r.stderr


def test_the_scale_is_iso_1328_one_class_beyond_its_coarsest():
    """Class 12 is class 11 times sqrt(2) (5.2.2), unrounded; class 11's rounded F_pT agrees to rounding."""
    eleven = flank_tolerances(11, 2.5, 360.0, 50.0)
    assert coarse_scale(2.5, 360.0)["F_pT"] == pytest.approx(eleven.F_pT * 2 ** 0.5, rel=0.01)
    assert coarse_scale(2.5, 75.0)["F_pT"] == pytest.approx(211.1, abs=0.1)


@pytest.mark.parametrize("name", sorted(p.name for p in CONFIGS.glob("*.toml")))
def test_the_shipped_drives_are_plausible(name):
    assert load_spec(CONFIGS / name).warnings == ()


def test_the_issues_impossible_drive_is_refused(tmp_path):
    """Module 0.05 mm, a 5 mm centre-distance error (the teeth are 0.1 mm deep) and one-tooth gears: its
    backlash would be 82 turns.  Refused at load, one line per impossible value."""
    text = _mch50("module_mm = 2.5                 # Table 1\n", "module_mm = 0.05\n")
    text = re.sub(r"^teeth = (144|18) ", "teeth = 1 ", text, flags=re.M)
    text = text.replace("gear_centre_distance_error_mm = 0.030", "gear_centre_distance_error_mm = 5.0")
    with pytest.raises(SpecError) as err:
        loads_spec(text, "x.toml")
    problems = err.value.problems
    assert len(problems) == 3
    assert problems[0].startswith("x.toml: assembly.gear_centre_distance_error_mm = 5 mm: more than the teeth's "
                                  "working depth 2 m (0.1 mm)")
    assert all("teeth = 1: a gear of 1 tooth cannot mesh" in p for p in problems[1:])


@pytest.mark.parametrize("old, new, key", [
    ("thickness_deviation_mm = 0.090", "thickness_deviation_mm = 5.0", "worm_pair.wheel.thickness_deviation_mm"),
    ("radial_composite_error_mm = 0.036", "radial_composite_error_mm = 6.0",
     "worm_pair.wheel.radial_composite_error_mm"),
    ("worm_eccentricity_mm = 0.012", "worm_eccentricity_mm = 5.5", "assembly.worm_eccentricity_mm"),
])
def test_a_value_deeper_than_the_teeth_or_thicker_than_the_tooth_is_impossible(old, new, key):
    with pytest.raises(SpecError) as err:
        loads_spec(_mch50(old, new), "x.toml")
    [problem] = err.value.problems
    assert problem.startswith(f"x.toml: {key} = ") and "which no built drive can have" in problem


@pytest.mark.parametrize("old, new, words", [
    ("lead_angle_deg = 3.178 ", "lead_angle_deg = 0.2 ", "the worm's diameter quotient q = d1 / m = 286"),
    ("face_width_mm = 50.0", "face_width_mm = 500.0", "the face width over the module b / m = 200"),
    ("teeth = 18 ", "teeth = 6 ", "gear_pair.pinion.teeth = 6: fewer than 9 teeth"),
])
def test_proportions_outside_what_is_made_warn(old, new, words):
    spec = loads_spec(_mch50(old, new), "x.toml")
    [line] = spec.warnings
    assert words in line


def test_every_length_tolerance_of_every_kind_is_held_against_a_scale():
    """Ranges as data: every tolerance-like key (mm, not a size of the part itself) has its rule."""
    sizes = {"module_mm", "face_width_mm", "pitch_mm", "centre_distance_mm", "worm.thrust_bearing_distance_mm"}
    ruled = {(kind, r.key) for r in RULES for kind in r.kinds}
    for kind, fields in STAGE_FIELDS.items():
        for f in fields:
            if f.unit == "mm" and f.path not in sizes:
                assert (kind, f.path) in ruled, (kind, f.path)
