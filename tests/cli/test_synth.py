"""Tests of ``wormgear synth`` (the command: files, seeds, options, messages)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.support.paths import MCH50
from tests.support.synth import csv_rows
from wormgear_cli.analysis.synth import COLUMNS
from wormgear_cli.cli import app
from wormgear_cli.measurement.readers import read_measurement
from wormgear_cli.spec.loader import load_spec


@pytest.fixture(scope="module")
def spec():
    return load_spec(MCH50)




def _synth(runner, tmp_path, *args, name="d.csv"):
    out = tmp_path / name
    res = runner.invoke(app, ["synth", str(MCH50), "-o", str(out), *args])
    assert res.exit_code == 0, res.stderr
    return out


def test_same_seed_same_bytes_other_seed_differs(runner, tmp_path):
    args = ["--noise-arcsec", "0.5", "--run-noise-arcsec", "1", "--temperature", "warmup:20:30:900"]
    a = _synth(runner, tmp_path, "--seed", "7", "--truth", str(tmp_path / "ta.json"), *args, name="a.csv")
    b = _synth(runner, tmp_path, "--seed", "7", "--truth", str(tmp_path / "tb.json"), *args, name="b.csv")
    c = _synth(runner, tmp_path, "--seed", "8", *args, name="c.csv")
    assert a.read_bytes() == b.read_bytes()
    assert (tmp_path / "ta.json").read_bytes() == (tmp_path / "tb.json").read_bytes()
    assert a.read_bytes() != c.read_bytes()
    _, ca = csv_rows(a.read_text())
    _, cc = csv_rows(c.read_text())
    assert not np.array_equal(ca["angle_deg"], cc["angle_deg"])  # other targets
    assert not np.array_equal(ca["error_arcsec"], cc["error_arcsec"])


def test_stdout_when_no_output(runner, tmp_path):
    res = runner.invoke(app, ["synth", str(MCH50), "--targets", "5", "--runs", "1"])
    assert res.exit_code == 0
    header, cols = csv_rows(res.stdout)
    assert tuple(header) == COLUMNS and len(cols["angle_deg"]) == 10


def test_written_file_reads_as_a_measurement(runner, tmp_path):
    out = _synth(runner, tmp_path, "--targets", "8", "--runs", "3", "--load", "steps:0:40")
    m = read_measurement(out)
    assert len(m) == 48
    assert m.present == {"direction", "run", "load_Nm", "temperature_C", "time_s"}
    assert set(m.run.tolist()) == {1, 2, 3}
    np.testing.assert_array_equal(np.unique(m.load[m.run == 2]), [40.0])


def test_truth_file_and_clean_data(runner, tmp_path):
    truth = tmp_path / "truth.json"
    out = _synth(runner, tmp_path, "--seed", "123", "--truth", str(truth), "--noise-arcsec", "0.37",
                 "--effect", "bearing_clearance:clearance_arcsec=6.5", "--effect", "thermal_backlash",
                 "--random-phases", "--temperature", "warmup:20:28:500")
    doc = json.loads(truth.read_text())
    assert doc["seed"] == 123 and doc["noise"]["white_arcsec"] == 0.37
    assert doc["effects"]["bearing_clearance"] == {"clearance_arcsec": 6.5}
    # thermal_backlash without a coefficient takes the physics prediction (steel/bronze/cast iron)
    spec = load_spec(MCH50)
    d_m1 = 2.5 / math.tan(spec.worm_pair.lead_angle)
    r1, r2 = d_m1 / 2, 2.5 * 30 / 2
    mat = spec.materials
    k_um = ((r1 + r2) * mat.housing_expansion - r1 * mat.worm_expansion - r2 * mat.wheel_expansion) * 1000
    assert doc["effects"]["thermal_backlash"]["centre_distance_um_per_K"] == pytest.approx(k_um)
    assert doc["random_phases"] is True
    phases = [v["phase_deg"] for v in doc["phases"].values()]
    assert len(set(phases)) == 5 and all(0 <= p < 360 for p in phases)
    text = out.read_text()
    comments = [ln for ln in text.splitlines() if ln.startswith("#")]
    assert comments and all(s not in "\n".join(comments) for s in ("123", "0.37", "6.5", "bearing", "thermal"))
    assert text.splitlines()[len(comments)] == ",".join(COLUMNS)


@pytest.mark.parametrize("args, message", [
    (["--temperature", "warmup:20:30"], "error: --temperature: expected constant:T, warmup:START:END:TAU_s, "
                                        "cycle:START:PEAK:TAU_s[:SWITCH_s] or "
                                        "mesh-warmup:START:END:TAU_s:HOUSING_SHARE:HOUSING_LAG_s, got 'warmup:20:30'"),
    (["--temperature", "warmup:20:30:0"], "error: --temperature: TAU_s must be > 0, got 0 in 'warmup:20:30:0'"),
    (["--temperature", "warmup:20:x:5"], "error: --temperature: expected a number, got 'x' in 'warmup:20:x:5'"),
    (["--load", "steps"], "error: --load: expected constant:L or steps:L1:L2:... [N m], got 'steps'"),
    (["--effect", "nope"], "error: --effect: unknown effect 'nope' (known: output_gear_runout, "
                           "intermediate_shaft_runout, worm_runout, gear_mesh_error, thermal_backlash, "
                           "thermal_drift, torsional_compliance, bearing_clearance)"),
    (["--effect", "worm_runout"], "error: --effect worm_runout: missing amplitude_um (a number in [0, 500] um)"),
    (["--effect", "bearing_clearance:clearance_arcsec=-3"],
     "error: --effect bearing_clearance: clearance_arcsec = -3 outside its range [0, 3600] arcsec"),
    (["--revs", "0"], "error: --revs: expected a number in (0, 1000], got 0"),
    (["--jitter", "0.5"], "error: --jitter: expected a number in [0, 0.5), got 0.5"),
])
def test_bad_options_exit_2(runner, tmp_path, args, message):
    out = tmp_path / "d.csv"
    res = runner.invoke(app, ["synth", str(MCH50), "-o", str(out), *args])
    assert res.exit_code == 2
    assert res.stderr.strip() == message
    assert not out.exists()


def test_typer_checks_exit_2(runner):
    for args in (["--runs", "0"], ["--plan", "random"], ["--targets", "1"], ["--run-noise", "walk"]):
        res = runner.invoke(app, ["synth", str(MCH50), *args])
        assert res.exit_code == 2, args


def test_output_files_must_differ_and_not_be_the_drive(runner, tmp_path):
    drive = tmp_path / "d.toml"
    drive.write_text(MCH50.read_text())
    res = runner.invoke(app, ["synth", str(drive), "-o", str(drive)])
    assert res.exit_code == 2 and drive.read_text() == MCH50.read_text()
    assert "refusing to overwrite the input file" in res.stderr
    same = tmp_path / "x.csv"
    res = runner.invoke(app, ["synth", str(drive), "-o", str(same), "--truth", str(same)])
    assert res.exit_code == 2
    assert res.stderr.strip() == f"error: {same}: -o and --truth name the same file"
    assert not same.exists()


def test_help_has_example(runner):
    res = runner.invoke(app, ["synth", "--help"])
    assert res.exit_code == 0 and "Example: wormgear synth" in res.stdout


@pytest.mark.pinned  # bytes made with the current numpy
def test_shipped_demo_is_exactly_what_its_documented_command_makes(runner, tmp_path):
    """configs/mch50-warm.csv is reproducible from the command kept in its truth file."""
    import json
    import shlex

    from tests.support.paths import CONFIGS, ROOT

    truth = json.loads((CONFIGS / "mch50-warm.truth.json").read_text())
    args = shlex.split(truth["command"])[1:]
    args[args.index("-o") + 1] = str(tmp_path / "warm.csv")
    args[args.index("--truth") + 1] = str(tmp_path / "warm.json")
    args[args.index("configs/mch50.toml")] = str(ROOT / "configs" / "mch50.toml")
    r = runner.invoke(app, args)
    assert r.exit_code == 0, r.stderr
    assert (tmp_path / "warm.csv").read_bytes() == (CONFIGS / "mch50-warm.csv").read_bytes()
    made = json.loads((tmp_path / "warm.json").read_text())
    assert made.pop("spec").endswith("configs/mch50.toml")
    assert made == {k: v for k, v in truth.items() if k not in ("command", "spec")}

