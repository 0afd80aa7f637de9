"""Two-temperature warm-up: the mesh (recorded) warms further and faster than the housing.

Covers ``models/thermal.py`` (mesh_housing_warmup, centre_distance_change_mm, the
prediction with a housing rise ratio) and what ``synth`` makes of a ``mesh-warmup``
programme and of ``--cycles``.  Golden values are hand calculations (stated below);
the synthetic error is checked against the lag equation integrated numerically, an
independent path from the closed form the code uses.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.paths import MCH50
from wormgear_cli.analysis.synth import Plan, parse_temperature, synthesize
from wormgear_cli.cli import app
from wormgear_cli.errors import UsageError
from wormgear_cli.physics.thermal import (
    centre_distance_change_mm,
    mesh_housing_warmup,
    predicted_centre_distance_um_per_K,
)

ARCSEC_PER_RAD = 648000.0 / math.pi


# --- models/thermal.py ---------------------------------------------------------------------------------------------


def test_prediction_with_a_housing_share_mch50_by_hand(mch50_spec):
    # hand calculation: d_m1 = 2.5 / tan(3.178 deg) = 45.026 mm, r1 = 22.513, r2 = 2.5 * 30 / 2 = 37.5, a = 60.013 mm;
    # k = a alpha_H q - (r1 alpha_1 + r2 alpha_2) = 60.013 * 10.5e-6 * 0.4 - (22.513 * 11.5e-6 + 37.5 * 18.5e-6)
    #   = 2.5205e-4 - 9.5265e-4 = -7.006e-4 mm/K = -0.7006 um/K   (to 5e-4 um/K: rounding of the radii)
    assert predicted_centre_distance_um_per_K(mch50_spec, 0.4) == pytest.approx(-0.7006, abs=5e-4)
    # q = 1 is the uniform case of the catalogue's default prediction (-0.3225 um/K, docs/models)
    assert predicted_centre_distance_um_per_K(mch50_spec, 1.0) == pytest.approx(-0.3225, abs=5e-4)
    assert predicted_centre_distance_um_per_K(mch50_spec) == predicted_centre_distance_um_per_K(mch50_spec, 1.0)
    # a housing that does not warm at all: only the worm and wheel grow, -0.9527 um/K
    assert predicted_centre_distance_um_per_K(mch50_spec, 0.0) == pytest.approx(-0.9527, abs=5e-4)


def test_centre_distance_change_is_housing_growth_minus_member_growth(mch50_spec):
    # housing 10 K, members 0 K: +a alpha_H 10 = 60.013 * 10.5e-6 * 10 = 6.301e-3 mm
    assert centre_distance_change_mm(mch50_spec, 0.0, 10.0) == pytest.approx(6.301e-3, abs=2e-6)
    # members 10 K, housing 0 K: -(22.513 * 11.5e-6 + 37.5 * 18.5e-6) * 10 = -9.527e-3 mm
    assert centre_distance_change_mm(mch50_spec, 10.0, 0.0) == pytest.approx(-9.527e-3, abs=2e-6)
    got = centre_distance_change_mm(mch50_spec, np.array([0.0, 5.0, 25.0]), np.array([0.0, 2.0, 10.0]))
    assert got.shape == (3,) and got[0] == 0.0 and got[2] < got[1] < 0.0


def _integrate_lag(t, rise, tau, share, lag, steps=200_000):
    """Housing rise by explicit integration of tau_L dH/dt = s m(t) - H (fine steps, the mesh rise m taken
    at each step's middle): an independent path.  The steps H_i = H_(i-1) + dt (s m_i - H_(i-1)) / tau_L
    run as scipy's linear recursive filter, H_i = (1 - dt/tau_L) H_(i-1) + (dt/tau_L) s m_i."""
    from scipy.signal import lfilter

    grid = np.linspace(0.0, float(np.max(t)), steps)
    dt = grid[1] - grid[0]
    m_mid = rise * (1.0 - np.exp(-(grid[:-1] + dt / 2) / tau))  # steps 1 .. steps - 1
    h = np.zeros_like(grid)
    if lag > 0:
        h[1:] = lfilter([dt / lag * share], [1.0, -(1.0 - dt / lag)], m_mid)
    else:
        h[1:] = share * m_mid
    return np.interp(t, grid, h)


@pytest.mark.parametrize("lag", [180.0, 1200.0, 2400.0, 6000.0])
def test_housing_follows_the_lag_equation(lag):
    t = np.array([0.0, 60.0, 600.0, 2400.0, 7200.0, 20000.0])
    mesh, housing = mesh_housing_warmup(t, 25.0, 2400.0, 0.4, lag)
    assert mesh == pytest.approx(25.0 * (1.0 - np.exp(-t / 2400.0)))
    assert housing == pytest.approx(_integrate_lag(t, 25.0, 2400.0, 0.4, lag), abs=2e-3)
    # further and faster: the mesh is ahead of the housing at every time, and the housing ends at 0.4 of it
    assert np.all(housing[1:] < mesh[1:]) and np.all(housing[1:] <= 0.4 * mesh[1:] + 1e-12)
    assert housing[-1] == pytest.approx(0.4 * 25.0, rel=0.05 if lag < 3000 else 0.2)


def test_no_lag_keeps_the_housing_proportional():
    t = np.linspace(0.0, 9000.0, 7)
    mesh, housing = mesh_housing_warmup(t, 30.0, 1800.0, 0.25, 0.0)
    assert housing == pytest.approx(0.25 * mesh)


# --- synth with a mesh-warmup --------------------------------------------------------------------------------------


def _synth(spec, temp, effects, **plan):
    return synthesize(spec, plan=Plan(kind="iso", targets=8, runs=2, **plan), effects=effects, seed=3,
                      temperature=parse_temperature(temp), random_phases=True)


@pytest.mark.parametrize("share, lag", [(0.4, 180.0), (0.6, 900.0)])
def test_synth_backlash_is_the_two_temperature_physics(mch50_spec, share, lag):
    temp = f"mesh-warmup:20:45:1500:{share}:{lag}"
    with_it = _synth(mch50_spec, temp, {"thermal_backlash": {}})
    without = _synth(mch50_spec, temp, {})
    cols = with_it.columns
    diff = (cols["error_arcsec"] - without.columns["error_arcsec"]) / ARCSEC_PER_RAD  # [rad]
    # independent path: housing by integrating the lag, Delta a by hand, backlash change 2 Delta a tan(alpha_t) at the
    # wheel pitch circle (r2 = 37.5 mm), divided by the spur ratio 144/18 = 8, half of it per direction, closing (-)
    t = cols["time_s"]
    mesh_dt = cols["temperature_C"] - 20.0
    housing_dt = _integrate_lag(t, 25.0, 1500.0, share, lag)
    r1 = 2.5 / math.tan(math.radians(3.178)) / 2.0
    a = r1 + 37.5
    delta_a = a * 10.5e-6 * housing_dt - (r1 * 11.5e-6 + 37.5 * 18.5e-6) * mesh_dt
    alpha_t = math.atan(math.tan(math.radians(20.0)) / math.cos(math.radians(3.178)))
    want = -cols["direction"] * (2.0 * delta_a * math.tan(alpha_t) / 37.5 / 8.0) / 2.0
    assert diff == pytest.approx(want, abs=2e-4 / ARCSEC_PER_RAD)  # 0.0001" rounding of the error column
    thermal = with_it.truth["thermal"]
    assert thermal["housing_share"] == share and thermal["housing_lag_s"] == lag
    # the truth's coefficient is the physics' own (housing share q = s)
    k = with_it.truth["effects"]["thermal_backlash"]["centre_distance_um_per_K"]
    assert k == predicted_centre_distance_um_per_K(mch50_spec, share)
    assert with_it.truth["effects"]["thermal_backlash"]["reference_temperature_C"] == 20.0
    # the lag leaves a non-linearity: the physical term minus the best linear term in the recorded temperature
    k_lin = float(np.sum(delta_a * mesh_dt) / np.sum(mesh_dt ** 2))
    assert thermal["linear_equivalent_um_per_K"] == pytest.approx(k_lin * 1000.0, abs=2e-3)
    dev = (want - (-cols["direction"] * k_lin * mesh_dt * math.tan(alpha_t) / 37.5 / 8.0)) * ARCSEC_PER_RAD
    assert thermal["nonlinearity_rms_arcsec"] == pytest.approx(float(np.sqrt(np.mean(dev ** 2))), abs=2e-3)
    assert thermal["nonlinearity_max_arcsec"] == pytest.approx(float(np.max(np.abs(dev))), abs=5e-3)


def test_no_lag_means_no_nonlinearity(mch50_spec):
    res = _synth(mch50_spec, "mesh-warmup:20:40:1200:0.5:0", {"thermal_backlash": {}})
    th = res.truth["thermal"]
    # left: the recorded temperature's rounding to 0.001 K (0.0005 K x 0.18"/K = 1e-4")
    assert th["nonlinearity_max_arcsec"] == pytest.approx(0.0, abs=2e-4)
    assert th["linear_equivalent_um_per_K"] == pytest.approx(th["predicted_um_per_K"], rel=1e-5)


def test_mesh_warmup_records_the_mesh_and_keeps_the_housing_out_of_the_data(mch50_spec):
    res = _synth(mch50_spec, "mesh-warmup:20:45:2400:0.4:180", {"thermal_backlash": {}})
    assert set(res.columns) == {"angle_deg", "error_arcsec", "direction", "run", "load_Nm", "temperature_C", "time_s"}
    t = res.columns["time_s"]
    assert res.columns["temperature_C"] == pytest.approx(20.0 + 25.0 * (1.0 - np.exp(-t / 2400.0)), abs=5e-4)
    assert res.truth["temperature"] == {"kind": "mesh-warmup", "start": 20.0, "end": 45.0, "tau_s": 2400.0,
                                        "housing_share": 0.4, "housing_lag_s": 180.0}
    assert res.comments[2].startswith("# temperature: warmup 20 -> 45 degC, tau 2400 s (sensor at the worm mesh)")


def test_explicit_coefficient_with_a_mesh_warmup_is_refused(mch50_spec):
    with pytest.raises(UsageError, match="give a bare --effect thermal_backlash"):
        _synth(mch50_spec, "mesh-warmup:20:45:2400:0.4:180",
               {"thermal_backlash": {"centre_distance_um_per_K": -0.5}})


@pytest.mark.parametrize("text, message", [
    ("mesh-warmup:20:45:2400:1.5:180", "HOUSING_SHARE must be in [0, 1]"),
    ("mesh-warmup:20:45:2400:0.4:-1", "HOUSING_LAG_s must be >= 0"),
    ("mesh-warmup:20:45:2400:0.4", "mesh-warmup:START:END:TAU_s:HOUSING_SHARE:HOUSING_LAG_s, got"),
])
def test_bad_mesh_warmup_is_refused(text, message):
    with pytest.raises(UsageError, match=r".*".join(map(__import__("re").escape, message.split("[")))):
        parse_temperature(text)


# --- cycles ---------------------------------------------------------------------------------------------------------


def test_cycles_repeat_the_runs_with_a_gap(mch50_spec):
    plan = Plan(kind="iso", targets=6, runs=5, dwell_s=10.0, cycles=3, cycle_gap_s=600.0)
    res = synthesize(mch50_spec, plan=plan, seed=2)
    cols = res.columns
    n_run = 2 * 6
    assert len(cols["angle_deg"]) == 3 * 5 * n_run
    assert list(np.unique(cols["run"])) == list(range(1, 16))
    # each run the same targets, forward then reverse
    first = cols["angle_deg"][:n_run]
    for r in range(15):
        assert list(cols["angle_deg"][r * n_run:(r + 1) * n_run]) == list(first)
    # within a cycle 10 s per point; between cycles 10 s + the 600 s gap
    steps = np.diff(cols["time_s"])
    jumps = np.flatnonzero(steps > 10.0 + 1e-9)
    assert list(jumps + 1) == [5 * n_run, 10 * n_run]
    assert steps[jumps] == pytest.approx([610.0, 610.0])
    assert res.truth["plan"]["cycles"] == 3 and res.truth["plan"]["cycle_gap_s"] == 600.0
    assert "3 cycles of 5 runs (600 s between cycles)" in res.comments[1]
    assert len(res.truth["noise"]["run_values_arcsec"]) == 15


def test_one_cycle_keeps_the_truth_and_comments_as_before(mch50_spec):
    res = synthesize(mch50_spec, plan=Plan(kind="iso", targets=6, runs=2), seed=2)
    assert "cycles" not in res.truth["plan"] and "cycle_gap_s" not in res.truth["plan"]
    assert res.comments[1].endswith("2 runs, each forward (+1) then reverse (-1); 10 s per point")


def test_cycles_on_the_command_line(runner, tmp_path):
    out = tmp_path / "d.csv"
    r = runner.invoke(app, ["synth", str(MCH50), "-o", str(out), "--targets", "4", "--runs", "2", "--cycles", "2",
                            "--cycle-gap-s", "300"])
    assert r.exit_code == 0, r.stderr
    rows = [line.split(",") for line in out.read_text().splitlines() if not line.startswith("#")][1:]
    assert len(rows) == 2 * 2 * 2 * 4 and rows[-1][3] == "4"
    bad = runner.invoke(app, ["synth", str(MCH50), "--cycles", "0"])
    assert bad.exit_code == 2
