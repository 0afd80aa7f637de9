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
