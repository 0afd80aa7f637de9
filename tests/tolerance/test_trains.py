"""Tolerance on any train: the metrics of sampled belt + worm, worm-only and three-stage drives against
analyze, the budget and simulate + ISO 230-2 of the same drive written out key by key (an independent
path: the spec loader and the registry of each sample); quantities addressed by stage keys; the
[statistics] table in either form; samples that do not move."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.paths import CONFIGS, MCH50
from wormgear_cli.analysis.accuracy import analyze
from wormgear_cli.analysis.budget import budget
from wormgear_cli.analysis.simulate import periodic_sources, simulate
from wormgear_cli.errors import SpecError
from wormgear_cli.measurement.iso230 import iso230_figures
from wormgear_cli.physics.effects import Signals
from wormgear_cli.spec.loader import load_spec, loads_spec, raw_copy, spec_from_dict, with_values
from wormgear_cli.spec.upgrade import upgrade_text
from wormgear_cli.tolerance import engine, metrics, quantities, sampling
from wormgear_cli.tolerance.quantities import layout, varied_quantities

EQ6 = CONFIGS / "eq6-belt-worm.toml"
TABLE = CONFIGS / "rotary-table-worm.toml"
RADAR = CONFIGS / "radar-pedestal-2start.toml"

SPECS = {"eq6": lambda: load_spec(EQ6), "worm-table": lambda: load_spec(TABLE), "radar": lambda: load_spec(RADAR)}


def _spec_at(spec, values: dict, j: int):
    """The spec with sample j's values written into it by their paths (array keys element by element)."""
    ch, arrays = {}, {}
    for k, a in values.items():
        path, _, rest = k.partition("[")
        if rest:
            arrays.setdefault(path, {})[int(rest[:-1])] = float(a[j])
        else:
            ch[k] = float(a[j])
    for path, elems in arrays.items():
        ch[path] = [elems[i] for i in range(len(elems))]
    return with_values(spec, ch)


def _draw(spec, seed, n):
    varied = varied_quantities(spec)
    d = sampling.draw(varied, seed, 0, n, layout(spec))
    return varied, d, {k: np.abs(a) for k, a in d.values.items()}  # the keys take magnitudes


@pytest.mark.parametrize("name", sorted(SPECS))
def test_paper_totals_equal_analyze_per_sample(name):
    spec = SPECS[name]()
    varied, _, values = _draw(spec, 7, 8)
    got = metrics.paper_totals(metrics.context(spec, varied, np.radians([0.0, 90.0])), values)
    for j in range(8):
        a = analyze(_spec_at(spec, values, j)).angles
        for m in metrics.PAPER_METRICS:
            assert np.broadcast_to(got[m], (8,))[j] == pytest.approx(a[m], rel=1e-11)


@pytest.mark.parametrize("name", sorted(SPECS))
def test_budget_totals_equal_the_budget_per_sample(name):
    spec = SPECS[name]()
    varied, _, values = _draw(spec, 8, 6)
    got = metrics.budget_totals(metrics.context(spec, varied, np.radians([0.0, 90.0])), values)
    for j in range(6):
        b = budget(_spec_at(spec, values, j))
        assert got["budget_linear"][j] == pytest.approx(b.linear, rel=1e-9)
        assert got["budget_rss"][j] == pytest.approx(b.rss, rel=1e-9)


@pytest.mark.parametrize("name", sorted(SPECS))
def test_iso_figures_equal_iso230_of_simulate(name):
    spec = SPECS[name]()
    varied, d, values = _draw(spec, 9, 5)
    targets = np.radians(engine.plan_targets(engine.Options(seed=9)))
    got = metrics.iso_figures(metrics.context(spec, varied, targets), values, d.phases)
    n = targets.size
    theta = np.concatenate([targets, targets[::-1]] * 2)  # two runs, each forward then reverse
    direction = np.tile(np.concatenate([np.ones(n), -np.ones(n)]), 2)
    time = np.arange(theta.size) % (2 * n) * 10.0
    for j in range(5):
        s = _spec_at(spec, values, j)
        names = {src.phase_path: src.name for src in periodic_sources(s, all_budget_sources=True)}
        assert set(names) == set(d.phases)
        err = simulate(s, Signals(theta, direction, np.zeros_like(theta), np.full_like(theta, 20.0), time),
                       {names[p]: float(d.phases[p][j]) for p in d.phases})
        f = iso230_figures(theta, err, direction)
        for m, ref in (("iso230_E", f.E), ("iso230_B", f.B), ("iso230_M", f.M), ("iso230_A", f.A)):
            assert got[m][j] == pytest.approx(ref, rel=1e-9, abs=1e-15)


def test_quantities_are_addressed_by_stage_keys_of_every_stage():
    spec = load_spec(EQ6)
    by = {v.path: v for v in varied_quantities(spec)}
    # the belt's (stage 1) and the worm's (stage 2) keys, tolerances as the file writes them
    assert by["stage.1.driver.eccentricity_mm"].tolerance == (0.010,)
    assert by["stage.1.pitch_error_mm"].tolerance == (0.05,)
    assert by["stage.1.backlash_mm"].tolerance == (0.02,)
    assert by["stage.2.wheel.runout_mm"].tolerance == (0.015,)
    assert by["stage.2.alignment_errors_mm"].tolerance == (0.010, 0.010, 0.010, 0.010, 0.015, 0.015)
    assert by["stage.2.alignment_errors_mm"].quantity.columns()[4] == "stage.2.alignment_errors_mm[4]"
    # signed keys live in [-T, T], magnitudes in [0, T]
    assert by["stage.2.lead_error_mm"].bounds() == (-0.003, 0.003)
    assert by["stage.1.pitch_error_mm"].bounds() == (0.0, 0.05)


def test_a_worm_and_spur_drive_gives_the_same_samples_in_either_form():
    legacy = load_spec(MCH50)
    staged = loads_spec(upgrade_text(MCH50.read_text(), str(MCH50)).text, "mch50-stages.toml")
    a = engine.setup(legacy, engine.Options(samples=300, seed=4, metrics="paper"))
    b = engine.setup(staged, engine.Options(samples=300, seed=4, metrics="paper"))
    # the stage form names the columns by stage key; the values and the metrics are the legacy form's
    rename = {layout_col: legacy_col for legacy_col, layout_col in zip(a.columns, b.columns)}
    assert rename["stage.2.eccentricity_mm"] == "assembly.gear_eccentricity_mm"
    assert rename["stage.1.alignment_errors_mm[3]"] == "assembly.worm_pair_errors_mm[3]"
    ba, bb = engine.block(a, 0), engine.block(b, 0)
    for new, old in rename.items():
        assert np.array_equal(bb.columns[new], ba.columns[old])
    for m in ba.metrics:
        assert np.array_equal(bb.metrics[m], ba.metrics[m])


def test_a_trains_samples_stay_when_its_kind_gains_a_key(monkeypatch):
    # a key added later (a higher `since`) gets rows after every existing one: no sample moves
    spec = load_spec(EQ6)
    varied = varied_quantities(spec)
    before = sampling.draw(varied, 3, 0, 500, layout(spec))
    belt = quantities.STAGE_QUANTITIES["belt"] + (quantities.StageQuantity("pitch_mm", quantities.Kind.signed,
                                                                           since=2),)
    monkeypatch.setitem(quantities.STAGE_QUANTITIES, "belt", belt)
    monkeypatch.setitem(quantities.STAGE_QUANTITY_BY_KEY, "belt", {q.key: q for q in belt})
    grown = varied_quantities(spec)
    after = sampling.draw(grown, 3, 0, 500, layout(spec))
    assert "stage.1.pitch_mm" in after.values and len(grown) == len(varied) + 1
    for k in before.values:
        assert np.array_equal(before.values[k], after.values[k])
    for k in before.phases:
        assert np.array_equal(before.phases[k], after.phases[k])


def _eq6_doc(statistics: dict) -> dict:
    doc = raw_copy(load_spec(EQ6))
    doc["statistics"] = statistics
    return doc


def test_statistics_takes_stage_keys():
    doc = _eq6_doc({"stage.1.pitch_error_mm": {"distribution": "uniform"},
                    "stage.2.wheel.thickness_deviation_mm": {"distribution": "normal", "cp": 1.33, "cpk": 1.0}})
    by = {v.path: v for v in varied_quantities(spec_from_dict(doc, "eq6.toml"))}
    assert by["stage.1.pitch_error_mm"].distribution == "uniform"
    assert (by["stage.2.wheel.thickness_deviation_mm"].cp, by["stage.2.wheel.thickness_deviation_mm"].cpk) == \
        (1.33, 1.0)
    assert by["stage.1.driver.eccentricity_mm"].distribution == "rayleigh"  # the default of a radial key


def test_statistics_of_a_worm_and_spur_drive_in_either_form():
    staged = raw_copy(loads_spec(upgrade_text(MCH50.read_text(), str(MCH50)).text, "m.toml"))
    staged["statistics"] = {"assembly.wheel_eccentricity_mm": {"distribution": "uniform"}}  # a legacy key
    by = {v.path: v for v in varied_quantities(spec_from_dict(staged, "m.toml"))}
    assert by["stage.1.wheel.runout_mm"].distribution == "uniform"
    legacy = raw_copy(load_spec(MCH50))
    legacy["statistics"] = {"stage.1.wheel.runout_mm": {"distribution": "uniform"}}  # a stage key
    by = {v.path: v for v in varied_quantities(spec_from_dict(legacy, "m.toml"))}
    assert by["assembly.wheel_eccentricity_mm"].distribution == "uniform"


@pytest.mark.parametrize("key, message", [
    ("stage.1.driver.teeth", "cannot be varied: the key has no tolerance (a nominal value such as teeth or module); "
                             "toleranced keys: stage.1.driver.eccentricity_mm, stage.1.driven.eccentricity_mm, "
                             "stage.1.pitch_error_mm, ..."),
    ("stage.2.lead_error_phase_deg", "phases are always drawn uniformly in [0, 360) deg; remove this entry"),
    ("stage.1.pitch_eror_mm", 'unknown key, expected the TOML path of a toleranced key (did you mean '
                              '"stage.1.pitch_error_mm"?)'),
    ("assembly.wheel_eccentricity_mm", 'unknown key, expected the TOML path of a toleranced key (did you mean '
                                       '"stage.2.wheel.runout_mm"?)'),
])
def test_statistics_names_what_cannot_be_varied(key, message):
    with pytest.raises(SpecError) as err:
        varied_quantities(spec_from_dict(_eq6_doc({key: {"distribution": "uniform"}}), "eq6.toml"))
    assert err.value.problems == [f'eq6.toml: statistics."{key}": {message}']
