"""Metrics per sample against analyze / simulate + iso230 (independent paths), and the engine's
corner, percentile and sensitivity properties."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.paths import CONFIGS
from tests.support.tolerance import mch50_doc, only, set_path, spec_of
from wormgear_cli.analysis.accuracy import analyze
from wormgear_cli.analysis.budget import budget
from wormgear_cli.analysis.simulate import periodic_sources, simulate
from wormgear_cli.measurement.iso230 import iso230_figures
from wormgear_cli.physics.effects import Signals
from wormgear_cli.spec.loader import load_spec, with_values
from wormgear_cli.tolerance import engine, metrics, sampling
from wormgear_cli.tolerance.quantities import PHASES, varied_quantities


def _spec_at(spec, values: dict, j: int):
    """The spec with sample j's values written into it (the path analyze and simulate read)."""
    ch = {k: float(a[j]) for k, a in values.items() if "[" not in k}
    ch["assembly.worm_pair_errors_mm"] = [float(values[f"assembly.worm_pair_errors_mm[{i}]"][j]) for i in range(6)]
    return with_values(spec, ch)


#: the paper's MCH50 (paper kinematics, no grades) and the rotary table (involute kinematics,
#: ISO 1328 grades giving the pitch deviations, no gear eccentricity written)
SPECS = {"mch50": lambda: spec_of(mch50_doc()), "rotary-table": lambda: load_spec(CONFIGS / "rotary-table-precision.toml")}


def _magnitudes(spec, d):
    """Sample values as the spec can hold them (its keys take magnitudes only)."""
    return {k: np.abs(a) for k, a in d.values.items()}


def test_rotary_table_is_read_with_the_involute_kinematics_and_grades():
    spec = SPECS["rotary-table"]()
    assert spec.gear_pair.kinematics == "involute"
    by = {v.path: v for v in varied_quantities(spec)}
    assert by["assembly.gear_eccentricity_mm"].tolerance == (0.0,)  # involute: only a written eccentricity
    assert by["assembly.gear_centre_distance_error_mm"].tolerance == (0.008,)
    assert by["gear_pair.output_gear.thickness_deviation_mm"].tolerance == (0.015,)
    # ISO 1328-1:2013 class 4, d = 360 mm, m = 2: F_pT = 17 um (the config's comment, `wormgear grade`)
    assert by["gear_pair.output_gear.cumulative_pitch_deviation_mm"].tolerance[0] == pytest.approx(0.017)
    # the paper's kinematics does not read the centre-distance error (only as Delta e's default)
    mch = SPECS["mch50"]()
    assert {v.path: v for v in varied_quantities(mch)}["assembly.gear_centre_distance_error_mm"].tolerance == (0.0,)


@pytest.mark.parametrize("name", sorted(SPECS))
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_paper_totals_equal_analyze_per_sample(seed, name):
    spec = SPECS[name]()
    varied = varied_quantities(spec)
    d = sampling.draw(varied, seed, 0, 12)
    values = _magnitudes(spec, d)
    ctx = metrics.context(spec, varied[0].tolerance[0], np.radians([0.0, 90.0]))
    got = metrics.paper_totals(ctx, values)
    for j in range(12):
        a = analyze(_spec_at(spec, values, j)).angles
        for m in metrics.PAPER_METRICS:
            assert got[m][j] == pytest.approx(a[m], rel=1e-11)


@pytest.mark.parametrize("name", sorted(SPECS))
@pytest.mark.parametrize("seed", [1, 2])
def test_budget_totals_equal_the_budget_per_sample(seed, name):
    spec = SPECS[name]()
    varied = varied_quantities(spec)
    d = sampling.draw(varied, seed, 0, 8)
    values = _magnitudes(spec, d)
    ctx = metrics.context(spec, varied[0].tolerance[0], np.radians([0.0, 90.0]))
    got = metrics.budget_totals(ctx, values)
    for j in range(8):
        b = budget(_spec_at(spec, values, j))
        assert got["budget_linear"][j] == pytest.approx(b.linear, rel=1e-9)
        assert got["budget_rss"][j] == pytest.approx(b.rss, rel=1e-9)


@pytest.mark.parametrize("name", sorted(SPECS))
@pytest.mark.parametrize("seed", [4, 5])
def test_iso_figures_equal_iso230_of_simulate(seed, name):
    spec = SPECS[name]()
    varied = varied_quantities(spec)
    d = sampling.draw(varied, seed, 0, 6)
    values = _magnitudes(spec, d)
    targets = np.radians(engine.plan_targets(engine.Options(seed=seed)))
    ctx = metrics.context(spec, varied[0].tolerance[0], targets)
    got = metrics.iso_figures(ctx, values, d.phases)
    n = targets.size
    theta = np.concatenate([targets, targets[::-1]] * 2)  # two runs, each forward then reverse
    direction = np.tile(np.concatenate([np.ones(n), -np.ones(n)]), 2)
    time = np.arange(theta.size) % (2 * n) * 10.0
    for j in range(6):
        s = _spec_at(spec, values, j)
        names = {src.phase_path: src.name for src in periodic_sources(s, all_budget_sources=True)}
        assert set(names) == set(PHASES)
        err = simulate(s, Signals(theta, direction, np.zeros_like(theta), np.full_like(theta, 20.0), time),
                       {names[p]: float(d.phases[p][j]) for p in PHASES})
        f = iso230_figures(theta, err, direction)
        for m, ref in (("iso230_E", f.E), ("iso230_B", f.B), ("iso230_M", f.M), ("iso230_A", f.A)):
            assert got[m][j] == pytest.approx(ref, rel=1e-9, abs=1e-15)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_no_sample_worse_than_the_corner_case(seed):
    spec = spec_of(mch50_doc())
    s = engine.setup(spec, engine.Options(samples=200_000, seed=seed, metrics="paper", unit="urad"))
    summary = engine.run(s)
    corner = analyze(spec).angles
    for m in metrics.PAPER_METRICS:
        assert summary.described[m]["percentiles"]["max"] <= corner[m] / 1e-6
        assert summary.corner[m] == corner[m] / 1e-6


def test_corner_is_reached_when_every_value_sits_at_its_limit():
    # the upper limit of each interval is the spec value, so analyze of the spec is the sample at the limits
    spec = spec_of(mch50_doc())
    varied = varied_quantities(spec)
    values = {col: np.array([v.tolerance[e]]) for v in varied for e, col in enumerate(v.quantity.columns())}
    ctx = metrics.context(spec, varied[0].tolerance[0], np.radians([0.0]))
    got = metrics.paper_totals(ctx, values)
    for m in metrics.PAPER_METRICS:
        assert got[m][0] == pytest.approx(analyze(spec).angles[m], rel=1e-13)


def _one_key_spec(path="assembly.wheel_eccentricity_mm", value=0.02):
    doc = only(mch50_doc(), {path: value})
    return spec_of(doc)


def test_percentile_of_a_monotone_metric_is_analyze_at_the_key_percentile():
    # one varied key (S2, Rayleigh); total TE grows with S2.  With N - 1 divisible by 10000 the
    # percentiles are order statistics, so p_q(TE) = analyze(S2 = p_q(S2)) exactly.
    spec = _one_key_spec()
    n = 10_001
    s = engine.setup(spec, engine.Options(samples=n, seed=3, metrics="paper", unit="arcsec"))
    rows = []
    summary = engine.run(s, on_block=lambda b: rows.append(b.columns["assembly.wheel_eccentricity_mm"]))
    x = np.concatenate(rows)
    t, sigma = 0.02, 0.02 / 3
    mass = 1 - math.exp(-t * t / (2 * sigma * sigma))
    eps = math.sqrt(math.log(2 / 1e-6) / (2 * n))  # DKW band at 1e-6
    for q in ("50", "90", "95", "99", "99.73"):
        xq = float(np.percentile(x, float(q)))
        te = analyze(with_values(spec, {"assembly.wheel_eccentricity_mm": xq})).angles["total_transmission_error"]
        assert summary.described["total_transmission_error"]["percentiles"][q] == pytest.approx(
            te / (math.pi / 648000), rel=1e-12)
        # and the key's percentile is where the truncated Rayleigh law puts it (written here independently)
        f = (1 - math.exp(-xq * xq / (2 * sigma * sigma))) / mass
        assert abs(f - float(q) / 100) < eps


def test_sensitivity_recovers_a_known_split():
    # total backlash with only Delta e (uniform on [0, Te]) and T_s1 (an allowance: uniform on [0, Ts]) varied:
    #   gear part  4 tan(alpha) De / (m1 z1)                         (paper: 2 Delta C1 / (m1 z1), Delta C1 = 2 De tan a)
    #   worm part  [T_s1 / (2 cos l) + |T_s1| / (12 cos l)] 2 / (m2 z3 i_c)   (central + half-width with only T_s1)
    # additive, so S_De = V1 / (V1 + V2), S_Ts1 = V2 / (V1 + V2) with
    #   V1 = a^2 Te^2 / 12,  V2 = (b + c)^2 Ts^2 / 12  (X ~ U(0, Ts): |X| = X)
    te, ts = 0.03, 0.045
    doc = only(mch50_doc(), {"assembly.gear_eccentricity_mm": te, "worm_pair.worm.thickness_deviation_mm": ts})
    doc["statistics"] = {"assembly.gear_eccentricity_mm": {"distribution": "uniform"},
                         "worm_pair.worm.thickness_deviation_mm": {"distribution": "uniform"}}
    spec = spec_of(doc)
    m1, z1, alpha = 2.5, 144, math.radians(20.0)
    m2, z3, lam, i_c = 2.5, 30, math.radians(3.178), 144 / 18
    a = 4 * math.tan(alpha) / (m1 * z1)
    k = 2 / (m2 * z3 * i_c)
    b, c = k / (2 * math.cos(lam)), k / (12 * math.cos(lam))
    v1, v2 = a * a * te * te / 12, (b + c) ** 2 * ts * ts / 12
    for seed in (1, 2):
        s = engine.setup(spec, engine.Options(samples=200_000, seed=seed, metrics="paper"))
        idx, rest = engine.run(s).sensitivity["total_backlash"]
        assert idx["assembly.gear_eccentricity_mm"] == pytest.approx(v1 / (v1 + v2), abs=0.01)
        assert idx["worm_pair.worm.thickness_deviation_mm"] == pytest.approx(v2 / (v1 + v2), abs=0.01)
        assert rest == pytest.approx(0.0, abs=0.01)
        assert sum(idx.values()) + rest == pytest.approx(1.0, abs=1e-12)


def test_sensitivity_sums_to_at_most_one_with_small_samples():
    spec = spec_of(mch50_doc())
    s = engine.setup(spec, engine.Options(samples=300, seed=5, metrics="all"))
    for idx, rest in engine.run(s).sensitivity.values():
        assert all(v >= 0 for v in idx.values())
        assert math.fsum(idx.values()) <= 1.0 + 1e-12
        assert rest >= 0.0


def test_rss_lies_between_the_single_worst_and_the_corner():
    spec = spec_of(mch50_doc())
    s = engine.setup(spec, engine.Options(samples=10, metrics="paper"))
    corner, rss = engine.reference_values(s)
    for m in metrics.PAPER_METRICS:
        assert rss[m] <= corner[m] + 1e-9


def test_dense_plan_and_effects_enter_the_iso_figures():
    doc = mch50_doc()
    set_path(doc, "effects.thermal_drift.arcsec_per_K", 0.5)
    spec = spec_of(doc)
    s = engine.setup(spec, engine.Options(samples=50, metrics="iso", plan="dense", points=90))
    assert s.targets_deg.size == 90
    summary = engine.run(s)
    assert summary.described["iso230_E"]["mean"] > 0
