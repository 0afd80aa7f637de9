"""The run structure of the diagnosis statistics, by hand: passes and runs (``make_groups``),
per-pass sums (``pass_sums``), the share of a column's sum of squares carried by run and pass
means (``level_shares``) and the "more than half" rule of the containment degrees of freedom.

Every expected value is counted or summed by hand in the docstrings (no project code on the
expected side); the structure checks compare each row with the pass it was put in."""

from __future__ import annotations

import numpy as np
import pytest

from wormgear_cli.diagnosis import containment_df, make_groups
from wormgear_cli.diagnosis.mixed import level_shares
from wormgear_cli.diagnosis.runs import pass_sums

RUN_TEXT = "run column: one pass per run and direction"
BLOCK_TEXT = "no run column: a pass is a block of consecutive rows in one direction"
RESTART_TEXT = " (a new one where time_s goes backwards)"
WHITE_TEXT = "; passes too short to carry run-to-run noise, noise taken as white"

# a small unbalanced design with a run column: run 1 = a forward pass of rows 0-1 and a reverse
# pass of row 2; run 2 = a forward pass of rows 3-5 and a reverse pass of rows 6-7
DIRECTION = np.array([1, 1, -1, 1, 1, 1, -1, -1])
RUN = np.array([1, 1, 1, 2, 2, 2, 2, 2])


def _same_pass(groups, rows_of_each_pass):
    """Every row of a listed pass has one pass id, different passes different ids."""
    ids = [set(groups.pass_id[rows].tolist()) for rows in rows_of_each_pass]
    assert all(len(i) == 1 for i in ids), ids
    assert len({next(iter(i)) for i in ids}) == len(ids)


def test_groups_from_a_run_column_by_hand():
    """Four passes (run, direction) of sizes 2, 1, 3, 2 in two runs; the mean pass size is 2 < 3,
    so the noise is taken as white (not random, hence not nested)."""
    g = make_groups(DIRECTION, RUN)
    assert g.passes == 4 and g.runs == 2
    _same_pass(g, [[0, 1], [2], [3, 4, 5], [6, 7]])
    np.testing.assert_array_equal(g.pass_size[g.pass_id], [2, 2, 1, 3, 3, 3, 2, 2])
    np.testing.assert_array_equal(g.pass_direction[g.pass_id], DIRECTION)
    run_of_row = g.pass_run[g.pass_id]
    assert run_of_row[0] == run_of_row[1] == run_of_row[2] != run_of_row[3]
    assert len(set(run_of_row[3:].tolist())) == 1
    assert not g.random and not g.nested
    assert g.describe == RUN_TEXT + WHITE_TEXT


def test_one_run_of_two_three_row_passes_is_nested_and_random():
    """The limits of 'random': at least 2 passes and a mean pass size of at least 3 rows; one run
    holding both passes is nested."""
    g = make_groups(np.array([1.0, 1.0, 1.0, -1.0, -1.0, -1.0]), np.full(6, 5))
    assert g.passes == 2 and g.runs == 1
    np.testing.assert_array_equal(g.pass_direction[g.pass_id], [1, 1, 1, -1, -1, -1])
    assert g.random and g.nested
    assert g.describe == RUN_TEXT
    # a single pass of 10 rows: not random
    one = make_groups(np.ones(10), np.ones(10))
    assert one.passes == 1 and not one.random and one.describe == RUN_TEXT + WHITE_TEXT


def test_groups_without_a_run_column_by_hand():
    """Blocks of consecutive rows in one direction: 3, 3 and 1 rows (the last pass is one row);
    each pass its own run."""
    d = np.array([1.0, 1.0, 1.0, -1.0, -1.0, -1.0, 1.0])
    g = make_groups(d, None)
    assert g.passes == 3 and g.runs == 3
    np.testing.assert_array_equal(g.pass_id, [0, 0, 0, 1, 1, 1, 2])
    np.testing.assert_array_equal(g.pass_size, [3, 3, 1])
    np.testing.assert_array_equal(g.pass_direction, [1, -1, 1])
    np.testing.assert_array_equal(g.pass_run, [0, 1, 2])
    assert not g.nested and not g.random  # mean size 7/3 < 3
    assert g.describe == BLOCK_TEXT + WHITE_TEXT
    # two blocks of three rows: random, and a time column that never goes backwards changes nothing
    g2 = make_groups(d[:6], None, time=np.arange(6.0))
    assert g2.passes == 2 and g2.random and not g2.nested
    assert g2.describe == BLOCK_TEXT


def test_time_going_backwards_starts_a_new_pass():
    """Nine rows in one direction, the clock restarting at rows 3 and 6: three passes of three."""
    g = make_groups(np.ones(9), None, time=np.array([0.0, 1, 2, 0, 1, 2, 0.5, 1, 2]))
    assert g.passes == 3 and g.runs == 3
    np.testing.assert_array_equal(g.pass_id, [0, 0, 0, 1, 1, 1, 2, 2, 2])
    np.testing.assert_array_equal(g.pass_direction, [1, 1, 1])
    assert g.random and not g.nested
    assert g.describe == BLOCK_TEXT + RESTART_TEXT


def test_pass_sums_by_hand():
    """Pass sums of the unbalanced design above, for a vector and a two-column array: column
    (1, 3, 2, 0, 1, 2, 4, 6) sums to 4, 2, 3, 10 over passes (1,+), (1,-), (2,+), (2,-)."""
    g = make_groups(DIRECTION, RUN)
    col = np.array([1.0, 3, 2, 0, 1, 2, 4, 6])
    want = np.array([4.0, 2.0, 3.0, 10.0])  # at the ids of the passes of rows 0, 2, 3, 6
    np.testing.assert_allclose(pass_sums(col, g)[g.pass_id[[0, 2, 3, 6]]], want)
    two = np.column_stack([col, -2 * col])
    np.testing.assert_allclose(pass_sums(two, g)[g.pass_id[[0, 2, 3, 6]]], np.column_stack([want, -2 * want]))
    assert pass_sums(np.zeros((8, 0)), g).shape == (4, 0)


def test_pass_sums_of_rows_not_grouped_by_pass():
    """Rows of the two runs interleaved (the file is not sorted by pass): the sums are the same."""
    perm = np.array([3, 0, 6, 1, 4, 2, 7, 5])
    g = make_groups(DIRECTION[perm], RUN[perm])
    col = np.array([1.0, 3, 2, 0, 1, 2, 4, 6])[perm]
    # first row of each pass in the permuted order: (1,+) row 1, (1,-) row 5, (2,+) row 0, (2,-) row 2
    first = [1, 5, 0, 2]
    want = np.array([4.0, 2.0, 3.0, 10.0])
    np.testing.assert_allclose(pass_sums(col, g)[g.pass_id[first]], want)
    np.testing.assert_allclose(pass_sums(col[:, None], g)[g.pass_id[first], 0], want)


def test_level_shares_by_hand():
    """Unbalanced design above.  Column a = (1, 3, 2, 0, 1, 2, 4, 6): sum of squares 71; pass sums
    4, 2, 3, 10 over sizes 2, 1, 3, 2 give 16/2 + 4/1 + 9/3 + 100/2 = 65; run sums 6 (3 rows) and 13
    (5 rows) give 36/3 + 169/5 = 45.8.  Column b = 0.1 x (1, 1, 1, 0, 0, 0, -1, -1), constant in
    each pass: sum of squares 0.05 = its pass share 1; run sums 0.3 (3 rows), -0.2 (5 rows):
    0.03 + 0.008 = 0.038, run share 0.76.  An all-zero column has no share at either level."""
    g = make_groups(DIRECTION, RUN)
    a = np.array([1.0, 3, 2, 0, 1, 2, 4, 6])
    b = 0.1 * np.array([1.0, 1, 1, 0, 0, 0, -1, -1])
    run_share, pass_share = level_shares(np.column_stack([a, b, np.zeros(8)]), g)
    np.testing.assert_allclose(run_share, [45.8 / 71, 0.76, 0.0], rtol=1e-12)
    np.testing.assert_allclose(pass_share, [65 / 71, 1.0, 0.0], rtol=1e-12)
    # one column given as a vector
    r1, p1 = level_shares(a, g)
    np.testing.assert_allclose([r1[0], p1[0]], [45.8 / 71, 65 / 71], rtol=1e-12)


def _half_and_half():
    """Two runs, each a forward and a reverse pass of 4 rows (16 rows).  Column h = run offset +-1
    plus the pattern (1, -1, 1, -1) in every pass: sum of squares 16 x 2 = 32, run sums +-8 over 8
    rows: 64/8 + 64/8 = 16, exactly half; its pass means are the run offsets, so its pass share is
    also exactly half."""
    run = np.repeat([0, 1], 8)
    d = np.tile(np.repeat([1.0, -1.0], 4), 2)
    h = np.where(run == 0, 1.0, -1.0) + np.tile([1.0, -1.0, 1.0, -1.0], 4)
    return make_groups(d, run), run, d, h


def test_exactly_half_the_sum_of_squares_is_not_more_than_half():
    """A column whose run and pass means carry exactly half its sum of squares lives within
    passes: df = rows - columns = 16 - 2.  As a model column it does not count at run or pass
    level: a run-level column given it has runs - 0 - 1 = 1 df, a pass-level one passes - 0 - 1
    = 3."""
    g, run, d, h = _half_and_half()
    assert g.random and g.nested
    run_share, pass_share = level_shares(h, g)
    assert run_share[0] == 0.5 and pass_share[0] == 0.5
    assert containment_df(g, np.ones((16, 1)), h[:, None]) == 16 - 2
    run_col = np.where(run == 0, 1.0, -1.0)[:, None]
    assert containment_df(g, h[:, None], run_col) == 2 - 0 - 1
    assert containment_df(g, h[:, None], d[:, None]) == 4 - 0 - 1


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_level_shares_do_not_depend_on_the_scale(scale):
    g = make_groups(DIRECTION, RUN)
    a = np.array([1.0, 3, 2, 0, 1, 2, 4, 6])
    run_share, pass_share = level_shares(scale * a, g)
    np.testing.assert_allclose([run_share[0], pass_share[0]], [45.8 / 71, 65 / 71], rtol=1e-12)
