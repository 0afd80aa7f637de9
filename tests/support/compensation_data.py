"""Measurements with a known error, written as CSV by their own code (tests of ``compensate``).

A rotary axis with orders 1, 2 and 9 and lost motion, measured as an ISO 230-2 test (irregular
targets, forward then reverse runs) or as a dense scan; a telescope mount tracking at the
sidereal rate with a worm-period error, drift and noise.  Figures of a corrected test are
computed here too, from their definitions (E: range of the per-target means of both
directions; B: largest |forward mean - reverse mean|), not by the project's code.
"""

from __future__ import annotations

import math

import numpy as np

SIDEREAL_DAY_S = 86164.0905
#: the axis' error [arcsec]: (order, amplitude, phase [rad]) of the mean of the directions
COMMON = ((1, 20.0, 0.3), (2, 8.0, 1.1), (9, 5.0, 2.0))
#: half the reversal [arcsec]: offset (lost motion) and (order, amplitude, phase)
HALF_REVERSAL = (-6.0, ((1, 2.0, 0.7),))


def axis_error(angle_deg, direction) -> np.ndarray:
    """The axis' true error [arcsec] at angles [deg] moving in direction (+1/-1)."""
    th = np.radians(np.asarray(angle_deg, dtype=float))
    d = np.asarray(direction, dtype=float)
    common = sum(a * np.sin(k * th + p) for k, a, p in COMMON)
    offset, terms = HALF_REVERSAL
    half = offset + sum(a * np.sin(k * th + p) for k, a, p in terms)
    return common + d * half


def iso_targets(count: int = 36, seed: int = 1000) -> np.ndarray:
    """Irregular targets [deg]: i * 360 / count plus up to +/-30 % of the spacing, the first at 0."""
    rng = np.random.default_rng(seed)
    p = 360.0 / count
    t = np.arange(count) * p + rng.uniform(-0.3 * p, 0.3 * p, count)
    t[0] = 0.0
    return np.round(t, 3)


def iso_rows(seed: int, targets=None, runs: int = 5, white: float = 0.5, run_sd: float = 0.3):
    """(angle_deg, error_arcsec, direction, run) of a test: each run forward then reverse."""
    t = iso_targets() if targets is None else np.asarray(targets, dtype=float)
    rng = np.random.default_rng(seed)
    a, d, r = [], [], []
    for j in range(1, runs + 1):
        a += list(t) + list(t[::-1])
        d += [1] * t.size + [-1] * t.size
        r += [j] * (2 * t.size)
    a, d, r = np.array(a), np.array(d), np.array(r)
    e = axis_error(a, d) + rng.normal(0.0, white, a.size) + rng.normal(0.0, run_sd, runs)[r - 1]
    return a, np.round(e, 4), d, r


def dense_rows(seed: int, points: int = 720, runs: int = 3, white: float = 0.5, run_sd: float = 0.3):
    """A dense scan: ``points`` evenly spaced angles per pass (between any test's targets)."""
    return iso_rows(seed, np.arange(points) * 360.0 / points + 0.25, runs, white, run_sd)


def rows_csv(angle, error, direction, run) -> str:
    lines = ["angle_deg,error_arcsec,direction,run"]
    lines += [f"{a:.6f},{e:.4f},{int(d)},{int(r)}" for a, e, d, r in zip(angle, error, direction, run)]
    return "\n".join(lines) + "\n"


def e_and_b(angle, error, direction) -> tuple[float, float]:
    """ISO 230-2 E and B of rows, from their definitions."""
    cells = {}
    for a, e, d in zip(np.round(angle, 6), error, direction):
        cells.setdefault((float(a), int(d)), []).append(float(e))
    means = {k: sum(v) / len(v) for k, v in cells.items()}
    values = list(means.values())
    e_range = max(values) - min(values)
    b = max(abs(means[(a, 1)] - means[(a, -1)]) for a, d in means if d == 1 and (a, -1) in means)
    return e_range, b


# --- a mount ------------------------------------------------------------------------------------------


#: the mount's periodic error: (harmonic of the worm order, amplitude [arcsec], phase [rad])
PE = ((1, 8.0, 0.4), (2, 1.0, 1.0), (3, 1.2, 2.0))


def mount_pe(angle_rad, worm_order: float) -> np.ndarray:
    """The mount's periodic error [arcsec of RA axis] at RA-axis angles [rad]."""
    th = np.asarray(angle_rad, dtype=float)
    return sum(a * np.sin(h * worm_order * th + p) for h, a, p in PE)


def tracking_rows(seed: int, worm_order: float = 180.0, duration_s: float = 2400.0, step_s: float = 2.0,
                  sessions: int = 1, noise: float = 0.4):
    """(angle_deg, error_arcsec, time_s, run) of a mount tracking at the sidereal rate: PE, a drift
    (a slope, a curvature and an offset per session) and seeing noise; angles wrapped to 0..360."""
    rng = np.random.default_rng(seed)
    a, e, t_all, r = [], [], [], []
    for s in range(sessions):
        t = np.arange(0.0, duration_s, step_s)
        th = math.radians(-60.0 + 37.0 * s) + 2.0 * math.pi * t / SIDEREAL_DAY_S
        drift = 0.004 * t - 2e-6 * (t - duration_s / 2) ** 2 + rng.normal(0.0, 1.0)
        a += list(np.degrees(th) % 360.0)
        e += list(mount_pe(th, worm_order) + drift + rng.normal(0.0, noise, t.size))
        t_all += list(t)
        r += [s + 1] * t.size
    return np.array(a), np.array(e), np.array(t_all), np.array(r)


def tracking_csv(angle, error, time, run) -> str:
    lines = ["angle_deg,error_arcsec,time_s,run"]
    lines += [f"{a:.7f},{x:.4f},{t:.3f},{int(s)}" for a, x, t, s in zip(angle, error, time, run)]
    return "\n".join(lines) + "\n"
