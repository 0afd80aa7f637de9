"""Issue 10: the thermal_backlash prediction says which housing warm-up it assumes ([materials] housing_rise_ratio).

The prediction is worked by hand here: the worm pair's centre distance a = r1 + r2
(r1 = z_worm m / tan(lambda) / 2 the worm pitch radius, r2 = m z3 / 2 the wheel's)
grows with the housing and shrinks as worm and wheel grow,

    k = a alpha_H q - (r1 alpha_1 + r2 alpha_2)   [mm/K],

with the housing rising q kelvin per kelvin of the measured (mesh) temperature
(linear thermal expansion, dL = L alpha dT, of each part).  MCH50: m = 2.5 mm,
lambda = 3.178 deg, z3 = 30, steel worm 11.5, bronze wheel 18.5, cast-iron
housing 10.5 ppm/K (the spec's [materials] defaults).  The demo
configs/mch50-warm.csv was made with the housing at 0.4 of the mesh's rise
(configs/mch50-warm.truth.json: -0.7006 um/K).
"""

from __future__ import annotations

import json
import math

import pytest

from tests.support.paths import CONFIGS, MCH50

R1 = 2.5 / math.tan(math.radians(3.178)) / 2.0
R2 = 2.5 * 30 / 2.0


def hand_k_um_per_K(q: float) -> float:
    return ((R1 + R2) * 10.5 * q - (R1 * 11.5 + R2 * 18.5)) * 1e-3  # ppm/K * mm = 1e-3 um/K


def _spec_copy(tmp_path, line: str):
    text = MCH50.read_text().replace("[materials]\n", f"[materials]\n{line}\n")
    path = tmp_path / "mch50-copy.toml"
    path.write_text(text)
    return path


def _prediction(runner, spec):
    from wormgear_cli.cli._app import app

    res = runner.invoke(app, ["diagnose", str(spec), str(CONFIGS / "mch50-warm.csv"), "-f", "json",
                              "--resamples", "10"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert [e["name"] for e in doc["effects_found"]] == ["thermal_backlash"]
    return doc["effects_found"][0]


def test_hand_values_match_the_truth_file():
    truth = json.loads((CONFIGS / "mch50-warm.truth.json").read_text())
    assert hand_k_um_per_K(0.4) == pytest.approx(truth["thermal"]["predicted_um_per_K"], rel=1e-3)


def test_housing_rise_ratio_makes_the_prediction_match_the_fit(runner, tmp_path):
    found = _prediction(runner, _spec_copy(tmp_path, "housing_rise_ratio = 0.4"))
    pred = found["prediction"]
    assert pred["centre_distance_um_per_K"] == pytest.approx(hand_k_um_per_K(0.4), rel=1e-3)
    assert pred["housing_rise_ratio"] == 0.4
    assert "0.4 K per K" in pred["basis"]
    assert pred["inside_interval"] is True
    assert pred["fitted_over_predicted"] == pytest.approx(1.0, abs=0.03)


def test_default_prediction_says_it_assumes_uniform_warming(runner):
    found = _prediction(runner, MCH50)
    pred = found["prediction"]
    assert pred["centre_distance_um_per_K"] == pytest.approx(hand_k_um_per_K(1.0), rel=1e-3)
    assert pred["housing_rise_ratio"] == 1.0 and "housing_rise_ratio = 1" in pred["basis"]
    assert pred["inside_interval"] is False


@pytest.mark.parametrize("value", ["0.0", "-0.2", "1.6"])
def test_housing_rise_ratio_outside_its_range_is_refused(runner, tmp_path, value):
    from wormgear_cli.cli._app import app

    res = runner.invoke(app, ["analyze", str(_spec_copy(tmp_path, f"housing_rise_ratio = {value}"))])
    assert res.exit_code == 2
    assert "housing_rise_ratio" in res.output


def test_housing_rise_ratio_at_the_top_of_its_range_loads(tmp_path):
    from wormgear_cli.spec.loader import load_spec

    assert load_spec(_spec_copy(tmp_path, "housing_rise_ratio = 1.5")).materials.housing_rise_ratio == 1.5
