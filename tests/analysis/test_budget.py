"""The full error budget (wormgear_cli.analysis.budget): lines, totals, origins, and agreement with simulate."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.support.examples import examples
from tests.support.paths import CONFIGS
from wormgear_cli.analysis.accuracy import analyze
from wormgear_cli.analysis.budget import Rule, budget
from wormgear_cli.analysis.simulate import simulate
from wormgear_cli.cli import app
from wormgear_cli.errors import SpecError
from wormgear_cli.physics.effects import Signals
from wormgear_cli.spec.loader import loads_spec, with_values
from wormgear_cli.units import to_unit

ARCSEC = math.pi / 648000.0

#: a drive with no error source at all (involute kinematics, no load, every tolerance 0)
BARE = """
[gear_pair]
module_mm = 2.0
pressure_angle_deg = 20.0
face_width_mm = 40.0
kinematics = "involute"
[gear_pair.output_gear]
teeth = 180
[gear_pair.pinion]
teeth = 20
[worm_pair]
module_mm = 3.0
normal_pressure_angle_deg = 20.0
lead_angle_deg = 3.434
[worm_pair.worm]
starts = 1
[worm_pair.wheel]
teeth = 45
"""


def bare(**extra):
    text = BARE
    for section, body in extra.items():
        text = text.replace(f"[{section}]\n", f"[{section}]\n{body}\n", 1)
    return loads_spec(text)


def test_cumulative_pitch_conversion_by_hand():
    # output gear F_p = 25 um on r = 180 mm: TE p-p 0.025/180 rad = 28.65", amplitude 14.32" (order 1);
    # pinion F_p = 17 um on r = 20 mm, i_c = 9: amplitude 0.017/40/9 rad = 9.74" (order 9)
    s = bare(**{"gear_pair.output_gear": "cumulative_pitch_deviation_mm = 0.025",
                "gear_pair.pinion": "cumulative_pitch_deviation_mm = 0.017"})
    lines = {ln.source: ln for ln in budget(s).lines}
    out, pin = lines["output_gear_cumulative_pitch"], lines["pinion_cumulative_pitch"]
    assert (out.order, pin.order) == (1.0, 9.0)
    assert out.amplitude / ARCSEC == pytest.approx(14.32, abs=0.01)
    assert 2 * out.amplitude / ARCSEC == pytest.approx(28.65, abs=0.01)
    assert pin.amplitude / ARCSEC == pytest.approx(9.74, abs=0.01)
    assert out.origin == "spec" and lines["wheel_cumulative_pitch"].origin == "default"


@pytest.mark.parametrize("path", ["configs/mch50.toml", "configs/rotary-table-precision.toml",
                                  "configs/radar-pedestal-2start.toml"])
def test_lines_add_up_to_the_totals_under_each_rule(path):
    from wormgear_cli.spec.loader import load_spec

    b = budget(load_spec(CONFIGS.parent / path))
    amps = [ln.amplitude for ln in b.lines]
    static = [ln.amplitude for ln in b.lines if ln.kind == "static"]
    periodic = [ln.amplitude for ln in b.lines if ln.kind != "static"]
    assert b.total(Rule.LINEAR) == pytest.approx(sum(amps), rel=1e-12)
    assert b.total("rss") == pytest.approx(sum(static) + math.sqrt(sum(a * a for a in periodic)), rel=1e-12)
    assert b.rss <= b.linear and b.peak <= b.linear * (1 + 1e-9)
    assert b.peak >= sum(static) + max(periodic) * (1 - 1e-3)


def test_aligned_phases_make_the_peak_the_linear_sum():
    # every source a sinusoid at a whole order with phase 90 deg: all peak at theta = 0
    spec = loads_spec((CONFIGS / "rotary-table-precision.toml").read_text())
    phases = dict.fromkeys(("gear_pair.output_gear.cumulative_pitch_phase_deg", "gear_pair.output_gear.single_pitch_phase_deg", "gear_pair.pinion.cumulative_pitch_phase_deg", "gear_pair.pinion.single_pitch_phase_deg", "worm_pair.lead_error_phase_deg", "assembly.worm_eccentricity_phase_deg", "worm_pair.wheel.radial_composite_phase_deg", "assembly.wheel_eccentricity_phase_deg"), 90.0)
    b = budget(with_values(spec, phases))
    assert b.peak == pytest.approx(b.linear, rel=1e-6)


@pytest.mark.parametrize("section, key, order, radius", [
    ("gear_pair.output_gear", "cumulative_pitch_deviation_mm", 1.0, 180.0),
    ("gear_pair.pinion", "cumulative_pitch_deviation_mm", 9.0, 20.0 * 9),
    ("gear_pair.output_gear", "single_pitch_deviation_mm", 180.0, 180.0),
    ("gear_pair.pinion", "single_pitch_deviation_mm", 180.0, 20.0 * 9),
])
def test_simulated_curve_of_a_single_source_has_its_budget_amplitude_and_order(section, key, order, radius):
    dev = 0.012  # mm
    s = bare(**{section: f"{key} = {dev}"})
    [line] = [ln for ln in budget(s).lines if ln.amplitude > 0]
    # expected amplitude by hand: dev / (2 r) reduced by the ratio to the output (r_pinion i_c = 180 mm)
    assert line.amplitude == pytest.approx(dev / (2 * radius), rel=1e-12) and line.order == order
    theta = np.linspace(0.0, 2 * np.pi, 4096, endpoint=False)
    err = simulate(s, Signals.make(theta, 1.0))
    spectrum = np.fft.rfft(err) * 2 / theta.size
    k = int(np.argmax(np.abs(spectrum)))
    assert k == order
    assert abs(spectrum[k]) == pytest.approx(line.amplitude, rel=1e-9)
    assert np.max(err) == pytest.approx(line.amplitude, rel=1e-6)


def test_grade_values_and_origins():
    s = bare(**{"gear_pair.output_gear": "accuracy_grade = 5\nsingle_pitch_deviation_mm = 0.004"})
    og = s.gear_pair.output_gear
    # class 5, d = 360 mm: F_pT 25 um, F_alphaT 8 um (hand, test_iso1328); f_p given explicitly wins
    assert og.cumulative_pitch_deviation == pytest.approx(0.025) and og.single_pitch_deviation == 0.004
    assert og.profile_error == pytest.approx(0.008)
    lines = {ln.source: ln for ln in budget(s).lines}
    assert lines["output_gear_cumulative_pitch"].origin == "grade"
    assert lines["output_gear_single_pitch"].origin == "spec"
    assert lines["pinion_single_pitch"].origin == "default"


@pytest.mark.parametrize("body, message", [
    ('[gear_pair.output_gear]\naccuracy_grade = 12', "gear_pair.output_gear.accuracy_grade: expected an integer "
                                                       "in [1, 11], got 12"),
    ('[gear_pair.pinion]\naccuracy_grade = 5', None),
])
def test_grade_key_range(body, message):
    text = BARE.replace(body.split("\n")[0] + "\n", body + "\n", 1)
    if message is None:
        loads_spec(text)
        return
    with pytest.raises(SpecError) as exc:
        loads_spec(text)
    assert any(message in p for p in exc.value.problems)


def test_gear_outside_the_standard_and_wheel_grade_exit_2(runner, tmp_path):
    text = BARE.replace("[gear_pair]\nmodule_mm = 2.0", "[gear_pair]\nmodule_mm = 0.4").replace(
        "[gear_pair.pinion]\n", "[gear_pair.pinion]\naccuracy_grade = 5\n").replace(
        "[worm_pair.wheel]\n", "[worm_pair.wheel]\naccuracy_grade = 6\n")
    path = tmp_path / "d.toml"
    path.write_text(text)
    r = runner.invoke(app, ["analyze", str(path)])
    assert r.exit_code == 2
    assert (f"{path}: gear_pair.pinion.accuracy_grade: module 0.4 outside ISO 1328-1:2013's scope [0.5, 70] mm"
            in r.stderr)
    assert f"{path}: worm_pair.wheel.accuracy_grade: worm pairs are not covered by ISO 1328-1/-2" in r.stderr


def test_analyze_json_budget_in_the_chosen_unit(runner):
    path = str(CONFIGS / "rotary-table-precision.toml")
    sec = json.loads(runner.invoke(app, ["analyze", path, "-f", "json"]).stdout)
    deg = json.loads(runner.invoke(app, ["analyze", path, "-f", "json", "--unit", "deg"]).stdout)
    assert {"source", "stage", "order", "amplitude", "origin"} <= set(sec["budget"][0])
    assert {ln["origin"] for ln in sec["budget"]} <= {"spec", "grade", "default"}
    for a, b in zip(sec["budget"], deg["budget"]):
        assert a["amplitude"] == pytest.approx(3600 * b["amplitude"], rel=1e-12)
    t = sec["total_with_budget"]
    assert t["transmission_error_linear"] == pytest.approx(sum(ln["amplitude"] for ln in sec["budget"]))
    assert t["transmission_error_rss"] <= t["transmission_error_linear"]
    # the paper's keys are untouched by the budget
    assert set(sec["total"]) == {"transmission_error", "backlash"}


def test_check_holds_a_budget_requirement(runner, tmp_path):
    text = (CONFIGS / "rotary-table-precision.toml").read_text().replace(
        "max_budget_statistical_arcsec = 10.0", "max_budget_statistical_arcsec = 5.0")
    path = tmp_path / "t.toml"
    path.write_text(text)
    r = runner.invoke(app, ["check", str(path), "--format", "json"])
    assert r.exit_code == 1
    [verdict] = [v for v in json.loads(r.stdout)["files"][0]["requirements"]
                 if v["key"] == "requirements.max_budget_statistical_arcsec"]
    assert verdict["passed"] is False and verdict["value_arcsec"] > 5.0


def test_paper_mode_leaves_the_paper_keys_and_involute_differs_by_hand(mch50_spec):
    paper = analyze(mch50_spec)
    inv = analyze(with_values(mch50_spec, {"gear_pair.kinematics": "involute"}))
    # worm stage is not part of the gear-stage kinematics
    assert inv.angles["worm_transmission_error"] == paper.angles["worm_transmission_error"]
    # involute, hand: no eccentricity given -> gear TE = delta1 / r_b1 = 1.556e-3 / 169.14 rad = 1.90";
    # backlash = (2 x 0.030 tan 20 + 0.055 + 0.045) / 180 + 2 x 1.556e-3 / 169.14 rad = 139.6" + 3.8" = 143.4"
    assert float(to_unit(inv.angles["gear_transmission_error"], "arcsec")) == pytest.approx(1.90, abs=0.01)
    assert float(to_unit(inv.angles["gear_backlash"], "arcsec")) == pytest.approx(143.4, abs=0.1)
    assert float(to_unit(inv.angles["gear_backlash_thickness"], "arcsec")) == pytest.approx(114.6, abs=0.1)


# --- mutation-testing round 2 (issue 13): the phased peak by hand, the report, the static lines ----

from wormgear_cli.analysis.budget import Budget, BudgetLine, phased_peak  # noqa: E402
from wormgear_cli.analysis.simulate import Source  # noqa: E402


def _sine_source(name, amplitude, order):
    return Source(name, "x", order, amplitude, 0.0, lambda t, p: amplitude * np.sin(order * t + p))


def test_phased_peak_of_two_sines_by_hand():
    # max of 3 sin(u) + sin(2u): 3 cos u + 2 cos 2u = 0 -> 4 c^2 + 3 c - 2 = 0, c = (-3 + sqrt 41)/8 = 0.4253905,
    # sin u = 0.9050100, sin 2u = 2 * 0.9050100 * 0.4253905 = 0.7699649 -> 2.7150300 + 0.7699649 = 3.4849949.
    # The phases (given as overrides by name) shift u = theta + 0.3 only: same maximum, off the sample grid.
    src = [_sine_source("a", 3.0, 1.0), _sine_source("b", 1.0, 2.0), _sine_source("zero", 0.0, 5.0)]
    assert phased_peak(src, {"a": 0.3, "b": 0.6}) == pytest.approx(3.4849949, rel=1e-7)
    assert phased_peak(src) == pytest.approx(3.4849949, rel=1e-7)
    # an override that changes the maximum: b at pi/2: 3 sin t + cos 2t = 1 + 3 s - 2 s^2, s = sin t,
    # largest at s = 3/4: 1 + 2.25 - 1.125 = 2.125
    assert phased_peak(src, {"b": math.pi / 2}) == pytest.approx(2.125, rel=1e-9)
    # one sine of order 7 and phase 1.0: its amplitude, reached off the grid of 4096 samples
    assert phased_peak([_sine_source("c", 2.0, 7.0)], {"c": 1.0}) == pytest.approx(2.0, rel=1e-12)


def test_phased_peak_without_sources_is_zero():
    assert phased_peak([]) == 0.0
    assert phased_peak([_sine_source("zero", 0.0, 1.0)]) == 0.0


def test_report_by_hand():
    # lines 3 and 1 (arcsec, in rad), linear 4: shares 75 % and 25 %; phase 0.5 rad = 28.6479 deg
    a = ARCSEC
    b = Budget("d", (BudgetLine("x", "gear", "shaft", 1.0, 3 * a, "spec", 0.5),
                     BudgetLine("y", "worm", "static", 0.0, 1 * a, "default")), 4 * a, 3.5 * a, 3.8 * a, 3.9 * a,
               5.0 * a)
    r = b.report("arcsec")
    assert r["budget"][0] == {"source": "x", "stage": "gear", "kind": "shaft", "order": 1.0,
                              "amplitude": pytest.approx(3.0, rel=1e-12), "origin": "spec",
                              "phase_deg": pytest.approx(28.6479, abs=1e-4), "share_pct": pytest.approx(75.0),
                              "stage_index": 0, "stage_kind": "", "part": ""}
    assert r["budget"][1]["share_pct"] == pytest.approx(25.0) and r["budget"][1]["phase_deg"] == 0.0
    assert r["total_with_budget"] == pytest.approx({
        "transmission_error_linear": 4.0, "transmission_error_rss": 3.5, "transmission_error_peak": 3.8,
        "transmission_error_amplitude_linear": 4.0, "transmission_error_amplitude_statistical": 3.9,
        "transmission_error_amplitude_peak": 3.8, "transmission_error_range_peak": 5.0}, rel=1e-12)
    assert "budget_offsets" not in r
    empty = Budget("d", (BudgetLine("x", "gear", "shaft", 1.0, 0.0, "spec"),), 0.0, 0.0, 0.0).report("arcsec")
    assert empty["budget"][0]["share_pct"] == 0.0


def test_static_lines_and_fields_of_the_rotary_table():
    # i_c = 180/20 = 9: the worm deflection is referred to the output by 1/9; both loads given in the spec
    from wormgear_cli.spec.loader import load_spec

    spec = load_spec(CONFIGS / "rotary-table-precision.toml")
    a = analyze(spec)
    b = budget(spec, a)
    assert b.drive == a.drive
    lines = {ln.source: ln for ln in b.lines}
    g, w = lines["gear_deflection"], lines["worm_deflection"]
    assert (g.stage, g.kind, g.order, g.origin) == ("gear", "static", 0.0, "spec")
    assert (w.stage, w.kind, w.order, w.origin) == ("worm", "static", 0.0, "spec")
    assert g.amplitude == pytest.approx(float(a.angles["gear_te_deformation"]), rel=1e-12)
    assert w.amplitude == pytest.approx(float(a.angles["worm_te_deformation"]) / 9.0, rel=1e-12)
    ecc = lines["gear_eccentricity"]
    assert (ecc.stage, ecc.kind) == ("gear", "shaft") and lines["pinion_single_pitch"].kind == "mesh"


def test_a_line_keeps_its_sources_phase():
    s = bare(**{"gear_pair.output_gear": "cumulative_pitch_deviation_mm = 0.025\ncumulative_pitch_phase_deg = 30.0"})
    [line] = [ln for ln in budget(s).lines if ln.source == "output_gear_cumulative_pitch"]
    assert line.phase == pytest.approx(math.radians(30.0), rel=1e-12)


def test_orders_beyond_the_sampled_ones_are_bounded_by_their_amplitudes(monkeypatch):
    """A train of many stages puts orders at the product of its ratios (10^6 and more): those past
    MAX_PEAK_SAMPLES / 64 are not sampled but added by their amplitudes (a fast term peaks within
    half its period of the slow curve's peak).  3 sin(t) + sin(2t) peaks at 3.4849949 (above); with
    a 0.5 term at order 10^9: 3.9849949, and at most 0.5 above the true maximum."""
    from wormgear_cli.analysis import budget

    src = [_sine_source("a", 3.0, 1.0), _sine_source("b", 1.0, 2.0), _sine_source("fast", 0.5, 1e9)]
    high, low = budget.phased_extremes(src)
    assert high == pytest.approx(3.4849949 + 0.5, rel=1e-7)
    assert low == pytest.approx(-3.4849949 - 0.5, rel=1e-7)
    # the bound is the exact answer's neighbour: lower the cap below order 2 and the sampled part
    # is order 1 alone (3), the bound adds 1 + 0.5
    monkeypatch.setattr(budget, "MAX_PEAK_SAMPLES", 64)
    assert budget.phased_extremes(src)[0] == pytest.approx(4.5, rel=1e-9)


def test_the_peak_is_searched_a_block_at_a_time_with_the_same_answer(monkeypatch):
    """Blocks of samples (memory bounded whatever the orders): the answer does not depend on the
    block length, a block boundary next to the peak included."""
    from wormgear_cli.analysis import budget

    src = [_sine_source("a", 3.0, 1.0), _sine_source("b", 1.0, 2.0), _sine_source("c", 0.2, 37.0)]
    whole = budget.phased_extremes(src, {"a": 0.3})
    for block in (7, 64, 1000):
        monkeypatch.setattr(budget, "_PEAK_BLOCK", block)
        assert budget.phased_extremes(src, {"a": 0.3}) == whole


@settings(max_examples=examples(40), deadline=None)
@given(orders=st.lists(st.floats(0.5, 5000.0), min_size=1, max_size=6, unique=True),
       first=st.integers(-1, 200_000), count=st.integers(1, 1500), n=st.integers(4096, 1 << 20), data=st.data())
def test_the_sampled_sines_are_the_sum_of_sines_taken_directly(orders, first, count, n, data):
    """The peak search's sum of one sine per order, by rows of complex matrix products, against
    numpy's sines of o theta + arg P summed here (within 64 units in the last place of the largest
    phase times the amplitudes' sum)."""
    from wormgear_cli.analysis.budget import _SampledSines

    amps = data.draw(st.lists(st.floats(0.01, 10.0), min_size=len(orders), max_size=len(orders)))
    phases = data.draw(st.lists(st.floats(-math.pi, math.pi), min_size=len(orders), max_size=len(orders)))
    phasors = {o: a * complex(math.cos(p), math.sin(p)) for o, a, p in zip(orders, amps, phases)}
    step = 2.0 * math.pi / n
    theta = np.arange(first, first + count) * step
    want = sum(a * np.sin(o * theta + p) for o, a, p in zip(orders, amps, phases))
    got = _SampledSines(phasors, step)(first, count)
    largest = max(1.0, max(orders) * float(np.max(np.abs(theta))))
    assert got.shape == (count,)
    assert np.max(np.abs(got - want)) <= 64 * np.finfo(float).eps * largest * sum(amps)
