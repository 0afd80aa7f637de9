"""The belt stage by hand: its sources, its TE and lost motion, its stretch and compliance.

A 1:1 belt (30 -> 30 teeth, pitch 2 mm, R = r = 30 x 2 / (2 pi)) before a worm of ratio 40 (one
start, 40 teeth): the belt's output shaft turns A = 40 times per output turn."""

from __future__ import annotations

import math

import pytest

from tests.drive.test_train import WORM
from wormgear_cli.analysis.accuracy import analyze
from wormgear_cli.analysis.simulate import periodic_sources
from wormgear_cli.drive import belt as belt_model
from wormgear_cli.drive.registry import build
from wormgear_cli.spec.loader import loads_spec

BELT = """
[[stage]]
kind = "belt"
pitch_mm = 2.0
belt_teeth = 100
backlash_mm = 0.03
pitch_error_mm = 0.04
pitch_error_phase_deg = 30.0
tooth_mesh_error_mm = 0.006
tensile_stiffness_N = 10000.0
effective_tension_N = 50.0
[stage.driver]
teeth = 30
eccentricity_mm = 0.012
eccentricity_phase_deg = 10.0
[stage.driven]
teeth = 30
eccentricity_mm = 0.005
"""
DRIVE = BELT + WORM.replace("teeth = 30\n", "teeth = 40\n")
R = 30 * 2.0 / (2 * math.pi)
A = 40.0
L = math.sqrt((100 * 2.0 - math.pi * 2 * R) ** 2 / 4.0)  # equal pulleys: C = (L_b - pi D) / 2, span = C


def test_belt_sources_at_the_output():
    reg = build(loads_spec(DRIVE))
    src = {s.name: s for s in reg.sources if s.stage_kind == "belt"}
    expected = {  # name: (kind, part, order, amplitude, phase key, phase [deg])
        "driver_pulley_eccentricity": ("shaft", "driver", A, 0.012 / R / A, "driver.eccentricity_phase_deg", 10.0),
        "driven_pulley_eccentricity": ("shaft", "driven", A, 0.005 / R / A, "driven.eccentricity_phase_deg", 0.0),
        "belt_pitch_error": ("belt", "belt", 30 * A / 100, 0.02 / R / A, "pitch_error_phase_deg", 30.0),
        "belt_tooth_mesh": ("mesh", "belt", 30 * A, 0.003 / R / A, "tooth_mesh_phase_deg", 0.0),
    }
    assert set(src) == set(expected)
    for name, (kind, part, order, amp, key, phase) in expected.items():
        s = src[name]
        assert (s.kind, s.part, s.stage, s.stage_index) == (kind, part, "belt", 1), name
        assert s.order == pytest.approx(order, rel=1e-15) and s.amplitude == pytest.approx(amp, rel=1e-12), name
        assert s.phase_path == f"stage.1.{key}" and s.phase == pytest.approx(math.radians(phase)), name
        assert s.curve(math.pi / (2 * order), -0.0) == pytest.approx(amp, rel=1e-12), name  # a sine of that order
        assert s.origin == "spec" and s.lost_motion is None, name
        key_of_size = {"driver_pulley_eccentricity": "driver.eccentricity_mm",
                       "driven_pulley_eccentricity": "driven.eccentricity_mm", "belt_pitch_error": "pitch_error_mm",
                       "belt_tooth_mesh": "tooth_mesh_error_mm"}[name]
        assert s.size_keys == (key_of_size,) and s.size_paths == (f"stage.1.{key_of_size}",), name
        assert s.size(lambda k, key=key_of_size: 2.0 if k == key else math.nan) == pytest.approx(
            2.0 * amp / {"driver_pulley_eccentricity": 0.012, "driven_pulley_eccentricity": 0.005,
                         "belt_pitch_error": 0.04, "belt_tooth_mesh": 0.006}[name], rel=1e-12), name
        assert s.tier == (2 if kind == "mesh" else 1), name
    stretch = 50.0 * L / (2 * 10000.0)
    (static,) = [x for x in reg.statics if x.stage_kind == "belt"]
    assert (static.name, static.origin, static.stage, static.stage_index) == ("belt_stretch", "spec", "belt", 1)
    assert static.size_paths == ("stage.1.effective_tension_N", "stage.1.tensile_stiffness_N")
    assert static.amplitude == pytest.approx(stretch / R / A, rel=1e-12)
    (clear,) = [c for c in reg.clearances if c.stage_kind == "belt"]
    assert (clear.name, clear.stage, clear.stage_index) == ("belt_backlash", "belt", 1)
    assert clear.amount == pytest.approx(0.03 / R / A, rel=1e-12)


def test_belt_stage_at_its_own_shaft():
    """TE = stretch + sum over orders of the root-sum-square at one order (the 1:1 belt's two pulleys
    share an order); backlash = clearance + 2 stretch."""
    spec = loads_spec(DRIVE)
    a = analyze(spec)
    r = a.stages[0]
    stretch = 50.0 * L / (2 * 10000.0) / R
    periodic = math.hypot(0.012, 0.005) / R + 0.02 / R + 0.003 / R
    assert (r.index, r.kind, r.name, r.ratio, r.after) == (1, "belt", "belt", 1.0, A)
    assert r.te_parts == pytest.approx({"stretch": stretch, "periodic": periodic}, rel=1e-12)
    assert r.transmission_error == pytest.approx(stretch + periodic, rel=1e-12)
    assert r.backlash_parts == pytest.approx({"clearance": 0.03 / R, "stretch": 2 * stretch}, rel=1e-12)
    assert r.backlash == pytest.approx(0.03 / R + 2 * stretch, rel=1e-12)
    assert r.info == pytest.approx({"effective_tension_N": 50.0, "stretch_um": stretch * R * 1e3,
                                    "span_length_mm": L, "centre_distance_mm": L}, rel=1e-12)
    assert r.symbols == ("", "")
    assert belt_model.stretch(spec.stages[0]._replace(tensile_stiffness=None), 50.0) == 0.0


def test_belt_compliance_and_process_lag():
    spec = loads_spec(DRIVE)
    lag, per_nm = belt_model.compliance(spec, spec.stages[0], build(spec).train)
    assert lag == pytest.approx(50.0 * L / (2 * 10000.0) / R / A, rel=1e-12)
    assert per_nm == pytest.approx(1000.0 / (2 * 10000.0 * R * R / L) / A**2, rel=1e-12)


def test_a_belt_source_without_size_is_left_out_of_simulate():
    spec = loads_spec(DRIVE.replace("tooth_mesh_error_mm = 0.006\n", "").replace(
        "eccentricity_mm = 0.005\n", ""))
    names = [s.name for s in periodic_sources(spec)]
    assert "belt_tooth_mesh" not in names and "driven_pulley_eccentricity" not in names
    assert "driver_pulley_eccentricity" in names and "belt_pitch_error" in names
    assert "belt_tooth_mesh" in [s.name for s in periodic_sources(spec, all_budget_sources=True)]


@pytest.mark.parametrize("drop, origin", [("effective_tension_N = 50.0\n", "spec"),
                                          ("tensile_stiffness_N = 10000.0\n", "spec"),
                                          ("effective_tension_N = 50.0\ntensile_stiffness_N = 10000.0\n", "default")])
def test_the_stretch_line_says_where_its_size_comes_from(drop, origin):
    """Either key written (the tension or the belt's stiffness) makes the stretch a spec value."""
    text = DRIVE.replace("tensile_stiffness_N = 10000.0\neffective_tension_N = 50.0\n",
                         "effective_tension_N = 50.0\ntensile_stiffness_N = 10000.0\n").replace(drop, "")
    (static,) = [x for x in build(loads_spec(text)).statics if x.stage_kind == "belt"]
    assert static.origin == origin
