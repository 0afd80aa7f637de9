"""Tests of the sweep core (:mod:`wormgear_cli.analysis.sweep`): the fast maximiser, the findings, the blocks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize_scalar


def paper_gear_te(phi, r1, r2, de, alpha, d1):
    """The paper's Delta phi_cc(phi), transcribed literally (valid for -pi < phi < pi)."""
    l = r1 + r2
    a = (l + de) / de
    lam1 = np.arctan(de * np.sin(phi) / (l + de * (1.0 - np.cos(phi))))
    bracket = 2.0 * np.arctan(np.sqrt((a + 1.0) / (a - 1.0)) * np.tan(phi / 2.0)) - (
        phi - np.tan(alpha) * np.log(1.0 + 2.0 * a * (1.0 - np.cos(phi)) / (a - 1.0) ** 2))
    return (r1 + r2) / (2.0 * r2) * bracket + d1 * np.sin(alpha + lam1) / r2


def reference_max(r1, r2, de, alpha, d1):
    """Dense sampling (3601 angles) refined by scipy's bounded optimiser."""
    phi = np.linspace(-math.pi + 1e-9, math.pi - 1e-9, 3601)
    values = paper_gear_te(phi, r1, r2, de, alpha, d1)
    j = int(np.argmax(values))
    lo, hi = phi[max(j - 1, 0)], phi[min(j + 1, phi.size - 1)]
    res = minimize_scalar(lambda p: -paper_gear_te(p, r1, r2, de, alpha, d1), bounds=(lo, hi), method="bounded",
                          options={"xatol": 1e-12})
    return max(-res.fun, float(values.max()))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    l=st.floats(20.0, 2000.0),
    i=st.floats(0.3, 30.0),
    ecc_ratio_exp=st.floats(-5.0, -2.0),
    alpha_deg=st.floats(5.0, 40.0),
    load=st.one_of(st.just(0.0), st.floats(1e-6, 5.0)),
)
def test_fast_maximum_matches_reference(l, i, ecc_ratio_exp, alpha_deg, load):
    from wormgear_cli.physics.spur import gear_te_max_fast

    r1, r2 = l / (1 + i), l * i / (1 + i)
    de, alpha = l * 10.0 ** ecc_ratio_exp, math.radians(alpha_deg)
    value, phi = gear_te_max_fast(r1, r2, de, alpha, load)
    ref = reference_max(r1, r2, de, alpha, load)
    assert value == pytest.approx(ref, rel=1e-9)
    # and phi is where the paper's curve takes that value
    p = phi if phi <= math.pi else phi - 2 * math.pi
    assert paper_gear_te(p, r1, r2, de, alpha, load) == pytest.approx(ref, rel=1e-9)


def test_fast_maximum_without_eccentricity_is_the_load_term():
    from wormgear_cli.physics.spur import gear_te_max_fast

    value, _ = gear_te_max_fast(22.5, 180.0, 0.0, math.radians(20), 0.002)
    assert value == pytest.approx(0.002 * math.sin(math.radians(20)) / 180.0, rel=1e-15)


def test_big_grid_sample_matches_reference(mch50_spec):
    """A 1000 x 1000 grid: a random sample of its points against the reference maximiser."""
    from wormgear_cli.analysis.sweep import RatioDistanceSweep

    sw = RatioDistanceSweep(mch50_spec, np.linspace(2, 10, 1000), np.linspace(100, 300, 1000))
    data = sw.collect()
    assert data["i"].size == 10**6
    de, alpha = mch50_spec.assembly.gear_eccentricity, mch50_spec.gear_pair.pressure_angle
    rng = np.random.default_rng(7)
    for k in rng.choice(10**6, size=25, replace=False):
        i, l = data["i"][k], data["l_mm"][k]
        d1 = data["gear_deflection_um"][k] * 1e-3  # the load is an input of the maximisation
        ref = reference_max(l / (1 + i), l * i / (1 + i), de, alpha, d1)
        assert data["gear_transmission_error"][k] == pytest.approx(ref, rel=1e-9)


@pytest.mark.parametrize("hold", ["force", "torque"])
def test_spec_point_reproduces_analyze(mch50_spec, hold):
    from wormgear_cli.analysis.accuracy import analyze
    from wormgear_cli.analysis.sweep import RatioDistanceSweep

    gp = mch50_spec.gear_pair
    i0 = gp.output_gear.teeth / gp.pinion.teeth
    l0 = gp.module * (gp.output_gear.teeth + gp.pinion.teeth) / 2
    data = RatioDistanceSweep(mch50_spec, [i0], [l0], hold=hold).collect()
    a = analyze(mch50_spec).angles
    for key in ("gear_transmission_error", "total_transmission_error", "total_backlash", "gear_backlash"):
        assert data[key][0] == pytest.approx(a[key], rel=1e-12), key


def test_module_snapping_reproduces_analyze_with_those_teeth(mch50_spec):
    from wormgear_cli.analysis.accuracy import analyze
    from wormgear_cli.analysis.sweep import RatioDistanceSweep
    from wormgear_cli.spec.loader import with_values

    m = 2.0
    sw = RatioDistanceSweep(mch50_spec, np.linspace(2, 10, 5), np.linspace(60, 300, 7), module=m)
    data = sw.collect()
    assert data["z1"].size > 0
    for k in range(data["z1"].size):
        z1, z2 = int(data["z1"][k]), int(data["z2"][k])
        spec = with_values(mch50_spec, {"gear_pair.module_mm": m, "gear_pair.output_gear.teeth": z1,
                                        "gear_pair.pinion.teeth": z2})
        a = analyze(spec).angles
        for key in ("gear_transmission_error", "total_transmission_error", "total_backlash", "gear_backlash"):
            assert data[key][k] == pytest.approx(a[key], rel=1e-9), (key, z1, z2)


def test_torque_hold_scales_the_gear_force_with_the_output_radius(mch50_spec):
    """At constant output torque F_N R2 = const, so delta1 carries (R2_spec / R2)^0.75 on top of the
    stiffness change that the force-held sweep already shows: below a line load of 100 N/mm (here
    12.5..34 N/mm) ISO 6336-1 scales c' with (F_t K_A / b / 100)^0.25, so delta ~ F^0.75."""
    from wormgear_cli.analysis.sweep import RatioDistanceSweep

    i, l = np.linspace(2, 10, 5), np.linspace(100, 300, 5)
    f = RatioDistanceSweep(mch50_spec, i, l, hold="force").collect()
    t = RatioDistanceSweep(mch50_spec, i, l, hold="torque").collect()
    r2 = f["l_mm"] * f["i"] / (1 + f["i"])
    r2_spec = 2.5 * 144 / 2
    np.testing.assert_allclose(t["gear_deflection_um"] / f["gear_deflection_um"], (r2_spec / r2) ** 0.75, rtol=1e-12)


@pytest.fixture(scope="module")
def mch50_grid():
    from tests.support.paths import MCH50
    from wormgear_cli.analysis.sweep import RatioDistanceSweep
    from wormgear_cli.spec.loader import load_spec

    i, l = np.linspace(2, 10, 9), np.linspace(100, 300, 21)
    data = RatioDistanceSweep(load_spec(MCH50), i, l).collect()
    return i, l, data["gear_transmission_error"].reshape(i.size, l.size)


def test_finding_te_more_sensitive_to_l_than_to_i(mch50_grid):
    i, l, te = mch50_grid
    change_over_l = 1 - te[:, -1] / te[:, 0]  # every row: l from 100 to 300 mm
    change_over_i = 1 - te[-1, :] / te[0, :]  # every column: i from 2 to 10
    assert change_over_l.min() > 2 * change_over_i.max()


def test_finding_gain_from_l_fades_beyond_200_mm(mch50_grid):
    i, l, te = mch50_grid
    a, b, c = (int(np.argmin(abs(l - x))) for x in (100, 200, 300))
    fall_below = 1 - te[:, b] / te[:, a]
    fall_above = 1 - te[:, c] / te[:, b]
    assert np.all(fall_below > 0.45) and np.all(fall_above < 0.36)
    assert np.all((te[:, b] - te[:, c]) < 0.5 * (te[:, a] - te[:, b]))  # absolute gain well under half


def test_finding_ratio_matters_only_below_6(mch50_grid):
    i, l, te = mch50_grid
    a, b, c = (int(np.argmin(abs(i - x))) for x in (2, 6, 10))
    fall_below = 1 - te[b] / te[a]
    fall_above = 1 - te[c] / te[b]
    assert np.all(fall_below > 0.2) and np.all(fall_above < 0.07)


def test_gear_te_decreases_monotonically_with_l(mch50_spec):
    from wormgear_cli.analysis.sweep import RatioDistanceSweep

    for hold in ("force", "torque"):
        i, l = np.linspace(1.5, 12, 8), np.linspace(40, 600, 60)
        te = RatioDistanceSweep(mch50_spec, i, l, hold=hold).collect()["gear_transmission_error"]
        assert np.all(np.diff(te.reshape(i.size, l.size), axis=1) < 0), hold


def test_findings_report(mch50_spec):
    from wormgear_cli.analysis.sweep import RatioDistanceSweep, findings

    out = {f["id"]: f for f in findings(RatioDistanceSweep(mch50_spec, np.linspace(2, 10, 9),
                                                            np.linspace(100, 300, 11)))}
    assert all(f["holds"] is True for f in out.values())
    fade = out["l_gain_fades_beyond_200mm"]
    assert fade["window"] == [100.0, 200.0, 300.0]
    assert fade["fall_below_pct"] > fade["fall_above_pct"]
    narrow = findings(RatioDistanceSweep(mch50_spec, np.linspace(7, 10, 4), np.linspace(210, 300, 4)))
    assert [f["holds"] for f in narrow[1:]] == [None, None]
    assert "does not straddle 200 mm" in narrow[1]["statement"]


def test_fall_pct_is_safe_on_zero():
    from wormgear_cli.analysis.sweep import _fall_pct

    assert math.isnan(_fall_pct(0.0, 0.0))
    assert _fall_pct(4.0, 3.0) == pytest.approx(25.0)


def test_long_l_axis_is_computed_in_blocks_with_the_same_values(mch50_spec, monkeypatch):
    """An l axis longer than a block gets its kinematic peak block by block (bounded memory);
    the values equal the precomputed path and do not depend on where a shard starts."""
    from wormgear_cli.analysis import sweep as core

    i, l = np.linspace(2, 10, 3), np.linspace(100, 300, 150)
    whole = core.RatioDistanceSweep(mch50_spec, i, l).collect()
    monkeypatch.setattr(core, "CHUNK_POINTS", 64)
    blocked = core.RatioDistanceSweep(mch50_spec, i, l)
    assert blocked._peak is None
    data = blocked.collect()
    np.testing.assert_allclose(data["gear_transmission_error"], whole["gear_transmission_error"], rtol=1e-13)
    parts = [blocked.collect(a, b) for a, b in ((0, 37), (37, 301), (301, 450))]
    for key in ("gear_transmission_error", "gear_te_phi_deg", "total_backlash"):
        assert np.array_equal(np.concatenate([p[key] for p in parts]), data[key])


def test_undercut_min_teeth_is_safe_for_any_angle():
    from wormgear_cli.analysis.sweep import MAX_MIN_TEETH, undercut_min_teeth

    # textbook values for a standard rack: 17 at 20 deg, 32 at 14.5 deg
    assert undercut_min_teeth(math.radians(20)) == 17 and undercut_min_teeth(math.radians(14.5)) == 32
    for alpha in (0.0, 1e-320, 1e-300, -0.3, float("nan"), float("inf")):
        assert undercut_min_teeth(alpha) == MAX_MIN_TEETH
    angles = np.radians(np.geomspace(1e-6, 45, 60))
    counts = [undercut_min_teeth(a) for a in angles]
    assert all(b <= a for a, b in zip(counts, counts[1:]))  # fewer teeth needed at larger angles
    assert counts[0] == MAX_MIN_TEETH and counts[-1] == 4  # 2/sin^2(45 deg) = 4



@pytest.mark.parametrize("config", ["rotary-table-precision.toml", "../tests/data/legacy/radar-pedestal-2start.toml"])
def test_involute_drives_are_swept_with_the_involute_stage(config):
    """A drive with ``gear_pair.kinematics = "involute"`` is swept by the stage analyze uses for it:
    at the spec's own point and at snapped designs the sweep equals analyze (the paper's
    Delta phi_cc would give other numbers)."""
    from tests.support.paths import CONFIGS
    from wormgear_cli.analysis.accuracy import analyze
    from wormgear_cli.analysis.sweep import RatioDistanceSweep
    from wormgear_cli.spec.loader import load_spec, with_values

    spec = load_spec(CONFIGS / config)
    gp = spec.gear_pair
    assert gp.kinematics == "involute"
    i0 = gp.output_gear.teeth / gp.pinion.teeth
    l0 = gp.module * (gp.output_gear.teeth + gp.pinion.teeth) / 2
    a = analyze(spec).angles
    data = RatioDistanceSweep(spec, [i0], [l0]).collect()
    for key in ("gear_transmission_error", "total_transmission_error", "total_backlash", "gear_backlash"):
        assert data[key][0] == pytest.approx(a[key], rel=1e-12), key
    paper = analyze(with_values(spec, {"gear_pair.kinematics": "paper"})).angles
    assert abs(paper["gear_backlash"] - a["gear_backlash"]) > 1e-3 * a["gear_backlash"]  # the readings differ here
    m = gp.module
    sw = RatioDistanceSweep(spec, [0.5 * i0, i0, 2.0 * i0], [0.8 * l0, l0], module=m)
    snapped = sw.collect()
    assert snapped["z1"].size > 0
    for k in range(snapped["z1"].size):
        z1, z2 = int(snapped["z1"][k]), int(snapped["z2"][k])
        other = with_values(spec, {"gear_pair.output_gear.teeth": z1, "gear_pair.pinion.teeth": z2})
        b = analyze(other).angles
        for key in ("gear_transmission_error", "total_backlash"):
            assert snapped[key][k] == pytest.approx(b[key], rel=1e-9), (key, z1, z2)


def test_the_sweep_table_names_the_involute_stage(runner):
    from tests.support.paths import CONFIGS
    from wormgear_cli.cli import app

    r = runner.invoke(app, ["sweep", str(CONFIGS / "rotary-table-precision.toml"), "--i", "2:6:3", "--l-mm",
                            "200:300:3"], env={"COLUMNS": "200"})
    assert r.exit_code == 0, r.output
    text = " ".join(r.stdout.split())  # titles wrap at the table's width
    assert "gear TE (involute stage)" in text and "Delta phi_cc" not in text
    assert "the paper's findings on this grid, with the involute stage" in text


@pytest.mark.parametrize("config,module", [("../tests/data/legacy/radar-pedestal-2start.toml", 4.0),
                                           ("mch50.toml", 2.5)])
def test_torque_hold_equals_analyze_at_the_torque_scaled_loads(config, module):
    """With the output torque held, a snapped design is analyze of that design at the loads the torque
    gives: spur normal force x R2_spec / R2 and worm normal force x i_spec / i (the worm stage is not
    linear in its force, so it is evaluated there, not interpolated)."""
    from tests.support.paths import CONFIGS
    from wormgear_cli.analysis.accuracy import analyze
    from wormgear_cli.analysis.sweep import RatioDistanceSweep
    from wormgear_cli.spec.loader import load_spec, with_values

    spec = load_spec(CONFIGS / config)
    gp, loads = spec.gear_pair, spec.loads
    i0, r2_0 = gp.output_gear.teeth / gp.pinion.teeth, gp.module * gp.output_gear.teeth / 2
    data = RatioDistanceSweep(spec, [2.0, 4.0, 6.0], [200.0, 300.0], hold="torque", module=module,
                              min_teeth=12).collect()
    assert data["z1"].size >= 4
    for k in range(data["z1"].size):
        z1, z2 = int(data["z1"][k]), int(data["z2"][k])
        r2 = module * z1 / 2
        other = with_values(spec, {
            "gear_pair.module_mm": module, "gear_pair.output_gear.teeth": z1, "gear_pair.pinion.teeth": z2,
            "loads.gear_normal_force_N": loads.gear_normal_force * r2_0 / r2,
            "loads.worm_normal_force_N": loads.worm_normal_force * i0 / (z1 / z2)})
        a = analyze(other).angles
        for key in ("gear_transmission_error", "total_transmission_error", "total_backlash"):
            assert data[key][k] == pytest.approx(a[key], rel=1e-9), (key, z1, z2)


# --- any train: the swept spur stage and the stages around it ------------------------------------------------------

RADAR3 = "radar-pedestal-2start.toml"  # spur gearmotor 17:85 -> two-start worm 2:60 -> pinion 25 : bull gear 200


@pytest.mark.parametrize("stage", [1, 3])
def test_a_spur_stage_of_a_three_stage_train_is_swept_as_analyze_of_that_design(stage):
    """The radar's output torque sets every stage's load (T through the ratios after it, over its radius),
    so holding the torque, a snapped design of stage 1 or 3 is analyze of the file with those teeth:
    the stages after the swept one as they are, the stage itself over O_k, those before it over i O_k."""
    from tests.support.paths import CONFIGS
    from wormgear_cli.analysis.accuracy import analyze
    from wormgear_cli.analysis.sweep import RatioDistanceSweep
    from wormgear_cli.spec.loader import load_spec, with_values

    spec = load_spec(CONFIGS / RADAR3)
    st = spec.stages[stage - 1]
    m = st.module
    i0, l0 = st.gear.teeth / st.pinion.teeth, m * (st.gear.teeth + st.pinion.teeth) / 2
    data = RatioDistanceSweep(spec, [0.6 * i0, i0, 1.5 * i0], [0.9 * l0, l0], hold="torque", module=m,
                              min_teeth=12, stage=stage).collect()
    assert data["z1"].size >= 4
    for k in range(data["z1"].size):
        z1, z2 = int(data["z1"][k]), int(data["z2"][k])
        a = analyze(with_values(spec, {f"stage.{stage}.gear.teeth": z1, f"stage.{stage}.pinion.teeth": z2}))
        own = a.stages[stage - 1]
        assert data["gear_transmission_error"][k] == pytest.approx(own.transmission_error, rel=1e-9)
        assert data["gear_backlash"][k] == pytest.approx(own.backlash, rel=1e-9)
        for key in ("total_transmission_error", "total_backlash"):
            assert data[key][k] == pytest.approx(a.angles[key], rel=1e-9), (key, z1, z2)


def test_the_default_spur_stage_is_the_last_and_a_train_without_one_is_refused():
    from tests.support.paths import CONFIGS
    from wormgear_cli.analysis.sweep import spur_stage
    from wormgear_cli.errors import UsageError
    from wormgear_cli.spec.loader import load_spec

    radar = load_spec(CONFIGS / RADAR3)
    assert spur_stage(radar).index == 3 and spur_stage(radar, 1).index == 1
    with pytest.raises(UsageError) as err:
        spur_stage(radar, 2)
    assert str(err.value) == (f"--stage 2: stage 2 of {radar.source} is a worm stage, the ratio and centre-distance "
                              "sweep varies a spur stage; its spur stages are 1, 3")
    with pytest.raises(UsageError) as err:
        spur_stage(radar, 4)
    assert str(err.value) == f"--stage 4: {radar.source} has 3 stages (stages: 1 spur, 2 worm, 3 spur)"
    with pytest.raises(UsageError):
        spur_stage(load_spec(CONFIGS / "rotary-table-worm.toml"))
