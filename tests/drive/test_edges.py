"""Issue 19, items 3 and 5: the worm's lost motion constant where its causes are, and the physics beyond
the paper (the worm's axial behaviour, shaft and bearing compliance, friction wind-up, temperature
differences), each checked against a hand calculation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.paths import CONFIGS
from wormgear_cli.analysis.accuracy import analyze
from wormgear_cli.analysis.budget import budget
from wormgear_cli.analysis.simulate import max_reversal, simulate
from wormgear_cli.drive.registry import build
from wormgear_cli.physics.effects import Signals
from wormgear_cli.spec.loader import load_spec, loads_spec

ARCSEC = math.pi / 648000.0
THETA = np.linspace(0.0, 2.0 * np.pi, 20000, endpoint=False)


def _worm_lost_motion(spec) -> np.ndarray:
    """The worm stage's lost motion over one output turn [arcsec at the output]: its clearance (the
    radial composite source's) plus twice its deflection lag."""
    reg = build(spec)
    src = next(s for s in reg.sources if s.name.endswith("wheel_radial_composite"))
    worm = reg.result("worm")
    deflection = worm.backlash_parts["deformation"] / worm.after
    return (src.lost_motion(THETA, src.phase) + deflection) / ARCSEC


def test_mch50s_worm_lost_motion_varies_by_at_most_one_and_a_half_over_a_turn():
    spec = load_spec(CONFIGS / "mch50.toml")
    lost = _worm_lost_motion(spec)
    assert lost.max() / lost.min() <= 1.5
    # its largest value is the paper's bound, Delta phi_wh / i_c (analyze's worm stage at the output)
    worm = analyze(spec).registry.result("worm")
    assert lost.max() == pytest.approx(worm.backlash / worm.after / ARCSEC, rel=1e-6)
    # the swing is the wheel's runout F_i: +/- F_i tan(alpha_2) / (r_w i_c) = 0.036 tan(20.03 deg) / 37.5 / 8
    swing = 0.036 * math.tan(math.radians(20.03)) / 37.5 / 8.0 / ARCSEC
    assert (lost.max() - lost.min()) / 2.0 == pytest.approx(swing, rel=2e-3)
    assert swing == pytest.approx(9.03, abs=0.01)


def test_without_a_wheel_runout_the_worm_lost_motion_is_constant():
    text = (CONFIGS / "mch50.toml").read_text().replace("radial_composite_error_mm = 0.036", "radial_composite_error_mm = 0.0")
    lost = _worm_lost_motion(loads_spec(text))
    assert np.ptp(lost) == pytest.approx(0.0, abs=1e-9)


WORM_SPUR = """
[drive]
name = "edges"
output_torque_Nm = 200.0
EXTRA_DRIVE
[[stage]]
kind = "worm"
module_mm = 2.5
normal_pressure_angle_deg = 20.0
lead_angle_deg = 3.178
face_width_mm = 37.5
EXTRA_WORM_STAGE
[stage.worm]
starts = 1
EXTRA_WORM
[stage.wheel]
teeth = 30
[[stage]]
kind = "spur"
module_mm = 2.5
pressure_angle_deg = 20.0
kinematics = "involute"
EXTRA_SPUR
[stage.pinion]
teeth = 18
[stage.gear]
teeth = 144
"""
R_W, I_C = 37.5, 8.0  # wheel pitch radius [mm], spur ratio 144 / 18


def drive(drive="", worm_stage="", worm="", spur=""):
    return loads_spec(WORM_SPUR.replace("EXTRA_DRIVE", drive).replace("EXTRA_WORM_STAGE", worm_stage)
                      .replace("EXTRA_WORM", worm).replace("EXTRA_SPUR", spur))


def _arcsec(spec, key):
    return analyze(spec).angles[key] / ARCSEC


def test_a_mesh_twenty_kelvin_above_the_housing_against_a_uniform_twenty_kelvin():
    """Hand: r_1 = 2.5 / (2 tan 3.178 deg) = 22.51 mm, r_2 = 37.5 mm, a = 60.01 mm; steel worm 11.5, bronze
    wheel 18.5, cast iron 10.5 ppm/K.  Mesh +20 K, housing 0: Delta a = -(22.51 x 11.5 + 37.5 x 18.5) 20e-6
    = -19.05 um, Delta j = 2 Delta a tan(20.03 deg) = -13.90 um, / 37.5 mm / 8 = -9.56 arcsec.  All +20 K:
    Delta a = (60.01 x 10.5 - 952.6) 20e-6 = -6.45 um: -3.24 arcsec."""
    thick = "thickness_deviation_mm = 0.090"  # a clearance to close (the MCH50's T_s1: 70 arcsec)
    base = _arcsec(drive(worm=thick), "total_backlash")
    mesh = drive(worm_stage="mesh_temperature_rise_K = 20.0", worm=thick)
    uniform = drive(worm_stage="mesh_temperature_rise_K = 20.0\nhousing_temperature_rise_K = 20.0", worm=thick)
    assert _arcsec(mesh, "total_backlash") - base == pytest.approx(-9.56, abs=0.01)
    assert _arcsec(uniform, "total_backlash") - base == pytest.approx(-3.24, abs=0.01)
    # simulate's reversal follows analyze (the clearance line of the registry)
    assert max_reversal(mesh) / ARCSEC == pytest.approx(_arcsec(mesh, "total_backlash"), rel=1e-6)
    # warmed shut: no negative clearance, the backlash stops at 0 (only the deflection's lag remains)
    shut = drive(worm_stage="mesh_temperature_rise_K = 20.0")
    assert _arcsec(shut, "worm_backlash") == 0.0


def test_the_worms_axial_growth_is_a_thermal_drift_line():
    """Hand: 100 mm of steel worm shaft warmed 10 K grows 100 x 11.5e-6 x 10 = 11.5 um, an arc of the wheel:
    11.5e-3 / 37.5 / 8 rad = 7.91 arcsec at the output; a budget line of kind thermal, in the totals."""
    spec = drive(worm_stage="worm_shaft_temperature_rise_K = 10.0", worm="thrust_bearing_distance_mm = 100.0")
    b = budget(spec)
    line = next(ln for ln in b.lines if ln.source == "worm_thermal_drift")
    assert (line.kind, line.order) == ("thermal", 0.0)
    assert line.amplitude / ARCSEC == pytest.approx(11.5e-3 / R_W / I_C / ARCSEC, rel=1e-9)
    assert line.amplitude / ARCSEC == pytest.approx(7.91, abs=0.01)
    without = budget(drive())
    assert b.linear - without.linear == pytest.approx(line.amplitude, rel=1e-9)
    # simulate shifts both directions alike by it (ranges, ISO's E, are unchanged)
    sig = Signals.make(THETA[:50], 1.0)
    assert (simulate(spec, sig) - simulate(drive(), sig)) / ARCSEC == pytest.approx(np.full(50, 7.91), abs=0.01)


def test_the_thrust_bearings_play_and_the_axial_runout_map_one_to_one_through_the_lead():
    """An axial shift x of the worm turns the wheel by the arc x: a play of 5 um is a lost motion
    5e-3 / 37.5 / 8 rad = 3.44 arcsec; an axial runout of 4 um (TIR) a sinusoid of 2 um, 1.375 arcsec,
    once per worm turn (order 30 x 8 = 240)."""
    spec = drive(worm="axial_play_mm = 0.005\naxial_runout_mm = 0.004")
    play = 0.005 / R_W / I_C / ARCSEC
    assert _arcsec(spec, "total_backlash") - _arcsec(drive(), "total_backlash") == pytest.approx(play, rel=1e-9)
    assert max_reversal(spec) / ARCSEC == pytest.approx(_arcsec(spec, "total_backlash"), rel=1e-6)
    line = next(ln for ln in budget(spec).lines if ln.source == "worm_axial_runout")
    assert (line.order, line.kind) == (240.0, "shaft")
    assert line.amplitude / ARCSEC == pytest.approx(0.002 / R_W / I_C / ARCSEC, rel=1e-9)
    assert not any(ln.source == "worm_axial_runout" for ln in budget(drive()).lines)  # listed when given


def test_compliance_of_the_thrust_bearing_and_the_shafts_and_the_friction_wind_up():
    """Per N m of output torque: the wheel's tangential force 1000 / (8 x 37.5) = 3.333 N is the worm's
    axial force, 3.333 N / 200 N/um = 0.01667 um, an arc of the wheel: 1.667e-5 / 37.5 / 8 rad; the wheel
    shaft of 50 N m/arcmin carries 1/8 N m: 1 / (50 x 8 x 8) arcmin; the gear shaft of 500 N m/arcmin
    1 / 500 arcmin.  A friction torque of 5 N m winds the train up both ways: 2 x 5 x C_out."""
    base = drive()
    spec = drive(drive="friction_torque_Nm = 5.0", worm_stage="shaft_stiffness_Nm_per_arcmin = 50.0",
                 worm="axial_stiffness_N_per_um = 200.0", spur="shaft_stiffness_Nm_per_arcmin = 500.0")
    arcmin = 60.0 * ARCSEC
    added = (1000.0 / (I_C * R_W) / 200_000.0 / R_W / I_C + arcmin / (50.0 * I_C * I_C) + arcmin / 500.0)
    got = build(spec).compliance.per_Nm - build(base).compliance.per_Nm
    assert got == pytest.approx(added, rel=1e-9)
    doc = analyze(spec).report("arcsec")
    windup = doc["total"]["backlash_additions"]["friction_windup"]
    assert windup == pytest.approx(2 * 5.0 * build(spec).compliance.per_Nm / ARCSEC, rel=1e-12)
    # analyze's total backlash holds every part, and simulate's reversal reaches it
    assert max_reversal(spec) / ARCSEC == pytest.approx(doc["total"]["backlash"], rel=1e-6)
    assert "backlash_additions" not in analyze(base).report("arcsec")["total"]
