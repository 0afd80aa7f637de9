"""The shipped warm-up demo, regenerated from its documented command, shows the effect clearly.

configs/mch50-warm.csv is made by the command kept in configs/mch50-warm.truth.json
(``command``).  Regenerated here into a temporary folder and diagnosed, it must give
what the walkthrough in docs/commands/diagnose.md promises (issue 10, "The demo"):
``thermal_backlash`` named, a gap before the effect is added of at least 3x the noise
floor, a gap after within 1.2x the noise floor, and a 95 % interval of the fitted
coefficient that holds the truth.  The truth's coefficient is the materials' physics
with the demo's housing share (models/thermal.py), not a number copied from a fit.
"""

from __future__ import annotations

import json
import re
import shlex

import pytest

from tests.support.paths import CONFIGS, MCH50, ROOT
from wormgear_cli.cli import app
from wormgear_cli.physics.thermal import predicted_centre_distance_um_per_K

TRUTH = json.loads((CONFIGS / "mch50-warm.truth.json").read_text())


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory):
    from typer.testing import CliRunner

    folder = tmp_path_factory.mktemp("demo")
    args = shlex.split(TRUTH["command"])
    assert args[:2] == ["wormgear", "synth"]
    args = args[1:]
    args[args.index("-o") + 1] = str(folder / "warm.csv")
    args[args.index("--truth") + 1] = str(folder / "warm.json")
    args[args.index("configs/mch50.toml")] = str(MCH50)
    runner = CliRunner()
    made = runner.invoke(app, args)
    assert made.exit_code == 0, made.stderr
    result = runner.invoke(app, ["diagnose", str(MCH50), str(folder / "warm.csv"), "-f", "json"])
    assert result.exit_code == 0, result.stderr
    return json.loads((folder / "warm.json").read_text()), json.loads(result.stdout), (folder / "warm.csv").read_text()


def test_demo_gap_is_clearly_above_the_noise_before_and_at_it_after(regenerated):
    _truth, doc, _text = regenerated
    floor = doc["noise"]["floor_arcsec"]
    assert floor > 0
    assert doc["gap_before"]["rms_arcsec"] >= 3.0 * floor
    assert doc["gap_after"]["rms_arcsec"] <= 1.2 * floor


def test_demo_names_thermal_backlash_and_its_interval_holds_the_truth(regenerated, mch50_spec):
    truth, doc, _text = regenerated
    assert [e["name"] for e in doc["effects_found"]] == ["thermal_backlash"]
    assert doc["verdict"] == "missing effect found: thermal_backlash"
    lo, hi = doc["effects_found"][0]["interval_95"]["centre_distance_um_per_K"]
    k_true = truth["effects"]["thermal_backlash"]["centre_distance_um_per_K"]
    assert lo <= k_true <= hi
    # the truth is the physics of the stated model, worked by hand (not through the package): worm and wheel
    # at the recorded (mesh) temperature, the housing rising by the housing share q = 0.4 of it.  Table 1:
    # worm pitch radius r1 = 1 x 2.5 / tan(3.178 deg) / 2 = 22.50 mm, wheel r2 = 2.5 x 30 / 2 = 37.5 mm,
    # a = 60.0 mm; k = a alpha_H q - (r1 alpha_1 + r2 alpha_2) = 60 x 10.5 x 0.4 - (22.5 x 11.5 + 37.5 x
    # 18.5) [1e-3 um/K] = 252 - (258.75 + 693.75) = -700.5e-3 um/K
    assert truth["thermal"]["housing_share"] == 0.4
    assert k_true == pytest.approx(-0.7005, abs=2e-4)
    assert k_true == pytest.approx(predicted_centre_distance_um_per_K(mch50_spec, 0.4), rel=1e-12)


def test_demo_is_physically_a_mesh_warming_further_than_its_housing(regenerated):
    truth, doc, _text = regenerated
    temp, thermal = truth["temperature"], truth["thermal"]
    assert temp["kind"] == "mesh-warmup"
    mesh_rise = doc["signals"]["temperature_C"][1] - doc["signals"]["temperature_C"][0]
    housing_rise = thermal["housing_temperature_C"][1] - thermal["housing_temperature_C"][0]
    # tens of kelvin at the mesh, the housing well behind
    assert mesh_rise >= 20.0 and housing_rise < 0.5 * mesh_rise
    # the lag's non-linearity (what the linear catalogue term cannot follow) stays well below the noise floor
    assert thermal["nonlinearity_rms_arcsec"] < 0.25 * doc["noise"]["floor_arcsec"]
    # an ISO 230-2 cycle (5 runs each way, irregular targets) repeated as the table warms
    plan = truth["plan"]
    assert plan["kind"] == "iso" and plan["runs"] == 5 and plan["cycles"] >= 3 and plan["jitter"] > 0


def test_regenerated_demo_is_the_shipped_one_and_gives_no_hint(regenerated):
    _truth, _doc, text = regenerated
    assert text == (CONFIGS / "mch50-warm.csv").read_text()
    lowered = text.lower()
    for word in ("thermal_backlash", "housing", "--seed", "share", "lag", "um_per_k", "um/k", "0.4:"):
        assert word not in lowered, word


def test_walkthrough_shows_the_documented_command():
    page = (ROOT / "docs" / "commands" / "diagnose.md").read_text(encoding="utf-8")
    flat = re.sub(r"\s*\\\n\s*", " ", page)
    assert TRUTH["command"] in flat


@pytest.mark.slow
def test_demo_design_is_not_seed_luck(tmp_path):
    """The same plan and physics with other seeds: every figure holds, the interval misses the truth rarely."""
    from typer.testing import CliRunner

    runner = CliRunner()
    base = shlex.split(TRUTH["command"])[1:]
    base[base.index("configs/mch50.toml")] = str(MCH50)
    covered = 0
    seeds = (2, 3, 4, 5, 6)
    for seed in seeds:
        args = list(base)
        args[args.index("--seed") + 1] = str(seed)
        args[args.index("-o") + 1] = str(tmp_path / f"w{seed}.csv")
        args[args.index("--truth") + 1] = str(tmp_path / f"w{seed}.json")
        assert runner.invoke(app, args).exit_code == 0
        doc = json.loads(runner.invoke(app, ["diagnose", str(MCH50), str(tmp_path / f"w{seed}.csv"),
                                             "-f", "json"]).stdout)
        floor = doc["noise"]["floor_arcsec"]
        assert [e["name"] for e in doc["effects_found"]] == ["thermal_backlash"], seed
        assert doc["gap_before"]["rms_arcsec"] >= 3.0 * floor, seed
        assert doc["gap_after"]["rms_arcsec"] <= 1.2 * floor, seed
        lo, hi = doc["effects_found"][0]["interval_95"]["centre_distance_um_per_K"]
        covered += lo <= TRUTH["effects"]["thermal_backlash"]["centre_distance_um_per_K"] <= hi
    # 95 % intervals: missing in 2 of 5 has probability 2.3 % when the coverage is nominal
    assert covered >= len(seeds) - 1
