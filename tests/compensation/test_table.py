"""Table points, the orders a table cannot carry, and the table applied as LinuxCNC applies it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.controllers import LinuxCncJoint
from wormgear_cli.compensation.table import CorrectionTable, TableGrid, apply_table, interpolation_loss, uncarried
from wormgear_cli.errors import UsageError
from wormgear_cli.output.writers import WriteOptions, get


def test_grid_covers_both_ends_strictly_increasing():
    a = TableGrid(256).angles_deg()
    assert a[0] == 0.0 and a[-1] == 360.0 and a.size == 256 and np.all(np.diff(a) > 0)
    assert TableGrid(256).spacing_deg == pytest.approx(360.0 / 255.0)
    assert np.array_equal(a, np.round(a, 6))


@pytest.mark.parametrize("grid, most, message", [
    (TableGrid(257), 256, "--points: expected an integer in [2, 256], got 257"),
    (TableGrid(1), None, "--points: expected an integer in [2, 1000000], got 1"),
    (TableGrid(10, 360.0, 0.0), None, "--range: expected START:END in deg with START < END, got 360:0"),
    (TableGrid(100, 0.0, 1e-5), None, "points closer than 1e-6 deg"),
])
def test_grid_refuses_what_a_controller_cannot_load(grid, most, message):
    with pytest.raises(UsageError, match=message.replace("[", r"\[").replace("]", r"\]")):
        grid.check(most)


def test_orders_shorter_than_four_spacings_are_not_carried():
    spacing = TableGrid(256).spacing_deg  # 1.41 deg
    assert uncarried([1, 9, 60, 63, 64, 240], spacing) == [64.0, 240.0]  # 360/63 = 5.71 deg = 4.05 spacings


def _sine_table(order, points=256, amplitude=1e-4):
    grid = TableGrid(points)
    th = np.radians(grid.angles_deg())
    return CorrectionTable(grid.angles_deg(), amplitude * np.sin(order * th), -amplitude * np.cos(order * th))


def test_apply_table_is_what_linuxcnc_applies():
    table = _sine_table(7)
    joint = LinuxCncJoint(get("linuxcnc").write(table, WriteOptions()), file_type=1)
    rng = np.random.default_rng(0)
    pos = rng.uniform(-20.0, 380.0, 500)
    d = np.where(rng.uniform(size=500) < 0.5, 1.0, -1.0)
    ours = np.degrees(apply_table(table, np.radians(pos), d))
    assert np.max(np.abs(ours - joint.apply(pos, d))) < 1e-9  # the file's 9 decimals


class _Sine:
    def __init__(self, order, amplitude):
        self.order, self.amplitude = order, amplitude

    def error(self, theta, direction):
        return -self.amplitude * np.sin(self.order * np.asarray(theta)) * np.ones_like(direction)


@pytest.mark.parametrize("order", [9, 30, 60])
def test_interpolation_loss_is_the_chord_error_of_the_sine(order):
    amplitude = 1e-4
    grid = TableGrid(256)
    from wormgear_cli.compensation.table import build_table

    model = _Sine(order, amplitude)
    loss = interpolation_loss(model, build_table(model, grid))
    bound = amplitude * (1.0 - math.cos(order * math.radians(grid.spacing_deg) / 2.0))  # sag of a chord
    assert 0.5 * bound <= loss <= bound * 1.0001
