"""The Python API (wormgear_cli.api, docs/api.md).

* The examples of docs/api.md and of the API's docstrings run (doctest).
* Every function's ``to_dict(unit)`` is the command's ``--format json --unit
  UNIT`` document, and its Angle fields are the document's values: the API
  and the CLI cannot drift apart.
* Angle rules (units from wormgear_cli.units, comparisons with angles only).
* ``import wormgear_cli`` stays light: no numpy, no scipy, no API, no core
  module until a name is used; ``wormgear analyze`` never loads the API.
"""

from __future__ import annotations

import csv
import doctest
import io
import json
import math
import subprocess
import sys

import numpy as np
import pytest

import wormgear_cli.api as wg
from tests.support.paths import CONFIGS, MCH50, ROOT
from wormgear_cli.angles import Angle, AngleArray
from wormgear_cli.cli import app
from wormgear_cli.errors import SpecError, UsageError
from wormgear_cli.units import RAD_PER_UNIT

WARM = CONFIGS / "mch50-warm.csv"
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def cli_json(runner, *args) -> dict:
    result = runner.invoke(app, [str(a) for a in args])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


# --- the documentation runs -----------------------------------------------------------------------------------


def test_api_page_examples_run(monkeypatch):
    monkeypatch.chdir(ROOT)  # the page names configs/... relative to the repository root
    result = doctest.testfile(str(ROOT / "docs" / "api.md"), module_relative=False, optionflags=FLAGS,
                              raise_on_error=False, verbose=False)
    assert result.attempted >= 40, "docs/api.md lost its examples"
    assert result.failed == 0


@pytest.mark.parametrize("module", ["wormgear_cli.api", "wormgear_cli.angles"])
def test_docstring_examples_run(monkeypatch, module):
    import importlib

    monkeypatch.chdir(ROOT)
    result = doctest.testmod(importlib.import_module(module), optionflags=FLAGS)
    assert result.attempted > 0
    assert result.failed == 0


def test_api_page_is_in_the_nav():
    assert "api.md" in (ROOT / "mkdocs.yml").read_text(encoding="utf-8")


# --- API == CLI -----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("unit", ["arcsec", "deg"])
def test_consistency_analyze_api_equals_cli(runner, unit):
    """A consistency check (both go through the same report code); the figures themselves are pinned
    against the paper and hand-worked values in tests/analysis/test_paper.py and tests/physics."""
    r = wg.analyze(MCH50)
    doc = cli_json(runner, "analyze", MCH50, "--format", "json", "--unit", unit)
    assert r.to_dict(unit) == doc
    assert r.transmission_error.to(unit) == doc["total"]["transmission_error"]
    assert r.backlash.to(unit) == doc["total"]["backlash"]
    w, g = doc["stages"]  # motor -> output: the worm stage, then the spur (gear) stage
    assert r.gear.transmission_error.to(unit) == g["transmission_error"]
    assert r.worm.backlash.to(unit) == w["backlash"]
    assert r.worm.parts["backlash"]["profile"].to(unit) == w["backlash_parts"]["profile"]
    assert r.worm.at_output["transmission_error"].to(unit) == pytest.approx(w["contribution"]["transmission_error"],
                                                                             rel=1e-14)
    assert r.ratios == doc["ratios"]


def test_analyze_metrics_need_no_unit_and_match_the_csv(runner):
    r = wg.analyze(MCH50)
    result = runner.invoke(app, ["analyze", str(MCH50), "--format", "csv", "--unit", "urad"])
    assert result.exit_code == 0
    row = next(csv.DictReader(io.StringIO(result.stdout)))
    from wormgear_cli.analysis.accuracy import INFO_COLUMNS, METRIC_COLUMNS

    assert set(r.metrics) == set(METRIC_COLUMNS) | set(INFO_COLUMNS)
    for c in METRIC_COLUMNS:
        assert isinstance(r.metrics[c], Angle)
        assert r.metrics[c].urad == pytest.approx(float(row[c]), rel=1e-12, abs=1e-12)
    for c in INFO_COLUMNS:
        assert r.metrics[c] == pytest.approx(float(row[c]), rel=1e-12)


@pytest.mark.parametrize("phases, effects, option", [
    ("aligned-error", None, []),
    ("spec", {"thermal_backlash": {"centre_distance_um_per_K": -0.3}},
     ["-e", "thermal_backlash:centre_distance_um_per_K=-0.3"]),
    ("aligned-reversal", {"thermal_backlash": {}}, ["-e", "thermal_backlash"]),
])
def test_simulate_matches_cli(runner, phases, effects, option):
    s = wg.simulate(MCH50, points=360, revs=2.0, temperature_c=30.0, load_nm=5.0, phases=phases, effects=effects)
    doc = cli_json(runner, "simulate", MCH50, "--points", "360", "--revs", "2", "--temperature-C", "30",
                   "--load-Nm", "5", "--phases", phases, *option, "--format", "json", "--unit", "arcmin")
    assert s.to_dict("arcmin") == doc
    np.testing.assert_array_equal(s.angle_deg, doc["curve"]["angle_deg"])
    np.testing.assert_allclose(s.forward.arcmin, doc["curve"]["forward"], rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(s.reverse.arcmin, doc["curve"]["reverse"], rtol=1e-13, atol=1e-15)
    sm = doc["summary"]
    assert s.common.rms().arcmin == pytest.approx(sm["common"]["rms"], rel=1e-12)
    assert s.lost_motion.max().arcmin == pytest.approx(sm["lost_motion"]["max"], rel=1e-12)
    assert s.forward.ptp().arcmin == pytest.approx(sm["forward"]["peak_to_peak"], rel=1e-12)


def test_simulate_at_matches_cli(runner):
    effects = {"thermal_backlash": {"centre_distance_um_per_K": -0.3}}
    s = wg.simulate(MCH50, at=WARM, effects=effects)
    doc = cli_json(runner, "simulate", MCH50, "--at", WARM, "-e", "thermal_backlash:centre_distance_um_per_K=-0.3",
                   "--format", "json")
    assert s.to_dict() == doc
    np.testing.assert_allclose(s.simulated.arcsec, doc["simulated_error"], rtol=1e-13, atol=1e-15)
    resid = s.measured.arcsec - s.simulated.arcsec
    assert float(np.sqrt(np.mean(resid ** 2))) == pytest.approx(doc["measured_minus_simulated"]["rms"], rel=1e-12)


def test_simulate_rejects_what_the_cli_rejects():
    with pytest.raises(UsageError):
        wg.simulate(MCH50, points=1)
    with pytest.raises(UsageError):
        wg.simulate(MCH50, revs=0)
    with pytest.raises(UsageError):
        wg.simulate(MCH50, temperature_c=float("nan"))
    with pytest.raises(UsageError):
        wg.simulate(MCH50, phases="aligned")


def test_read_measurement_fields():
    m = wg.read_measurement(WARM)
    rows = list(csv.DictReader(line for line in WARM.read_text().splitlines() if not line.startswith("#")))
    assert len(m) == len(rows)
    # an independent path: the file's own numbers, converted with the units table
    np.testing.assert_allclose(m.angle.deg, [float(r["angle_deg"]) for r in rows], rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(m.error.rad, [float(r["error_arcsec"]) * RAD_PER_UNIT["arcsec"] for r in rows],
                               rtol=1e-13)
    np.testing.assert_array_equal(m.direction, [int(r["direction"]) for r in rows])
    np.testing.assert_allclose(m.temperature_C, [float(r["temperature_C"]) for r in rows])


def test_read_measurement_options(tmp_path):
    f = tmp_path / "export.csv"
    f.write_text("Position;Abweichung\n0;1,5\n90;-0,5\n180;0,25\n", encoding="utf-8")
    m = wg.read_measurement(f, column_map={"angle_deg": "Position", "error_arcsec": "Abweichung"},
                            error_unit="arcmin")
    assert m.error.arcmin.tolist() == pytest.approx([1.5, -0.5, 0.25])
    assert m.angle[1] == Angle(90, "deg")


@pytest.mark.parametrize("unit", ["arcsec", "urad"])
def test_measure_matches_cli(runner, unit):
    r = wg.measure(WARM, drive=str(MCH50))
    doc = cli_json(runner, "measure", WARM, "--drive", MCH50, "--format", "json", "--unit", unit)
    assert r.to_dict(unit) == doc
    for key, value in doc["iso230_2"].items():
        if value is None:
            assert r.iso230_2[key] is None
        else:
            assert r.iso230_2[key].to(unit) == pytest.approx(value, rel=1e-12, abs=1e-12)
    for o, item in zip(r.orders, doc["orders"]["items"]):
        assert (o.order, o.label, o.status) == (item["order"], item["label"], item["status"])
        if item["common"]["amplitude"] is not None:
            assert o.amplitude.to(unit) == pytest.approx(item["common"]["amplitude"], rel=1e-12)
            assert o.phase_deg == pytest.approx(item["common"]["phase_deg"], rel=1e-12)
    assert r.verdict == doc["verdict"]


def test_measure_takes_a_measurement_and_orders(runner):
    m = wg.read_measurement(WARM)
    r = wg.measure(m, orders=[1, 8, 240])
    doc = cli_json(runner, "measure", WARM, "--orders", "1,8,240", "--format", "json")
    assert r.to_dict() == doc
    assert [o.order for o in r.orders] == [1.0, 8.0, 240.0]


def test_diagnose_matches_cli(runner):
    d = wg.diagnose(MCH50, WARM)
    doc = cli_json(runner, "diagnose", MCH50, WARM, "--format", "json")
    assert d.to_dict() == doc
    assert d.verdict == doc["verdict"]
    assert d.effects == tuple(e["name"] for e in doc["effects_found"])
    for name in ("gap_as_specified", "gap_before", "gap_after"):
        gap = getattr(d, name)
        assert gap.rms.arcsec == pytest.approx(doc[name]["rms_arcsec"], rel=1e-12)
        assert gap.differential_max.arcsec == pytest.approx(doc[name]["differential_max_arcsec"], rel=1e-12)
    assert d.noise_floor.arcsec == pytest.approx(doc["noise"]["floor_arcsec"], rel=1e-12)


def test_diagnose_augmented_spec_is_what_the_cli_writes(runner, tmp_path):
    out = tmp_path / "aug.toml"
    d = wg.diagnose(MCH50, WARM)
    result = runner.invoke(app, ["diagnose", str(MCH50), str(WARM), "--write-spec", str(out), "--format", "json"])
    assert result.exit_code == 0, result.output
    assert d.augmented_spec() == out.read_text(encoding="utf-8")
    assert wg.load_spec(d.augmented_spec()).effects  # the text is a valid spec with the named effect


@pytest.mark.parametrize("unit", ["arcsec", "deg"])
def test_sweep_matches_cli(runner, unit):
    s = wg.sweep(MCH50, i="2:10:5", l_mm="100:300:3", hold="torque")
    doc = cli_json(runner, "sweep", MCH50, "--i", "2:10:5", "--l-mm", "100:300:3", "--hold", "torque",
                   "--format", "json", "--unit", unit)
    assert s.to_dict(unit) == doc
    assert s.i.tolist() == doc["grid"]["i"] and s.l_mm.tolist() == doc["grid"]["l_mm"]
    pts = doc["points"]
    for c in ("gear_transmission_error", "total_transmission_error", "total_backlash"):
        np.testing.assert_allclose(s.points[c].to(unit), [p[c] for p in pts], rtol=1e-13)
    best = doc["summary"]["best"]["total_transmission_error"]
    assert s.best["total_transmission_error"]["total_transmission_error"].to(unit) == pytest.approx(
        best["total_transmission_error"], rel=1e-13)


def test_sweep_values_equal_ranges():
    a = wg.sweep(MCH50, i="2:10:5", l_mm="100:300:3")
    b = wg.sweep(MCH50, i=[2, 4, 6, 8, 10], l_mm=np.array([100.0, 200.0, 300.0]))
    assert a.to_dict() == b.to_dict()
    with pytest.raises(UsageError):
        wg.sweep(MCH50, i=[2, -1])
    with pytest.raises(UsageError):
        wg.sweep(MCH50, i="2:10:5", hold="speed")


def test_sweep_hold_in_any_case_as_on_the_command_line(runner):
    """--hold TORQUE is accepted by the CLI (its choices ignore case); hold="TORQUE" is the same run."""
    s = wg.sweep(MCH50, i="2:10:3", l_mm="100:300:2", hold="TORQUE")
    doc = cli_json(runner, "sweep", MCH50, "--i", "2:10:3", "--l-mm", "100:300:2", "--hold", "TORQUE",
                   "--format", "json")
    assert s.to_dict() == doc == wg.sweep(MCH50, i="2:10:3", l_mm="100:300:2", hold="torque").to_dict()
    assert doc["hold"] == "torque"


@pytest.mark.parametrize(("call", "message"), [
    (lambda: wg.sweep(MCH50, i="4:8:3", l_mm="150:250:3", module_mm=2, figures="no"),
     "figures='no': expected True or False"),
    (lambda: wg.sweep(MCH50, i="4:8:3", l_mm="150:250:3", module_mm=2, figures=1),
     "figures=1: expected True or False"),
    (lambda: wg.sweep(MCH50, i="2:10:5", hold="speed"), "hold='speed': expected one of force, torque"),
    (lambda: wg.compensate(CONFIGS / "mch50-warm.csv", "csv", harmonics=7),
     "--harmonics applies with --drive (the harmonics of its shafts and meshes) or to a mount's PEC curve "
     "(--format eqmod), not to the csv table being written without --drive; drop it, give --drive, or choose "
     "that format (--format, or the -o file's ending)"),
])
def test_api_arguments_that_would_be_ignored_or_misread_are_refused(call, message):
    with pytest.raises(UsageError) as e:
        call()
    assert str(e.value) == message


def test_sweep_snapped_matches_cli(runner):
    s = wg.sweep(MCH50, i="4:8:3", l_mm="150:250:3", module_mm=1.0)
    doc = cli_json(runner, "sweep", MCH50, "--i", "4:8:3", "--l-mm", "150:250:3", "--module-mm", "1",
                   "--format", "json")
    assert s.to_dict() == doc
    assert s.points["z1"].tolist() == [p["z1"] for p in doc["points"]]


@pytest.mark.parametrize("unit", ["arcsec", "deg"])
def test_tolerance_matches_cli(runner, unit):
    t = wg.tolerance(MCH50, samples=500, seed=3, metrics="paper")
    doc = cli_json(runner, "tolerance", MCH50, "-n", "500", "--seed", "3", "--metrics", "paper", "--format", "json",
                   "--unit", unit)
    assert t.to_dict(unit) == doc
    for name, m in doc["metrics"].items():
        st = t.metrics[name]
        assert st.mean.to(unit) == pytest.approx(m["mean"], rel=1e-12)
        assert st.corner.to(unit) == pytest.approx(m["corner"], rel=1e-12)
        assert st.percentiles["99"].to(unit) == pytest.approx(m["percentiles"]["99"], rel=1e-12)
    assert t.yields == doc["yield"]


def test_tolerance_allocation_matches_cli(runner):
    t = wg.tolerance(MCH50, samples=300, seed=2, metrics="paper", target_yield=0.999)
    doc = cli_json(runner, "tolerance", MCH50, "-n", "300", "--seed", "2", "--metrics", "paper",
                   "--target-yield", "0.999", "--format", "json")
    assert t.to_dict() == doc
    assert t.allocation is not None and t.allocation == doc["allocation"]


def test_tolerance_target_yield_without_limits(tmp_path):
    text = MCH50.read_text(encoding="utf-8")
    assert "[requirements]" in text
    spec = wg.load_spec(text.split("[requirements]")[0])
    with pytest.raises(UsageError):
        wg.tolerance(spec, samples=100, metrics="paper", target_yield=0.9)


def test_errors_are_the_cli_errors(tmp_path):
    with pytest.raises(SpecError) as exc:
        wg.analyze(tmp_path / "missing.toml")
    assert exc.value.problems


# --- angles ---------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("unit", sorted(RAD_PER_UNIT))
def test_angle_units_use_the_one_table(unit):
    a = Angle(2.5, unit)
    assert a.rad == 2.5 * RAD_PER_UNIT[unit]
    assert a.to(unit) == pytest.approx(2.5, rel=1e-15)
    assert getattr(a, unit) == pytest.approx(2.5, rel=1e-15)


def test_angle_by_hand():
    # 1 deg = 60 arcmin = 3600 arcsec = pi/180 rad = 17453.29... urad (by definition)
    a = Angle(1, "deg")
    assert a.arcmin == pytest.approx(60.0, rel=1e-15)
    assert a.arcsec == pytest.approx(3600.0, rel=1e-15)
    assert a.urad == pytest.approx(1e6 * math.pi / 180.0, rel=1e-15)
    assert float(a) == pytest.approx(math.pi / 180.0, rel=1e-15)
    assert repr(Angle(53.077808, "arcsec")) == "Angle(53.08 arcsec)"


@pytest.mark.parametrize("spec,text", [
    (".2f", "53.59 arcsec"), ("", "53.59 arcsec"), (".4f deg", "0.0149 deg"), (".1f arcmin", "0.9 arcmin"),
    ("urad", "259.8 urad"), (".3e rad", "2.598e-04 rad"), (">9.1f", "     53.6 arcsec"), (",.0f urad", "260 urad"),
])
def test_angle_formats_in_f_strings_with_its_unit(spec, text):
    a = wg.Angle(53.5875, "arcsec")  # 53.5875 arcsec = 0.014885 deg = 259.80 urad, by hand
    assert format(a, spec) == text
    assert f"{a:{spec}}" == text


def test_angle_format_refuses_an_unknown_unit_and_a_bad_spec():
    a = wg.Angle(1, "arcsec")
    with pytest.raises(ValueError, match="unknown angle unit 'furlong'"):
        format(a, ".2f furlong")
    with pytest.raises(ValueError):
        format(a, ".2q")


def test_angle_comparisons_need_angles():
    a = Angle(1, "deg")
    assert a > Angle(59, "arcmin") and a >= Angle(60, "arcmin") and a < Angle(61, "arcmin")
    assert (a == 1) is False
    for bad in (lambda: a < 1, lambda: a > 1.0, lambda: a <= 0, lambda: a >= 0):
        with pytest.raises(TypeError):
            bad()
    with pytest.raises(TypeError):
        a + 1
    with pytest.raises(ValueError):
        Angle(1, "grad")


def test_angle_arithmetic():
    a, b = Angle(30, "arcsec"), Angle(1, "arcmin")
    assert (a + a).isclose(b) and (b - a).isclose(a)
    assert (2 * a).isclose(b) and (b / 2).isclose(a)
    assert a / b == pytest.approx(0.5)
    assert abs(-a) == a
    assert len({Angle(1.0), Angle(1.0)}) == 1


def test_angle_array():
    v = AngleArray([10.0, -20.0, 30.0], "arcsec")
    np.testing.assert_allclose(np.asarray(v), np.array([10.0, -20.0, 30.0]) * RAD_PER_UNIT["arcsec"])
    assert isinstance(v[0], Angle) and isinstance(v[1:], AngleArray) and len(v[1:]) == 2
    assert v.max().arcsec == pytest.approx(30.0) and v.min().arcsec == pytest.approx(-20.0)
    assert v.rms().arcsec == pytest.approx(math.sqrt((100 + 400 + 900) / 3))
    assert v.mean().arcsec == pytest.approx(20.0 / 3)
    assert [x.arcsec for x in v] == pytest.approx([10.0, -20.0, 30.0])


# --- import cost ----------------------------------------------------------------------------------------------


def _modules_after(code: str) -> set:
    probe = code + "\nimport sys, json\nsys.stderr.write('\\n' + json.dumps(sorted(sys.modules)))\n"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, cwd=ROOT, check=False)
    return set(json.loads(out.stderr.strip().splitlines()[-1]))


HEAVY = ("numpy", "scipy", "wormgear_cli.api", "wormgear_cli.angles", "wormgear_cli.analysis.accuracy",
         "wormgear_cli.analysis.simulate", "wormgear_cli.physics", "wormgear_cli.diagnosis", "wormgear_cli.spec.loader")


def test_import_wormgear_cli_is_light():
    mods = _modules_after("import wormgear_cli")
    assert not [m for m in mods if m.split(".")[0] in ("numpy", "scipy")]
    assert not [m for m in HEAVY if m in mods]


def test_api_names_load_the_api_on_first_use():
    mods = _modules_after("import wormgear_cli\nwormgear_cli.analyze")
    assert "wormgear_cli.api" in mods
    assert not [m for m in mods if m.split(".")[0] == "scipy"]
    mods = _modules_after("import wormgear_cli.api")
    assert not [m for m in mods if m.split(".")[0] == "scipy"]
    assert "wormgear_cli.analysis.accuracy" not in mods


def test_analyze_command_never_loads_the_api_or_scipy():
    code = ("import runpy, sys\nsys.argv = ['wormgear', 'analyze', 'configs/mch50.toml', '--format', 'json']\n"
            "try:\n    runpy.run_module('wormgear_cli', run_name='__main__')\nexcept SystemExit:\n    pass")
    mods = _modules_after(code)
    assert "wormgear_cli.analysis.accuracy" in mods  # the probe did run the command
    assert "wormgear_cli.api" not in mods and "wormgear_cli.angles" not in mods
    assert not [m for m in mods if m.split(".")[0] == "scipy"]


def test_package_names_do_not_shadow_submodules():
    import wormgear_cli
    from wormgear_cli import tolerance  # the core modules, as the CLI imports them
    from wormgear_cli.analysis import sweep

    assert sweep.__name__ == "wormgear_cli.analysis.sweep" and tolerance.__name__ == "wormgear_cli.tolerance"
    assert wormgear_cli.analyze is wg.analyze and wormgear_cli.Angle is Angle
    with pytest.raises(AttributeError):
        wormgear_cli.no_such_name  # noqa: B018


# --- compensate ----------------------------------------------------------------------------------------------


def test_compensate_matches_cli(runner, tmp_path):
    out, rep = tmp_path / "t.comp", tmp_path / "t.json"
    result = runner.invoke(app, ["compensate", str(WARM), "--orders", "1,8", "-o", str(out), "--report", str(rep),
                                 "--unit", "arcmin"])
    assert result.exit_code == 0, result.stderr
    c = wg.compensate(WARM, "linuxcnc", orders=[1, 8], output=tmp_path / "api.comp", unit="arcmin")
    assert c.text == out.read_text() == (tmp_path / "api.comp").read_text()
    doc = json.loads(rep.read_text())
    api_doc = c.to_dict("arcmin")
    assert api_doc.pop("load")[1] == "COMP_FILE = " + str(tmp_path / "api.comp")
    assert doc.pop("load")[1] == "COMP_FILE = " + str(out)
    assert api_doc == doc
    for k, f in doc["prediction"]["after"].items():
        assert c.predicted[k].arcmin == pytest.approx(f["median"], rel=1e-12)
        assert c.predicted_range[k][1].arcmin == pytest.approx(f["high_95pct"], rel=1e-12)
    assert c.measured["E"].arcmin == pytest.approx(doc["prediction"]["before"]["E"], rel=1e-12)
    assert c.method == "cross-validated" and c.format == "linuxcnc" and c.orders == (1.0, 8.0)


def test_compensate_takes_a_measurement_and_a_limit_as_an_angle():
    m = wg.read_measurement(WARM)
    by_path = wg.compensate(WARM, "csv", orders=[1, 8], points=19)
    by_record = wg.compensate(m, "csv", orders=[1, 8], points=19)
    by_core = wg.compensate(m.core, "csv", orders=[1, 8], points=19)
    assert by_path.text == by_record.text == by_core.text
    limited = wg.compensate(m, "csv", orders=[1, 8], points=19, max_correction=Angle(1, "arcmin"))
    assert limited.exceeded and limited.largest_correction > Angle(1, "arcmin")
    assert not wg.compensate(m, "csv", orders=[1, 8], points=19, max_correction=10.0, unit="arcmin").exceeded
    with pytest.raises(UsageError, match="unit='mm'"):
        wg.compensate(m, "csv", unit="mm")
