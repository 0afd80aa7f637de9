"""Drives of other trains through the commands: a belt + worm mount, a worm-only table, templates of
every suggested train, and the two-start radar's worm mesh."""

from __future__ import annotations

import json

import pytest

from tests.support.paths import CONFIGS
from wormgear_cli.cli import app
from wormgear_cli.spec.template import SUGGESTED

EQ6 = CONFIGS / "eq6-belt-worm.toml"
RADAR = CONFIGS / "radar-pedestal-2start.toml"


def run(runner, *args, code=0):
    r = runner.invoke(app, [str(a) for a in args])
    assert r.exit_code == code, r.stderr
    return r


def test_belt_and_worm_through_analyze_check_simulate_and_synth(runner, tmp_path):
    doc = json.loads(run(runner, "analyze", EQ6, "-f", "json").stdout)
    assert [(s["kind"], s["ratio"], s["ratio_after"]) for s in doc["stages"]] == [
        ("belt", pytest.approx(47 / 12), 180.0), ("worm", 180.0, 1.0)]
    assert doc["ratios"]["total"] == pytest.approx(705.0)
    belt, worm = doc["stages"]
    assert doc["total"]["transmission_error"] == pytest.approx(
        worm["transmission_error"] + belt["transmission_error"] / 180.0, rel=1e-12)
    assert "ok" in run(runner, "check", EQ6).stdout
    sim = json.loads(run(runner, "simulate", EQ6, "--points", "4000", "-f", "json").stdout)
    assert sim["sources"]["belt_pitch_error"]["order"] == pytest.approx(47 * 180 / 80)
    assert sim["sources"]["belt_pitch_error"]["phase_key"] == "stage.1.pitch_error_phase_deg"
    run(runner, "synth", EQ6, "-o", tmp_path / "m.csv", "--truth", tmp_path / "t.json", "--seed", "3")
    truth = json.loads((tmp_path / "t.json").read_text())
    assert truth["phases"]["driver_pulley_eccentricity"]["order"] == pytest.approx(705.0)
    csv = json.loads(run(runner, "measure", tmp_path / "m.csv", "--drive", EQ6, "-f", "json").stdout)
    assert csv["schema_version"] == 2


@pytest.mark.parametrize("stages", SUGGESTED)
def test_every_suggested_template_runs(runner, tmp_path, stages):
    path = tmp_path / "d.toml"
    run(runner, "new", path, "--stages", stages)
    run(runner, "check", path)
    run(runner, "simulate", path, "--points", "200", "-o", tmp_path / "c.csv")
    run(runner, "synth", path, "-o", tmp_path / "m.csv", "--seed", "1")
    doc = json.loads(run(runner, "analyze", path, "-f", "json").stdout)
    assert [s["kind"] for s in doc["stages"]] == stages.split(",")


def test_new_refuses_an_unknown_kind(runner, tmp_path):
    r = run(runner, "new", tmp_path / "d.toml", "--stages", "belt,chain", code=2)
    assert r.stderr.startswith("error: --stages: unknown stage kind 'chain'")
    assert not (tmp_path / "d.toml").exists()


def test_the_radar_worm_mesh_is_at_480_in_measure_and_diagnose(runner, tmp_path):
    """Two starts: the worm shaft turns 240 times per output turn (i_c 8 x 60 / 2), its mesh 480."""
    from wormgear_cli.analysis.accuracy import geometry
    from wormgear_cli.measurement.harmonics import physical_orders
    from wormgear_cli.spec.loader import load_spec

    labels = dict(physical_orders(geometry(load_spec(RADAR)), 3))  # what diagnose's call sites pass
    assert labels[240.0] == "worm shaft" and labels[480.0] == "worm mesh / 2nd harmonic of worm shaft"
    assert labels[960.0] == "2nd harmonic of worm mesh" and labels[1440.0] == "3rd harmonic of worm mesh"
    run(runner, "synth", RADAR, "--plan", "dense", "--points", "6000", "-o", tmp_path / "m.csv", "--seed", "1")
    doc = json.loads(run(runner, "measure", tmp_path / "m.csv", "--drive", RADAR, "-f", "json").stdout)
    measured = {o["order"]: o["label"] for o in doc["orders"]["items"]}
    assert measured[480.0] == labels[480.0] and measured[240.0] == "worm shaft"


def test_a_ratio_sweep_of_a_drive_without_a_spur_stage_says_so(runner):
    r = run(runner, "sweep", EQ6, "--i", "2:12:3", "--l-mm", "100:300:3", code=2)
    assert r.stderr == (f"error: --i/--l-mm: the ratio and centre-distance sweep varies a spur stage; {EQ6} has "
                        "none (stages: 1 belt, 2 worm); sweep another key with --param KEY=START:STOP:N, e.g. "
                        "stage.2.module_mm=...\n")
