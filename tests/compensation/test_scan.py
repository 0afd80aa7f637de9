"""Single-order scans and the forward selection of the strongest orders."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support import compensation_data as data
from wormgear_cli.compensation.scan import order_amplitudes, strongest_order, strongest_orders


def test_each_candidate_is_the_least_squares_fit_of_its_own_columns():
    rng = np.random.default_rng(0)
    th = rng.uniform(0, 2 * np.pi, 300)
    d = np.where(rng.uniform(size=300) < 0.5, 1.0, -1.0)
    y = rng.normal(size=300) + 2 * np.sin(3 * th + 0.2) + d * 0.7 * np.cos(5 * th)
    scan = order_amplitudes(th, y, d, [3, 5, 7.5])
    base = np.column_stack([np.ones(300), d])
    rss0 = np.sum((y - base @ np.linalg.lstsq(base, y, rcond=None)[0]) ** 2)
    for i, k in enumerate((3, 5, 7.5)):
        c, s = np.cos(k * th), np.sin(k * th)
        x = np.column_stack([base, c, s, d * c, d * s])
        beta, res, *_ = np.linalg.lstsq(x, y, rcond=None)  # the oracle: numpy's solver
        assert scan.common[i] == pytest.approx(np.hypot(beta[2], beta[3]), rel=1e-9)
        assert scan.differential[i] == pytest.approx(np.hypot(beta[4], beta[5]), rel=1e-9)
        assert scan.reduction[i] == pytest.approx(rss0 - res[0], rel=1e-8)


def test_finds_the_planted_orders_on_the_target_means():
    a, e, d, r = data.iso_rows(seed=7)
    th = np.radians(a)
    targets = np.unique(th)
    means, dirs, counts, at = [], [], [], []
    for t in targets:
        for s in (1, -1):
            rows = (th == t) & (d == s)
            means.append(e[rows].mean())
            dirs.append(s)
            counts.append(rows.sum())
            at.append(t)
    sel = strongest_orders(np.array(at), np.array(means), np.array(dirs, float), range(1, 19), noise_var=0.25,
                           weights=np.array(counts))
    assert sorted(sel.orders) == [1.0, 2.0, 9.0]
    assert "not significant" in sel.reason


def test_on_noise_alone_nothing_is_chosen_in_most_data_sets():
    chosen = 0
    for seed in range(30):
        rng = np.random.default_rng(seed)
        th = np.sort(rng.uniform(0, 2 * np.pi, 72))
        sel = strongest_orders(th, rng.normal(size=72), np.ones(72), range(1, 30))
        chosen += bool(sel.orders)
    assert chosen <= 3  # alpha 0.01 per step (Bonferroni): about 0.3 expected


def test_strongest_order_finds_a_period_on_a_short_arc():
    rng = np.random.default_rng(1)
    th = np.linspace(1.0, 1.0 + np.radians(10.0), 1200)  # ten degrees of axis: five cycles of order 180
    drift = np.column_stack([np.ones_like(th), th - th.mean()])
    y = 3 * np.sin(180.0 * th + 1.0) + 40 * (th - th.mean()) + rng.normal(0, 0.5, th.size)
    k, amp = strongest_order(th, y, np.ones_like(th), 60.0, 1000.0, base=drift)
    assert k == pytest.approx(180.0, abs=1.0)
    assert amp == pytest.approx(3.0, rel=0.1)


def test_weighted_scan_is_the_weighted_least_squares_fit():
    rng = np.random.default_rng(3)
    th = rng.uniform(0, 2 * np.pi, 120)
    d = np.where(rng.uniform(size=120) < 0.5, 1.0, -1.0)
    w = rng.uniform(0.1, 5.0, 120)
    y = rng.normal(size=120) / np.sqrt(w) + 1.5 * np.sin(4 * th) + d * 0.4 * np.sin(2 * th + 1)
    scan = order_amplitudes(th, y, d, [2, 4], weights=w)
    sw = np.sqrt(w)
    base = np.column_stack([np.ones(120), d])
    rss0 = np.sum(((y - base @ np.linalg.lstsq(base * sw[:, None], y * sw, rcond=None)[0]) * sw) ** 2)
    assert scan.rss == pytest.approx(rss0, rel=1e-9) and scan.dof == 118 and scan.columns == 4
    for i, k in enumerate((2, 4)):
        c, s = np.cos(k * th), np.sin(k * th)
        x = np.column_stack([base, c, s, d * c, d * s])
        beta, res, *_ = np.linalg.lstsq(x * sw[:, None], y * sw, rcond=None)
        assert scan.common[i] == pytest.approx(np.hypot(beta[2], beta[3]), rel=1e-9)
        assert scan.differential[i] == pytest.approx(np.hypot(beta[4], beta[5]), rel=1e-9)
        assert scan.reduction[i] == pytest.approx(rss0 - res[0], rel=1e-8)


def test_one_direction_scans_the_common_mode_only_and_blocks_change_nothing(monkeypatch):
    th = np.linspace(0, 2 * np.pi, 50, endpoint=False) + 0.01
    y = 2.0 * np.cos(3 * th) + 0.1 * np.sin(7 * th)
    scan = order_amplitudes(th, y, np.ones(50), range(1, 10))
    assert scan.columns == 2 and np.all(np.isnan(scan.differential))
    assert scan.common[2] == pytest.approx(2.0, rel=1e-9) and scan.common[6] == pytest.approx(0.1, rel=1e-9)
    import wormgear_cli.compensation.scan as module

    monkeypatch.setattr(module, "BLOCK_CELLS", 150)  # one candidate per block
    again = order_amplitudes(th, y, np.ones(50), range(1, 10))
    assert np.array_equal(again.common, scan.common) and np.array_equal(again.reduction, scan.reduction)


def test_a_candidate_the_samples_cannot_tell_from_the_base_is_not_scanned():
    th = np.arange(24) * 2 * np.pi / 24  # order 24 is constant on these angles, 12 has one phase only
    scan = order_amplitudes(th, np.sin(3 * th), np.ones(24), [3, 12, 24])
    assert scan.common[0] == pytest.approx(1.0)
    assert np.isnan(scan.common[1]) and np.isnan(scan.common[2])
    assert list(scan.reduction[1:]) == [0.0, 0.0]
    # a repeated base column does not count twice in the degrees of freedom
    twice = order_amplitudes(th, np.sin(3 * th), np.ones(24), [3], base=np.column_stack([np.ones(24)] * 2))
    assert twice.dof == 23


def test_selection_p_values_are_the_tail_probabilities_times_the_candidates():
    from scipy import stats

    rng = np.random.default_rng(5)
    th = np.sort(rng.uniform(0, 2 * np.pi, 200))
    y = 0.5 * np.sin(5 * th) + rng.normal(0, 1.0, 200)
    base = np.ones((200, 1))
    rss0 = np.sum((y - y.mean()) ** 2)
    x = np.column_stack([base, np.cos(5 * th), np.sin(5 * th)])
    rss1 = np.linalg.lstsq(x, y, rcond=None)[1][0]
    chi = strongest_orders(th, y, np.ones(200), [5, 6, 7], noise_var=1.0)
    assert chi.orders[0] == 5.0
    assert chi.p_values[0] == pytest.approx(3 * stats.chi2.sf(rss0 - rss1, 2), rel=1e-6)
    f = strongest_orders(th, y, np.ones(200), [5, 6, 7])
    fstat = ((rss0 - rss1) / 2) / (rss1 / (200 - 3))
    assert f.p_values[0] == pytest.approx(3 * stats.f.sf(fstat, 2, 197), rel=1e-6)


def test_selection_stops_for_its_stated_reason():
    th = np.linspace(0, 2 * np.pi, 60, endpoint=False) + 0.02
    y = 5 * np.sin(th) + 4 * np.sin(2 * th + 1) + 3 * np.sin(3 * th + 2)
    d = np.ones(60)
    assert strongest_orders(th, y, d, [1, 2, 3, 4], noise_var=0.01, max_orders=2).reason == \
        "2 orders chosen (the most this selection takes)"
    assert strongest_orders(th, y, d, [1, 2, 3], noise_var=0.01).reason == "no candidate left (3 tried)"
    three = np.array([0.1, 2.2, 4.3])
    few = strongest_orders(three, np.sin(three) + np.array([0.1, 0.0, -0.2]), np.ones(3), [1])
    assert few.reason == "no degrees of freedom left to judge a further order"
    even = np.arange(24) * 2 * np.pi / 24
    assert strongest_orders(even, np.cos(12 * even), np.ones(24), [12, 24], noise_var=1.0).reason == \
        "no further candidate can be told apart from the orders chosen on these angles"
    rng = np.random.default_rng(0)
    noise = strongest_orders(th, rng.normal(size=60), d, [1, 2, 3, 4, 5, 6, 7, 8, 9, 10], noise_var=1e6)
    assert noise.orders == () and noise.reason.startswith("the strongest further order (")
    assert noise.reason.endswith(") is not significant (adjusted p = 1 >= 0.01)")


def test_weights_decide_the_selection():
    th = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    y = np.where(np.arange(80) < 40, 3 * np.sin(4 * th), 3 * np.sin(6 * th))
    w = np.where(np.arange(80) < 40, 1.0, 1e-6)
    sel = strongest_orders(th, y, np.ones(80), [4, 6], noise_var=0.01, weights=w, max_orders=1)
    assert sel.orders == (4.0,)
    sel = strongest_orders(th, y, np.ones(80), [4, 6], noise_var=0.01, weights=w[::-1], max_orders=1)
    assert sel.orders == (6.0,)


def test_both_directions_are_used_when_both_were_measured():
    th = np.tile(np.linspace(0, 2 * np.pi, 40, endpoint=False), 2)
    d = np.repeat([1.0, -1.0], 40)
    y = d * 2 * np.sin(5 * th)  # a differential pattern only
    sel = strongest_orders(th, y, d, [4, 5, 6], noise_var=0.01, max_orders=1)
    assert sel.orders == (5.0,)
    one = strongest_orders(th[:40], y[:40], d[:40], [4, 5, 6], noise_var=0.01, max_orders=1)
    assert one.orders == (5.0,)  # forward only: the pattern is common mode there


def test_strongest_order_precision_range_drift_and_weights():
    th = np.linspace(1.0, 1.0 + np.radians(20.0), 2000)
    clean = np.sin(180.37 * th + 0.3)
    assert strongest_order(th, clean, np.ones_like(th), 60.0, 1000.0)[0] == pytest.approx(180.37, abs=0.01)
    # the search stays within its range
    assert 200.0 <= strongest_order(th, clean, np.ones_like(th), 200.0, 1000.0)[0]
    assert 100.0 <= strongest_order(th, clean, np.ones_like(th), 100.0, 150.0)[0] <= 150.0
    # a large drift is taken out by the base columns, not found as a slow order
    drift = 400.0 * (th - th.mean())
    base = np.column_stack([np.ones_like(th), th - th.mean()])
    assert strongest_order(th, clean + drift, np.ones_like(th), 60.0, 1000.0, base=base)[0] == \
        pytest.approx(180.37, abs=0.01)
    # rows of weight ~0 do not count
    spoiled = clean.copy()
    spoiled[:1000] = 50 * np.sin(90.0 * th[:1000])
    w = np.r_[np.full(1000, 1e-9), np.ones(1000)]
    assert strongest_order(th, spoiled, np.ones_like(th), 60.0, 1000.0, weights=w)[0] == pytest.approx(180.37, abs=0.05)


def test_selection_in_radians_with_a_zero_noise_and_its_record():
    th = np.linspace(0, 2 * np.pi, 60, endpoint=False) + 0.02
    rng = np.random.default_rng(2)
    y = 5 * np.sin(th) + 4 * np.sin(2 * th + 1) + 3 * np.sin(3 * th + 2) + rng.normal(0, 0.1, 60)
    d = np.ones(60)
    two = strongest_orders(th, y, d, [1, 2, 3, 4], noise_var=0.01, max_orders=2)
    assert len(two.orders) == 2 and two.candidates == (1.0, 2.0, 3.0, 4.0)
    scaled = strongest_orders(th, y * 4.848e-6, d, [1, 2, 3, 4], noise_var=0.01 * 4.848e-6 ** 2)
    assert sorted(scaled.orders) == [1.0, 2.0, 3.0]  # arcsec as radians: the same choice
    zero = strongest_orders(th, y, d, [1, 2, 3, 4], noise_var=0.0)  # no noise figure: the F-test
    assert zero == strongest_orders(th, y, d, [1, 2, 3, 4])
