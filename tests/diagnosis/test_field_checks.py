"""Issue 10: what the file does not state is said in diagnose's verdict line, as measure says it.

Each case is a clean measurement (a perfect MCH50 with a 6 um output-gear
runout hidden, written from the physics) with one fault made by hand; the
count or kind of the fault is known by construction.  ``measure`` and
``diagnose`` must flag it in their verdict lines with the same words (one
definition of each check).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.support.field_data import error_arcsec, perfect_mch50_toml, plan_angles, rows, to_csv

RUNOUT = {"output_gear_runout": {"eccentricity_um": 6.0, "phase_deg": 50.0}}


def _rows(seed: int, directions=(1, -1)):
    rng = np.random.default_rng(seed)
    r = rows(plan_angles(24, True, rng), runs=4, directions=directions)
    r["error_arcsec"] = error_arcsec(r, RUNOUT, rng)
    return r


def _take(r, idx):
    return {k: v[idx] for k, v in r.items()}


def _duplicated(r):
    n = r["angle_deg"].shape[0]
    return _take(r, np.r_[np.arange(n), [5, 40, 77]])  # three rows pasted again at the end


def _time_backwards(r):
    r = dict(r, time_s=r["time_s"].copy())
    r["time_s"][10], r["time_s"][11] = r["time_s"][11], r["time_s"][10]  # two rows of run 1 out of order
    return r


CASES = {
    # name: (make rows, columns written, the flag both verdicts must carry)
    "duplicates": (_duplicated, None, "3 duplicate rows"),
    "time": (_time_backwards, None, "time not monotonic inside a run"),
    "one-direction": (lambda r: r, None, "one direction only (forward)"),
    "flattened-up-down": (lambda r: r, ("angle_deg", "error_arcsec", "run", "time_s"),
                          "targets repeat within a run without a direction column"),
    "flattened-no-run": (lambda r: r, ("angle_deg", "error_arcsec", "time_s"),
                         "targets repeat without direction or run column"),
}


def _verdicts(runner, tmp_path, text):
    from wormgear_cli.cli import app

    spec = tmp_path / "drive.toml"
    spec.write_text(perfect_mch50_toml())
    data = tmp_path / "data.csv"
    data.write_text(text)
    d = runner.invoke(app, ["diagnose", str(spec), str(data), "--format", "json", "--resamples", "10"])
    assert d.exit_code == 0, d.output
    m = runner.invoke(app, ["measure", str(data), "--format", "json"])
    assert m.exit_code == 0, m.output
    return json.loads(d.stdout)["verdict"], json.loads(m.stdout)["verdict"], d


@pytest.mark.parametrize("case", list(CASES))
def test_structure_faults_are_in_the_diagnose_verdict_line(runner, tmp_path, case):
    make, columns, flag = CASES[case]
    r = make(_rows(3, directions=(1,) if case == "one-direction" else (1, -1)))
    text = to_csv(r, columns) if columns else to_csv(r)
    diag_verdict, measure_verdict, _ = _verdicts(runner, tmp_path, text)
    assert flag in measure_verdict
    assert flag in diag_verdict


def test_a_clean_file_has_no_data_flags(runner, tmp_path):
    diag_verdict, _, _ = _verdicts(runner, tmp_path, to_csv(_rows(4)))
    for _, _, flag in CASES.values():
        assert flag not in diag_verdict
    assert "duplicate" not in diag_verdict and "check the units" not in diag_verdict


def test_the_table_verdict_line_carries_the_flag(runner, tmp_path):
    from wormgear_cli.cli import app

    spec = tmp_path / "drive.toml"
    spec.write_text(perfect_mch50_toml())
    data = tmp_path / "data.csv"
    data.write_text(to_csv(_duplicated(_rows(5))))
    res = runner.invoke(app, ["diagnose", str(spec), str(data), "--resamples", "10"])
    assert res.exit_code == 0, res.output
    flat = " ".join(res.stdout.split())
    assert "3 duplicate rows" in flat.split("verdict: ", 1)[1].split(" gap:", 1)[0]
