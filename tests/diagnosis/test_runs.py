"""Run structure under diagnose: passes and runs from the columns, cells of target and direction."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.diagnosis_data import (
    TB,
    WARM_SLOW,
    Plan,
    diagnose_doc,
    drop_column,
    gap_never_grows,
    make_csv,
    set_column,
)
from tests.support.paths import CONFIGS, ROOT
from wormgear_cli import diagnosis as dg
from wormgear_cli.diagnosis import diagnose


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


# --- sessions joined end to end: time_s restarts and there is no run column ------------------------------------------

FIELD = ROOT / "tests" / "data" / "field"


def test_time_going_backwards_starts_a_new_pass():
    d = np.ones(7)
    t = np.array([0.0, 1.0, 2.0, 0.5, 1.5, 0.2, 0.3])
    assert list(dg.time_restarts(t)) == [False, False, False, True, False, True, False]
    g = dg.make_groups(d, None, t)
    assert list(g.pass_id) == [0, 0, 0, 1, 1, 2, 2] and g.runs == 3
    assert "time_s goes backwards" in g.describe
    # a run column wins; no time column, or time never going back, changes nothing
    assert dg.make_groups(d, np.array([1, 1, 1, 1, 2, 2, 2]), t).passes == 2
    assert dg.make_groups(d, None).passes == 1 and dg.make_groups(d, None, np.arange(7.0)).passes == 1


def test_field_case_time_restarts_gives_the_noise_floor_of_the_run_column():
    # ../cases/field README: 0.62 arcsec with and without the run column (1.45 before the fix)
    from wormgear_cli.measurement.readers import read_measurement
    from wormgear_cli.spec.loader import load_spec

    spec = load_spec(FIELD / "telescope-mount.toml")
    floors = [diagnose(spec, read_measurement(FIELD / f"time-restarts-{kind}.csv"), resamples=0).noise_floor
              for kind in ("no-run", "with-run")]
    assert floors[0] == pytest.approx(0.62, abs=0.005)
    assert floors[0] == pytest.approx(floors[1], rel=1e-9)


@pytest.mark.parametrize("seed", [2, 3, 4])
def test_sessions_joined_without_a_run_column_keep_the_white_noise_floor(seed):
    # another drive, one direction, two sessions whose clocks both start at 0; the only noise is white
    # (0.3 arcsec, run offsets 0): the point-to-point floor must be about 0.3 whether or not the run
    # column is there (sorting both sessions by time would interleave them and inflate it)
    from wormgear_cli.measurement.readers import parse_measurement
    from wormgear_cli.spec.loader import load_spec

    spec = load_spec(CONFIGS / "rotary-table-precision.toml")
    plan = Plan(kind="dense", targets=150, runs=2, directions=(1,), dwell_s=2.0)
    text, _ = make_csv(spec, plan, seed=seed, white=0.3, run_sd=0.0)
    lines = text.splitlines()
    header = lines[1].split(",")
    it, ir = header.index("time_s"), header.index("run")
    rows = [line.split(",") for line in lines[2:]]
    for r in rows:
        r[it] = repr(float(r[it]) - (int(r[ir]) - 1) * plan.targets * plan.dwell_s)
    joined = "\n".join(lines[:2] + [",".join(r) for r in rows]) + "\n"
    floor_run = diagnose(spec, parse_measurement(joined, "<run>"), resamples=0).noise_floor
    no_run = drop_column(joined, "run")
    floor_time = diagnose(spec, parse_measurement(no_run, "<no run>"), resamples=0).noise_floor
    assert floor_time == pytest.approx(floor_run, rel=1e-9)
    assert floor_time == pytest.approx(0.3, rel=0.25)


def test_the_run_structure_line_says_runs_were_inferred_from_time(runner):
    # field case: no run column, time_s restarts -> the report's structure says the runs were inferred
    import json

    from wormgear_cli.cli import app

    docs = []
    for kind in ("no-run", "with-run"):
        r = runner.invoke(app, ["diagnose", str(FIELD / "telescope-mount.toml"), str(FIELD / f"time-restarts-{kind}.csv"),
                                "--format", "json", "--resamples", "0"])
        assert r.exit_code == 0, r.output
        docs.append(json.loads(r.stdout))
    structures = [_find_structure(d) for d in docs]
    assert structures[0].startswith("no run column: runs inferred where time_s goes backwards, one pass per run "
                                    "and direction")
    assert structures[1].startswith("run column: one pass per run and direction")


def _find_structure(doc):
    found = []

    def walk(x):
        if isinstance(x, dict):
            if "structure" in x and "passes" in x:
                found.append(x["structure"])
            for v in x.values():
                walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)

    walk(doc)
    assert found and len(set(found)) == 1  # (before and after the effects: one structure)
    return found[0]
