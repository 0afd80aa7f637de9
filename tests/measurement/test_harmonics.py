"""Harmonic least squares at exact orders, aliasing and order labels (wormgear_cli.measurement.harmonics)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wormgear_cli.measurement.harmonics import (
    alias_groups,
    fit_modes,
    fit_orders,
    folded_orders,
    physical_orders,
    physical_priority,
)
from wormgear_cli.measurement.orders import OrdersOptions, analyse_orders
from wormgear_cli.physics.effects import DriveGeometry

TWO_PI = 2.0 * math.pi


def uneven(n, seed):
    """n unevenly spaced angles over one turn (sorted uniform draws)."""
    return np.sort(np.random.default_rng(seed).uniform(0.0, TWO_PI, n))


def even(n):
    return np.arange(n) * TWO_PI / n


# --- fit_orders ----------------------------------------------------------------------------------------------


def test_recovers_non_integer_orders_on_uneven_spacing():
    rng = np.random.default_rng(7)
    theta = uneven(300, 1)
    y = 0.7 + 2.0 * np.sin(2.5 * theta + 0.4) + 0.8 * np.sin(7.25 * theta - 1.1) + rng.normal(0, 0.01, theta.size)
    fit = fit_orders(theta, y, [2.5, 7.25])
    assert fit.amplitude == pytest.approx([2.0, 0.8], abs=0.01)
    assert fit.phase == pytest.approx([0.4, -1.1], abs=0.02)
    assert fit.offset == pytest.approx(0.7, abs=0.01)
    # the coefficients follow y ~ a cos + b sin with a = A sin(phi), b = A cos(phi)
    assert fit.cos == pytest.approx([2.0 * math.sin(0.4), 0.8 * math.sin(-1.1)], abs=0.02)
    assert fit.sin == pytest.approx([2.0 * math.cos(0.4), 0.8 * math.cos(-1.1)], abs=0.02)
    assert not fit.rank_deficient
    assert fit.identifiable.all()
    # residual is what is left: the noise
    assert np.std(fit.residual) == pytest.approx(0.01, rel=0.2)
    assert fit.residual == pytest.approx(y - fit.evaluate(theta), abs=1e-12)


def test_standard_error_matches_the_spread_over_repeats():
    theta = uneven(60, 2)
    rng = np.random.default_rng(3)
    amps, ses = [], []
    for _ in range(300):
        y = 1.5 * np.sin(3.3 * theta + 1.0) + rng.normal(0, 0.2, theta.size)
        fit = fit_orders(theta, y, [3.3, 1.0])
        amps.append(fit.amplitude[0])
        ses.append(fit.amplitude_stderr[0])
    # for a white-noise fit, the stderr should describe the scatter of the estimate (0.2 * sqrt(2/60) ~ 0.037)
    assert np.std(amps) == pytest.approx(np.mean(ses), rel=0.2)
    assert np.mean(ses) == pytest.approx(0.2 * math.sqrt(2 / 60), rel=0.25)


def test_weights_ignore_rows_with_zero_weight():
    theta = uneven(80, 4)
    y = 3.0 * np.sin(theta - 0.5)
    y_bad = y.copy()
    y_bad[::7] += 50.0  # gross outliers
    w = np.ones(theta.size)
    w[::7] = 0.0
    fit = fit_orders(theta, y_bad, [1.0], weights=w)
    assert fit.amplitude[0] == pytest.approx(3.0, abs=1e-9)
    assert fit.phase[0] == pytest.approx(-0.5, abs=1e-9)


def test_design_extra_columns_are_fitted_alongside():
    theta = uneven(120, 5)
    time_s = np.linspace(0.0, 3600.0, theta.size)  # a slow drift over an hour
    y = 2.0 * np.sin(4 * theta + 0.3) + 1e-3 * time_s
    fit = fit_orders(theta, y, [4.0], design_extra=time_s)
    assert fit.extra[0] == pytest.approx(1e-3, rel=1e-9)
    assert fit.amplitude[0] == pytest.approx(2.0, abs=1e-9)


def test_aliased_columns_do_not_crash_and_are_flagged():
    theta = even(24)
    y = 5.0 + 2.0 * np.sin(theta + 0.25)
    fit = fit_orders(theta, y, [1.0, 240.0])  # cos(240 theta) = 1 on 24 even targets
    assert fit.rank_deficient
    assert list(fit.identifiable) == [True, False]
    assert not fit.offset_identifiable
    assert fit.amplitude[0] == pytest.approx(2.0, abs=1e-9)
    assert fit.phase[0] == pytest.approx(0.25, abs=1e-9)
    assert math.isnan(fit.amplitude_stderr[1])
    assert np.all(np.isfinite(fit.residual))


def test_repeated_order_is_not_identifiable():
    theta = uneven(50, 6)
    fit = fit_orders(theta, np.sin(8 * theta), [8.0, 8.0])
    assert fit.rank_deficient
    assert not fit.identifiable.any()
    # the minimum-norm split still reproduces the data
    assert np.max(np.abs(fit.residual)) < 1e-9


def test_more_columns_than_samples():
    theta = np.array([0.1, 1.0, 2.5, 4.0])
    fit = fit_orders(theta, np.sin(theta), [1.0, 2.0, 3.0, 5.0])
    assert fit.rank_deficient and fit.rank == 4
    assert math.isnan(fit.sigma)


@settings(max_examples=30, deadline=None)
@given(
    k1=st.floats(0.3, 20.0), dk=st.floats(0.7, 15.0),
    a1=st.floats(0.1, 10.0), a2=st.floats(0.1, 10.0),
    p1=st.floats(-3.0, 3.0), p2=st.floats(-3.0, 3.0),
    seed=st.integers(0, 10_000),
)
def test_noiseless_fit_is_exact(k1, dk, a1, a2, p1, p2, seed):
    theta = uneven(200, seed)
    k2 = k1 + dk
    y = a1 * np.sin(k1 * theta + p1) + a2 * np.sin(k2 * theta + p2)
    fit = fit_orders(theta, y, [k1, k2])
    assert fit.amplitude == pytest.approx([a1, a2], abs=1e-6)
    for got, want in zip(fit.phase, (p1, p2)):
        assert math.cos(got - want) == pytest.approx(1.0, abs=1e-9)


# --- fit_modes -----------------------------------------------------------------------------------------------


def test_modes_separate_common_and_differential_with_different_angles_per_direction():
    rng = np.random.default_rng(8)
    th_f, th_r = uneven(150, 9), uneven(150, 10)
    theta = np.concatenate([th_f, th_r])
    d = np.concatenate([np.ones(150), -np.ones(150)])
    # common: 1 + 3 sin(theta + 0.2); lost motion 4 (differential offset -2) plus 0.5 sin(3 theta - 0.7)
    y = 1.0 + 3.0 * np.sin(theta + 0.2) + d * (-2.0 + 0.5 * np.sin(3 * theta - 0.7)) + rng.normal(0, 0.02, 300)
    fit = fit_modes(theta, y, d, [1.0, 3.0])
    assert fit.common.amplitude == pytest.approx([3.0, 0.0], abs=0.02)
    assert fit.common.phase[0] == pytest.approx(0.2, abs=0.02)
    assert fit.common.offset == pytest.approx(1.0, abs=0.01)
    assert fit.differential.offset == pytest.approx(-2.0, abs=0.01)
    assert fit.differential.amplitude == pytest.approx([0.0, 0.5], abs=0.02)
    assert fit.differential.phase[1] == pytest.approx(-0.7, abs=0.05)


def test_modes_with_one_direction_leave_the_differential_undefined():
    theta = uneven(40, 11)
    fit = fit_modes(theta, 2 * np.sin(theta), np.ones(40), [1.0])
    assert fit.common.amplitude[0] == pytest.approx(2.0)
    assert math.isnan(fit.differential.amplitude[0]) and math.isnan(fit.differential.offset)
    assert not fit.rank_deficient


# --- aliasing ------------------------------------------------------------------------------------------------


def test_alias_groups_for_24_even_targets():
    theta = even(24)
    # on 24 samples per turn: 240 = 10 * 24 looks constant, 300 = 12 * 24 + 12 looks like 12,
    # 23 = 24 - 1 looks like -1 (same cos/sin span as 1), 25 = 24 + 1 looks like 1
    groups = alias_groups(theta, [1, 8, 12, 23, 25, 240, 300])
    assert groups == [(0.0, 240.0), (1.0, 23.0, 25.0), (12.0, 300.0)]


def test_alias_groups_within_a_turn_of_repeated_runs():
    # repeated runs at the same angles do not change what can be told apart
    theta = np.tile(even(24), 5)
    assert alias_groups(theta, [240, 300, 12]) == [(0.0, 240.0), (12.0, 300.0)]


def test_jittered_targets_break_the_aliases():
    rng = np.random.default_rng(12)
    theta = even(24) + np.radians(rng.uniform(-3.0, 3.0, 24))
    assert alias_groups(theta, [1, 8, 12, 23, 25, 240, 300]) == []
    assert folded_orders(theta, [12, 240, 300]) == []


def test_same_order_twice_is_one_group():
    assert alias_groups(uneven(50, 13), [8, 3, 8]) == [(8.0, 8.0)]


def test_folded_orders_see_one_phase_component():
    theta = even(24)
    # sin(12 theta) = sin(pi j) = 0 at every target
    assert folded_orders(theta, [1, 12, 5]) == [12.0]


def test_analyse_orders_statuses_on_even_targets():
    theta = np.tile(even(24), 2)
    d = np.repeat([1.0, -1.0], 24)
    y = 4.0 * np.sin(theta + 0.5) - 1.5 * d
    res = analyse_orders(theta, y, d, [1, 8, 16, 240, 12, 300])
    st_ = {it.order: it.status for it in res.items}
    assert st_ == {1.0: "fitted", 8.0: "fitted", 16.0: "aliased", 240.0: "aliased", 12.0: "folded",
                   300.0: "aliased"}
    by = {it.order: it for it in res.items}
    assert by[16.0].aliased_with == (8.0,)  # 16 = 24 - 8
    assert by[240.0].aliased_with == (0.0,)
    assert by[1.0].common[0] == pytest.approx(4.0)
    assert math.degrees(by[1.0].common[2]) == pytest.approx(math.degrees(0.5))
    assert res.differential_offset == pytest.approx(-1.5)


def test_analyse_orders_keeps_the_priority_orders_when_targets_are_few():
    theta = np.array([0.0, 1.1, 2.3, 3.9, 5.0])  # 5 distinct targets: offset + 2 orders at most
    y = np.sin(theta)
    res = analyse_orders(theta, y, np.ones(5), [1, 2, 3, 4], OrdersOptions(priority=(3, 1, 4, 2)))
    assert {it.order: it.status for it in res.items} == {1.0: "fitted", 2.0: "unresolved", 3.0: "fitted",
                                                          4.0: "unresolved"}


# --- physical orders -----------------------------------------------------------------------------------------


def test_physical_orders_of_mch50(mch50_spec):
    from wormgear_cli.analysis.accuracy import geometry

    # MCH50: z1 = 144, z2 = 18 -> i_c = 8; wheel z3 = 30, single-start worm -> n_w = 8 * 30 = 240
    orders = physical_orders(geometry(mch50_spec), harmonics=3)
    assert [k for k, _ in orders] == [1, 2, 3, 8, 16, 24, 144, 240, 288, 432, 480, 720]
    labels = dict(orders)
    assert labels[1.0] == "output gear (table)"
    assert labels[8.0] == "intermediate shaft (pinion and wheel)"
    assert labels[144.0] == "spur mesh"
    assert labels[240.0] == "worm shaft and worm mesh"
    assert labels[480.0] == "2nd harmonic of worm shaft and worm mesh"
    assert physical_priority(geometry(mch50_spec), harmonics=2) == [1, 8, 144, 240, 2, 16, 288, 480]


def _geometry(i_c, n_w, z1):
    return DriveGeometry(output_pitch_radius=100.0, output_base_radius=94.0, wheel_pitch_radius=40.0,
                         gear_ratio=i_c, worm_order=n_w, output_teeth=z1, axial_pressure_angle=0.35,
                         worm_centre_distance=60.0)


def test_coinciding_orders_are_merged_with_joined_labels():
    # i_c = 2 coincides with the 2nd harmonic of the output gear
    orders = physical_orders(_geometry(2.0, 60.0, 40), harmonics=2)
    ks = [k for k, _ in orders]
    assert ks.count(2.0) == 1
    assert dict(orders)[2.0] == "intermediate shaft (pinion and wheel) / 2nd harmonic of output gear (table)"


def test_multi_start_worm_has_separate_shaft_and_mesh_orders():
    # 2-start worm: worm turns n_w = 120 per output turn, teeth mesh at 2 * 120 = 240
    orders = dict(physical_orders(_geometry(4.0, 120.0, 72), harmonics=1, worm_starts=2))
    assert orders[120.0] == "worm shaft"
    assert orders[240.0] == "worm mesh"
