"""Issue 19, item 2: ISO 230-2 acceptance figures as requirements, predicted on the spec's [test_plan].

Done when: the precision table fails ``max_iso230_E_arcsec = 20`` and passes a limit above its
predicted E.  The prediction is checked against the same test measured by another path (synth's
noise-free rows read by the ISO 230-2 code measure uses) and against figures worked by hand.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from tests.support.paths import CONFIGS
from wormgear_cli.analysis.acceptance import plan_targets, predict
from wormgear_cli.cli import app
from wormgear_cli.spec.loader import load_spec, loads_spec

ARCSEC = math.pi / 648000.0
PRECISION = CONFIGS / "rotary-table-precision.toml"


def _with_requirements(tmp_path, source, lines: str, name="d.toml"):
    text = source.read_text(encoding="utf-8")
    text = re.sub(r"(?ms)^\[requirements\].*?(?=^\[|\Z)", "", text)
    path = tmp_path / name
    path.write_text(text + "\n[requirements]\n" + lines, encoding="utf-8")
    return path


def test_the_precision_table_fails_e_20_and_passes_a_limit_above_its_predicted_e(runner, tmp_path):
    e = predict(load_spec(PRECISION)).figure("E") / ARCSEC
    assert e > 20.0
    failing = _with_requirements(tmp_path, PRECISION, "max_iso230_E_arcsec = 20.0\n", "fail.toml")
    r = runner.invoke(app, ["check", str(failing), "-f", "json"])
    assert r.exit_code == 1
    [row] = json.loads(r.stdout)["files"][0]["requirements"]
    assert row["key"] == "requirements.max_iso230_E_arcsec" and row["measure"] == "range"
    assert row["value_arcsec"] == pytest.approx(e, rel=1e-12) and row["passed"] is False
    assert row["predicted"] == {"figure": "ISO 230-2 E", "targets": 24, "spacing": "irregular", "jitter": 0.25,
                                "seed": 0, "runs": 5, "reading_scatter_arcsec": 1.0}
    text = runner.invoke(app, ["check", str(failing)])
    assert text.stdout == (f"{failing}: FAIL requirements.max_iso230_E_arcsec: limit 20 arcsec, predicted ISO 230-2 "
                           f"E (range) {e:.2f} arcsec\n")
    passing = _with_requirements(tmp_path, PRECISION, f"max_iso230_E_arcsec = {math.ceil(e) + 1}\n", "pass.toml")
    r = runner.invoke(app, ["check", str(passing)])
    assert r.exit_code == 0 and r.stdout == f"{passing}: ok (1 requirement met)\n"


def test_the_prediction_is_the_test_synth_plans_read_as_measure_reads_it():
    """Another path to the same figures: synth's iso plan with the same seed (its targets), no noise,
    the rows through iso230_figures (as measure reads a file); synth rounds to 1e-4 arcsec."""
    from wormgear_cli.analysis.synth import Plan, synthesize
    from wormgear_cli.measurement.iso230 import iso230_figures

    spec = load_spec(PRECISION)
    got = predict(spec)
    cols, truth = synthesize(spec, Plan(kind="iso", targets=24, runs=5), seed=0)
    assert np.radians(truth["plan"]["target_angles_deg"]) == pytest.approx(got.targets, abs=1e-12)
    ref = iso230_figures(np.radians(cols["angle_deg"]), cols["error_arcsec"] * ARCSEC, cols["direction"])
    for name in ("E", "M", "B", "E_up", "E_down"):
        assert getattr(ref, name) / ARCSEC == pytest.approx(got.figure(name) / ARCSEC, abs=2e-4), name


BARE = """
[[stage]]
kind = "spur"
module_mm = 2.0
pressure_angle_deg = 20.0
kinematics = "involute"
[stage.pinion]
teeth = 20
[stage.gear]
teeth = 180
cumulative_pitch_deviation_mm = 0.020
[test_plan]
targets_deg = [TARGETS]
runs = 5
reading_scatter_arcsec = 1.5
"""


def test_figures_by_hand_on_a_single_once_per_turn_error():
    """One source: the gear's F_p = 20 um on r = 180 mm, a TE of amplitude a = F_p / (2 r) = 11.459 arcsec
    at order 1 (phase 0), no lost motion.  On targets every 10 deg the test reads a sin(theta): E = M =
    2 a (at 90 and 270 deg), B = 0; with a reading scatter s = 1.5 arcsec, A = E + 4 s, R = 4 s."""
    targets = ", ".join(str(10.0 * k) for k in range(36))
    spec = loads_spec(BARE.replace("TARGETS", targets))
    got = predict(spec)
    a = 0.020 / 360.0 / ARCSEC
    assert got.figure("E") / ARCSEC == pytest.approx(2 * a, rel=1e-9)
    assert got.figure("M") / ARCSEC == pytest.approx(2 * a, rel=1e-9)
    assert got.figure("B") / ARCSEC == pytest.approx(0.0, abs=1e-9)
    assert got.figure("A") / ARCSEC == pytest.approx(2 * a + 4 * 1.5, rel=1e-9)
    assert got.figure("R") / ARCSEC == pytest.approx(4 * 1.5, rel=1e-9)
    assert got.describe()["targets_deg"] == "as listed in [test_plan]"


def test_the_default_plan_is_iso_230_2s_cycle_with_irregular_targets():
    spec = load_spec(PRECISION)
    t = np.degrees(plan_targets(spec.test_plan))
    assert (spec.test_plan.targets, spec.test_plan.runs) == (24, 5)
    steps = np.diff(t)
    assert t.size == 24 and t[0] == 0.0 and np.all(steps > 0)
    assert steps.std() > 1.0  # irregular: not the 15 deg grid that would alias order 24
    assert np.all(np.abs(t - 15.0 * np.arange(24)) <= 0.25 * 15.0 + 1e-9)


def test_min_yield_counts_the_iso_limits_on_the_plans_targets(runner, tmp_path):
    """With min_yield an ISO 230-2 limit is judged by the yield of built drives (the tolerance engine's
    ISO metrics on the plan's targets): a limit above every sampled E passes all, one below none."""
    loose = _with_requirements(tmp_path, PRECISION, "max_iso230_E_arcsec = 500.0\nmin_yield = 0.9\n", "loose.toml")
    tight = _with_requirements(tmp_path, PRECISION, "max_iso230_E_arcsec = 1.0\nmin_yield = 0.9\n", "tight.toml")
    from wormgear_cli.workflows.check import check_yield

    assert check_yield(load_spec(loose), samples=2000).estimate.value == 1.0
    assert check_yield(load_spec(tight), samples=2000).estimate.value == 0.0
    r = runner.invoke(app, ["check", str(tight)])
    assert r.exit_code == 1
    assert "worst case over requirements.max_iso230_E_arcsec" in r.stdout and "FAIL requirements.min_yield" in r.stdout
