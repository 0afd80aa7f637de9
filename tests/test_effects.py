"""The effect catalogue: every signature against its formula written out here, the
registry's structure, unit conversion, the spec loader, and the thermal prediction."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wormgear_cli.analysis import geometry
from wormgear_cli.models.effects import EFFECTS, Signals, params_from_keys, params_to_keys
from wormgear_cli.models.thermal import centre_distance_growth, predicted_centre_distance_um_per_K
from wormgear_cli.spec import loads_spec

AS = math.pi / 648000.0  # rad per arcsec, written out independently of the package

FIXED = {
    "output_gear_runout": ("eccentricity_um", "phase_deg"),
    "intermediate_shaft_runout": ("eccentricity_um", "phase_deg"),
    "worm_runout": ("amplitude_um", "phase_deg"),
    "gear_mesh_error": ("amplitude_um", "phase_deg"),
    "thermal_backlash": ("centre_distance_um_per_K", "reference_temperature_C"),
    "thermal_drift": ("arcsec_per_K", "reference_temperature_C"),
    "torsional_compliance": ("stiffness_Nm_per_arcsec",),
    "bearing_clearance": ("clearance_arcsec",),
}


@pytest.fixture(scope="module")
def spec():
    from pathlib import Path

    from wormgear_cli.spec import load_spec

    return load_spec(Path(__file__).resolve().parent.parent / "configs" / "mch50.toml")


@pytest.fixture(scope="module")
def hand(spec):
    """The geometry the issue's formulas need, computed here by hand from the spec's inputs."""
    gp, wp = spec.gear_pair, spec.worm_pair
    m1, z1, z2 = gp.module, gp.output_gear.teeth, gp.pinion.teeth
    alpha = gp.pressure_angle
    i_c = z1 / z2
    return {
        "r_b1": m1 * z1 * math.cos(alpha) / 2.0,
        "r_1": m1 * z1 / 2.0,
        "r_wheel": wp.module * wp.wheel.teeth / 2.0,
        "i_c": i_c,
        "n_w": i_c * wp.wheel.teeth / wp.worm.starts,
        "z1": z1,
        # wheel transverse = worm axial pressure angle (90 deg shaft angle), from alpha_n and the lead angle
        "alpha_x": math.atan(math.tan(wp.normal_pressure_angle) / math.cos(wp.lead_angle)),
    }


def _signals(seed: int, n: int = 64):
    rng = np.random.default_rng(seed)
    theta = rng.uniform(-4 * math.pi, 4 * math.pi, n)
    d = rng.choice([-1.0, 1.0], n)
    load = rng.uniform(-200, 200, n)
    temp = rng.uniform(0, 60, n)
    time = rng.uniform(0, 1e4, n)
    return Signals(theta, d, load, temp, time), theta, d, load, temp


def _eval(name, spec, signals, **keys):
    eff = EFFECTS[name]
    return eff.function(signals, geometry(spec), **params_from_keys(name, keys)) / AS  # -> arcsec


def test_catalogue_names_and_keys_are_the_fixed_ones():
    for name, keys in FIXED.items():
        assert name in EFFECTS
        assert tuple(p.key for p in EFFECTS[name].params) == keys


def test_every_param_has_unit_range_and_doc():
    for eff in EFFECTS.values():
        assert eff.doc and eff.function.__doc__
        assert eff.amplitude in {p.name for p in eff.params}
        for p in eff.params:
            assert p.unit and p.doc
            assert p.lo < p.hi
            if p.default is not None:
                assert p.lo <= p.default <= p.hi


def test_reference_temperature_defaults_to_20():
    for name in ("thermal_backlash", "thermal_drift"):
        assert EFFECTS[name].param("reference_temperature_C").default == 20.0


@settings(max_examples=15, deadline=None)
@given(e_um=st.floats(0.0, 500.0), psi=st.floats(-360.0, 360.0), seed=st.integers(0, 2**16))
def test_output_gear_runout(spec, hand, e_um, psi, seed):
    s, theta, *_ = _signals(seed)
    got = _eval("output_gear_runout", spec, s, eccentricity_um=e_um, phase_deg=psi)
    want = (e_um / 1000.0 / hand["r_b1"]) * np.sin(theta + math.radians(psi)) * 206264.80624709636
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)


@settings(max_examples=15, deadline=None)
@given(e_um=st.floats(0.0, 500.0), psi=st.floats(-360.0, 360.0), seed=st.integers(0, 2**16))
def test_intermediate_shaft_runout(spec, hand, e_um, psi, seed):
    s, theta, *_ = _signals(seed)
    got = _eval("intermediate_shaft_runout", spec, s, eccentricity_um=e_um, phase_deg=psi)
    want = (e_um / 1000.0 / hand["r_b1"]) * np.sin(hand["i_c"] * theta + math.radians(psi)) * 206264.80624709636
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)


@settings(max_examples=15, deadline=None)
@given(a_um=st.floats(0.0, 500.0), psi=st.floats(-360.0, 360.0), seed=st.integers(0, 2**16))
def test_worm_runout(spec, hand, a_um, psi, seed):
    s, theta, *_ = _signals(seed)
    got = _eval("worm_runout", spec, s, amplitude_um=a_um, phase_deg=psi)
    want = (a_um / 1000.0 / hand["r_wheel"]) / hand["i_c"] * np.sin(hand["n_w"] * theta + math.radians(psi))
    np.testing.assert_allclose(got, want * 206264.80624709636, rtol=1e-9, atol=1e-12)


@settings(max_examples=15, deadline=None)
@given(a_um=st.floats(0.0, 100.0), psi=st.floats(-360.0, 360.0), seed=st.integers(0, 2**16))
def test_gear_mesh_error(spec, hand, a_um, psi, seed):
    s, theta, *_ = _signals(seed)
    got = _eval("gear_mesh_error", spec, s, amplitude_um=a_um, phase_deg=psi)
    want = (a_um / 1000.0 / hand["r_1"]) * np.sin(hand["z1"] * theta + math.radians(psi)) * 206264.80624709636
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-10)


@settings(max_examples=15, deadline=None)
@given(k=st.floats(-20.0, 20.0), t_ref=st.floats(-50.0, 150.0), seed=st.integers(0, 2**16))
def test_thermal_backlash(spec, hand, k, t_ref, seed):
    s, theta, d, load, temp = _signals(seed)
    got = _eval("thermal_backlash", spec, s, centre_distance_um_per_K=k, reference_temperature_C=t_ref)
    delta_b = 2.0 * (k / 1000.0) * (temp - t_ref) * math.tan(hand["alpha_x"]) / hand["r_wheel"] / hand["i_c"]
    want = -d * delta_b / 2.0 * 206264.80624709636
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-10)


def test_thermal_backlash_growing_centre_distance_grows_lost_motion(spec):
    # warmer than the reference with k > 0: reverse - forward (the lost motion) increases
    s = Signals.make(np.zeros(2), np.array([1.0, -1.0]), 0.0, 30.0)
    e = _eval("thermal_backlash", spec, s, centre_distance_um_per_K=1.0)
    assert e[1] - e[0] > 0


@settings(max_examples=15, deadline=None)
@given(k=st.floats(-100.0, 100.0), t_ref=st.floats(-50.0, 150.0), seed=st.integers(0, 2**16))
def test_thermal_drift(spec, k, t_ref, seed):
    s, theta, d, load, temp = _signals(seed)
    got = _eval("thermal_drift", spec, s, arcsec_per_K=k, reference_temperature_C=t_ref)
    np.testing.assert_allclose(got, k * (temp - t_ref), rtol=1e-9, atol=1e-9)


@settings(max_examples=15, deadline=None)
@given(k=st.floats(1e-3, 1e9), seed=st.integers(0, 2**16))
def test_torsional_compliance(spec, k, seed):
    s, theta, d, load, temp = _signals(seed)
    got = _eval("torsional_compliance", spec, s, stiffness_Nm_per_arcsec=k)
    np.testing.assert_allclose(got, load / k, rtol=1e-9, atol=1e-15)


@settings(max_examples=15, deadline=None)
@given(c=st.floats(0.0, 3600.0), seed=st.integers(0, 2**16))
def test_bearing_clearance(spec, c, seed):
    s, theta, d, *_ = _signals(seed)
    got = _eval("bearing_clearance", spec, s, clearance_arcsec=c)
    np.testing.assert_allclose(got, -d * c / 2.0, rtol=1e-9, atol=1e-12)


def test_orders_of_periodic_effects(hand, mch50_spec):
    g = geometry(mch50_spec)
    assert EFFECTS["output_gear_runout"].order(g) == 1.0
    assert EFFECTS["intermediate_shaft_runout"].order(g) == pytest.approx(hand["i_c"])
    assert EFFECTS["worm_runout"].order(g) == pytest.approx(hand["n_w"])
    assert EFFECTS["gear_mesh_error"].order(g) == hand["z1"]
    for name in ("thermal_backlash", "thermal_drift", "torsional_compliance", "bearing_clearance"):
        assert EFFECTS[name].order is None and EFFECTS[name].needs is not None


def test_linear_in_the_amplitude_parameter(mch50_spec):
    s, *_ = _signals(7)
    g = geometry(mch50_spec)
    for name, eff in EFFECTS.items():
        p = {q.name: (q.default if q.default is not None else 0.5 * (q.lo + q.hi)) * q.scale for q in eff.params}
        p[eff.amplitude] = 2.0 * eff.param(next(q.key for q in eff.params if q.name == eff.amplitude)).scale
        base = eff.function(s, g, **p)
        p2 = dict(p, **{eff.amplitude: 2.0 * p[eff.amplitude]})
        doubled = eff.function(s, g, **p2)
        factor = 0.5 if eff.extra.get("inverse") else 2.0
        np.testing.assert_allclose(doubled, factor * base, rtol=1e-12, atol=1e-18, err_msg=name)


def test_keys_round_trip_and_units():
    keys = {"eccentricity_um": 12.5, "phase_deg": 90.0}
    internal = params_from_keys("output_gear_runout", keys)
    assert internal == pytest.approx({"eccentricity": 0.0125, "phase": math.pi / 2})
    assert params_to_keys("output_gear_runout", internal) == pytest.approx(keys)
    # defaults filled in
    assert params_from_keys("thermal_drift", {"arcsec_per_K": 1.0})["reference_temperature"] == 20.0
    assert params_from_keys("torsional_compliance", {"stiffness_Nm_per_arcsec": 2.0})["stiffness"] == \
        pytest.approx(2.0 / AS)


SPEC_HEAD = """
[gear_pair]
module_mm = 2.5
pressure_angle_deg = 20
[gear_pair.output_gear]
teeth = 144
[gear_pair.pinion]
teeth = 18
[worm_pair]
module_mm = 2.5
normal_pressure_angle_deg = 20
lead_angle_deg = 3.178
[worm_pair.worm]
starts = 1
[worm_pair.wheel]
teeth = 30
"""


def test_spec_loader_reads_effect_tables():
    spec = loads_spec(SPEC_HEAD + "[effects.bearing_clearance]\nclearance_arcsec = 8\n"
                      "[effects.thermal_drift]\narcsec_per_K = -0.5\n", "d.toml")
    assert set(spec.effects) == {"bearing_clearance", "thermal_drift"}
    assert spec.effects["bearing_clearance"]["clearance"] == pytest.approx(8 * AS)
    assert spec.effects["thermal_drift"]["reference_temperature"] == 20.0


def test_spec_loader_rejects_out_of_range_effect():
    from wormgear_cli.errors import SpecError

    with pytest.raises(SpecError) as exc:
        loads_spec(SPEC_HEAD + "[effects.bearing_clearance]\nclearance_arcsec = -1\n", "d.toml")
    assert exc.value.problems == ["d.toml: effects.bearing_clearance.clearance_arcsec: expected a number in "
                                  "[0, 3600] [arcsec], got -1"]


# --- thermal prediction -------------------------------------------------------------


def test_predicted_centre_distance_mch50_by_hand(mch50_spec):
    wp, mat = mch50_spec.worm_pair, mch50_spec.materials
    d_m1 = 1 * 2.5 / math.tan(math.radians(3.178))  # z_worm m / tan(lambda)
    r1, r2 = d_m1 / 2, 2.5 * 30 / 2
    a = r1 + r2
    assert wp.module == 2.5 and wp.wheel.teeth == 30 and wp.worm.starts == 1
    alpha_h, alpha_1, alpha_2 = (mat.housing_expansion, mat.worm_expansion, mat.wheel_expansion)
    want_um = (a * alpha_h - (r1 * alpha_1 + r2 * alpha_2)) * 1000.0
    assert predicted_centre_distance_um_per_K(mch50_spec) == pytest.approx(want_um, rel=1e-9)
    # steel worm 11.5, bronze wheel 18.5, cast-iron housing 10.5 ppm/K: about -0.32 um/K, warming closes it
    if (alpha_h, alpha_1, alpha_2) == pytest.approx((10.5e-6, 11.5e-6, 18.5e-6)):
        assert predicted_centre_distance_um_per_K(mch50_spec) == pytest.approx(-0.3225, abs=5e-4)


def test_one_material_everywhere_gives_no_change():
    # a = r1 + r2 without profile shift: equal expansion everywhere keeps the mesh as it is
    spec = loads_spec(SPEC_HEAD + "[materials]\nworm_expansion_ppm_per_K = 12\nwheel_expansion_ppm_per_K = 12\n"
                      "housing_expansion_ppm_per_K = 12\n", "d.toml")
    assert predicted_centre_distance_um_per_K(spec) == pytest.approx(0.0, abs=1e-12)


def test_centre_distance_growth_separate_temperatures():
    # housing 5 K warmer than the gears: only the housing term remains
    got = centre_distance_growth(100.0, 20.0, 80.0, 11e-6, 12e-6, 18e-6, housing_dt=5.0, worm_dt=0.0, wheel_dt=0.0)
    assert got == pytest.approx(100.0 * 11e-6 * 5.0)
