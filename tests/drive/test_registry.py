"""The registry of error sources: built once from the train, the one list every command reads."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.paths import CONFIGS, MCH50
from wormgear_cli.analysis.budget import budget
from wormgear_cli.analysis.simulate import components, periodic_sources, simulate
from wormgear_cli.drive.registry import build
from wormgear_cli.drive.train import drive_geometry
from wormgear_cli.physics.effects import EFFECTS, Signals
from wormgear_cli.spec.loader import load_spec, loads_spec
from wormgear_cli.units import ARCSEC

SPECS = ["mch50", "rotary-table-precision", "radar-pedestal-2start", "rotary-table-worm", "eq6-belt-worm"]


@pytest.mark.parametrize("name", SPECS)
def test_simulate_and_the_budget_read_the_registry(name):
    spec = load_spec(CONFIGS / f"{name}.toml")
    reg = build(spec)
    assert [s.name for s in periodic_sources(spec, all_budget_sources=True)] == [s.name for s in reg.sources]
    lines = budget(spec).lines
    assert [ln.source for ln in lines] == [x.name for x in reg.lines]
    for ln, x in zip(lines, reg.lines):
        assert ln.amplitude == pytest.approx(getattr(x, "peak", None) or x.amplitude, rel=1e-15)
    # every source's vectorised size function gives its amplitude from the stage's own values
    from wormgear_cli.spec.stages import record_values

    for s in reg.sources:
        own = record_values(spec.stages[s.stage_index - 1])
        assert float(s.size(own.__getitem__)) == pytest.approx(s.peak, rel=1e-12), s.name


def test_every_source_names_its_stage_part_and_keys():
    spec = load_spec(CONFIGS / "eq6-belt-worm.toml")
    for s in build(spec).sources:
        stage = spec.stages[s.stage_index - 1]
        assert s.stage == stage.name and s.stage_kind == stage.kind
        assert s.size_paths == tuple(f"stage.{stage.index}.{k}" for k in s.size_keys)
        assert s.phase_path.startswith(f"stage.{stage.index}.") and s.phase_path.endswith("_phase_deg")
        assert s.origin in ("spec", "grade", "default")


def test_the_wheel_runout_has_one_size():
    """S2 is a radial runout (total indicator reading, 2 e for an eccentric wheel): the budget's line,
    S2 / (2 cos(alpha_2)) on the wheel's pitch circle reduced by i_c, is the involute rule
    e / (r_b,wheel i_c) of the effect catalogue with e = S2 / 2 (here C2 = 0)."""
    spec = load_spec(CONFIGS / "rotary-table-precision.toml")
    spec = loads_spec(_set(spec, {"assembly.wheel_bearing_clearance_mm": 0.0}))
    line = next(ln for ln in budget(spec).lines if ln.source == "wheel_eccentricity")
    s2, r_w, i_c = 0.006, 3.0 * 45 / 2, 180 / 20
    alpha2 = math.atan(math.tan(math.radians(20)) / math.cos(math.radians(3.434)))
    e = s2 / 2
    assert line.amplitude == pytest.approx(e / (r_w * math.cos(alpha2) * i_c), rel=1e-12)


def _set(spec, changes: dict) -> str:
    import tomli_w

    from wormgear_cli.spec.loader import raw_copy, set_path

    doc = raw_copy(spec)
    for k, v in changes.items():
        set_path(doc, k, v)
    return tomli_w.dumps(doc)


def test_a_duplex_worm_reverses_by_its_residual_and_deflection():
    """anti_backlash = duplex: the clearance terms are replaced by the residual; the simulated
    reversal (reverse - forward) is residual + 2 x the deflection lag, the same at every angle."""
    spec = load_spec(CONFIGS / "rotary-table-worm.toml")
    reg = build(spec)
    theta = np.linspace(0, 2 * np.pi, 721)
    rev = simulate(spec, Signals.make(theta, -1.0)) - simulate(spec, Signals.make(theta, 1.0))
    expected = 8.0 * ARCSEC + 2 * reg.compliance.process_lag
    assert np.allclose(rev, expected, rtol=1e-12, atol=0)
    res = reg.results[0]
    assert res.backlash == pytest.approx(8.0 * ARCSEC + res.backlash_parts["deformation"], rel=1e-12)
    assert "wheel_radial_composite" in components(spec, Signals.make(theta))


def test_belt_sources_move_the_belt_and_turn_the_driven_pulley():
    """A driver eccentricity e gives e / R at the driven pulley, / A at the output, once per motor
    turn (order 705 on the EQ6 class: 47/12 x 180)."""
    spec = load_spec(CONFIGS / "eq6-belt-worm.toml")
    src = {s.name: s for s in build(spec).sources}
    R = 47 * 2.0 / (2 * math.pi)
    d = src["driver_pulley_eccentricity"]
    assert d.order == pytest.approx(705.0, rel=1e-15)
    assert d.amplitude == pytest.approx(0.010 / R / 180, rel=1e-12)
    assert src["belt_pitch_error"].order == pytest.approx(47 * 180 / 80)
    assert src["belt_pitch_error"].amplitude == pytest.approx(0.05 / 2 / R / 180, rel=1e-12)


def test_the_mch50_budget_keeps_the_catalogue_orders():
    spec = load_spec(MCH50)
    lines = {ln.source: ln for ln in budget(spec).lines}
    assert lines["worm_lead_error"].order == 240.0 and lines["wheel_eccentricity"].order == 8.0
    assert lines["worm_deflection"].kind == "static" and lines["worm_deflection"].stage_index == 1
    assert lines["gear_eccentricity"].stage == "gear" and lines["gear_eccentricity"].stage_kind == "spur"
    assert EFFECTS["intermediate_shaft_runout"].order(drive_geometry(spec)) == 8.0
