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


def test_grid_bounds_and_range_parsing():
    from wormgear_cli.compensation.table import parse_range

    TableGrid(2).check(256)
    TableGrid(256).check(256)
    TableGrid(361, 0.0, 1.0).check()  # spacings well below a degree are fine
    TableGrid(3, -1e6, 1e6).check()
    for grid in (TableGrid(5, 10.0, 10.0), TableGrid(5, -1e6 - 1, 0.0), TableGrid(5, 0.0, 1e6 + 1)):
        with pytest.raises(UsageError):
            grid.check()
    with pytest.raises(UsageError) as e:
        TableGrid(5, 0.0, 2e6).check()
    assert e.value.problems == ["--range: the ends must lie within +/-1e6 deg"]
    assert parse_range("0:360") == (0.0, 360.0) and parse_range("-360:720") == (-360.0, 720.0)
    for bad in ("0-360", "1:2:3", "a:b"):
        with pytest.raises(UsageError) as e:
            parse_range(bad)
        assert e.value.problems == [f"--range: expected START:END in deg, e.g. 0:360, got {bad!r}"]


def test_carried_at_exactly_four_spacings():
    assert uncarried([90.0], 1.0) == []  # period 4.0 deg = 4 spacings: carried
    assert uncarried([90.1], 1.0) == [90.1]  # 3.996 spacings: not
    assert uncarried([1.0], 100.0) == [1.0] and uncarried([0.0], 1.0) == []


class _Reversal:
    """error = +1 forward, -2 reverse (rad), and a one-direction plan."""

    class plan:
        both = False

    def error(self, theta, direction):
        return np.where(np.asarray(direction) > 0, 1.0, -2.0) * np.ones_like(theta)


def test_build_table_evaluates_each_direction_and_keeps_the_plan():
    from wormgear_cli.compensation.table import build_table

    t = build_table(_Reversal(), TableGrid(3))
    assert list(t.forward) == [-1.0] * 3 and list(t.reverse) == [2.0] * 3 and t.both is False
    assert build_table(_Sine(1, 1.0), TableGrid(3)).both is True  # no plan: both directions assumed
    d = np.array([1, -1, 1])
    assert list(apply_table(t, np.zeros(3), d)) == [-1.0, 2.0, -1.0]


class _Spike:
    """A narrow bump of the reverse error halfway between two given table points."""

    def __init__(self, centre_deg, width_deg=0.1):
        self.centre, self.width = centre_deg, width_deg

    def error(self, theta, direction):
        deg = np.degrees(np.asarray(theta))
        bump = np.clip(1.0 - np.abs(deg - self.centre) / self.width, 0.0, None)
        return np.where(np.asarray(direction) < 0, 1e-4 * bump, 0.0)


@pytest.mark.parametrize("interval", [0, 254])
def test_interpolation_loss_looks_at_every_interval_in_reverse(interval):
    from wormgear_cli.compensation.table import build_table

    grid = TableGrid(256)
    a = grid.angles_deg()
    model = _Spike(0.5 * (a[interval] + a[interval + 1]))
    assert interpolation_loss(model, build_table(model, grid)) == pytest.approx(1e-4, rel=0.02)
