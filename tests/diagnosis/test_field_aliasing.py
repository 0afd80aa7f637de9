"""Issue 10: orders folded onto each other by the target spacing are named together.

With 136 equally spaced targets theta_k = 2 pi k / 136, sin(144 theta_k + psi)
= sin(8 theta_k + 2 pi k + psi) = sin(8 theta_k + psi): a spur-mesh error
(order z1 = 144) and an intermediate-shaft runout (order i_c = 8) give the
same numbers at every target, so neither can be named alone.  Jittered
targets break the identity and the right one must be named.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.support.diagnosis_data import R_1, R_B1
from tests.support.field_data import error_arcsec, perfect_mch50_toml, plan_angles, rows, to_csv, wheel_ecc_amplitude

MESH = {"gear_mesh_error": {"amplitude_um": 4.0, "phase_deg": 30.0}}


def _files(tmp_path, jitter: bool, s2_mm: float, seed: int):
    rng = np.random.default_rng(seed)
    r = rows(plan_angles(136, jitter, rng), runs=4)
    model = None
    if s2_mm:
        amp, psi = wheel_ecc_amplitude(s2_mm), float(rng.uniform(0, 2 * math.pi))
        model = lambda theta, d: amp * np.sin(8.0 * theta + psi)  # noqa: E731
    r["error_arcsec"] = error_arcsec(r, MESH, rng, model)
    spec = tmp_path / "drive.toml"
    spec.write_text(perfect_mch50_toml(s2_mm))
    data = tmp_path / "data.csv"
    data.write_text(to_csv(r))
    return spec, data


def _run(runner, spec, data, *extra):
    from wormgear_cli.cli._app import app

    res = runner.invoke(app, ["diagnose", str(spec), str(data), "--resamples", "20", *extra])
    assert res.exit_code == 0, res.output
    return res.output


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("s2_mm", [0.0, 0.016], ids=["no-order-8-source", "wheel-eccentricity-in-spec"])
def test_136_even_targets_name_mesh_error_and_shaft_runout_together(runner, tmp_path, s2_mm, seed):
    spec, data = _files(tmp_path, False, s2_mm, seed)
    doc = json.loads(_run(runner, spec, data, "--format", "json"))
    status = {c["name"]: c for c in doc["candidates"]}
    named = [e["name"] for e in doc["effects_found"]]
    assert named == ["intermediate_shaft_runout"] or named == ["gear_mesh_error"], doc["verdict"]
    other = ({"intermediate_shaft_runout", "gear_mesh_error"} - set(named)).pop()
    assert status[other]["status"] == "indistinguishable"
    assert named[0] in status[other]["reason"]
    assert other in doc["effects_found"][0]["indistinguishable_from"]
    verdict = doc["verdict"]
    assert "gear_mesh_error" in verdict and "intermediate_shaft_runout" in verdict and "144" in verdict
    assert "irregular target spacing" in verdict
    # the data are explained: the gap falls to the noise (0.3 white + 0.2 per run)
    assert doc["gap_after"]["rms_arcsec"] < 0.45 < 2.0 < doc["gap_before"]["rms_arcsec"]
    if not s2_mm:
        # sizes by hand: a mesh error a [um] is a / R_1 rad; the same numbers as an order-8 eccentricity
        # e / R_b1 need e = a R_b1 / R_1 (phase unchanged: 144 theta_k = 8 theta_k + 2 pi k)
        a = MESH["gear_mesh_error"]["amplitude_um"]
        twin = status["gear_mesh_error"] if named == ["intermediate_shaft_runout"] else None
        if twin is not None:
            assert doc["effects_found"][0]["parameters"]["eccentricity_um"] == pytest.approx(a * R_B1 / R_1, rel=0.05)
            assert twin["estimate"]["amplitude_um"] == pytest.approx(a, rel=0.05)
            assert twin["estimate"]["phase_deg"] == pytest.approx(30.0, abs=3.0)
    table = _run(runner, spec, data)
    flat = " ".join(table.split())
    assert "gear_mesh_error" in flat and "indistinguishable" in flat
    verdict_line = flat.split("verdict: ", 1)[1].split(" gap:", 1)[0]
    assert "gear_mesh_error" in verdict_line and "intermediate_shaft_runout" in verdict_line


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("s2_mm", [0.0, 0.016], ids=["no-order-8-source", "wheel-eccentricity-in-spec"])
def test_jittered_targets_of_the_same_drive_name_the_mesh_error(runner, tmp_path, s2_mm, seed):
    spec, data = _files(tmp_path, True, s2_mm, seed)
    doc = json.loads(_run(runner, spec, data, "--format", "json"))
    assert [e["name"] for e in doc["effects_found"]] == ["gear_mesh_error"], doc["verdict"]
    found = doc["effects_found"][0]
    assert found["parameters"]["amplitude_um"] == pytest.approx(4.0, rel=0.05)
    assert "intermediate_shaft_runout" not in doc["verdict"]
    assert found["indistinguishable_from"] == []


@pytest.mark.parametrize("n, expected", [(136, [("gear_mesh_error", 144.0)]), (152, [("gear_mesh_error", 144.0)]),
                                         (24, []), (1000, [])])
def test_aliased_effects_follow_the_target_count(mch50_spec, n, expected):
    # 144 - 136 = 8 and 152 - 144 = 8 (mirrored); with 24 targets order 144 falls on a constant (144 = 6 x 24),
    # not on order 8; 1000 targets resolve every catalogue order (all below 500)
    from wormgear_cli.analysis.accuracy import geometry
    from wormgear_cli.diagnosis.candidates import aliased_effects
    from wormgear_cli.physics.effects import EFFECTS

    theta = 2 * math.pi * np.arange(n) / n
    assert aliased_effects(theta, "intermediate_shaft_runout", list(EFFECTS), geometry(mch50_spec)) == expected
