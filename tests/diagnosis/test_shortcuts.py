"""The speed and memory shortcuts of diagnose give the plain computation's numbers, bit for bit.

Each shortcut (sources evaluated per distinct (angle, direction) pair, scan columns per
distinct angle, pass sums of passes stored as blocks, one design for several order tables,
one pass for alias groups and folded orders, in-place scaling in ``orthonormal``) is
compared with the same computation done the plain way: exact equality, no tolerance.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from tests.support.paths import CONFIGS
from wormgear_cli import diagnosis as dg
from wormgear_cli.diagnosis import phases, runs, scan
from wormgear_cli.measurement import harmonics
from wormgear_cli.measurement.readers import read_measurement
from wormgear_cli.spec.loader import load_spec

DEMO = CONFIGS / "mch50-warm.csv"


def _report_json(meas, spec) -> str:
    return json.dumps(dg.report(dg.diagnose(spec, meas)), sort_keys=True, default=repr)


def _radar_measurement(tmp_path):
    from wormgear_cli.analysis.synth import Noise, Plan, format_csv, synthesize

    spec = load_spec(CONFIGS / "radar-pedestal-2start.toml")
    syn = synthesize(spec, Plan(kind="iso", points=40, runs=5, dwell_s=0.1),
                     effects={"bearing_clearance": {"clearance_arcsec": 20.0}}, noise=Noise(0.3, 0.2), seed=3,
                     random_phases=True)
    path = tmp_path / "radar.csv"
    path.write_text(format_csv(syn))
    return spec, read_measurement(path)


@pytest.mark.parametrize("case", ["demo", "radar"])
def test_report_is_the_same_without_any_shortcut(monkeypatch, tmp_path, case):
    # the demo (MCH50) and a two-start radar drive (whose designs come out in Fortran order) repeat every
    # (angle, direction) pair over their runs and store passes as blocks
    if case == "demo":
        spec, meas = load_spec(CONFIGS / "mch50.toml"), read_measurement(DEMO)
    else:
        spec, meas = _radar_measurement(tmp_path)
    sig = meas.signals()
    assert phases.distinct_pairs(sig) is not None
    groups = dg.make_groups(meas.direction, meas.run)
    assert not groups.in_order and groups.blocks is not None
    fast = _report_json(meas, spec)

    monkeypatch.setattr(phases, "distinct_pairs", lambda sig, max_share=0.5: None)
    monkeypatch.setattr(scan, "distinct_pairs", lambda sig, max_share=0.5: None)
    post_init = runs.Groups.__post_init__

    def no_blocks(self):
        post_init(self)
        object.__setattr__(self, "blocks", None)

    monkeypatch.setattr(runs.Groups, "__post_init__", no_blocks)
    assert fast == _report_json(meas, spec)


def test_pointwise_source_values_per_distinct_pair_equal_the_rows(mch50_spec):
    from wormgear_cli.analysis.accuracy import geometry
    from wormgear_cli.physics.effects import Signals

    rng = np.random.default_rng(11)
    theta = np.radians(np.tile(rng.uniform(0, 360, 50), 6))
    d = np.tile(np.repeat([1.0, -1.0], 25), 6)
    sig = Signals.make(theta, d)
    sources, _ = dg.phase_sources(mch50_spec, geometry(mch50_spec), sig)
    n = theta.shape[0]
    groups = dg.make_groups(d, np.repeat(np.arange(6), 50))
    ctx = dg.FitContext(np.zeros(n), sig, groups, np.zeros(n), tuple(sources), tuple(s.phase for s in sources))
    assert ctx.distinct is not None and ctx.distinct.sig.theta.shape[0] == 50
    for s in sources:
        assert s.pointwise
        for psi in (0.0, 1.234, -2.5):
            assert np.array_equal(ctx.values(s, psi), s.contrib(sig, psi))


@pytest.mark.parametrize("drive", ["mch50", "radar-pedestal-2start", "rotary-table-precision"])
def test_source_curves_per_distinct_angle_equal_the_rows(drive):
    # forward and reverse passes over the same targets: the pairs repeat their angles, and the sources'
    # curves (and lost motion) are evaluated once per angle
    from wormgear_cli.analysis.accuracy import geometry
    from wormgear_cli.physics.effects import Signals

    spec = load_spec(CONFIGS / f"{drive}.toml")
    rng = np.random.default_rng(12)
    targets = np.radians(rng.uniform(-30, 390, 40))
    theta = np.tile(np.concatenate([targets, targets[::-1]]), 3)
    d = np.tile(np.repeat([1.0, -1.0], 40), 3)
    sig = Signals.make(theta, d)
    sources, _ = dg.phase_sources(spec, geometry(spec), sig)
    n = theta.shape[0]
    groups = dg.make_groups(d, np.repeat(np.arange(3), 80))
    ctx = dg.FitContext(np.zeros(n), sig, groups, np.zeros(n), tuple(sources), tuple(s.phase for s in sources))
    assert ctx.distinct is not None and ctx.distinct.angles is not None
    assert ctx.distinct.sig.theta.shape[0] == 80 and ctx.distinct.angles[0].shape[0] == 40
    assert sources
    for s in sources:
        for psi in (0.0, 1.234, -2.5):
            assert np.array_equal(phases.pair_values(s, ctx.distinct, psi), s.contrib(ctx.distinct.sig, psi))
            assert np.array_equal(ctx.values(s, psi), s.contrib(sig, psi))


def test_distinct_pairs_only_when_rows_repeat():
    from wormgear_cli.physics.effects import Signals

    theta = np.linspace(0.0, 1.0, 40)
    assert phases.distinct_pairs(Signals.make(theta, 1.0)) is None
    # -0.0 and 0.0 are different keys (bitwise), so a sign of zero is never swapped
    sig = Signals.make(np.array([0.0, -0.0, 0.0, -0.0]), 1.0)
    d = phases.distinct_pairs(sig)
    assert d is not None and d.sig.theta.shape[0] == 2
    assert np.array_equal(np.signbit(d.sig.theta[d.inverse]), np.signbit(sig.theta))


def test_phase_fit_is_the_same_per_pair_and_per_row(mch50_spec):
    from wormgear_cli.analysis.accuracy import geometry
    from wormgear_cli.analysis.simulate import periodic_sources, simulate
    from wormgear_cli.physics.effects import Signals

    rng = np.random.default_rng(5)
    theta = np.radians(np.tile(np.sort(rng.uniform(0, 360, 60)), 4))
    d = np.repeat([1.0, -1.0, 1.0, -1.0], 60)
    sig = Signals.make(theta, d)
    truth = {s.name: float(rng.uniform(0, 2 * np.pi)) for s in periodic_sources(mch50_spec)}
    y = simulate(mch50_spec, sig, truth) / dg.ARCSEC + rng.normal(0.0, 0.3, theta.shape[0])
    sources, _ = dg.phase_sources(mch50_spec, geometry(mch50_spec), sig)
    base = simulate(mch50_spec, sig) / dg.ARCSEC - dg.sources_total(sources, sig, [s.phase for s in sources])
    groups = dg.make_groups(d, np.repeat([1, 1, 2, 2], 60))
    psi0 = tuple(s.phase for s in sources)
    fast = dg.fit_model(dg.FitContext(y, sig, groups, base, tuple(sources), psi0), np.ones((y.shape[0], 1)))
    plain_sources = tuple(dataclasses.replace(s, pointwise=False) for s in sources)
    plain = dg.fit_model(dg.FitContext(y, sig, groups, base, plain_sources, psi0), np.ones((y.shape[0], 1)))
    assert np.array_equal(fast.psi, plain.psi)
    assert np.array_equal(fast.residual, plain.residual)
    assert np.array_equal(fast.jac, plain.jac)
    assert fast.var.gp == plain.var.gp and fast.var.gr == plain.var.gr


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pass_sums_of_blocks_equal_the_gathered_sums(seed):
    rng = np.random.default_rng(seed)
    sizes = rng.integers(1, 40, 7)
    passes = rng.permutation(7)  # passes stored as blocks, not in pass order
    pass_id = np.repeat(passes, sizes)
    direction = np.where(pass_id % 2 == 0, 1.0, -1.0)
    groups = dg.make_groups(direction, pass_id // 2)
    assert groups.blocks is not None
    x = rng.normal(size=(pass_id.shape[0], 5)) * 10.0 ** rng.uniform(-3, 3, 5)
    gathered = np.add.reduceat(x[groups.order], groups.starts, axis=0)
    assert np.array_equal(dg.runs.pass_sums(x, groups), gathered)
    # and they are the per-pass sums
    for p in range(groups.passes):
        assert dg.runs.pass_sums(x, groups)[p] == pytest.approx(x[groups.pass_id == p].sum(axis=0), rel=1e-12)


def test_scattered_passes_still_gather():
    direction = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0])
    groups = dg.make_groups(direction, np.array([0, 0, 0, 0, 0, 0]))  # one run, directions interleaved
    assert groups.blocks is None and not groups.in_order
    x = np.arange(12.0).reshape(6, 2)
    # pass 0 is the reverse direction (rows 1, 3, 5: passes sort by run, then direction), pass 1 the forward
    assert np.array_equal(dg.runs.pass_sums(x, groups), [[2 + 6 + 10, 3 + 7 + 11], [0 + 4 + 8, 1 + 5 + 9]])


def test_mode_fits_of_several_responses_equal_one_at_a_time():
    rng = np.random.default_rng(3)
    n = harmonics.BLOCK_ROWS + 1000  # two blocks
    theta = rng.uniform(0, 2 * np.pi, n)
    d = np.where(rng.random(n) < 0.5, 1.0, -1.0)
    ys = [rng.normal(size=n) + k * np.sin(3 * theta) for k in range(3)]
    together = harmonics.fit_modes_each(theta, ys, d, [1.0, 3.0, 8.0])
    for y, fit in zip(ys, together):
        alone = harmonics.fit_modes(theta, y, d, [1.0, 3.0, 8.0])
        for mode in ("common", "differential"):
            a, b = getattr(fit, mode), getattr(alone, mode)
            for field in ("amplitude", "phase", "amplitude_stderr", "cos", "sin"):
                assert np.array_equal(getattr(a, field), getattr(b, field))
            assert a.offset == b.offset
        assert np.array_equal(fit.residual, alone.residual) and fit.sigma == alone.sigma


def test_order_tables_equal_order_table_each(mch50_spec):
    from wormgear_cli.analysis.accuracy import geometry

    meas = read_measurement(DEMO)
    rng = np.random.default_rng(8)
    resids = [rng.normal(size=len(meas)), meas.error / dg.ARCSEC]
    g = geometry(mch50_spec)
    assert dg.order_tables(meas, resids, g) == [dg.order_table(meas, r, g) for r in resids]


def test_aliasing_is_alias_groups_and_folded_orders():
    theta = np.radians(np.arange(24) * 15.0)  # 24 evenly spaced targets
    orders = [1.0, 8.0, 12.0, 24.0, 25.0, 144.0]
    assert harmonics.aliasing(theta, orders) == (harmonics.alias_groups(theta, orders),
                                                 harmonics.folded_orders(theta, orders))
    assert harmonics.aliasing(theta, []) == ([], [])


def test_orthonormal_in_place_gives_the_same_basis():
    rng = np.random.default_rng(2)
    x = rng.normal(size=(500, 4)) * [1.0, 1e3, 1e-3, 5.0]
    kept = x.copy()
    plain, rank = dg.design.orthonormal(x)
    assert np.array_equal(x, kept)  # not given up: untouched
    own, rank_own = dg.design.orthonormal(x.copy(), own=True)
    assert rank == rank_own == 4 and np.array_equal(plain, own)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_passes_from_two_column_uniques_equal_sorting_rows(seed):
    rng = np.random.default_rng(seed)
    n = 500
    run = rng.integers(-3, 12, n)
    direction = rng.choice([1.0, -1.0], n)
    groups = dg.make_groups(direction, run)
    uniq, pass_id = np.unique(np.stack([run.astype(float), direction], axis=1), axis=0, return_inverse=True)
    assert np.array_equal(groups.pass_id, pass_id.reshape(-1))
    assert np.array_equal(groups.pass_direction, uniq[:, 1])
    assert groups.runs == np.unique(run).shape[0]


def test_gap_summary_with_cells_made_once_is_the_same():
    meas = read_measurement(DEMO)
    resid = np.random.default_rng(4).normal(size=len(meas))
    assert dg.gap_summary(meas, resid, dg.residuals.target_run_cells(meas)) == dg.gap_summary(meas, resid)


@pytest.mark.parametrize("seed", [0, 1])
def test_mode_fits_from_a_table_of_distinct_angles_equal_the_row_by_row_columns(monkeypatch, seed):
    # repeated runs visit each angle several times: the cos/sin columns are made once per distinct angle
    rng = np.random.default_rng(seed)
    targets = np.sort(rng.uniform(0, 2 * np.pi, 300))
    theta = np.tile(targets, 6)
    d = np.repeat([1.0, -1.0] * 3, targets.shape[0])
    ys = [rng.normal(size=theta.shape[0]) + 2.0 * np.cos(5 * theta + 0.3) * d, rng.normal(size=theta.shape[0])]
    assert harmonics._harmonic_table(theta, np.array([1.0, 5.0])) is not None
    fast = harmonics.fit_modes_each(theta, ys, d, [1.0, 5.0, 12.0, 37.5])
    monkeypatch.setattr(harmonics, "_harmonic_table", lambda theta, orders: None)
    plain = harmonics.fit_modes_each(theta, ys, d, [1.0, 5.0, 12.0, 37.5])
    for a_fit, b_fit in zip(fast, plain):
        for mode in ("common", "differential"):
            a, b = getattr(a_fit, mode), getattr(b_fit, mode)
            for field in ("amplitude", "phase", "amplitude_stderr", "cos", "sin"):
                assert np.array_equal(getattr(a, field), getattr(b, field))
        assert np.array_equal(a_fit.residual, b_fit.residual) and a_fit.sigma == b_fit.sigma


def test_no_table_when_every_angle_is_distinct():
    theta = np.linspace(0.0, 6.0, 1000)
    assert harmonics._harmonic_table(theta, np.array([1.0, 2.0])) is None
    assert harmonics._harmonic_table(np.tile(theta, 2), np.array([1.0, 2.0])) is not None
