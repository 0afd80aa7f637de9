"""Measurements written from the physics, for the field-fault tests of ``diagnose`` (issue 10).

No call to ``wormgear_cli.analysis.simulate``: the drives are made so that their
model is known by hand.

* A *perfect* MCH50 (:func:`perfect_mch50_toml`): every tolerance,
  clearance, eccentricity and load of configs/mch50.toml set to zero.  A
  drive without geometric errors, clearances or load transmits the motion
  exactly, so its model is zero at every angle and in both directions.
* The same with the wheel eccentricity S2 kept (:func:`wheel_ecc_amplitude`):
  the paper's worm-stage error of one source is (x / 2) sin(i_c theta + psi)
  at the wheel pitch circle, x = S2 / cos(alpha_t) (alpha_t the worm pair's
  transverse pressure angle), i.e. x / (2 r_wheel i_c) rad at the output.

The hidden catalogue effects come from
:func:`tests.support.diagnosis_data.hidden_error` (the catalogue formulas written out
by hand; tests/diagnosis/test_data.py checks them against the registry).
Noise: white per point plus one offset per run.
"""

from __future__ import annotations

import math
import re

import numpy as np

from tests.support.diagnosis_data import ALPHA, I_C, LEAD, R_WHEEL, hidden_error
from tests.support.paths import MCH50
from wormgear_cli.units import ARCSEC

#: keys of configs/mch50.toml set to zero for a perfect drive (line-start patterns)
_ZERO = re.compile(r"^(\w*(profile_error|thickness_deviation|lead_error|radial_composite_error|centre_distance_error|"
                   r"eccentricity|bearing_clearance)_mm|\w+_normal_force_N)(\s*=\s*)[-0-9.eE]+", re.M)


def perfect_mch50_toml(wheel_eccentricity_mm: float = 0.0, extra: str = "") -> str:
    """configs/mch50.toml with every error source and load at zero (optionally S2 kept), as TOML text."""
    text = _ZERO.sub(lambda m: f"{m.group(1)}{m.group(3)}0.0", MCH50.read_text())
    text = re.sub(r"^worm_pair_errors_mm\s*=.*$", "worm_pair_errors_mm = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]", text,
                  flags=re.M)
    text = re.sub(r"^wheel_eccentricity_mm(\s*=\s*)0\.0", rf"wheel_eccentricity_mm\g<1>{wheel_eccentricity_mm!r}",
                  text, flags=re.M)
    return text + extra


def wheel_ecc_amplitude(s2_mm: float) -> float:
    """Output error amplitude [arcsec] of a wheel eccentricity S2 [mm] (module doc)."""
    alpha_t = math.atan(math.tan(ALPHA) / math.cos(LEAD))
    return s2_mm / math.cos(alpha_t) / 2.0 / (R_WHEEL * I_C) / ARCSEC


def plan_angles(n: int, jitter: bool, rng) -> np.ndarray:
    """n targets over a turn [deg]: equally spaced, or each moved by up to 30 % of the step (ISO 230-2 style)."""
    step = 360.0 / n
    angles = np.arange(n) * step
    if jitter:
        angles = angles + np.concatenate([[0.0], rng.uniform(-0.3 * step, 0.3 * step, n - 1)])
    return np.round(angles, 4)


def rows(angles_deg, runs: int, directions=(1, -1)) -> dict:
    """Runs of the targets, each forward (rising angles) then reverse; time 5 s per point."""
    blocks = []
    for r in range(1, runs + 1):
        for d in directions:
            a = angles_deg if d > 0 else angles_deg[::-1]
            blocks.append((a, np.full(a.shape[0], float(d)), np.full(a.shape[0], r)))
    angle = np.concatenate([b[0] for b in blocks])
    return {"angle_deg": angle, "direction": np.concatenate([b[1] for b in blocks]),
            "run": np.concatenate([b[2] for b in blocks]), "time_s": np.arange(angle.shape[0]) * 5.0}


def error_arcsec(r: dict, hidden: dict, rng, model=None, white: float = 0.3, run_sd: float = 0.2,
                 offset: float = 0.5) -> np.ndarray:
    """Hidden effects + model(theta [rad], direction) [arcsec] + offset + noise, per row."""
    theta = np.radians(r["angle_deg"])
    d = r["direction"]
    zero = np.zeros_like(theta)
    y = np.full_like(theta, offset)
    for name, params in hidden.items():
        y = y + hidden_error(name, params, theta, d, zero, zero + 20.0)
    if model is not None:
        y = y + model(theta, d)
    runs = int(np.max(r["run"]))
    return y + rng.normal(0.0, white, theta.shape) + rng.normal(0.0, run_sd, runs)[r["run"] - 1]


def to_csv(r: dict, columns=("angle_deg", "error_arcsec", "direction", "run", "time_s"), header=None) -> str:
    """The rows as CSV text (``header`` replaces the column names)."""
    out = [",".join(header or columns)]
    for i in range(r["angle_deg"].shape[0]):
        out.append(",".join(_cell(r[c][i]) for c in columns))
    return "\n".join(out) + "\n"


def _cell(v) -> str:
    v = float(v)
    return str(int(v)) if v == int(v) else repr(round(v, 6))
