"""The effect catalogue: the MCH50 geometry the signatures see (by hand), the
registry's structure, unit conversion, the spec loader, and the thermal prediction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.paths import MCH50
from tests.support.specs import SPEC_HEAD
from wormgear_cli.analysis.accuracy import geometry
from wormgear_cli.physics.effects import EFFECTS, Signals, params_from_keys, params_to_keys
from wormgear_cli.physics.thermal import centre_distance_growth, predicted_centre_distance_um_per_K
from wormgear_cli.spec.loader import loads_spec

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
    from wormgear_cli.spec.loader import load_spec

    return load_spec(MCH50)


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


def test_geometry_of_the_mch50_by_hand(spec):
    """The DriveGeometry the signatures see, from Table 1 by hand: r_1 = 2.5 * 144/2 = 180 mm,
    r_b1 = 180 cos 20 deg = 169.144672 mm, r_wheel = 2.5 * 30/2 = 37.5 mm, i_c = 144/18 = 8,
    n_w = 8 * 30 = 240, z1 = 144, alpha_x = atan(tan 20 deg / cos 3.178 deg) = 20.028358 deg.
    (The signatures themselves are checked against hand values on an explicit geometry in
    test_effects_hand.py; the earlier tests here re-typed each docstring formula.)"""
    g = geometry(spec)
    assert g.output_pitch_radius == pytest.approx(180.0, rel=1e-12)
    assert g.output_base_radius == pytest.approx(169.144672, rel=1e-8)
    assert g.wheel_pitch_radius == pytest.approx(37.5, rel=1e-12)
    assert g.gear_ratio == pytest.approx(8.0, rel=1e-12)
    assert g.worm_order == pytest.approx(240.0, rel=1e-12)
    assert g.output_teeth == 144
    assert math.degrees(g.axial_pressure_angle) == pytest.approx(20.028358, abs=1e-6)


def test_thermal_backlash_growing_centre_distance_grows_lost_motion(spec):
    # warmer than the reference with k > 0: reverse - forward (the lost motion) increases
    s = Signals.make(np.zeros(2), np.array([1.0, -1.0]), 0.0, 30.0)
    e = _eval("thermal_backlash", spec, s, centre_distance_um_per_K=1.0)
    assert e[1] - e[0] > 0


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
    """d_m1 = 2.5 / tan(3.178 deg) = 2.5 / 0.05552352 = 45.025967, r1 = 22.512984, r2 = 37.5,
    a = 60.012984 mm; cast iron 10.5, steel 11.5, bronze 18.5 ppm/K:
    60.012984 * 10.5e-6 - (22.512984 * 11.5e-6 + 37.5 * 18.5e-6)
    = 6.301363e-4 - (2.588993e-4 + 6.9375e-4) = -3.225130e-4 mm/K: warming closes the backlash."""
    mat = mch50_spec.materials
    assert (mat.housing_expansion, mat.worm_expansion, mat.wheel_expansion) == pytest.approx(
        (10.5e-6, 11.5e-6, 18.5e-6), rel=1e-12)
    assert predicted_centre_distance_um_per_K(mch50_spec) == pytest.approx(-0.3225130, rel=1e-6)


def test_one_material_everywhere_gives_no_change():
    # a = r1 + r2 without profile shift: equal expansion everywhere keeps the mesh as it is
    spec = loads_spec(SPEC_HEAD + "[materials]\nworm_expansion_ppm_per_K = 12\nwheel_expansion_ppm_per_K = 12\n"
                      "housing_expansion_ppm_per_K = 12\n", "d.toml")
    assert predicted_centre_distance_um_per_K(spec) == pytest.approx(0.0, abs=1e-12)


def test_centre_distance_growth_separate_temperatures():
    # housing 5 K warmer than the gears: only the housing term remains
    got = centre_distance_growth(100.0, 20.0, 80.0, 11e-6, 12e-6, 18e-6, housing_dt=5.0, worm_dt=0.0, wheel_dt=0.0)
    assert got == pytest.approx(100.0 * 11e-6 * 5.0)


def _amplified(eff) -> dict:
    """Internal parameters of ``eff`` with defaults, and a quarter of the range's top for the rest (ten times
    the bottom for a parameter the signature is inverse in: a stiffness)."""
    out = {q.name: (q.default if q.default is not None else 0.25 * q.hi) * q.scale for q in eff.params}
    if eff.extra.get("inverse"):
        q = next(q for q in eff.params if q.name == eff.amplitude)
        out[q.name] = 10.0 * q.lo * q.scale
    return out


@pytest.mark.parametrize("name", list(EFFECTS))
def test_the_records_diagnosis_metadata_is_what_the_signature_does(name, mch50_spec):
    """``mode``, ``pattern`` and ``needs`` on the record (what diagnose reads) agree with the signature
    function itself, evaluated here: a common-mode effect is the same in both directions, a
    differential one is not; a trend changes with its signal and with nothing else but the direction; a
    reversal with the direction alone; a periodic effect repeats after 1/order of a turn."""
    from wormgear_cli.physics.signals import SIGNALS

    eff, g = EFFECTS[name], geometry(mch50_spec)
    s, theta, _, load, temp = _signals(11)
    conditions = {"load": load, "temperature": temp, "time": s.time}

    def f(direction, theta=theta, **changed):
        values = {**conditions, **changed}
        sig = Signals(theta, np.full(theta.shape, direction), values["load"], values["temperature"], values["time"])
        return eff.function(sig, g, **_amplified(eff))

    assert eff.mode in ("common", "differential")
    assert eff.needs is None or eff.needs in SIGNALS
    diff = f(1.0) - f(-1.0)
    if eff.mode == "common":
        np.testing.assert_allclose(diff, 0.0, atol=1e-15)
    else:
        assert np.max(np.abs(diff)) > 1e-9 and eff.needs is not None
    others = [k for k in conditions if k != eff.needs]
    if eff.pattern == "trend":
        assert SIGNALS[eff.needs].slope_unit and eff.signature
        assert np.max(np.abs(f(1.0, **{eff.needs: conditions[eff.needs] + 10.0}) - f(1.0))) > 1e-9
        for k in others:
            np.testing.assert_allclose(f(1.0, **{k: conditions[k] + 10.0}), f(1.0), atol=1e-15, err_msg=k)
        np.testing.assert_allclose(f(1.0, theta=theta + 0.3), f(1.0), atol=1e-15)
    elif eff.pattern == "reversal":
        assert eff.needs == "direction" and eff.mode == "differential" and eff.signature
        for k in conditions:
            np.testing.assert_allclose(f(1.0, **{k: conditions[k] + 10.0}), f(1.0), atol=1e-15, err_msg=k)
        np.testing.assert_allclose(f(1.0, theta=theta + 0.3), f(1.0), atol=1e-15)
    else:
        assert eff.pattern is None and eff.order is not None
        period = 2.0 * math.pi / float(eff.order(g))
        np.testing.assert_allclose(f(1.0, theta=theta + period), f(1.0), atol=1e-12)
        assert np.max(np.abs(f(1.0, theta=theta + 0.5 * period) - f(1.0))) > 1e-9
        assert "order" in eff.signature_text(g)


def test_every_signal_has_its_reader_column_with_a_default_and_a_range():
    """The operating signals' registry is where the readers' optional columns come from."""
    from wormgear_cli.measurement.reader import DEFAULTS, OPTIONAL
    from wormgear_cli.measurement.readers.values import RANGES
    from wormgear_cli.physics.signals import SIGNALS

    for s in SIGNALS.values():
        assert s.column in OPTIONAL and DEFAULTS[s.column] == s.default, s.name
        assert RANGES[s.column] == (s.lo, s.hi) and s.lo <= s.default <= s.hi, s.name
    assert set(SIGNALS) == {"direction", "load", "temperature", "time"} == set(Signals.__dataclass_fields__) - {"theta"}
