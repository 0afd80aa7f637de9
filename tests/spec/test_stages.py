"""The stage form of a drive file: [[stage]] tables, their messages, defaults, loads and paths."""

from __future__ import annotations

import math

import pytest

from tests.drive.test_train import SPUR, WORM
from tests.support.paths import CONFIGS, MCH50
from wormgear_cli.errors import SpecError
from wormgear_cli.spec.loader import load_spec, loads_spec, value_origin, with_values


def problems(text: str) -> list[str]:
    with pytest.raises(SpecError) as exc:
        loads_spec(text, "d.toml")
    return list(exc.value.problems)


def test_a_mistake_names_the_stage_by_position_and_kind():
    text = WORM + SPUR.replace("module_mm = 2.5", "module_mm = -2.5")
    assert problems(text) == ["d.toml: stage 2 (spur): module_mm: expected a number in [0.05, 100] [mm], got -2.5"]


def test_unknown_keys_name_the_nearest_valid_key():
    got = problems(WORM.replace("lead_error_mm", "lead_eror_mm") + SPUR.replace("[stage.gear]", "[stage.gears]"))
    assert got == ["d.toml: stage 1 (worm): lead_eror_mm: unknown key (did you mean lead_error_mm?)",
                   "d.toml: stage 2 (spur): gears: unknown table (did you mean gear?)",
                   "d.toml: stage 2 (spur): gear.teeth: missing required key, expected an integer in [1, 10000] "
                   "(in a [stage.gear] table)"]


def test_a_key_of_another_kind_says_so():
    got = problems(SPUR.replace("module_mm = 2.5", "module_mm = 2.5\nlead_angle_deg = 3.0"))
    assert got == ['d.toml: stage 1 (spur): lead_angle_deg: unknown key (a key of worm stages; this stage has '
                   'kind = "spur")']


def test_kind_is_required_and_checked():
    assert problems("[[stage]]\nmodule_mm = 2\n") == [
        'd.toml: stage 1: kind: missing required key, expected one of "worm", "spur", "belt"']
    assert problems('[[stage]]\nkind = "chain"\n') == [
        'd.toml: stage 1: kind: expected one of "worm", "spur", "belt", got "chain"']


def test_legacy_tables_cannot_join_the_stage_form():
    got = problems(WORM + "[loads]\ngear_normal_force_N = 1.0\n")
    assert len(got) == 1 and got[0].startswith("d.toml: loads: unknown table (a table of the legacy two-table form")
    got = problems(WORM + "[requirements]\nmax_gear_backlash_arcsec = 10.0\n")
    assert got == ["d.toml: requirements.max_gear_backlash_arcsec: unknown key (in the stage form: "
                   "max_backlash_arcsec of the spur stage's [[stage]] table)"]


def test_stage_names_default_by_kind_and_must_differ():
    spec = loads_spec(WORM + SPUR)
    assert [s.name for s in spec.stages] == ["worm", "gear"]
    got = problems(WORM.replace('kind = "worm"', 'kind = "worm"\nname = "x"') +
                   SPUR.replace('kind = "spur"', 'kind = "spur"\nname = "x"'))
    assert got == ['d.toml: stage 2 (spur): name: "x" is also the name of stage 1 (worm); give each stage its own name']


def test_a_residual_needs_an_anti_backlash_arrangement():
    got = problems(WORM.replace("normal_force_N = 85.0", "normal_force_N = 85.0\nresidual_lost_motion_arcsec = 5"))
    assert got == ['d.toml: stage 1 (worm): residual_lost_motion_arcsec: only with an anti-backlash arrangement; set '
                   'anti_backlash = "duplex" or remove the key']


def test_a_belt_too_short_for_its_pulleys():
    text = """[[stage]]
kind = "belt"
pitch_mm = 2.0
belt_teeth = 30
[stage.driver]
teeth = 20
[stage.driven]
teeth = 60
""" + WORM
    assert problems(text) == ["d.toml: stage 1 (belt): belt_teeth: a belt of 30 x 2 mm is too short for pulleys of "
                              "20 and 60 teeth; give a longer belt"]


def test_loads_follow_the_output_torque_through_the_ratios():
    """EQ6 class, T = 2 N m on the RA axis: the worm mesh carries F_N = T / (r_w cos(alpha_n) cos(lambda)),
    r_w = 0.6 x 180 / 2 mm; the belt's driven pulley (on the worm shaft, 180 turns per RA turn) the
    tension (T / 180) / R, R = 47 x 2 / (2 pi) mm."""
    spec = load_spec(CONFIGS / "eq6-belt-worm.toml")
    belt, worm = spec.stages
    assert worm.normal_force == pytest.approx(2000.0 / (54.0 * math.cos(math.radians(20)) *
                                                        math.cos(math.radians(2.15))), rel=1e-12)
    assert belt.effective_tension == pytest.approx(2000.0 / 180 / (47 * 2.0 / (2 * math.pi)), rel=1e-12)
    assert worm.origins["normal_force_N"] == "spec"  # derived from the written torque


def test_stage_paths_reach_any_stage_in_either_form():
    spec = load_spec(CONFIGS / "eq6-belt-worm.toml")
    changed = with_values(spec, {"stage.2.wheel.teeth": 144, "stage.1.driver.teeth": 16})
    assert changed.stages[1].wheel.teeth == 144 and changed.stages[0].driver.teeth == 16
    legacy = load_spec(MCH50)
    a = with_values(legacy, {"stage.2.gear.teeth": 150})
    b = with_values(legacy, {"gear_pair.output_gear.teeth": 150})
    assert a.gear_pair.output_gear.teeth == b.stages[1].gear.teeth == 150
    staged = loads_spec(WORM + SPUR)
    assert with_values(staged, {"gear_pair.output_gear.teeth": 150}).stages[1].gear.teeth == 150
    assert value_origin(staged, "gear_pair.pinion.teeth") == value_origin(staged, "stage.2.pinion.teeth") == "spec"
    assert value_origin(staged, "stage.2.eccentricity_mm") == "default"


def test_legacy_names_still_read_a_worm_spur_drive_of_the_stage_form():
    old, new = load_spec(MCH50), loads_spec(WORM + SPUR)
    assert new.gear_pair == old.gear_pair and new.worm_pair == old.worm_pair and new.assembly == old.assembly
    assert loads_spec(WORM).gear_pair is None
    assert old.stages[0].wheel.runout == old.assembly.wheel_eccentricity == 0.016
