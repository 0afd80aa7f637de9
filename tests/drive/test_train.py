"""The train of stages: the paper's drive in either form, single stages, other orders, a hand-checked
three-stage train, orders at the output and compliance referred to the output.

Golden values: the MCH50's stage figures recorded by the two-stage implementation before drive trains
existed (analyze --format json of configs/mch50.toml, arcsec), and closed forms written out here."""

from __future__ import annotations

import math

import pytest

from tests.support.paths import CONFIGS, DATA, MCH50
from wormgear_cli.analysis.accuracy import analyze
from wormgear_cli.drive import train as train_mod
from wormgear_cli.drive.registry import build
from wormgear_cli.spec.loader import load_spec, loads_spec
from wormgear_cli.spec.upgrade import upgrade_text
from wormgear_cli.units import ARCSEC

#: the MCH50's figures [arcsec] (the worm mesh's ISO 6336 stiffness with the worm as a rack in the wheel's
#: slot of q', z_n2 = infinity: docs/models.md)
OLD_MCH50 = {"gear_te": 34.37843996519304, "gear_bl": 28.589949569086553, "worm_te": 153.4654035329265,
             "worm_bl": 1152.9967971635378, "total_te": 53.56161540680885, "total_bl": 172.71454921452877}

WORM = """
[[stage]]
kind = "worm"
module_mm = 2.5
normal_pressure_angle_deg = 20.0
lead_angle_deg = 3.178
face_width_mm = 37.5
lead_error_mm = 0.030
centre_distance_error_mm = 0.035
alignment_errors_mm = [0.030, 0.030, 0.030, 0.030, 0.040, 0.040]
normal_force_N = 85.0
[stage.worm]
starts = 1
profile_error_mm = 0.036
thickness_deviation_mm = 0.045
runout_mm = 0.012
bearing_clearance_mm = 0.010
[stage.wheel]
teeth = 30
profile_error_mm = 0.011
thickness_deviation_mm = 0.090
radial_composite_error_mm = 0.036
runout_mm = 0.016
bearing_clearance_mm = 0.015
"""
SPUR = """
[[stage]]
kind = "spur"
module_mm = 2.5
pressure_angle_deg = 20.0
face_width_mm = 50.0
centre_distance_error_mm = 0.030
normal_force_N = 666.0
[stage.pinion]
teeth = 18
profile_error_mm = 0.008
thickness_deviation_mm = 0.045
[stage.gear]
teeth = 144
profile_error_mm = 0.007
thickness_deviation_mm = 0.055
"""


def arcsec(x: float) -> float:
    return x / ARCSEC


def totals(spec) -> tuple[float, float]:
    a = analyze(spec)
    return arcsec(a.angles["total_transmission_error"]), arcsec(a.angles["total_backlash"])


@pytest.mark.parametrize("name", ["mch50", "rotary-table-precision", "legacy/radar-pedestal-2start"])
def test_old_form_and_upgraded_give_the_same_totals(name):
    path = (DATA if name.startswith("legacy") else CONFIGS) / f"{name}.toml"
    old = load_spec(path)
    new = loads_spec(upgrade_text(path.read_text(), str(path)).text, "upgraded.toml")
    assert new.form == "stages" and old.form == "legacy"
    for a, b in zip(totals(old), totals(new)):
        assert b == pytest.approx(a, rel=1e-9, abs=0.0)


def test_mch50_keeps_its_figures():
    a = analyze(load_spec(MCH50))
    got = {f"{k}_{q}": arcsec(a.angles[f"{n}_{w}"]) for k, n in (("gear", "gear"), ("worm", "worm"), ("total", "total"))
           for q, w in (("te", "transmission_error"), ("bl", "backlash"))}
    assert got == pytest.approx(OLD_MCH50, rel=1e-9)


def test_the_worm_stage_alone_gives_the_old_worm_stage_figures_as_the_drive_totals():
    te, bl = totals(loads_spec(WORM))
    assert te == pytest.approx(OLD_MCH50["worm_te"], rel=1e-9)
    assert bl == pytest.approx(OLD_MCH50["worm_bl"], rel=1e-9)


def test_the_same_stages_in_the_other_order_divide_the_spur_stage_by_the_worm_ratio():
    """[spur, worm]: each stage divided by the ratio after it, worm + spur / 30."""
    te, bl = totals(loads_spec(SPUR + WORM))
    assert te == pytest.approx(OLD_MCH50["worm_te"] + OLD_MCH50["gear_te"] / 30.0, rel=1e-9)
    assert bl == pytest.approx(OLD_MCH50["worm_bl"] + OLD_MCH50["gear_bl"] / 30.0, rel=1e-9)
    # and in the paper's order, spur + worm / 8 (i_c = 144/18)
    te, bl = totals(loads_spec(WORM + SPUR))
    assert te == pytest.approx(OLD_MCH50["gear_te"] + OLD_MCH50["worm_te"] / 8.0, rel=1e-9)


THREE = """
[[stage]]
kind = "belt"
pitch_mm = 2.0
belt_teeth = 137
backlash_mm = 0.02
tensile_stiffness_N = 15000.0
effective_tension_N = 0.0
[stage.driver]
teeth = 20
eccentricity_mm = 0.010
[stage.driven]
teeth = 60

[[stage]]
kind = "spur"
kinematics = "involute"
module_mm = 2.0
pressure_angle_deg = 20.0
centre_distance_error_mm = 0.010
[stage.pinion]
teeth = 20
thickness_deviation_mm = 0.02
[stage.gear]
teeth = 80
thickness_deviation_mm = 0.03

[[stage]]
kind = "worm"
module_mm = 3.0
normal_pressure_angle_deg = 20.0
lead_angle_deg = 5.0
lead_error_mm = 0.020
[stage.worm]
starts = 1
thickness_deviation_mm = 0.030
[stage.wheel]
teeth = 60
thickness_deviation_mm = 0.030
"""


def test_three_stage_train_by_hand():
    """belt 20 -> 60 (i = 3), spur 20 -> 80 involute (i = 4), worm 1 -> 60 (i = 60), no load.

    By hand, at each stage's own output shaft:
    belt: TE = e / R (the driver's eccentricity moves the belt by e), backlash = c / R, R = 60 x 2 / (2 pi);
    spur: TE = 0 (no eccentricity, no load), backlash = (2 Delta a tan 20 + E_sn1 + E_sn2) / r, r = 80 mm;
    worm: TE = h / r_w with h = f_hL / 2 (the only TE source), r_w = 90 mm; backlash = Delta j / r_w with
    Delta j = (T_s1 + T_s2) / (2 cos 5) + 1/2 sqrt((T_s1^2 + T_s2^2) / (36 cos^2 5) + 4 f_hL^2).
    At the output: worm + spur / 60 + belt / 240."""
    spec = loads_spec(THREE)
    R = 60 * 2.0 / (2 * math.pi)
    belt_te, belt_bl = 0.010 / R, 0.02 / R
    spur_te, spur_bl = 0.0, (2 * 0.010 * math.tan(math.radians(20)) + 0.05) / 80.0
    cos5 = math.cos(math.radians(5))
    dj = 0.06 / (2 * cos5) + 0.5 * math.sqrt(2 * 0.03**2 / (36 * cos5**2) + 4 * 0.02**2)
    worm_te, worm_bl = 0.010 / 90.0, dj / 90.0
    a = analyze(spec)
    assert a.angles["total_transmission_error"] == pytest.approx(worm_te + spur_te / 60 + belt_te / 240, rel=1e-12)
    assert a.angles["total_backlash"] == pytest.approx(worm_bl + spur_bl / 60 + belt_bl / 240, rel=1e-12)
    assert [r.after for r in a.stages] == [240.0, 60.0, 1.0]
    assert a.angles["belt_transmission_error"] == pytest.approx(belt_te, rel=1e-12)
    assert a.angles["gear_backlash"] == pytest.approx(spur_bl, rel=1e-12)
    assert a.angles["worm_backlash"] == pytest.approx(worm_bl, rel=1e-12)


def test_three_stage_orders_at_the_output():
    """Shafts turn 720, 240, 60, 1 times per output turn; the spur mesh is at 80 x 60, the worm
    mesh at 60, the belt's teeth at 60 x 240 and the belt itself once per 137 of them."""
    t = train_mod.of(loads_spec(THREE))
    assert t.turns == (720.0, 240.0, 60.0, 1.0)
    got = {(o.kind, o.stage): o.order for o in train_mod.orders(t)}
    assert got[("mesh", 3)] == 60.0
    assert got[("mesh", 2)] == 80 * 60.0
    assert got[("mesh", 1)] == 60 * 240.0
    assert got[("belt", 1)] == pytest.approx(60 * 240.0 / 137)
    assert not float(got[("belt", 1)]).is_integer()
    reg = build(loads_spec(THREE))
    orders = {s.name: s.order for s in reg.sources}
    assert orders["driver_pulley_eccentricity"] == 720.0 and orders["worm_lead_error"] == 60.0


def test_belt_stretch_is_a_compliance_referred_to_the_output():
    """1/k_out = sum_h 1 / (k_h O_h^2): the belt's stiffness at its driven pulley, k = 2 E A R^2 / L
    (both spans, L = sqrt(C^2 - (R - r)^2), C from the belt length), seen at the output through
    O = 240: the wind-up per N m with the belt minus the same drive with a rigid belt."""
    stiff = build(loads_spec(THREE)).compliance.per_Nm
    rigid = build(loads_spec(THREE.replace("tensile_stiffness_N = 15000.0\n", ""))).compliance.per_Nm
    R, r, L_belt = 60 * 2.0 / (2 * math.pi), 20 * 2.0 / (2 * math.pi), 137 * 2.0
    b = L_belt - math.pi * (2 * R + 2 * r) / 2
    C = (b + math.sqrt(b * b - 2 * (2 * R - 2 * r) ** 2)) / 4
    L = math.sqrt(C * C - (R - r) ** 2)
    k = 2 * 15000.0 * R * R / L  # [N mm / rad]
    assert stiff - rigid == pytest.approx(1000.0 / (k * 240.0**2), rel=1e-12)


def test_a_stage_name_repeating_gets_its_stage_in_the_source_names():
    two_spurs = loads_spec(SPUR.replace("normal_force_N = 666.0\n", "") * 2)
    names = [s.name for s in build(two_spurs).sources]
    assert len(names) == len(set(names))
    assert "stage1_gear_eccentricity" in names and "stage2_gear_eccentricity" in names
    assert [s.name for s in two_spurs.stages] == ["gear1", "gear2"]


def test_every_shaft_and_mesh_is_named():
    """EQ6 class: the motor (driving pulley) at 705, the worm shaft (driven pulley and worm) and the worm
    mesh at 180, the RA axis (wheel) at 1; the belt's teeth at 47 x 180 and the belt at 47 x 180 / 80."""
    spec = load_spec(CONFIGS / "eq6-belt-worm.toml")
    t = train_mod.of(spec)
    assert t.ratios == pytest.approx((47 / 12, 180.0)) and t.total_ratio == pytest.approx(705.0)
    got = [(o.order, o.kind, o.stage, o.label) for o in train_mod.orders(t)]
    assert got == [(1.0, "shaft", 2, "output shaft (wheel)"),
                   (180.0, "shaft", 1, "shaft 1 (driven pulley, worm)"),
                   (pytest.approx(705.0), "shaft", 0, "motor shaft (driving pulley)"),
                   (180.0, "mesh", 2, "worm mesh"),
                   (47 * 180.0, "mesh", 1, "belt tooth mesh"),
                   (pytest.approx(47 * 180 / 80), "belt", 1, "belt revolution")]
    three = [(o.kind, o.stage, o.label) for o in train_mod.orders(train_mod.of(loads_spec(THREE)))]
    assert three[4:] == [("mesh", 3, "worm mesh"), ("mesh", 2, "spur mesh"), ("mesh", 1, "belt tooth mesh"),
                         ("belt", 1, "belt revolution")]
    mch50 = {(o.kind, o.stage): o.order for o in train_mod.orders(train_mod.of(loads_spec(WORM + SPUR)))}
    assert mch50[("mesh", 1)] == 240.0 and mch50[("mesh", 2)] == 144.0  # worm mesh z3 i_c, spur mesh z1
    two = train_mod.of(loads_spec(WORM + WORM))
    labels = [o.label for o in train_mod.orders(two)]
    assert labels == ["output shaft (wheel of stage 2)", "shaft 1 (wheel of stage 1, worm of stage 2)",
                      "motor shaft (worm of stage 1)", "worm mesh of stage 2", "worm mesh of stage 1"]
