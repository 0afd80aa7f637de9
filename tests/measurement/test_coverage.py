"""Coverage of the turn, beyond-span orders, order choice by determinacy, wrap independence, folding.

Constructed cases: the right values are the amplitudes put into the data (exact signals), the
geometry of the sampling (spans, alias arithmetic k2 = N - k1 or N + k1), never this code's output.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from wormgear_cli.cli import app
from wormgear_cli.measurement.coverage import coverage, unwrap_passes
from wormgear_cli.measurement.harmonics import resolvable_orders, select_orders
from wormgear_cli.measurement.orders import analyse_orders


def test_coverage_of_a_table_a_scan_across_zero_and_passes():
    even = np.radians(np.arange(24) * 15.0)
    c = coverage(even)
    assert c.full_turn and c.span == pytest.approx(2 * math.pi) and c.distinct == 24
    # a 10 deg scan written wrapped across zero: 355 .. 359.9, 0 .. 5
    scan = np.radians(np.concatenate([np.linspace(355, 359.9, 50), np.linspace(0, 5, 51)]))
    c = coverage(scan)
    assert not c.full_turn
    assert math.degrees(c.span) == pytest.approx(10.0, abs=1e-9)
    assert math.degrees(c.start) == pytest.approx(355.0)
    # the same scan unwrapped (355 .. 365) covers the same span
    assert math.degrees(coverage(np.unwrap(scan)).span) == pytest.approx(10.0, abs=1e-9)
    # two passes: 0..30 and 100..160 deg
    th = np.radians(np.concatenate([np.linspace(0, 30, 31), np.linspace(100, 160, 61)]))
    c = coverage(th, np.repeat([0, 1], [31, 61]))
    assert [math.degrees(s) for s in c.pass_spans] == pytest.approx([30.0, 60.0])
    assert math.degrees(c.span) == pytest.approx(160.0)  # largest gap 200 deg (160 -> 360)


def test_two_targets_close_together_are_a_partial_span():
    c = coverage(np.radians([10.0, 20.0]))
    assert not c.full_turn and math.degrees(c.span) == pytest.approx(10.0)


@pytest.mark.parametrize("orders", [[2, 200], [200, 2], [200]])
def test_partial_span_constructed_order_200_whatever_the_list(orders):
    # a 25 deg scan of 1500 random angles; 3 arcsec at order 200 plus a large once-per-turn error
    rng = np.random.default_rng(4)
    theta = np.radians(np.sort(np.concatenate([[40.0, 65.0], rng.uniform(40.0, 65.0, 1498)])))
    y = 3.0 * np.sin(200 * theta + 0.3) + 80.0 * np.sin(theta + 1.0) + 25.0 * np.sin(2 * theta - 0.4)
    res = analyse_orders(theta, y, np.ones_like(theta), orders)
    items = {it.order: it for it in res.items}
    assert items[200.0].status == "fitted"
    # the slow part is not a cubic exactly: tolerance 0.01 of the 3 arcsec put in
    assert items[200.0].common[0] == pytest.approx(3.0, abs=0.01)
    if 2 in orders:
        assert items[2.0].status == "beyond span"  # period 180 deg > 25 deg
        assert math.isnan(items[2.0].common[0])
        assert "25 deg" in items[2.0].reason
    assert res.trend_degree == 3 and not res.coverage.full_turn


def test_selection_follows_determinacy_not_list_order():
    # 24 even targets: order 24.002 is nearly constant on them (determinacy ~0), order 5 is clean
    theta = np.radians(np.arange(24) * 15.0 + 0.0)
    for cands in ([24.002, 5.0], [5.0, 24.002]):
        res = select_orders(theta, cands)
        assert res.kept == (5.0,)
        assert res.determinacy[5.0] == pytest.approx(1.0)  # orthogonal to the offset on even targets
        assert "not determined apart from the other orders" in res.reason[24.002]
    assert resolvable_orders(theta, [24.002, 5.0]) == [5.0]


def test_exact_ties_fall_back_to_the_list_order():
    # 5 distinct angles hold the offset and two orders; a third cannot be added: the later one is left out
    theta = np.array([0.0, 1.1, 2.3, 3.9, 5.0])
    assert select_orders(theta, [3.0, 1.0, 4.0]).kept == (3.0, 1.0)
    assert select_orders(theta, [4.0, 1.0, 3.0]).kept == (4.0, 1.0)
    assert "too few distinct angles (5) for 7 coefficients" in select_orders(theta, [3.0, 1.0, 4.0]).reason[4.0]


def test_non_integer_order_does_not_depend_on_wrapping():
    # a tracking log over 2.2 turns; a motor-period error at order 2.5 (say, 144 s per cycle converted)
    theta = np.radians(np.linspace(30.0, 30.0 + 792.0, 4000))
    y = 4.0 * np.sin(2.5 * theta + 0.7)
    wrapped = np.mod(theta, 2 * np.pi)
    a = analyse_orders(theta, y, np.ones_like(theta), [2.5])
    b = analyse_orders(wrapped, y, np.ones_like(theta), [2.5])
    assert a.items[0].common[0] == pytest.approx(4.0, abs=1e-6)
    assert b.items[0].common[0] == pytest.approx(4.0, abs=1e-6)
    assert b.items[0].common[2] == pytest.approx(a.items[0].common[2], abs=1e-9)
    assert np.allclose(unwrap_passes(wrapped), unwrap_passes(theta))


def test_folded_orders_are_named_together(runner, tmp_path):
    # 100 equally spaced targets: order 103 = 100 + 3 looks exactly like order 3
    targets = np.arange(100) * 3.6
    err = 5.0 * np.sin(np.radians(103 * targets))
    path = tmp_path / "fold.csv"
    path.write_text("angle_deg,error_arcsec,direction,run\n" + "".join(
        f"{a:.6f},{e:.9f},{d},{r}\n" for r in range(2) for d in (1, -1) for a, e in zip(targets, err)))
    doc = json.loads(runner.invoke(app, ["measure", str(path), "-f", "json", "--orders", "3,103"]).stdout)
    items = {it["order"]: it for it in doc["orders"]["items"]}
    assert items[103.0]["status"] == "aliased" and items[103.0]["aliased_with"] == [3.0]
    # the content shows at order 3 (sin(103 x) = sin(3 x) on these targets)
    assert items[3.0]["common"]["amplitude"] == pytest.approx(5.0, abs=1e-6)
    assert ("order 103 is aliased by the target spacing onto order 3: order 103 and order 3 are indistinguishable "
            "on these targets, the amplitude shown at order 3 belongs to either or both") in doc["notes"]


def test_mesh_order_folds_on_the_intermediate_shaft_with_136_targets():
    # 136 equal targets: 144 = 136 + 8
    theta = np.radians(np.arange(136) * 360.0 / 136)
    res = analyse_orders(theta, np.sin(144 * theta), np.ones(136), [8, 144])
    items = {it.order: it for it in res.items}
    assert items[144.0].status == "aliased" and items[144.0].aliased_with == (8.0,)
    assert items[8.0].aliased_with == (144.0,)


def test_one_angle_has_no_orders():
    theta = np.zeros(10)
    res = analyse_orders(theta, np.arange(10.0), np.ones(10), [1, 2])
    assert [it.status for it in res.items] == ["unresolved", "unresolved"]
    assert res.items[0].reason.startswith("too few distinct angles (1)")
