"""Catalogue effects against hand values on an explicit geometry, and their default phases.

The geometry is written out here (not derived from the MCH50): output gear pitch radius
100 mm, base radius 80 mm, wheel pitch radius 40 mm, i_c = 4, worm order 120, 50 output
teeth, tan(alpha_x) = 0.4.  Angles are chosen where the sine is exact (0, 1/2, sqrt(3)/2,
1), so each expected value is one line of arithmetic, written in the test.  1 arcsec =
pi/648000 rad (written out here, not imported).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from wormgear_cli.physics.effects import EFFECTS, DriveGeometry, Signals, effect_error, params_from_keys, params_to_keys

AS = math.pi / 648000.0

G = DriveGeometry(output_pitch_radius=100.0, output_base_radius=80.0, wheel_pitch_radius=40.0, gear_ratio=4.0,
                  worm_order=120.0, output_teeth=50, axial_pressure_angle=math.atan(0.4), worm_centre_distance=60.0)


def err(name, keys, theta, direction=1.0, load=0.0, temperature=20.0):
    """Error [rad] of effect ``name`` given its TOML keys (defaults filled by the catalogue)."""
    s = Signals.make(np.atleast_1d(np.asarray(theta, dtype=float)), direction, load, temperature)
    return effect_error(name, s, G, params_from_keys(name, keys))


# --- signatures -----------------------------------------------------------------------------------


def test_output_gear_runout_by_hand():
    """(e / r_b1) sin(theta + psi): e 20 um, r_b1 80 mm -> 2.5e-4 rad peak; theta 30 deg -> 1.25e-4;
    psi 90 deg at theta 0 -> the peak; psi 90 at theta 90 -> sin(180) = 0."""
    assert err("output_gear_runout", {"eccentricity_um": 20.0, "phase_deg": 0.0}, math.pi / 6)[0] == \
        pytest.approx(1.25e-4, rel=1e-12)
    assert err("output_gear_runout", {"eccentricity_um": 20.0, "phase_deg": 90.0}, 0.0)[0] == \
        pytest.approx(2.5e-4, rel=1e-12)
    assert err("output_gear_runout", {"eccentricity_um": 20.0, "phase_deg": 90.0}, math.pi / 2)[0] == \
        pytest.approx(0.0, abs=1e-18)


def test_intermediate_shaft_runout_by_hand():
    """(e / r_b1) sin(i_c theta + psi): e 20 um, i_c 4, theta 7.5 deg -> sin(30 deg) -> 1.25e-4 rad;
    psi 30 deg -> sin(60 deg) = 0.8660254 -> 2.1650635e-4 rad."""
    assert err("intermediate_shaft_runout", {"eccentricity_um": 20.0, "phase_deg": 0.0}, math.pi / 24)[0] == \
        pytest.approx(1.25e-4, rel=1e-12)
    assert err("intermediate_shaft_runout", {"eccentricity_um": 20.0, "phase_deg": 30.0}, math.pi / 24)[0] == \
        pytest.approx(2.1650635e-4, rel=1e-8)


def test_worm_runout_by_hand():
    """(a / r_wheel) / i_c sin(n_w theta + psi): a 10 um -> 0.01/40/4 = 6.25e-5 rad peak;
    theta 0.5 deg -> sin(60 deg) = 0.8660254 -> 5.4126588e-5; psi -60 deg -> sin(0) = 0."""
    assert err("worm_runout", {"amplitude_um": 10.0, "phase_deg": 0.0}, math.pi / 360)[0] == \
        pytest.approx(5.4126588e-5, rel=1e-8)
    assert err("worm_runout", {"amplitude_um": 10.0, "phase_deg": -60.0}, math.pi / 360)[0] == \
        pytest.approx(0.0, abs=1e-15)


def test_gear_mesh_error_by_hand():
    """(a / r_1) sin(z1 theta + psi): a 5 um, r_1 100 mm -> 5e-5 rad peak; theta 0.6 deg -> sin(30 deg);
    psi 60 deg -> sin(90 deg): the peak."""
    assert err("gear_mesh_error", {"amplitude_um": 5.0, "phase_deg": 0.0}, math.pi / 300)[0] == \
        pytest.approx(2.5e-5, rel=1e-12)
    assert err("gear_mesh_error", {"amplitude_um": 5.0, "phase_deg": 60.0}, math.pi / 300)[0] == \
        pytest.approx(5e-5, rel=1e-12)


def test_thermal_backlash_by_hand():
    """Delta B = 2 k (T - T_ref) tan(alpha_x) / r_wheel / i_c = 2 * 0.002 * 10 * 0.4 / 40 / 4 = 1e-4 rad;
    forward (d = +1) -Delta B/2 = -5e-5, reverse +5e-5 (a growing centre distance grows lost motion)."""
    keys = {"centre_distance_um_per_K": 2.0, "reference_temperature_C": 20.0}
    e = err("thermal_backlash", keys, [0.0, 0.0], direction=np.array([1.0, -1.0]), temperature=30.0)
    np.testing.assert_allclose(e, [-5e-5, 5e-5], rtol=1e-12)


def test_thermal_drift_by_hand():
    """k (T - T_ref): 2 arcsec/K * (25 - 20) K = 10 arcsec in both directions (T_ref default 20 degC)."""
    e = err("thermal_drift", {"arcsec_per_K": 2.0}, [0.0, 0.0], direction=np.array([1.0, -1.0]), temperature=25.0)
    np.testing.assert_allclose(e / AS, [10.0, 10.0], rtol=1e-12)


def test_torsional_compliance_by_hand():
    """load / k: 100 N m / (50 N m/arcsec) = 2 arcsec, both directions."""
    e = err("torsional_compliance", {"stiffness_Nm_per_arcsec": 50.0}, [0.0, 0.0],
            direction=np.array([1.0, -1.0]), load=100.0)
    np.testing.assert_allclose(e / AS, [2.0, 2.0], rtol=1e-12)


def test_bearing_clearance_by_hand():
    """-d c / 2: 8 arcsec -> forward -4, reverse +4 arcsec."""
    e = err("bearing_clearance", {"clearance_arcsec": 8.0}, [0.0, 0.0], direction=np.array([1.0, -1.0]))
    np.testing.assert_allclose(e / AS, [-4.0, 4.0], rtol=1e-12)


def test_orders_on_the_explicit_geometry():
    assert EFFECTS["output_gear_runout"].order(G) == 1.0
    assert EFFECTS["intermediate_shaft_runout"].order(G) == 4.0
    assert EFFECTS["worm_runout"].order(G) == 120.0
    assert EFFECTS["gear_mesh_error"].order(G) == 50.0


# --- default phases ------------------------------------------------------------------------------


@pytest.mark.parametrize("name, amp_key, theta, peak", [
    ("output_gear_runout", "eccentricity_um", math.pi / 2, 20e-3 / 80.0),       # sin(pi/2)
    ("intermediate_shaft_runout", "eccentricity_um", math.pi / 8, 20e-3 / 80.0),  # sin(4 * pi/8)
    ("worm_runout", "amplitude_um", math.pi / 240, 20e-3 / 40.0 / 4.0),        # sin(120 * pi/240)
    ("gear_mesh_error", "amplitude_um", math.pi / 100, 20e-3 / 100.0),         # sin(50 * pi/100)
])
def test_effect_without_phase_deg_has_phase_zero(name, amp_key, theta, peak):
    """An effect given without ``phase_deg`` is a sine through zero at theta = 0 (phase 0 deg):
    value 0 at theta = 0 and the full amplitude a quarter period later.  A default of 90 deg would
    put the peak at theta = 0 and zero at the quarter period."""
    keys = {amp_key: 20.0}
    assert params_from_keys(name, keys)["phase"] == 0.0
    assert err(name, keys, 0.0)[0] == pytest.approx(0.0, abs=1e-18)
    assert err(name, keys, theta)[0] == pytest.approx(peak, rel=1e-12)
    assert EFFECTS[name].param("phase_deg").default == 0.0


def test_spec_default_phases_are_zero():
    """The drive spec's phase keys default to 0 deg: a spec without them loads phases of exactly 0,
    and an [effects] table without phase_deg gets phase 0."""
    from tests.support.specs import SPEC_HEAD
    from wormgear_cli.spec.loader import loads_spec

    spec = loads_spec(SPEC_HEAD + "[effects.gear_mesh_error]\namplitude_um = 3\n", "d.toml")
    assert spec.worm_pair.lead_error_phase == 0.0
    assert spec.worm_pair.wheel.radial_composite_phase == 0.0
    assert spec.assembly.gear_eccentricity_phase == 0.0
    assert spec.assembly.worm_eccentricity_phase == 0.0
    assert spec.assembly.wheel_eccentricity_phase == 0.0
    assert spec.effects["gear_mesh_error"]["phase"] == 0.0
    assert spec.effects["gear_mesh_error"]["amplitude"] == pytest.approx(3e-3, rel=1e-12)


def test_params_to_keys_converts_back_by_hand():
    """0.0125 mm -> 12.5 um; pi/2 rad -> 90 deg; a parameter not given is left out."""
    assert params_to_keys("output_gear_runout", {"eccentricity": 0.0125, "phase": math.pi / 2}) == \
        pytest.approx({"eccentricity_um": 12.5, "phase_deg": 90.0}, rel=1e-12)
    assert params_to_keys("output_gear_runout", {"eccentricity": 0.0125}) == pytest.approx({"eccentricity_um": 12.5})
    # the stiffness key: 2 N m/arcsec = 2 / (pi/648000) N m/rad
    assert params_from_keys("torsional_compliance", {"stiffness_Nm_per_arcsec": 2.0})["stiffness"] == \
        pytest.approx(2.0 * 648000.0 / math.pi, rel=1e-12)


def test_signals_make_broadcasts_every_signal_as_float():
    """Scalars broadcast to theta's shape; integers become floats (angles and temperatures are real)."""
    s = Signals.make(np.array([0, 1, 2]), direction=-1, load=2, temperature=25, time=3)
    for name, value in (("theta", [0.0, 1.0, 2.0]), ("direction", [-1.0] * 3), ("load", [2.0] * 3),
                        ("temperature", [25.0] * 3), ("time", [3.0] * 3)):
        arr = getattr(s, name)
        assert arr.dtype == np.float64, name
        np.testing.assert_array_equal(arr, value, err_msg=name)
    d = Signals.make([0.5, 1.5])
    np.testing.assert_array_equal(d.direction, [1.0, 1.0])
    np.testing.assert_array_equal(d.load, [0.0, 0.0])
    np.testing.assert_array_equal(d.temperature, [20.0, 20.0])
    np.testing.assert_array_equal(d.time, [0.0, 0.0])


def test_phase_parameter_record():
    """The phase parameter of every periodic effect: key phase_deg, internal name phase, unit deg,
    scale pi/180, range [-360, 360] deg, default 0 deg."""
    for name in ("output_gear_runout", "intermediate_shaft_runout", "worm_runout", "gear_mesh_error"):
        p = EFFECTS[name].param("phase_deg")
        assert (p.key, p.name, p.unit, p.lo, p.hi, p.default) == ("phase_deg", "phase", "deg", -360.0, 360.0, 0.0)
        assert p.scale == pytest.approx(math.pi / 180.0, rel=1e-15)
        assert p.doc == "phase of the error at theta = 0"
        assert EFFECTS[name].phase == "phase"


def test_reference_temperature_parameter_record():
    """The reference temperature of the thermal effects: key reference_temperature_C, internal name
    reference_temperature, unit degC, scale 1, range [-50, 150] degC, default 20 degC."""
    for name in ("thermal_backlash", "thermal_drift"):
        p = EFFECTS[name].param("reference_temperature_C")
        assert (p.key, p.name, p.unit, p.scale, p.lo, p.hi, p.default) == (
            "reference_temperature_C", "reference_temperature", "degC", 1.0, -50.0, 150.0, 20.0)
        assert p.doc == "temperature at which the effect is zero"
    # used: a drift of 2 arcsec/K seen at 25 degC with the reference at 30 degC is -10 arcsec
    e = err("thermal_drift", {"arcsec_per_K": 2.0, "reference_temperature_C": 30.0}, [0.0], temperature=25.0)
    assert e[0] / AS == pytest.approx(-10.0, rel=1e-12)
