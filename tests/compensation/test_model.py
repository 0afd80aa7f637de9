"""The correction model: fitted orders per direction, per-target means where they do not explain
the data, held ends over a partial span (data from tests.support.compensation_data)."""

from __future__ import annotations

import math

import numpy as np

from tests.support import compensation_data as data
from wormgear_cli.compensation.model import plan_model
from wormgear_cli.units import ARCSEC


def _rows(seed=1, **kw):
    a, e, d, r = data.iso_rows(seed, **kw)
    return np.radians(a), e * ARCSEC, d.astype(float), r


def test_exact_orders_give_the_true_error_between_the_targets():
    theta, y, d, run = _rows(white=0.0, run_sd=0.0)
    plan, analysis, test, model = plan_model(theta, y, d, [1, 2, 9], run=run)
    assert plan.orders == (1.0, 2.0, 9.0) and not plan.per_target
    probe = np.linspace(0.0, 360.0, 1441)
    for sign in (1, -1):
        got = model.error(np.radians(probe), np.full(probe.size, sign)) / ARCSEC
        assert np.max(np.abs(got - data.axis_error(probe, sign))) < 2e-4  # the file's 4 decimals


def test_no_per_target_means_when_the_orders_explain_the_data():
    significant = 0
    for seed in range(20):
        theta, y, d, run = _rows(seed)
        plan, _, test, _ = plan_model(theta, y, d, [1, 2, 9], run=run)
        assert test.testable
        significant += test.significant
    assert significant <= 2  # alpha 0.01: 0.2 false alarms expected in 20


def test_per_target_means_when_an_order_is_missing():
    theta, y, d, run = _rows(2)
    plan, _, test, model = plan_model(theta, y, d, [1, 2], run=run)  # order 9 (5 arcsec) left out
    assert test.significant and plan.per_target
    assert test.rms > 3.0 * test.expected_rms
    # at the targets the model now follows the measured per-target means
    targets = np.unique(theta)
    for sign in (1, -1):
        rows = d == sign
        means = np.array([y[rows & (theta == t)].mean() for t in targets])
        assert np.allclose(model.error(targets, np.full(targets.size, sign)), means, atol=1e-9)


def test_without_orders_the_model_is_the_per_target_means():
    theta, y, d, run = _rows(3)
    plan, _, test, model = plan_model(theta, y, d, [], run=run)
    assert plan.orders == () and plan.per_target
    t = np.unique(theta)
    fwd = np.array([y[(d > 0) & (theta == x)].mean() for x in t])
    assert np.allclose(model.error(t, np.ones(t.size)), fwd, atol=1e-9)
    # between the targets: the periodic cubic spline through their means (scipy's, the oracle)
    from scipy.interpolate import CubicSpline

    spline = CubicSpline(np.append(t, t[0] + 2 * np.pi), np.append(fwd, fwd[0]), bc_type="periodic")
    mid = 0.5 * (t[:-1] + t[1:])
    assert np.allclose(model.error(mid, np.ones(mid.size)), spline(mid), rtol=0, atol=1e-15)


def test_one_run_per_target_cannot_be_tested():
    theta, y, d, run = _rows(4, runs=1)
    plan, _, test, _ = plan_model(theta, y, d, [1, 2, 9], run=run)
    assert not test.testable and not plan.per_target
    assert "cannot be told from noise" in test.reason


def test_a_partial_span_is_held_at_the_ends_outside_it():
    t = np.linspace(10.0, 100.0, 31)
    a = np.concatenate([t, t[::-1]] * 3)
    d = np.concatenate([np.ones(t.size), -np.ones(t.size)] * 3)
    run = np.repeat([1, 2, 3], 2 * t.size)
    y = data.axis_error(a, d) * ARCSEC
    plan, _, _, model = plan_model(np.radians(a), y, d, [9], run=run)
    assert not plan.coverage.full_turn and plan.trend_degree == 3
    e = lambda deg, s=1: model.error(np.radians(np.atleast_1d(deg)), np.full(np.size(deg), s))  # noqa: E731
    assert np.allclose(e([120.0, 200.0]), e(100.0))  # nearer the end at 100 deg
    assert np.allclose(e([300.0, 0.0]), e(10.0))  # nearer the start at 10 deg
    inside = np.linspace(10.0, 100.0, 91)
    # orders 1 and 2 (28 arcsec) as a cubic trend over 90 deg, order 9 fitted: within 1 %
    assert np.max(np.abs(e(inside) / ARCSEC - data.axis_error(inside, 1))) < 0.3


def test_one_direction_repeats_forward_in_reverse():
    theta, y, d, run = _rows(5)
    fwd = d > 0
    plan, _, _, model = plan_model(theta[fwd], y[fwd], d[fwd], [1, 2, 9], run=run[fwd])
    assert not plan.both
    probe = np.radians(np.linspace(0, 360, 50))
    assert np.array_equal(model.error(probe, np.ones(50)), model.error(probe, -np.ones(50)))


def test_orders_the_targets_cannot_resolve_are_not_fitted():
    # 24 evenly spaced targets: order 240 is constant on them (aliased onto the offset)
    t = np.arange(24) * 15.0
    a = np.concatenate([t, t[::-1]] * 3)
    d = np.concatenate([np.ones(24), -np.ones(24)] * 3)
    y = (3.0 * np.sin(np.radians(a)) + 2.0 * np.sin(240 * np.radians(a) + 0.5)) * ARCSEC
    plan, analysis, _, _ = plan_model(np.radians(a), y, d, [1, 240], run=np.repeat([1, 2, 3], 48))
    assert plan.orders == (1.0,)
    assert [it.status for it in analysis.items] == ["fitted", "aliased"]
    assert math.isclose(analysis.items[0].common[0] / ARCSEC, 3.0, rel_tol=1e-6)
