"""Orders too close to separate (issue 22, item 1): one ambiguous group, the span needed, honest errors.

Constructed cases: a guide-log-like 39 deg arc (the RA axis turning at the sidereal rate, one row
every 2 s) whose error is 1.63 arcsec at order 225 plus AR(1) seeing noise and a slow wander, made
here with numpy from the formulas, never from the code under test.  The right values are the
amplitude put in and the Rayleigh arithmetic (orders k apart need 360 deg / k of arc).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from wormgear_cli.measurement.orders import OrdersOptions, analyse_orders
from wormgear_cli.measurement.separation import SEPARATION_CORR, canonical_correlations, separation_groups

SIDEREAL_S = 86164.09


def ar1(rng, n, rho, sd):
    """AR(1) noise of marginal standard deviation ``sd``."""
    e = rng.normal(0.0, sd * math.sqrt(1.0 - rho * rho), n)
    out = np.empty(n)
    out[0] = rng.normal(0.0, sd)
    for i in range(1, n):
        out[i] = rho * out[i - 1] + e[i]
    return out


def guide_arc(seed, span_deg=39.0, amplitude=1.63, order=225.0, rho=0.8, noise=0.5):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, span_deg / 360.0 * SIDEREAL_S, 2.0)
    theta = math.radians(40.0) + 2.0 * math.pi * t / SIDEREAL_S
    y = amplitude * np.sin(order * theta + rng.uniform(0, 2 * math.pi)) + ar1(rng, t.size, rho, noise)
    return theta, y, t


@pytest.mark.parametrize("seed", range(5))
def test_orders_closer_than_360_over_span_are_one_ambiguous_group(seed):
    theta, y, t = guide_arc(seed)
    res = analyse_orders(theta, y, np.ones_like(theta), [224, 225, 226], OrdersOptions(time=t))
    items = {it.order: it for it in res.items}
    assert {it.status for it in res.items} == {"ambiguous"}
    carriers = [it for it in res.items if math.isfinite(it.common[0])]
    assert len(carriers) == 1  # never several "fitted" amplitudes
    amp, se, _ = carriers[0].common
    assert abs(amp - 1.63) < 4.0 * se + 0.05  # the group's amplitude is the one put in (a neighbour alone gives it too)
    assert se < 0.5
    assert items[224.0].group == (224.0, 225.0, 226.0)
    (grp,) = res.groups
    assert grp.orders == (224.0, 225.0, 226.0) and grp.correlation >= SEPARATION_CORR
    assert grp.span_needed_deg == pytest.approx(360.0)  # orders 1 apart: a full turn
    assert "a span of at least a full turn would separate them" in items[226.0].reason
    assert "39 deg arc" in items[226.0].reason


def test_the_same_orders_on_a_full_turn_are_fitted_apart():
    rng = np.random.default_rng(3)
    theta = np.radians(np.sort(rng.uniform(0, 360, 3000)))
    y = 1.63 * np.sin(225 * theta) + 0.8 * np.sin(224 * theta + 1) + 0.1 * rng.normal(size=theta.size)
    res = analyse_orders(theta, y, np.ones_like(theta), [224, 225, 226])
    items = {it.order: it for it in res.items}
    assert [it.status for it in res.items] == ["fitted"] * 3 and not res.groups
    assert items[225.0].common[0] == pytest.approx(1.63, abs=0.02)
    assert items[224.0].common[0] == pytest.approx(0.8, abs=0.02)


def test_orders_far_enough_apart_on_the_arc_stay_separate():
    # on a 39 deg arc orders 360 / 39 = 9.2 apart are at the Rayleigh limit: 225 and 240 are told apart
    theta, y, t = guide_arc(1, noise=0.1, rho=0.0)
    y = y + 2.0 * np.sin(240 * theta)
    res = analyse_orders(theta, y, np.ones_like(theta), [225, 240], OrdersOptions(time=t))
    assert [it.status for it in res.items] == ["fitted", "fitted"]
    assert res.items[1].common[0] == pytest.approx(2.0, abs=0.1)


def test_canonical_correlation_agrees_with_scipy_subspace_angles():
    scipy_linalg = pytest.importorskip("scipy.linalg")
    rng = np.random.default_rng(0)
    theta = np.radians(np.sort(rng.uniform(10.0, 49.0, 800)))
    fixed = np.column_stack([np.ones_like(theta), theta, theta**2])
    orders = [224.0, 225.0, 230.0]
    cols = [np.column_stack([np.cos(k * theta), np.sin(k * theta)]) for k in orders]
    x = np.hstack([fixed, *cols])
    corr = canonical_correlations(x.T @ x, 3, 3)
    q = np.linalg.qr(fixed)[0]

    def resid(a):
        return a - q @ (q.T @ a)

    for i in range(3):
        for j in range(3):
            if i == j:
                continue
            # the largest canonical correlation is the cosine of the smallest principal angle
            angle = float(np.min(scipy_linalg.subspace_angles(resid(cols[i]), resid(cols[j]))))
            assert corr[i, j] == pytest.approx(math.cos(angle), abs=1e-7)


def test_groups_need_both_closeness_and_correlation():
    corr = np.array([[1.0, 0.95, 0.95], [0.95, 1.0, 0.2], [0.95, 0.2, 1.0]])
    # on a full turn whole orders are never closer than 360 deg / span apart: no group, whatever the correlation
    assert separation_groups([1.0, 2.0, 3.0], corr, 2 * math.pi, True) == []
    # on a 30 deg arc 1 and 2 are too close and correlate; 1 and 3 are too close and correlate: one group
    (grp,) = separation_groups([1.0, 2.0, 3.0], corr, math.radians(30.0), False)
    assert grp.orders == (1.0, 2.0, 3.0) and grp.span_needed_deg == pytest.approx(360.0)
    # orders 0.5 apart need 720 deg of data
    (grp,) = separation_groups([10.0, 10.5], corr[:2, :2], 2 * math.pi, True)
    assert grp.span_needed_deg == pytest.approx(720.0)
    assert "720 deg (more than a full turn)" in grp.describe(360.0)


def test_the_note_names_the_span_that_would_separate_them():
    from wormgear_cli.measurement.separation import SeparationGroup

    assert SeparationGroup((10.0, 13.0), 0.95, 120.0).describe(40.0) == (
        "orders 10, 13 cannot be told apart on this 40 deg arc (closer than 360 deg / span apart; their columns "
        "correlate 0.95); a span of at least 120 deg would separate them")
    assert "on a full turn" in SeparationGroup((1.0, 1.5), 0.99, 720.0).describe(360.0)
    assert "a span of at least a full turn would" in SeparationGroup((1.0, 2.0), 0.99, 360.0).describe(30.0)


def test_canonical_correlations_without_fixed_columns_and_with_a_vanishing_pair():
    theta = np.linspace(0.0, 2 * math.pi, 24, endpoint=False)
    cols = [np.column_stack([np.cos(k * theta), np.sin(k * theta)]) for k in (1.0, 2.0, 12.0)]
    x = np.hstack(cols)
    corr = canonical_correlations(x.T @ x, 0, 3)
    assert np.allclose(np.diag(corr), 1.0)
    assert corr[0, 1] == pytest.approx(0.0, abs=1e-12)  # orthogonal on a full even turn
    # order 12 on 24 even targets: sin vanishes, cos is left; the pair keeps one direction (still a pair)
    y = np.column_stack([np.ones(24), x])
    full = canonical_correlations(y.T @ y, 1, 3)
    assert full.shape == (3, 3) and np.all(full <= 1.0)
    # a pair that vanishes entirely once the offset is projected out (order 24 = a constant) is inseparable
    z = np.column_stack([np.ones(24), cols[0], np.cos(24 * theta), np.sin(24 * theta)])
    c2 = canonical_correlations(z.T @ z, 1, 2)
    assert c2[0, 1] == 1.0 and c2[1, 0] == 1.0


def test_groups_are_sorted_and_report_their_largest_correlation():
    corr = np.array([[1.0, 0.93, 0.2], [0.93, 1.0, 0.91], [0.2, 0.91, 1.0]])
    (grp,) = separation_groups([12.0, 10.0, 11.0], corr, math.radians(20.0), False)
    assert grp.orders == (10.0, 11.0, 12.0)  # sorted, joined through 10-11 (0.91) and 12-10 (0.93)
    assert grp.correlation == pytest.approx(0.93)
    assert grp.span_needed_deg == pytest.approx(360.0)
    assert separation_groups([12.0, 10.0, 11.0], corr, math.radians(20.0), False, threshold=0.95) == []
