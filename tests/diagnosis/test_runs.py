"""Run structure under diagnose: passes and runs from the columns, cells of target and direction."""

from __future__ import annotations

import numpy as np

from wormgear_cli import diagnosis as dg

from tests.diagnosis.data import TB, WARM_SLOW, Plan, diagnose_doc, gap_never_grows, make_csv, set_column


def test_groups_with_and_without_a_run_column():
    d = np.array([1, 1, -1, -1, 1, 1, -1, -1], dtype=float)
    g = dg.make_groups(d, np.array([1, 1, 1, 1, 2, 2, 2, 2]))
    assert (g.passes, g.runs, g.nested) == (4, 2, False)  # passes of 2 rows are too short for random effects
    g = dg.make_groups(np.repeat(d, 3), np.repeat([1, 1, 1, 1, 2, 2, 2, 2], 3))
    assert (g.passes, g.runs, g.nested, g.random) == (4, 2, True, True)
    assert list(g.pass_run) == [0, 0, 1, 1]
    g = dg.make_groups(np.repeat(d, 3), None)
    assert (g.passes, g.runs, g.nested) == (4, 4, False)
    assert list(g.pass_id[:7]) == [0, 0, 0, 0, 0, 0, 1]


def test_cells_and_cell_level_columns():
    theta = np.radians(np.tile([0.0, 10.0, 20.0], 4))
    d = np.repeat([1.0, -1.0, 1.0, -1.0], 3)
    cells = dg.make_cells(theta, d)
    assert cells.cells == 6 and cells.replicated
    assert dg.cell_level(np.sin(3 * theta) * d, cells)
    assert not dg.cell_level(np.arange(12.0), cells)


def test_a_run_column_holding_one_run_estimates_no_run_variance(mch50_spec):
    text, _ = make_csv(mch50_spec, Plan(runs=6, warmup=WARM_SLOW), hidden=TB, seed=1)
    doc = diagnose_doc(mch50_spec, set_column(text, "run", "1"))
    gap_never_grows(doc)
    assert doc["effects_found"] == []
    assert doc["noise"]["after"]["runs"] == 1 and doc["noise"]["after"]["run_arcsec"] is None
