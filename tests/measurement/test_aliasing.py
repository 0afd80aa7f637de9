"""Aliasing decided on the samples: samplings built to sit just inside and just outside the
default tolerance (two orders alias when the correlation of their sampled exponentials is at
least 1 - 1e-3).

Construction (worked by hand, no project code): on N = 24 evenly spaced angles
theta_j = 2 pi j / N, orders k and k + N + d differ by N + d, and exp(i N theta_j) = 1, so their
correlation is the Dirichlet kernel |mean_j exp(i d theta_j)| = |sin(pi d)| / (N |sin(pi d / N)|),
which falls from 1 at d = 0 as 1 - pi^2 d^2 (N^2 - 1) / (6 N^2).  Solving for a correlation of
1 - 5e-4 (inside: aliased) and 1 - 2e-3 (outside: resolved) gives the two offsets d.  The other
correlations (each order with the offset, and k + (k + N + d) mirrored) stay far from 1.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from wormgear_cli.measurement.harmonics import ALIAS_TOL, alias_groups, folded_orders

N = 24
THETA = 2 * np.pi * np.arange(N) / N


def dirichlet(d: float, n: int = N) -> float:
    return abs(math.sin(math.pi * d)) / (n * abs(math.sin(math.pi * d / n)))


def offset_for(corr: float) -> float:
    """d in (0, 0.5) with dirichlet(d) = corr."""
    return brentq(lambda d: dirichlet(d) - corr, 1e-9, 0.5, xtol=1e-15)


INSIDE = offset_for(1 - 5e-4)   # ~0.0175
OUTSIDE = offset_for(1 - 2e-3)  # ~0.0349


def test_the_construction_is_what_it_says():
    """Checked numerically from the definition (mean over the samples), independent of the package."""
    for d, corr in ((INSIDE, 1 - 5e-4), (OUTSIDE, 1 - 2e-3)):
        assert abs(np.mean(np.exp(1j * (N + d) * THETA))) == pytest.approx(corr, abs=1e-12)
        # order 1 and order 25 + d: offset and mirror correlations are small
        assert abs(np.mean(np.exp(1j * 1.0 * THETA))) < 1e-12
        assert abs(np.mean(np.exp(1j * (1 + d) * THETA))) < 0.1
        assert abs(np.mean(np.exp(1j * (26 + d) * THETA))) < 0.6


def test_default_tolerance_is_1e3():
    assert ALIAS_TOL == 1e-3


def test_just_inside_the_tolerance_is_aliased():
    k2 = 25 + INSIDE
    assert alias_groups(THETA, [1.0, k2]) == [(1.0, k2)]


def test_just_outside_the_tolerance_is_resolved():
    assert alias_groups(THETA, [1.0, 25 + OUTSIDE]) == []


def test_just_inside_and_outside_of_an_explicit_tolerance():
    """The tolerance argument is honoured both ways: 1 - 2e-3 is aliased at tol 3e-3, not at 1e-3."""
    k2 = 25 + OUTSIDE
    assert alias_groups(THETA, [1.0, k2], tol=3e-3) == [(1.0, k2)]
    assert alias_groups(THETA, [1.0, k2], tol=1e-3) == []


def test_onto_the_offset_just_inside_and_outside():
    """Order N + d against the constant: correlation |mean exp(i (N + d) theta)| = dirichlet(d)."""
    assert alias_groups(THETA, [N + INSIDE]) == [(0.0, N + INSIDE)]
    assert alias_groups(THETA, [N + OUTSIDE]) == []


def test_folding_just_inside_and_outside():
    """Order N/2 + e folds onto its own mirror when |mean exp(2 i (N/2 + e) theta)| = dirichlet(2 e)
    >= 1 - tol: e = INSIDE/2 is folded, e = OUTSIDE/2 is not."""
    assert folded_orders(THETA, [N / 2 + INSIDE / 2]) == [N / 2 + INSIDE / 2]
    assert folded_orders(THETA, [N / 2 + OUTSIDE / 2]) == []


def test_mirror_alias_just_inside_and_outside():
    """k and N - k + d: the sum k + (N - k + d) = N + d, so C_plus = dirichlet(d)."""
    assert alias_groups(THETA, [5.0, 19 + INSIDE]) == [(5.0, 19 + INSIDE)]
    assert alias_groups(THETA, [5.0, 19 + OUTSIDE]) == []


def test_diagnosis_resolvable_orders_uses_the_same_tolerance():
    """``diagnose`` keeps only the lowest of aliased orders: just inside, the higher one is dropped."""
    from wormgear_cli.diagnosis import unaliased_orders

    keep, aliased = unaliased_orders(THETA, [1.0, 25 + INSIDE])
    assert keep == [1.0] and 25 + INSIDE in aliased
    keep, aliased = unaliased_orders(THETA, [1.0, 25 + OUTSIDE])
    assert keep == [1.0, 25 + OUTSIDE] and not aliased


def test_order_and_offset_correlations_by_hand():
    """On the 24 even angles: C_minus between k and k + N + d is dirichlet(d), 1 on the diagonal;
    C_plus of 5 and 19 + d is dirichlet(d); the offset correlation of N + d is dirichlet(d), of 1 zero."""
    from wormgear_cli.measurement.harmonics import offset_correlations, order_correlations

    c_minus, c_plus = order_correlations(THETA, [1.0, 25 + OUTSIDE])
    assert c_minus[0, 1] == pytest.approx(1 - 2e-3, abs=1e-12) and c_minus[1, 0] == pytest.approx(1 - 2e-3, abs=1e-12)
    np.testing.assert_allclose(np.diag(c_minus), [1.0, 1.0], atol=1e-12)
    _, c_plus = order_correlations(THETA, [5.0, 19 + INSIDE])
    assert c_plus[0, 1] == pytest.approx(1 - 5e-4, abs=1e-12)
    np.testing.assert_allclose(offset_correlations(THETA, [N + INSIDE, 1.0]), [1 - 5e-4, 0.0], atol=1e-12)


def test_weights_decide_like_the_weighted_samples():
    """Five extra angles with weight 0 change nothing: orders 1 and 25 + INSIDE stay aliased; with
    the same five angles counted (no weights) they are told apart.  Repeating every angle twice
    (row counts) is the same as once."""
    extra = np.array([0.3, 1.1, 2.9, 4.2, 5.5])
    theta = np.concatenate([THETA, extra])
    weights = np.concatenate([np.ones(N), np.zeros(5)])
    k2 = 25 + INSIDE
    assert alias_groups(theta, [1.0, k2], weights=weights) == [(1.0, k2)]
    assert alias_groups(theta, [1.0, k2], weights=1e-3 * weights) == [(1.0, k2)]  # only ratios count
    assert alias_groups(theta, [1.0, k2]) == []
    assert folded_orders(theta, [N / 2 + INSIDE / 2], weights=weights) == [N / 2 + INSIDE / 2]
    assert folded_orders(theta, [N / 2 + INSIDE / 2]) == []
    assert alias_groups(np.concatenate([THETA, THETA]), [1.0, k2]) == [(1.0, k2)]
    from wormgear_cli.measurement.harmonics import offset_correlations

    np.testing.assert_allclose(offset_correlations(theta, [N + INSIDE], weights=weights), [1 - 5e-4], atol=1e-12)
    from wormgear_cli.measurement.harmonics import order_correlations

    c_minus, _ = order_correlations(theta, [1.0, k2], weights=weights)
    assert c_minus[0, 1] == pytest.approx(1 - 5e-4, abs=1e-12)


def test_an_order_on_clustered_angles_is_grouped_with_the_offset():
    """Angles within 0.01 rad of each other: order 1 is (nearly) constant there, grouped with 0.0
    even though 0.0 was not asked for."""
    theta = np.linspace(0.0, 0.01, 10)
    assert alias_groups(theta, [1.0]) == [(0.0, 1.0)]


def test_angles_must_be_one_dimensional():
    with pytest.raises(ValueError, match="^theta must be one-dimensional$"):
        alias_groups(THETA.reshape(4, 6), [1.0])
