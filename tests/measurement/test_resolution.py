"""The resolution of the readings (measurement/resolution.py) and ISO 230-2 cells below it.

Quantised data are made here by an independent path: a continuous error, the actual position rounded
to whole counts of an encoder (or to an instrument's step), minus a target that is itself off the grid,
written with a fixed number of decimals as an instrument export would be.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from wormgear_cli.measurement.iso230 import group_targets, iso230_figures
from wormgear_cli.measurement.resolution import reading_resolution
from wormgear_cli.units import RAD_PER_UNIT

ARCSEC = RAD_PER_UNIT["arcsec"]


def iso_table(rng, step_arcsec, decimals=3, targets=11, runs=5, noise=None):
    """(angle [rad], error [rad], direction) of an ISO cycle whose actual positions are whole steps of
    ``step_arcsec``; run-to-run scatter ``noise`` [arcsec] (default 0.6 steps)."""
    target = np.sort(rng.uniform(0, 360, targets))  # irregular, off the grid
    rows = []
    for _run in range(runs):
        for d in (1.0, -1.0):
            for t in target if d > 0 else target[::-1]:
                true = 3600 * t + 40 * math.sin(math.radians(2 * t)) + 15 * d + rng.normal(0, 0.6 * step_arcsec if noise is None else noise)
                actual = np.round(true / step_arcsec) * step_arcsec
                rows.append((t, round(actual - 3600 * t, decimals), d))
    a = np.array(rows)
    return np.radians(a[:, 0]), a[:, 1] * ARCSEC, a[:, 2]


@pytest.mark.parametrize("seed", range(6))
def test_an_encoder_grid_is_found_whatever_the_targets(seed):
    rng = np.random.default_rng(seed)
    bits = int(rng.integers(12, 19))
    step = 1296000.0 / 2**bits
    angle, error, _ = iso_table(rng, step, decimals=4)
    res = reading_resolution(error, "arcsec", group_targets(angle)[0])
    assert res.quantised
    assert res.step / ARCSEC == pytest.approx(step, rel=1e-6)
    assert res.basis == f"whole counts of an encoder with {2**bits} counts per turn"


@pytest.mark.parametrize("seed", range(4))
def test_an_instruments_own_step_is_found(seed):
    rng = np.random.default_rng(seed)
    angle, error, _ = iso_table(rng, 0.5, decimals=3)  # a 0.5 arcsec display, written to 3 decimals
    res = reading_resolution(error, "arcsec", group_targets(angle)[0])
    assert res.quantised and res.step / ARCSEC == pytest.approx(0.5, rel=1e-6)
    assert res.basis == "the readings of a target differ by whole steps"


@pytest.mark.parametrize("seed", range(6))
def test_continuous_readings_are_not_called_quantised(seed):
    rng = np.random.default_rng(seed)
    angle, error, _ = iso_table(rng, 1e-9, decimals=3, noise=0.8)  # no grid: only the 3 decimals written
    res = reading_resolution(error, "arcsec", group_targets(angle)[0])
    assert not res.quantised
    assert res.step / ARCSEC == pytest.approx(0.001, rel=1e-6)
    assert res.basis == "the readings are written to 3 decimals"
    full = reading_resolution(error + rng.normal(0, 1e-3, error.size) * ARCSEC * math.pi, "arcsec",
                              group_targets(angle)[0])
    assert full is None  # full double precision: no step can be told


def test_the_digits_are_read_in_the_files_unit():
    error = np.array([0.070350, -0.084579, 0.105507, 0.070350]) * RAD_PER_UNIT["deg"]
    res = reading_resolution(error, "deg", np.arange(4))
    assert not res.quantised and res.step / RAD_PER_UNIT["deg"] == pytest.approx(1e-6)


def test_cells_whose_readings_are_all_equal_are_flagged_and_only_they():
    # two targets; forward at 0 deg: three equal readings; the others spread
    q = 316.40625 * ARCSEC
    angle = np.radians([0, 0, 0, 0, 0, 0, 90, 90, 90, 90, 90, 90.0])
    error = np.array([3, 3, 3, -4, -3, -4, 2, 3, 2, -5, -5, -4]) * q
    direction = np.array([1, 1, 1, -1, -1, -1] * 2, dtype=float)
    fig = iso230_figures(angle, error, direction)
    assert fig.targets.equal_up.tolist() == [True, False]
    assert fig.targets.equal_down.tolist() == [False, False]
    assert fig.below == ()  # the axis R forward comes from the 90 deg cell: a number
    assert fig.R_up == pytest.approx(4 * np.std([2, 3, 2], ddof=1) * q)
    # every reverse cell equal: R reverse is zero only by quantisation
    error_all = np.array([3, 3, 3, -4, -4, -4, 2, 3, 2, -5, -5, -5]) * q
    fig = iso230_figures(angle, error_all, direction)
    assert fig.below == ("R_down",) and fig.R_down == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("decimals", [1, 2, 3, 4])
def test_no_grid_is_found_in_continuous_readings_over_seeds(decimals):
    found = 0
    for seed in range(20):
        rng = np.random.default_rng(100 + seed)
        angle, error, _ = iso_table(rng, 1e-9, decimals=decimals, noise=float(rng.uniform(0.3, 3.0)))
        found += reading_resolution(error, "arcsec", group_targets(angle)[0]).quantised
    assert found == 0


def test_one_repeated_difference_is_an_offset_not_a_grid():
    # perfectly repeatable readings: forward all 2.000, reverse all 32.000 at every target (a reversal of 30)
    angle = np.radians(np.repeat([0.0, 90.0, 180.0], 6))
    error = np.tile([2.0, 2.0, 2.0, 32.0, 32.0, 32.0], 3) * ARCSEC
    res = reading_resolution(error, "arcsec", group_targets(angle)[0])
    assert not res.quantised and res.step / ARCSEC == pytest.approx(1.0)  # written without decimals
    fig = iso230_figures(angle, error, np.tile([1.0, 1, 1, -1, -1, -1], 3))
    assert fig.below == ("R_up", "R_down")  # and every cell flagged: s below one written digit


def test_a_dial_gauge_step_is_no_fine_encoder_grid():
    # one-position test read off a dial indicator: 0.01 mm at 150 mm = 13.751 arcsec a division; three levels
    # (-82.506, -68.755, -55.004) written to 3 decimals.  13.751 is within a digit of 89 counts of a 2^23
    # encoder (0.1545 arcsec), but one distinct difference on so fine a grid is chance, not evidence
    readings = np.array([-68.755, -55.004, -82.506, -68.755, -82.506, -55.004, -68.755, -55.004]) * ARCSEC
    res = reading_resolution(readings, "arcsec", np.zeros(8, dtype=int))
    assert res.quantised and res.step / ARCSEC == pytest.approx(13.751, abs=1e-9)
    assert res.basis == "the readings of a target differ by whole steps"


def test_full_precision_readings_on_an_encoder_grid_are_found():
    # readings in degrees written to full precision, on whole counts of a 16-bit encoder, targets off the grid
    rng = np.random.default_rng(7)
    q = 360.0 / 2**16
    target = np.repeat(rng.uniform(0, 360, 6), 8)
    actual = np.round((target + rng.normal(0, 2 * q, target.size)) / q) * q
    res = reading_resolution((actual - target) * RAD_PER_UNIT["deg"], "deg", np.repeat(np.arange(6), 8))
    assert res.quantised and res.step / RAD_PER_UNIT["deg"] == pytest.approx(q, rel=1e-9)


def test_long_columns_are_sampled_and_still_give_the_grid(monkeypatch):
    from wormgear_cli.measurement import resolution

    rng = np.random.default_rng(3)
    angle, error, _ = iso_table(rng, 1296000.0 / 2**14, decimals=4, targets=40, runs=6)
    monkeypatch.setattr(resolution, "SAMPLE", 97)  # every 5th of the 480 readings
    res = reading_resolution(error, "arcsec", group_targets(angle)[0])
    assert res.quantised and res.step / ARCSEC == pytest.approx(1296000.0 / 2**14, rel=1e-6)


def test_one_decimal_is_said_in_the_singular_and_no_reading_gives_none():
    res = reading_resolution(np.array([0.1, 0.3, 0.2]) * ARCSEC, "arcsec", np.arange(3))
    assert res.basis == "the readings are written to 1 decimal" and not res.quantised
    assert reading_resolution(np.array([np.nan, np.nan]), "arcsec", np.arange(2)) is None
