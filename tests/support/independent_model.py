"""Measurements for the diagnosis statistics tests, written from the physics alone.

Nothing here calls ``wormgear_cli.analysis.simulate`` or the effect registry.  The drive is a
"perfect" drive (every tolerance, clearance and load of the spec zero), so the spec's own
model is zero and the measured error is the hidden effects plus noise:

* geometry of the spec below, by hand: output gear m 2.5, z1 144, alpha 20 deg -> pitch radius
  r_1 = 180 mm, base radius r_b1 = 180 cos 20 deg = 169.1447 mm; pinion z2 18 -> i_c = 8;
  worm module 2.5, wheel z3 30 -> r_wheel = 37.5 mm, single start -> worm order 240;
  alpha_n 20 deg, lead angle 3.178 deg -> tan(alpha_x) = tan(alpha_n)/cos(lambda) (DIN 3975, ZN).
* effects (output error, actual - target):
  runout of a shaft turning k times per output turn with eccentricity e at a radius r seen
  through the base circle: (e / r) sin(k theta + psi); thermal drift: k (T - T_ref); wind-up
  under a torque M of a drive of stiffness c: M / c; a lost motion L (bearing clearance, or
  the backlash change 2 k dT tan(alpha_x) of a centre distance growing k per kelvin, reduced
  to the output through r_wheel and i_c) shows as -d L / 2 in direction d.
* noise: a nested random intercept model -- one offset per run (N(0, s_run^2), shared by both
  directions of the run), one per pass (a run in one direction, N(0, s_pass^2)) and white
  noise per point (N(0, s_white^2)), in arcsec.

Targets: ``targets`` angles drawn once per data set, uniformly over a turn (irregular spacing,
so no order of interest aliases); every run visits them forward then in reverse.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass

import numpy as np

ARCSEC = math.pi / 648000.0  # rad

SPEC_TOML = """
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

R_1 = 2.5 * 144 / 2.0
R_B1 = R_1 * math.cos(math.radians(20.0))
I_C = 144 / 18
R_WHEEL = 2.5 * 30 / 2.0
N_W = I_C * 30
TAN_ALPHA_X = math.tan(math.radians(20.0)) / math.cos(math.radians(3.178))


def perfect_spec():
    """The drive above with every error source, clearance and load set to zero, and made stiff
    (face widths 5000 mm): its own wind-up under an external torque is then 1.5e-4 arcsec/(N m),
    below 0.2 % of the compliance 1/c >= 0.1 arcsec/(N m) the stiffness tests hide (a bias far
    inside their intervals).  The generator adds no wind-up of its own."""
    from wormgear_cli.spec.loader import loads_spec, with_values

    spec = loads_spec(SPEC_TOML, "independent.toml")
    zero = dict.fromkeys(("assembly.gear_centre_distance_error_mm", "assembly.worm_centre_distance_error_mm", "assembly.worm_eccentricity_mm", "assembly.worm_bearing_clearance_mm", "assembly.wheel_eccentricity_mm", "assembly.wheel_bearing_clearance_mm", "assembly.gear_eccentricity_mm", "worm_pair.lead_error_mm", "worm_pair.worm.profile_error_mm", "worm_pair.wheel.profile_error_mm", "worm_pair.worm.thickness_deviation_mm", "worm_pair.wheel.thickness_deviation_mm", "worm_pair.wheel.radial_composite_error_mm", "loads.gear_normal_force_N", "loads.worm_normal_force_N"), 0.0)
    zero["assembly.worm_pair_errors_mm"] = [0.0] * 6
    zero["gear_pair.face_width_mm"] = 5000.0
    zero["worm_pair.face_width_mm"] = 5000.0
    return with_values(spec, zero)


def effect_arcsec(name: str, p: dict, theta, d, load, temp) -> np.ndarray:
    """Effect ``name`` [arcsec] with parameters ``p`` in catalogue units (see the module doc)."""
    psi = math.radians(p.get("phase_deg", 0.0))
    t_ref = p.get("reference_temperature_C", 20.0)
    zero = np.zeros_like(theta)
    if name == "output_gear_runout":
        return p["eccentricity_um"] * 1e-3 / R_B1 * np.sin(theta + psi) / ARCSEC
    if name == "intermediate_shaft_runout":
        return p["eccentricity_um"] * 1e-3 / R_B1 * np.sin(I_C * theta + psi) / ARCSEC
    if name == "worm_runout":
        return p["amplitude_um"] * 1e-3 / R_WHEEL / I_C * np.sin(N_W * theta + psi) / ARCSEC
    if name == "gear_mesh_error":
        return p["amplitude_um"] * 1e-3 / R_1 * np.sin(144 * theta + psi) / ARCSEC
    if name == "thermal_drift":
        return p["arcsec_per_K"] * (temp - t_ref) + zero
    if name == "torsional_compliance":
        return load / p["stiffness_Nm_per_arcsec"] + zero
    if name == "bearing_clearance":
        return -d * p["clearance_arcsec"] / 2.0
    if name == "thermal_backlash":
        lost = 2.0 * p["centre_distance_um_per_K"] * 1e-3 * (temp - t_ref) * TAN_ALPHA_X / R_WHEEL / I_C
        return -d * lost / 2.0 / ARCSEC
    raise KeyError(name)


@dataclass(frozen=True)
class Design:
    """A measurement plan: ``runs`` runs over ``targets`` targets, forward then reverse.
    ``temperature``: per-run temperatures [degC] cycled over the runs (heating and cooling, so
    temperature is not collinear with the run index); ``loads``: per-run torques [N m] cycled."""

    runs: int = 6
    targets: int = 24
    temperature: tuple = (20.0,)
    loads: tuple = (0.0,)
    s_run: float = 0.5
    s_pass: float = 0.3
    s_white: float = 0.4


def rows(design: Design, seed: int):
    """(theta [rad], direction, run, load, temperature) of every row of the plan."""
    rng = np.random.default_rng(seed)
    targets = np.sort(rng.uniform(0.0, 2 * np.pi, design.targets))
    theta, d, run, load, temp = [], [], [], [], []
    for r in range(design.runs):
        t = design.temperature[r % len(design.temperature)]
        m = design.loads[r % len(design.loads)]
        for direction, order in ((1.0, targets), (-1.0, targets[::-1])):
            theta.append(order)
            d.append(np.full(order.shape, direction))
            run.append(np.full(order.shape, r + 1))
            load.append(np.full(order.shape, m))
            temp.append(np.full(order.shape, t))
    return tuple(np.concatenate(a) for a in (theta, d, run, load, temp))


def noise(design: Design, run, d, rng) -> np.ndarray:
    """Nested run / pass / white noise [arcsec] for rows with ``run`` and direction ``d``."""
    runs = np.unique(run)
    u = dict(zip(runs, rng.normal(0.0, design.s_run, runs.shape[0])))
    v = {(r, s): rng.normal(0.0, design.s_pass) for r in runs for s in (1.0, -1.0)}
    return (np.array([u[r] for r in run]) + np.array([v[(r, s)] for r, s in zip(run, d)])
            + rng.normal(0.0, design.s_white, run.shape[0]))


def measurement(design: Design, hidden: dict, seed: int):
    """A :class:`~wormgear_cli.measurement.reader.Measurement` of the perfect drive with ``hidden``
    effects ({name: catalogue-unit parameters}) and the design's noise, via the CSV reader."""
    from wormgear_cli.measurement.readers import parse_measurement

    theta, d, run, load, temp = rows(design, seed)
    rng = np.random.default_rng(10_000 + seed)
    y = noise(design, run, d, rng)
    for name, p in hidden.items():
        y = y + effect_arcsec(name, p, theta, d, load, temp)
    out = io.StringIO()
    out.write("angle_deg,error_arcsec,direction,run,load_Nm,temperature_C\n")
    for row in zip(np.degrees(theta), y, d, run, load, temp):
        out.write(f"{row[0]:.12g},{row[1]:.12g},{int(row[2])},{int(row[3])},{row[4]:.12g},{row[5]:.12g}\n")
    return parse_measurement(out.getvalue(), f"independent-{seed}.csv")
