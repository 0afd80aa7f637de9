"""ISO 230-2 core (iso230.py): one-position tests, withheld figures, target grouping.

The figures follow ISO 230-2:2014 (clause 2 definitions); hand-worked values are written out with
their arithmetic.  The hand example over three targets is in test_measure_cli.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from wormgear_cli.measurement.iso230 import axis_figures, group_targets, iso230_figures, withhold_directional


def test_one_position_test_hand_worked():
    # 4 landings from each side at 30 deg (arcsec):
    #   forward 1, 2, 3, 6: mean 3, s = sqrt((4 + 1 + 0 + 9) / 3) = sqrt(14/3) = 2.160247
    #   reverse 10, 12, 14, 16: mean 13, s = sqrt((9 + 1 + 1 + 9) / 3) = sqrt(20/3) = 2.581989
    #   B = 3 - 13 = -10; R fwd = 4 s = 8.640988; R rev = 10.327956
    #   R = max(2 * 2.160247 + 2 * 2.581989 + 10, 8.64, 10.33) = 19.484472
    arc = math.pi / 648000
    err = np.array([1, 2, 3, 6, 10, 12, 14, 16]) * arc
    d = np.array([1, 1, 1, 1, -1, -1, -1, -1])
    f = iso230_figures(np.full(8, math.radians(30)), err, d)
    assert f.B_signed / arc == pytest.approx(-10.0)
    assert f.targets.s_up[0] / arc == pytest.approx(2.160247, abs=1e-6)
    assert f.targets.s_down[0] / arc == pytest.approx(2.581989, abs=1e-6)
    assert f.R_up / arc == pytest.approx(8.640988, abs=1e-6)
    assert f.R_down / arc == pytest.approx(10.327956, abs=1e-6)
    assert f.R / arc == pytest.approx(19.484472, abs=1e-6)
    assert all(math.isnan(x) for x in (f.A, f.A_up, f.A_down, f.E, f.E_up, f.E_down, f.M))
    assert any("one target only" in n for n in f.notes)


def test_withheld_figures_are_undefined_and_said_so():
    arc = math.pi / 648000
    ang = np.radians(np.repeat([0.0, 90.0, 180.0], 4))
    err = np.arange(12.0) * arc
    f = withhold_directional(iso230_figures(ang, err, np.ones(12)), "mixed")
    assert all(math.isnan(x) for x in (f.A_up, f.E_up, f.R_up, f.A, f.R))
    assert np.all(np.isnan(f.targets.s_up)) and f.notes[-1] == "mixed"


@given(st.lists(st.sampled_from([0.0, 1e-9, 0.5, 0.5 + 1e-9, 1.0, 2.0, 2.0 + 1e-3]), min_size=2, max_size=40))
def test_grouping_from_the_sorted_angles_is_the_same(values):
    angle = np.asarray(values)
    direct = group_targets(angle)
    shared = group_targets(angle, unique=np.unique(angle, return_inverse=True))
    assert np.array_equal(direct[0], shared[0])
    assert np.allclose(direct[1], shared[1])


@pytest.mark.parametrize("case", ["both directions", "a cell of one run", "forward only", "one target"])
def test_axis_figures_of_many_error_rows_are_each_rows_own(case):
    """The batch a table's simulated repeat tests use gives, row by row, the figures iso230_figures gives
    for that row alone, to the bit, NaN where that row's are undefined."""
    rng = np.random.default_rng(11)
    angle = np.tile(np.repeat([0.0, 0.5, 1.0, 1.5], 2), 3)
    direction = np.tile([1.0, -1.0], 12)
    if case == "a cell of one run":  # target 1.5 rad read by the first run only: its s undefined
        keep = (angle != 1.5) | (np.arange(angle.size) < 8)
        angle, direction = angle[keep], direction[keep]
    elif case == "forward only":
        direction = np.ones_like(direction)
    elif case == "one target":
        angle = np.zeros_like(angle)
    errors = rng.normal(0.0, 1e-5, (5, angle.size)) + 3e-5 * direction
    got = axis_figures(errors, direction, group_targets(angle))
    for r in range(errors.shape[0]):
        want = iso230_figures(angle, errors[r], direction).axis()
        assert set(got) == set(want)
        for k, v in want.items():
            assert got[k][r] == v or (math.isnan(v) and math.isnan(got[k][r])), (case, r, k)
