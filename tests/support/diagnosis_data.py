"""Hidden-effect measurements for the diagnose tests, built independently of the code under test.

The hidden effects are the catalogue formulas written out here from the
issue's table, with the MCH50 geometry computed from Table 1 by hand (not
through ``wormgear_cli.analysis.accuracy`` or the effect registry).  Only the spec's
own model (what ``diagnose`` fits against) comes from
``wormgear_cli.analysis.simulate.simulate``.  Noise: white per point plus one
offset per run (both directions of a run share it).

tests/diagnosis/test_data.py checks the hand-written formulas against the
registry, so the two paths must agree before the data are trusted.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass

import numpy as np

from wormgear_cli.diagnosis import diagnose, report
from wormgear_cli.measurement.readers import parse_measurement
from wormgear_cli.spec.loader import with_values
from wormgear_cli.units import ARCSEC

# --- MCH50 geometry from Table 1 (module 2.5 mm; z1 = 144, z2 = 18, wheel z3 = 30, single-start worm) --------------
MODULE = 2.5
Z1, Z2, Z3 = 144, 18, 30
ALPHA = math.radians(20.0)
LEAD = math.radians(3.178)
I_C = Z1 / Z2  # 8
N_W = I_C * Z3  # 240 worm turns per output turn
R_1 = MODULE * Z1 / 2.0  # output gear pitch radius, 180 mm
R_B1 = R_1 * math.cos(ALPHA)  # its base radius
R_WHEEL = MODULE * Z3 / 2.0  # 37.5 mm
ALPHA_X = math.atan(math.tan(ALPHA) / math.cos(LEAD))  # axial pressure angle of a ZN-type worm (DIN 3975)


def hidden_error(name: str, p: dict, theta, d, load, temp) -> np.ndarray:
    """The catalogue effect ``name`` [arcsec] from the issue's formulas (parameters in catalogue units)."""
    ph = math.radians(p.get("phase_deg", 0.0))
    t_ref = p.get("reference_temperature_C", 20.0)
    if name == "output_gear_runout":
        rad = p["eccentricity_um"] * 1e-3 / R_B1 * np.sin(theta + ph)
    elif name == "intermediate_shaft_runout":
        rad = p["eccentricity_um"] * 1e-3 / R_B1 * np.sin(I_C * theta + ph)
    elif name == "worm_runout":
        rad = p["amplitude_um"] * 1e-3 / R_WHEEL / I_C * np.sin(N_W * theta + ph)
    elif name == "gear_mesh_error":
        rad = p["amplitude_um"] * 1e-3 / R_1 * np.sin(Z1 * theta + ph)
    elif name == "thermal_backlash":
        delta_b = 2.0 * p["centre_distance_um_per_K"] * 1e-3 * (temp - t_ref) * math.tan(ALPHA_X) / R_WHEEL / I_C
        rad = -d * delta_b / 2.0
    elif name == "thermal_drift":
        return p["arcsec_per_K"] * (temp - t_ref) + 0.0 * theta
    elif name == "torsional_compliance":
        return load / p["stiffness_Nm_per_arcsec"] + 0.0 * theta
    elif name == "bearing_clearance":
        return -d * p["clearance_arcsec"] / 2.0 + 0.0 * theta
    else:
        raise KeyError(name)
    return rad / ARCSEC


@dataclass(frozen=True)
class Plan:
    """A measurement plan: ``kind`` "iso" (jittered targets), "even" (evenly spaced) or "dense";
    ``runs`` each forward then reverse (``directions`` (1, -1)) or forward only ((1,));
    ``warmup``: (T0, T1, tau_s) or None (no temperature column); ``loads``: torque per run, cycling,
    or None (no load column); ``dwell_s`` per point."""

    kind: str = "iso"
    targets: int = 24
    runs: int = 5
    directions: tuple = (1, -1)
    warmup: tuple | None = None
    loads: tuple | None = None
    dwell_s: float = 10.0


def make_rows(plan: Plan, rng: np.random.Generator) -> dict:
    n = plan.targets
    if plan.kind == "iso":
        step = 360.0 / n
        angles = np.arange(n) * step + np.concatenate([[0.0], rng.uniform(-0.3 * step, 0.3 * step, n - 1)])
    else:
        angles = np.arange(n) * 360.0 / n
    angles = np.round(angles, 4)
    blocks = []
    for r in range(1, plan.runs + 1):
        for d in plan.directions:
            a = angles if d > 0 else angles[::-1]
            blocks.append((a, np.full(n, d), np.full(n, r)))
    angle = np.concatenate([b[0] for b in blocks])
    direction = np.concatenate([b[1] for b in blocks]).astype(float)
    run = np.concatenate([b[2] for b in blocks])
    time = np.arange(angle.shape[0]) * plan.dwell_s
    rows = {"angle_deg": angle, "direction": direction, "run": run, "time_s": time}
    if plan.warmup is not None:
        t0, t1, tau = plan.warmup
        rows["temperature_C"] = np.round(t0 + (t1 - t0) * (1.0 - np.exp(-time / tau)), 3)
    if plan.loads is not None:
        rows["load_Nm"] = np.asarray(plan.loads, dtype=float)[(run - 1) % len(plan.loads)]
    return rows


def make_csv(spec, plan: Plan, hidden: dict | None = None, seed: int = 0, white: float = 0.3,
             run_sd: float = 0.2, phases: str = "random", offset: float = 0.7, decoy=None):
    """(CSV text, truth dict): the spec's model at random (or the spec's) phases plus the hidden
    effects, an optional decoy callable(theta, d) -> arcsec, a zero offset, and noise."""
    from wormgear_cli.analysis.simulate import periodic_sources, simulate
    from wormgear_cli.physics.effects import Signals

    rng = np.random.default_rng(seed)
    rows = make_rows(plan, rng)
    theta = np.radians(rows["angle_deg"])
    d = rows["direction"]
    load = rows.get("load_Nm", np.zeros_like(theta))
    temp = rows.get("temperature_C", np.full_like(theta, 20.0))
    names = [s.name for s in periodic_sources(spec)]
    used = {n: float(rng.uniform(0, 2 * math.pi)) for n in names} if phases == "random" else None
    model = simulate(spec, Signals(theta, d, load, temp, rows["time_s"]), used) / ARCSEC
    signal = np.zeros_like(theta)
    for name, params in (hidden or {}).items():
        signal = signal + hidden_error(name, params, theta, d, load, temp)
    if decoy is not None:
        signal = signal + decoy(theta, d)
    noise = rng.normal(0.0, white, theta.shape) + rng.normal(0.0, run_sd, plan.runs)[rows["run"] - 1]
    rows["error_arcsec"] = np.round(model + signal + offset + noise, 5)
    cols = ["angle_deg", "error_arcsec", "direction", "run", "time_s"]
    cols += [c for c in ("load_Nm", "temperature_C") if c in rows]
    out = io.StringIO()
    out.write("# test data: the spec's model plus hidden effects (see tests/diagnosis/test_data.py)\n")
    out.write(",".join(cols) + "\n")
    for i in range(theta.shape[0]):
        out.write(",".join(_cell(rows[c][i]) for c in cols) + "\n")
    truth = {"hidden": hidden or {}, "phases": used, "signal_rms": float(np.sqrt(np.mean(signal**2)))}
    return out.getvalue(), truth


def _cell(v) -> str:
    v = float(v)
    return str(int(v)) if v == int(v) else repr(v)


def make_measurement(spec, plan: Plan, **kw):
    from wormgear_cli.measurement.readers import parse_measurement

    text, truth = make_csv(spec, plan, **kw)
    return parse_measurement(text, "<test>"), truth


#: spec variants without periodic sources on one shaft (so a catalogue effect on that order is identifiable)
NO_ORDER_8 = {"assembly.gear_eccentricity_mm": 0.0, "assembly.wheel_eccentricity_mm": 0.0,
              "assembly.wheel_bearing_clearance_mm": 0.0, "worm_pair.wheel.radial_composite_error_mm": 0.0}
NO_ORDER_240 = {"worm_pair.lead_error_mm": 0.0, "assembly.worm_eccentricity_mm": 0.0,
                "assembly.worm_bearing_clearance_mm": 0.0}


# --- the hand-written formulas agree with the registry ---------------------------------------------------------------

CASES = {
    "output_gear_runout": {"eccentricity_um": 7.0, "phase_deg": 33.0},
    "intermediate_shaft_runout": {"eccentricity_um": 5.0, "phase_deg": -70.0},
    "worm_runout": {"amplitude_um": 3.0, "phase_deg": 120.0},
    "gear_mesh_error": {"amplitude_um": 2.0, "phase_deg": 10.0},
    "thermal_backlash": {"centre_distance_um_per_K": -0.5, "reference_temperature_C": 21.0},
    "thermal_drift": {"arcsec_per_K": 0.4, "reference_temperature_C": 19.0},
    "torsional_compliance": {"stiffness_Nm_per_arcsec": 25.0},
    "bearing_clearance": {"clearance_arcsec": 4.0},
}


# --- plans and helpers shared by the diagnosis tests ------------------------------------------------------------

WARM = (20.0, 35.0, 1200.0)
STEPS = (0.0, 250.0, -250.0)

#: each catalogue effect hidden alone at a realistic size, with the signals it needs varying:
#: name -> (spec changes, plan, parameters in catalogue units, keys to check against the 95 % interval)
HIDDEN = {
    "output_gear_runout": ({}, Plan(), {"eccentricity_um": 8.0, "phase_deg": 40.0}, ("eccentricity_um", "phase_deg")),
    "intermediate_shaft_runout": (NO_ORDER_8, Plan(), {"eccentricity_um": 6.0, "phase_deg": -110.0},
                                  ("eccentricity_um", "phase_deg")),
    "worm_runout": (NO_ORDER_240, Plan(kind="dense", targets=1000, runs=2, dwell_s=1.0),
                    {"amplitude_um": 3.0, "phase_deg": 75.0}, ("amplitude_um", "phase_deg")),
    "gear_mesh_error": ({}, Plan(kind="dense", targets=1000, runs=2, dwell_s=1.0),
                        {"amplitude_um": 2.0, "phase_deg": -20.0}, ("amplitude_um", "phase_deg")),
    "thermal_backlash": ({}, Plan(warmup=WARM), {"centre_distance_um_per_K": -0.8}, ("centre_distance_um_per_K",)),
    "thermal_drift": ({}, Plan(warmup=WARM), {"arcsec_per_K": 0.45}, ("arcsec_per_K",)),
    "torsional_compliance": ({}, Plan(runs=6, loads=STEPS), {"stiffness_Nm_per_arcsec": 30.0},
                             ("stiffness_Nm_per_arcsec",)),
    "bearing_clearance": ({}, Plan(), {"clearance_arcsec": 3.0}, ("clearance_arcsec",)),
}


def spec_with(mch50_spec, changes):
    return with_values(mch50_spec, changes) if changes else mch50_spec


WARM_SLOW = (20.0, 34.0, 1500.0)
TB = {"thermal_backlash": {"centre_distance_um_per_K": -0.3225}}
REMEDY = "at least 3 runs in each direction"


def drop_column(text: str, name: str) -> str:
    lines = text.splitlines()
    header = lines[1].split(",")
    j = header.index(name)
    return "\n".join(lines[:1] + [",".join(c for i, c in enumerate(line.split(",")) if i != j)
                                  for line in lines[1:]]) + "\n"


def set_column(text: str, name: str, value: str) -> str:
    lines = text.splitlines()
    j = lines[1].split(",").index(name)
    return "\n".join(lines[:2] + [",".join(value if i == j else c for i, c in enumerate(line.split(",")))
                                  for line in lines[2:]]) + "\n"


def diagnose_doc(spec, text, **kw):
    return report(diagnose(spec, parse_measurement(text, "<test>"), resamples=kw.pop("resamples", 20), **kw))


def gap_never_grows(doc):
    for e in doc["effects_found"]:
        assert e["gap_share_pct"] > 0.0, e
    assert doc["gap_after"]["rms_arcsec"] <= doc["gap_before"]["rms_arcsec"] + 1e-9
