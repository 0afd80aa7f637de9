"""Structure the file does not state, the verdict line, one-position tests, and 80-column tables.

Hand-worked values are written out with their arithmetic; data are constructed so the right
answer is known without this code.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from wormgear_cli.cli import app
from wormgear_cli.workflows.measure import measure


def write(tmp_path, name, header, rows):
    path = tmp_path / name
    path.write_text(header + "\n" + "".join(",".join(str(c) for c in r) + "\n" for r in rows))
    return path


def test_flattened_up_down_table_with_run_column_withholds_one_direction_figures(tmp_path):
    # 3 runs over 4 targets at 0, 90, 180, 270 deg, up then down in each run, direction column lost
    rows = []
    for run in range(3):
        for a in (0, 90, 180, 270):
            rows.append((a, 1.0 + run, run))
        for a in (270, 180, 90, 0):
            rows.append((a, -5.0 - run, run))
    res = measure(write(tmp_path, "flat.csv", "angle_deg,error_arcsec,run", rows))
    assert res.mixed_directions
    assert math.isnan(res.figures.R_up) and math.isnan(res.figures.A_up) and math.isnan(res.figures.E_up)
    assert "targets repeat within a run without a direction column" in res.verdict
    # with a direction column the same rows are an ordinary table: nothing withheld
    rows_d = [(a, e, r, 1 if k % 8 < 4 else -1) for k, (a, e, r) in enumerate(rows)]
    res = measure(write(tmp_path, "dir.csv", "angle_deg,error_arcsec,run,direction", rows_d))
    assert not res.mixed_directions
    # forward errors per target 1, 2, 3: s = 1, R fwd = 4 s = 4
    assert res.figures.R_up / (math.pi / 648000) == pytest.approx(4.0)


def test_verdict_names_duplicates_time_order_and_one_direction(tmp_path):
    rows = [(0, 1, 0, 0.0, 1), (90, 2, 0, 1.0, 1), (90, 2, 0, 1.0, 1), (180, 3, 0, 0.5, 1), (270, 4, 0, 3.0, 1)]
    res = measure(write(tmp_path, "odd.csv", "angle_deg,error_arcsec,run,time_s,direction", rows))
    v = res.verdict
    assert "1 duplicate row" in v
    assert "time not monotonic inside a run" in v
    assert "one direction only (forward)" in v


def test_tables_fit_80_columns_without_cutting_numbers(runner, tmp_path, mch50_path):
    # large deviations (-1234.57 arcsec) and long drive labels
    rows = []
    for run in range(2):
        for d in (1, -1):
            for k, a in enumerate(np.arange(0, 360, 15.0) + 0.123456):
                rows.append((round(a, 6), round(-1234.567 + 11.1 * k + 300 * (d < 0) + 0.7 * run, 3), d, run))
    path = write(tmp_path, "big.csv", "angle_deg,error_arcsec,direction,run", rows)
    result = runner.invoke(app, ["measure", str(path), "--drive", str(mch50_path)], env={"COLUMNS": "80"})
    assert result.exit_code == 0
    out = result.stdout
    assert "…" not in out
    assert max(len(line) for line in out.splitlines()) <= 80
    assert "-1234.22" in out  # first target, forward mean of -1234.567 and -1233.867, whole
    doc = json.loads(runner.invoke(app, ["measure", str(path), "-f", "json"]).stdout)
    for t in doc["per_target"]:
        assert f"{t['mean_forward']:.2f}" in out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_duplicate_count_matches_a_set_of_rows(tmp_path, seed):
    from collections import Counter

    from wormgear_cli.measurement.checks import duplicate_rows
    from wormgear_cli.measurement.readers import read_measurement

    rng = np.random.default_rng(seed)
    rows = [(int(rng.integers(0, 6)) * 30, int(rng.integers(0, 3)), int(rng.choice([-1, 1])), int(rng.integers(0, 2)))
            for _ in range(60)]
    m = read_measurement(write(tmp_path, "d.csv", "angle_deg,error_arcsec,direction,run", rows))
    expected = sum(c - 1 for c in Counter(rows).values())  # rows beyond the first of each distinct row
    _, inverse = np.unique(m.angle, return_inverse=True)
    repeated = np.bincount(inverse)[inverse] > 1
    assert duplicate_rows(m) == expected
    assert duplicate_rows(m, repeated) == expected
