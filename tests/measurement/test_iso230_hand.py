"""ISO 230-2:2014 figures on a small data set worked by hand.

Three targets, three runs in each direction (numbers in arbitrary angle units; the figures
are linear in the data).  Per target and direction, mean x and sample standard deviation s
(n - 1):

    target  up runs     x_up  s_up     down runs   x_dn  s_dn
    0.0     1, 2, 3      2     1        8, 10, 12   10    2
    1.0     -3, -3, 0   -2     sqrt(3)  -2, -1, 0   -1    1
    2.0     8, 8, 8      8     0        2, 3, 4      3    1

Reversal B_i = x_up - x_dn = -8, -1, 5: B = 8, B signed -8, B mean -4/3.
Mean bidirectional (x_up + x_dn)/2 = 6, -1.5, 5.5: M = 7.5.
E_up = 8 - (-2) = 10, E_down = 10 - (-1) = 11, E = 10 - (-2) = 12.
R_i(up) = 4 s = 4, 6.9282032, 0 -> R_up 6.9282032; R_i(down) = 8, 4, 4 -> R_down 8.
R_i = max(2 s_up + 2 s_dn + |B_i|, R_i up, R_i down) = max(14, 4, 8) = 14,
      max(2*1.7320508 + 2 + 1 = 6.4641016, 6.9282032, 4) = 6.9282032, max(7, 0, 4) = 7 -> R = 14.
A_up: max(x + 2s) = max(4, 1.4641016, 8) = 8, min(x - 2s) = min(0, -5.4641016, 8) -> 13.4641016.
A_down: max(14, 1, 5) = 14, min(6, -3, 1) = -3 -> 17.
A: max(8, 14) - min(-5.4641016, -3) = 19.4641016.
Each figure differs from the others, so swapping two of them fails.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from wormgear_cli.measurement.iso230 import TARGET_TOL, group_targets, iso230_figures, measurement_figures

R3 = math.sqrt(3.0)
UP = {0.0: (1, 2, 3), 1.0: (-3, -3, 0), 2.0: (8, 8, 8)}
DOWN = {0.0: (8, 10, 12), 1.0: (-2, -1, 0), 2.0: (2, 3, 4)}


def rows(jitter=0.0, seed=3):
    """The table's rows, shuffled; each angle moved by up to ``jitter`` (rows stay one target)."""
    angle, error, direction = [], [], []
    for d, table in ((1.0, UP), (-1.0, DOWN)):
        for t, values in table.items():
            for v in values:
                angle.append(t)
                error.append(float(v))
                direction.append(d)
    rng = np.random.default_rng(seed)
    order = rng.permutation(len(angle))
    angle = np.asarray(angle)[order] + rng.uniform(-jitter, jitter, len(angle))
    return angle, np.asarray(error)[order], np.asarray(direction)[order]


def figures():
    """The table's figures (computed in each test, not in a fixture: mutation testing follows the
    calls a test makes itself)."""
    return iso230_figures(*rows(jitter=0.3 * TARGET_TOL))


def test_axis_figures_by_hand():
    fig = figures()
    assert fig.B == pytest.approx(8.0, rel=1e-12)
    assert fig.B_signed == pytest.approx(-8.0, rel=1e-12)
    assert fig.B_mean == pytest.approx(-4.0 / 3.0, rel=1e-12)
    assert fig.M == pytest.approx(7.5, rel=1e-12)
    assert fig.E_up == pytest.approx(10.0, rel=1e-12)
    assert fig.E_down == pytest.approx(11.0, rel=1e-12)
    assert fig.E == pytest.approx(12.0, rel=1e-12)
    assert fig.R_up == pytest.approx(4 * R3, rel=1e-12)
    assert fig.R_down == pytest.approx(8.0, rel=1e-12)
    assert fig.R == pytest.approx(14.0, rel=1e-12)
    assert fig.A_up == pytest.approx(10.0 + 2 * R3, rel=1e-12)
    assert fig.A_down == pytest.approx(17.0, rel=1e-12)
    assert fig.A == pytest.approx(16.0 + 2 * R3, rel=1e-12)
    assert fig.rows == 18
    assert fig.notes == ()


def test_target_table_by_hand():
    t = figures().targets
    assert len(t) == 3
    np.testing.assert_allclose(t.target, [0.0, 1.0, 2.0], atol=TARGET_TOL)
    np.testing.assert_array_equal(t.n_up, [3, 3, 3])
    assert t.n_up.dtype.kind == "i" and t.n_down.dtype.kind == "i"  # counts of runs
    np.testing.assert_array_equal(t.n_down, [3, 3, 3])
    np.testing.assert_allclose(t.mean_up, [2, -2, 8], rtol=1e-12)
    np.testing.assert_allclose(t.mean_down, [10, -1, 3], rtol=1e-12)
    np.testing.assert_allclose(t.s_up, [1, R3, 0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(t.s_down, [2, 1, 1], rtol=1e-12)
    np.testing.assert_allclose(t.reversal, [-8, -1, 5], rtol=1e-12)
    np.testing.assert_allclose(t.mean_bi, [6, -1.5, 5.5], rtol=1e-12)
    np.testing.assert_allclose(t.r_up, [4, 4 * R3, 0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(t.r_down, [8, 4, 4], rtol=1e-12)
    np.testing.assert_allclose(t.r_bi, [14, 4 * R3, 7], rtol=1e-12)


def test_measurement_figures_reads_the_measurement_columns():
    a, e, d = rows()
    f = measurement_figures(SimpleNamespace(angle=a, error=e, direction=d))
    assert f.A == pytest.approx(16.0 + 2 * R3, rel=1e-12) and f.R == pytest.approx(14.0, rel=1e-12)


def test_group_targets_by_hand():
    """Sorted angles 0, 0.5e-8, 1, 1 + 2e-8 with tol 1e-8: three targets (the 2e-8 step splits),
    target angles the means of their rows: 0.25e-8, 1, 1 + 2e-8."""
    idx, tgt = group_targets(np.array([1.0, 0.0, 1.0 + 2e-8, 0.5e-8, 1.0]), tol=1e-8)
    np.testing.assert_array_equal(idx, [1, 0, 2, 0, 1])
    np.testing.assert_allclose(tgt, [0.25e-8, 1.0, 1.0 + 2e-8], rtol=0, atol=1e-15)
    # a step of exactly tol joins, a step just above it splits
    idx, _ = group_targets(np.array([0.0, 1e-8]), tol=1e-8)
    assert list(idx) == [0, 0]
    assert TARGET_TOL == pytest.approx(math.radians(1e-6), rel=1e-12)


def test_single_run_cell_leaves_s_undefined():
    """Target 2.0 with one up run only (value 8): s_up NaN there, so R_up, R, A_up, A undefined;
    E, M, B need no s: E_up still 10 (means 2, -2, 8)."""
    a, e, d = rows()
    drop = np.flatnonzero((a == 2.0) & (d > 0))[1:]
    keep = np.setdiff1d(np.arange(a.shape[0]), drop)
    f = iso230_figures(a[keep], e[keep], d[keep])
    assert math.isnan(f.R_up) and math.isnan(f.A_up) and math.isnan(f.A) and math.isnan(f.R)
    assert f.R_down == pytest.approx(8.0) and f.A_down == pytest.approx(17.0)
    assert f.E_up == pytest.approx(10.0) and f.B == pytest.approx(8.0) and f.M == pytest.approx(7.5)
    assert f.targets.n_up[2] == 1 and math.isnan(f.targets.s_up[2])
    assert len(f.notes) == 1 and "single run" in f.notes[0] and "forward" in f.notes[0]


def test_one_direction_only():
    """Forward rows only: unidirectional figures as above, every bidirectional one NaN."""
    a, e, d = rows()
    up = d > 0
    f = iso230_figures(a[up], e[up], d[up])
    assert f.E_up == pytest.approx(10.0) and f.R_up == pytest.approx(4 * R3) and f.A_up == pytest.approx(10 + 2 * R3)
    for name in ("A", "B", "B_signed", "B_mean", "E", "M", "R", "A_down", "E_down", "R_down"):
        assert math.isnan(getattr(f, name)), name
    assert len(f.notes) == 1 and "no reverse" in f.notes[0]


def test_target_measured_in_one_direction_only():
    """Target 1.0 without its down rows: B, M, R from targets 0 and 2 only: B_i = -8, 5 -> B 8,
    B mean -1.5; M = 6 - 5.5 = 0.5; R = max(14, 7) = 14; E_down = 10 - 3 = 7."""
    a, e, d = rows()
    keep = ~((a == 1.0) & (d < 0))
    f = iso230_figures(a[keep], e[keep], d[keep])
    assert f.B == pytest.approx(8.0) and f.B_mean == pytest.approx(-1.5) and f.M == pytest.approx(0.5)
    assert f.R == pytest.approx(14.0) and f.E_down == pytest.approx(7.0)
    assert math.isnan(f.targets.reversal[1]) and math.isnan(f.targets.r_bi[1])
    assert len(f.notes) == 1 and "one direction only" in f.notes[0]


def test_axis_lists_the_thirteen_figures():
    axis = figures().axis()
    assert list(axis) == ["A", "A_up", "A_down", "B", "B_signed", "B_mean", "E", "E_up", "E_down", "M", "R",
                          "R_up", "R_down"]
    assert axis["A"] == pytest.approx(16.0 + 2 * R3) and axis["B_signed"] == pytest.approx(-8.0)
    assert axis["R_down"] == pytest.approx(8.0) and axis["E_up"] == pytest.approx(10.0)


# --- the notes, word for word -------------------------------------------------------------------


def _without(mask):
    a, e, d = rows()
    keep = ~mask(a, d)
    return iso230_figures(a[keep], e[keep], d[keep])


def test_note_one_single_run_cell():
    f = _without(lambda a, d: (a == 2.0) & (d > 0) & (np.cumsum((a == 2.0) & (d > 0)) > 1))
    assert f.notes == ("1 target/direction cell has a single run: the standard deviation is undefined there, "
                       "so R and A are not given for the forward direction nor bidirectionally",)


def test_note_single_run_cells_in_both_directions():
    f = _without(lambda a, d: (a == 2.0) & (np.cumsum((a == 2.0) & (d > 0)) > 1) & (d > 0)
                 | (a == 0.0) & (d < 0) & (np.cumsum((a == 0.0) & (d < 0)) > 1))
    assert f.notes == ("2 target/direction cells have a single run: the standard deviation is undefined there, "
                       "so R and A are not given for the forward and reverse directions nor bidirectionally",)
    for name in ("R_up", "R_down", "R", "A_up", "A_down", "A"):
        assert math.isnan(getattr(f, name)), name


def test_note_no_forward_rows():
    f = _without(lambda a, d: d > 0)
    assert f.notes == ("no forward (direction +1) rows: reversal B, M and the bidirectional figures are "
                       "undefined",)
    assert f.E_down == pytest.approx(11.0) and f.R_down == pytest.approx(8.0) and f.A_down == pytest.approx(17.0)
    assert math.isnan(f.E_up) and math.isnan(f.R_up) and math.isnan(f.A_up) and math.isnan(f.E)


def test_note_no_reverse_rows():
    f = _without(lambda a, d: d < 0)
    assert f.notes == ("no reverse (direction -1) rows: reversal B, M and the bidirectional figures are "
                       "undefined",)


def test_note_targets_measured_one_way():
    f = _without(lambda a, d: (a != 0.0) & (d < 0))
    assert f.notes == ("2 targets were measured in one direction only: no reversal or bidirectional figures "
                       "there",)
    f = _without(lambda a, d: (a == 1.0) & (d < 0))
    assert f.notes == ("1 target was measured in one direction only: no reversal or bidirectional figures "
                       "there",)


def test_note_no_common_target():
    """Forward at 0 and 1, reverse at 2 only: E is defined (means of both directions), B, M, R are not."""
    f = _without(lambda a, d: ((a == 2.0) & (d > 0)) | ((a != 2.0) & (d < 0)))
    assert f.notes == ("no target was measured in both directions (different angles per direction?): "
                       "reversal B, M and the bidirectional R are undefined",)
    assert math.isnan(f.B) and math.isnan(f.M) and math.isnan(f.R)
    # E over forward means 2, -2 and the reverse mean 3: 3 - (-2) = 5; A: max(4, 3.4641, 5) - min(0, -5.4641, 1)
    assert f.E == pytest.approx(5.0)
    assert f.A == pytest.approx(5.0 + 2 + 2 * R3)


def test_largest_reversal_not_at_the_first_target():
    """Target 0.0 left out: B_i = -1, 5 -> B 5, B signed +5, B mean 2; M = 5.5 - (-1.5) = 7;
    E_up = 8 - (-2) = 10, E_down = 3 - (-1) = 4, E = 10; R = max(6.9282032, 7) = 7."""
    f = _without(lambda a, d: a == 0.0)
    assert (f.B, f.B_signed, f.B_mean, f.M) == pytest.approx((5.0, 5.0, 2.0, 7.0))
    assert (f.E_up, f.E_down, f.E, f.R) == pytest.approx((10.0, 4.0, 10.0, 7.0))


def test_two_runs_are_enough_for_s():
    """Cells of two runs: s = |x1 - x2| / sqrt(2); up 1, 3 and down 2, 6 at one target, up 0, 2 and
    down 1, 1 at another: s_up sqrt(2), sqrt(2); s_down 2 sqrt(2), 0 -> R_up = 4 sqrt(2)."""
    a = np.array([0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0])
    e = np.array([1.0, 3.0, 2.0, 6.0, 0.0, 2.0, 1.0, 1.0])
    d = np.array([1.0, 1.0, -1.0, -1.0, 1.0, 1.0, -1.0, -1.0])
    f = iso230_figures(a, e, d)
    np.testing.assert_allclose(f.targets.s_up, [math.sqrt(2), math.sqrt(2)], rtol=1e-12)
    np.testing.assert_allclose(f.targets.s_down, [2 * math.sqrt(2), 0.0], rtol=1e-12, atol=1e-15)
    assert f.R_up == pytest.approx(4 * math.sqrt(2)) and f.notes == ()


def test_explicit_target_tolerance():
    """Rows 1e-7 rad apart: one target with tol 1e-6 rad, two with the default (1e-6 deg = 1.7e-8 rad)."""
    a = np.array([0.0, 1e-7, 0.0, 1e-7, 1.0, 1.0, 1.0, 1.0])
    e = np.array([1.0, 3.0, 2.0, 6.0, 0.0, 2.0, 1.0, 1.0])
    d = np.array([1.0, 1.0, -1.0, -1.0, 1.0, 1.0, -1.0, -1.0])
    assert len(iso230_figures(a, e, d, tol=1e-6).targets) == 2
    assert len(iso230_figures(a, e, d).targets) == 3


def test_no_error_values_give_undefined_figures():
    """A measurement without errors (NaN) has no figures, and says nothing false."""
    a, e, d = rows()
    f = iso230_figures(a, np.full(e.shape, np.nan), d)
    for name in ("A", "B", "E", "E_up", "E_down", "M", "R"):
        assert math.isnan(getattr(f, name)), name


def test_one_forward_run_still_counts_as_forward():
    """A single forward run (values 2, -2, 8 at the three targets) and the three reverse runs: the
    forward direction is present (E_up = 8 - (-2) = 10, E = 10 - (-2) = 12), only its s is undefined."""
    a, e, d = rows()
    first_up = np.zeros(a.shape[0], dtype=bool)
    for t, v in ((0.0, 2.0), (1.0, -2.0), (2.0, 8.0)):
        a = np.append(a, t)
        e = np.append(e, v)
        d = np.append(d, 1.0)
        first_up = np.append(first_up, True)
    keep = (d < 0) | first_up
    f = iso230_figures(a[keep], e[keep], d[keep])
    assert f.E_up == pytest.approx(10.0) and f.E == pytest.approx(12.0) and f.B == pytest.approx(8.0)
    assert math.isnan(f.R_up) and f.R_down == pytest.approx(8.0)
    assert f.notes[0].startswith("3 target/direction cells have a single run")


def test_measurement_figures_passes_the_tolerance_on():
    a = np.array([0.0, 1e-7, 0.0, 1e-7, 1.0, 1.0, 1.0, 1.0])
    e = np.array([1.0, 3.0, 2.0, 6.0, 0.0, 2.0, 1.0, 1.0])
    d = np.array([1.0, 1.0, -1.0, -1.0, 1.0, 1.0, -1.0, -1.0])
    m = SimpleNamespace(angle=a, error=e, direction=d)
    assert len(measurement_figures(m, tol=1e-6).targets) == 2
    assert len(measurement_figures(m).targets) == 3


def test_one_reverse_run_still_counts_as_reverse():
    """A single reverse run (values 10, -1, 3) and the three forward runs: E_down = 10 - (-1) = 11."""
    a, e, d = rows()
    keep = d > 0
    a = np.concatenate([a[keep], [0.0, 1.0, 2.0]])
    e = np.concatenate([e[keep], [10.0, -1.0, 3.0]])
    d = np.concatenate([d[keep], [-1.0, -1.0, -1.0]])
    f = iso230_figures(a, e, d)
    assert f.E_down == pytest.approx(11.0) and f.E == pytest.approx(12.0) and f.B == pytest.approx(8.0)
    assert math.isnan(f.R_down) and f.R_up == pytest.approx(4 * R3)
