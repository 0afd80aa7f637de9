"""``wormgear diagnose`` through the command line: the shipped warm-up demo, -o, --write-spec, --plot, bad input,
help, tables at 80 columns."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tomllib

import pytest

from tests.support.paths import CONFIGS, ROOT
from wormgear_cli.cli import app
from wormgear_cli.physics.effects import EFFECTS
from wormgear_cli.spec.loader import load_spec

DEMO = CONFIGS / "mch50-warm.csv"
TRUTH = CONFIGS / "mch50-warm.truth.json"


def run(runner, *args):
    return runner.invoke(app, ["diagnose", *map(str, args)])


@pytest.fixture(scope="module")
def demo_json():
    from typer.testing import CliRunner

    result = CliRunner().invoke(app, ["diagnose", str(CONFIGS / "mch50.toml"), str(DEMO), "-f", "json"])
    assert result.exit_code == 0, result.stderr
    return result.stdout


def test_demo_names_thermal_backlash_and_the_gap_shrinks(demo_json):
    doc = json.loads(demo_json)
    truth = json.loads(TRUTH.read_text())
    k_true = truth["effects"]["thermal_backlash"]["centre_distance_um_per_K"]
    assert [e["name"] for e in doc["effects_found"]] == ["thermal_backlash"]
    found = doc["effects_found"][0]
    # parameters keyed as in the catalogue
    assert set(found["parameters"]) == {p.key for p in EFFECTS["thermal_backlash"].params}
    lo, hi = found["interval_95"]["centre_distance_um_per_K"]
    assert lo <= k_true <= hi
    assert doc["gap_after"]["rms_arcsec"] < 0.7 * doc["gap_before"]["rms_arcsec"]
    assert doc["gap_after"]["differential_rms_arcsec"] < 0.5 * doc["gap_before"]["differential_rms_arcsec"]
    # diagnose's own prediction assumes uniform warming; the demo's mesh warms 2.5x as far as its housing
    # (truth "thermal"), and the materials with that housing share predict the coefficient it was made with
    from wormgear_cli.physics.thermal import predicted_centre_distance_um_per_K

    assert found["prediction"]["inside_interval"] is False
    share = truth["thermal"]["housing_share"]
    assert lo <= predicted_centre_distance_um_per_K(load_spec(CONFIGS / "mch50.toml"), share) <= hi
    # the CSV gives away nothing of the truth: not its values, not the effect, not the seed
    # (the command that made it is in the truth file and in docs/commands/diagnose.md)
    text = DEMO.read_text()
    assert f"{k_true}" not in text and "phase_deg" not in text
    assert "thermal_backlash" not in text and "--seed" not in text


def test_demo_report_has_every_view(demo_json):
    doc = json.loads(demo_json)
    for key in ("gap_as_specified", "gap_before", "gap_after"):
        assert {"rms_arcsec", "max_arcsec", "common_rms_arcsec", "differential_rms_arcsec"} <= set(doc[key])
    assert doc["gap_as_specified"]["rms_arcsec"] > doc["gap_before"]["rms_arcsec"]
    assert {p["source"] for p in doc["fit"]["phases"]} >= {"gear_eccentricity", "wheel_eccentricity"}
    assert doc["noise"]["before"]["repeat_std_arcsec"] > 0 and doc["noise"]["after"]["white_arcsec"] > 0
    assert any(row["order"] == 8.0 and row["identifiable"] for row in doc["orders"]["before"])
    assert set(doc["residual_vs"]["before"]) == {"temperature_C", "time_s"}  # the load does not vary
    assert set(doc["iso230"]) == {"measured", "simulated_before", "simulated_after"}
    meas_b = doc["iso230"]["measured"]["B"]
    assert abs(doc["iso230"]["simulated_after"]["B"] - meas_b) <= abs(doc["iso230"]["simulated_before"]["B"] - meas_b)
    status = {c["name"]: c["status"] for c in doc["candidates"]}
    assert status["thermal_backlash"] == "named" and status["torsional_compliance"] == "unobservable"
    assert set(status) == set(EFFECTS)


def test_augmented_spec_loads_and_explains_the_data(runner, mch50_path, tmp_path, demo_json):
    out = tmp_path / "mch50-warm.toml"
    result = run(runner, mch50_path, DEMO, "--write-spec", out, "-f", "json")
    assert result.exit_code == 0, result.stderr
    assert f"wrote {out}" in result.stderr
    doc = json.loads(result.stdout)
    assert doc["augmented_spec"] == str(out)
    spec = load_spec(out)
    assert "thermal_backlash" in spec.effects
    raw = tomllib.loads(out.read_text())
    assert raw["effects"]["thermal_backlash"] == doc["effects_found"][0]["parameters"]
    fitted = {p["key"]: p["fitted_deg"] for p in doc["fit"]["phases"]}
    assert raw["assembly"]["wheel_eccentricity_phase_deg"] == fitted["assembly.wheel_eccentricity_phase_deg"]
    # diagnosing the augmented spec: nothing missing any more, and its starting gap is the first run's final gap
    again = json.loads(run(runner, out, DEMO, "-f", "json").stdout)
    assert again["effects_found"] == []
    assert again["verdict"].startswith("no missing effect found")
    assert again["gap_before"]["rms_arcsec"] == pytest.approx(doc["gap_after"]["rms_arcsec"], abs=0.01)
    assert {c["name"]: c["status"] for c in again["candidates"]}["thermal_backlash"] == "in_spec"


def test_output_never_overwrites_an_input(runner, mch50_path, tmp_path):
    spec = tmp_path / "drive.toml"
    data = tmp_path / "data.csv"
    shutil.copy(mch50_path, spec)
    shutil.copy(DEMO, data)
    before = spec.read_bytes()
    result = run(runner, spec, data, "-o", spec)
    assert result.exit_code == 2
    assert result.stderr == f"error: {spec}: refusing to overwrite the input file; choose another -o\n"
    assert spec.read_bytes() == before
    result = run(runner, spec, data, "--write-spec", spec)
    assert result.exit_code == 2
    assert result.stderr == f"error: {spec}: refusing to overwrite the input file; choose another --write-spec\n"
    assert spec.read_bytes() == before
    result = run(runner, spec, data, "--plot", data)
    assert result.exit_code == 2 and "refusing to overwrite" in result.stderr


BAD_CSV = {
    "no_error_column": ("angle_deg,direction\n0,1\n10,1\n", "missing required column error_arcsec"),
    "not_a_number": ("angle_deg,error_arcsec\n0,1.0\n10,abc\n", ":3: column error_arcsec: expected a number"),
    "one_row": ("angle_deg,error_arcsec\n0,1.0\n", "only one data row"),
}


@pytest.mark.parametrize("case", sorted(BAD_CSV))
def test_bad_measurement_exits_2_naming_the_line(case, runner, mch50_path, tmp_path):
    text, message = BAD_CSV[case]
    data = tmp_path / "bad.csv"
    data.write_text(text)
    result = run(runner, mch50_path, data)
    assert result.exit_code == 2
    assert result.stderr.startswith(f"error: {data}") and message in result.stderr
    assert result.stdout == ""


@pytest.mark.parametrize("args, message", [
    (("--alpha", "0.7"), "--alpha: expected a number in (0, 0.5), got 0.7"),
    (("--plot", "figure.txt"), "--plot expects a file ending in .png, .svg, .pdf"),
    (("--write-spec", "spec.json"), "--write-spec writes a drive spec; expected a file name ending in .toml"),
    (("-o", "same.toml", "--write-spec", "same.toml"), "-o and --write-spec name the same file"),
])
def test_bad_options_exit_2(args, message, runner, mch50_path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = run(runner, mch50_path, DEMO, *args)
    assert result.exit_code == 2
    assert message in result.stderr and result.stderr.startswith("error: ")
    assert not list(tmp_path.iterdir())


def test_missing_files_and_bad_spec_exit_2(runner, mch50_path, tmp_path):
    result = run(runner, mch50_path, tmp_path / "absent.csv")
    assert result.exit_code == 2 and result.stderr == f"error: {tmp_path / 'absent.csv'}: file not found\n"
    spec = tmp_path / "bad.toml"
    spec.write_text("[gear_pair]\nmodule_mm = -1\n")
    result = run(runner, spec, DEMO)
    assert result.exit_code == 2 and result.stderr.startswith(f"error: {spec}: ")


def test_same_input_same_output(runner, mch50_path, demo_json):
    assert run(runner, mch50_path, DEMO, "-f", "json").stdout == demo_json


def test_table_report_in_the_chosen_unit(runner, mch50_path):
    result = run(runner, mch50_path, DEMO)
    assert result.exit_code == 0
    assert "verdict: missing effect found: thermal_backlash" in result.stdout
    assert "gap: measured - simulated [arcsec]" in result.stdout
    assert "physics predicts" in result.stdout
    deg = run(runner, mch50_path, DEMO, "--unit", "deg").stdout
    assert "gap: measured - simulated [deg]" in deg and "[arcsec]" not in deg


def test_keep_phases_holds_the_spec_phases(runner, mch50_path):
    doc = json.loads(run(runner, mch50_path, DEMO, "-f", "json", "--keep-phases").stdout)
    assert doc["fit"]["phases_fitted"] is False
    assert all(p["fitted_deg"] == p["specified_deg"] for p in doc["fit"]["phases"])
    # the demo's phases are random: held at 0 deg the model misses the table badly
    assert doc["gap_before"]["rms_arcsec"] > 10.0


def test_help_has_an_example(runner):
    result = runner.invoke(app, ["diagnose", "--help"])
    assert result.exit_code == 0 and "Example: wormgear diagnose" in result.stdout


def test_plot_is_written(runner, mch50_path, tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "diag.png"
    result = run(runner, mch50_path, DEMO, "--plot", out, "-f", "json")
    assert result.exit_code == 0, result.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"wrote {out}" in result.stderr


def test_plot_without_matplotlib_exits_2_with_the_install_hint(runner, mch50_path, tmp_path, monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "matplotlib" else real(name, *a))
    result = run(runner, mch50_path, DEMO, "--plot", tmp_path / "x.png")
    assert result.exit_code == 2
    assert result.stderr == "error: plotting needs matplotlib: pip install matplotlib\n"


def test_importing_the_cli_does_not_import_the_diagnosis_core():
    code = "import sys, wormgear_cli.cli; print('wormgear_cli.diagnosis' in sys.modules, 'matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False False"
def test_unit_help_says_json_stays_in_arcsec(runner):
    result = runner.invoke(app, ["diagnose", "--help"], env={"COLUMNS": "200"})
    text = " ".join(result.stdout.split())
    assert "every angle in the output" not in text
    assert re.search(r"--unit.*JSON report is always in arcsec", text)


def test_o_writes_the_report_in_the_chosen_format(runner, mch50_path, tmp_path, demo_json):
    # -o means what it means in every command: the result (the report), in --format
    out = tmp_path / "report.json"
    result = run(runner, mch50_path, DEMO, "-f", "json", "-o", out)
    assert result.exit_code == 0, result.stderr
    assert result.stdout == ""
    assert out.read_text() == demo_json
    assert json.loads(out.read_text())["augmented_spec"] is None
    table = tmp_path / "report.txt"
    result = run(runner, mch50_path, DEMO, "-o", table, "--resamples", "0")
    assert result.exit_code == 0 and result.stdout == ""
    assert "verdict: missing effect found: thermal_backlash" in table.read_text()


def test_write_spec_help_says_the_comments_are_not_kept(runner):
    result = runner.invoke(app, ["diagnose", "--help"], env={"COLUMNS": "200"})
    text = " ".join(result.stdout.split())
    assert re.search(r"--write-spec.*the input's comments are not kept", text)
    assert re.search(r"--output.*Write the result to FILE", text)


FIELD = ROOT / "tests" / "data" / "field"


@pytest.mark.parametrize("drive, data", [
    ("mch50.toml", DEMO),
    ("mch50.toml", FIELD / "no-direction-column.csv"),
    (FIELD / "telescope-mount.toml", FIELD / "time-restarts-no-run.csv"),
])
def test_tables_fit_80_columns_without_cutting_a_number(drive, data, runner):
    drive = drive if isinstance(drive, type(CONFIGS)) else CONFIGS / drive
    result = runner.invoke(app, ["diagnose", str(drive), str(data), "--resamples", "0"], env={"COLUMNS": "80"})
    assert result.exit_code == 0, result.stderr
    assert "\u2026" not in result.stdout
    assert max(len(line) for line in result.stdout.splitlines()) <= 80
