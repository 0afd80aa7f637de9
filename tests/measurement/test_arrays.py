"""measurement.arrays gives numpy's own results (np.unique, np.cumsum, np.unwrap are the oracles) with
fewer temporaries; the serial statistics give the same figures whether the rows come in time order
(no sort) or shuffled (sorted back)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from tests.support.examples import examples
from wormgear_cli.measurement import arrays
from wormgear_cli.measurement.serial import lag1_autocorrelation, point_noise, serial_blocks

FLOATS = hnp.arrays(np.float64, st.integers(0, 300), elements=st.sampled_from(
    [0.0, -0.0, 1.5, -2.25, 3.0, 1e300, -1e-300, np.nan, np.inf, 7.125]))
@settings(max_examples=examples(150), deadline=None)
@given(x=st.one_of(FLOATS, hnp.arrays(np.int64, st.integers(0, 300), elements=st.integers(-50, 50)),
                   hnp.arrays(np.int64, st.integers(1, 50), elements=st.integers(-2**62, 2**62)),
                   hnp.arrays(np.int8, st.integers(1, 50)), hnp.arrays(np.bool_, st.integers(1, 50)),
                   hnp.arrays(np.uint16, st.integers(1, 50))),
       index=st.booleans(), counts=st.booleans())
def test_unique_is_numpys(x, index, counts):
    want = np.unique(x, return_index=index, return_inverse=True, return_counts=counts)
    got = arrays.unique(x, return_index=index, return_counts=counts)
    assert len(got) == len(want)
    for g, w in zip(got, want):
        np.testing.assert_array_equal(g, np.ravel(w))
        assert g.dtype == np.ravel(w).dtype or g.dtype.kind == np.ravel(w).dtype.kind == "i"


def test_unique_of_long_arrays_across_blocks():
    """Whole numbers counted (pass numbers), and floats sorted, over several rank blocks."""
    rng = np.random.default_rng(5)
    for x in (rng.integers(0, 300, 3 * arrays.RANK_BLOCK + 17), rng.integers(-5, 2**40, 2 * arrays.RANK_BLOCK),
              np.round(rng.normal(size=2 * arrays.RANK_BLOCK + 3), 2)):
        want = np.unique(x, return_index=True, return_inverse=True, return_counts=True)
        for g, w in zip(arrays.unique(x, return_index=True, return_counts=True), want):
            np.testing.assert_array_equal(g, np.ravel(w))


@settings(max_examples=examples(60), deadline=None)
@given(mask=hnp.arrays(np.bool_, st.integers(1, 3 * 700)), block=st.integers(1, 70))
def test_ranks_and_order(mask, block):
    old = arrays.RANK_BLOCK
    arrays.RANK_BLOCK = block
    try:
        np.testing.assert_array_equal(arrays.ranks(mask), np.cumsum(mask) - 1)
        x = np.cumsum(mask.astype(float) - 0.3)
        assert arrays.non_decreasing(x) == bool(np.all(np.diff(x) >= 0))
        assert arrays.non_decreasing(np.cumsum(mask))
        p = np.cumsum(np.where(mask, 3.5, -1.0))  # jumps above pi, below pi, exactly... wrapped by unwrap
        np.testing.assert_array_equal(arrays.unwrap(np.mod(p, 2 * np.pi)), np.unwrap(np.mod(p, 2 * np.pi)))
        np.testing.assert_array_equal(arrays.unwrap(p), np.unwrap(p))
    finally:
        arrays.RANK_BLOCK = old


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_serial_figures_in_time_order_or_shuffled(seed):
    """Rows in time order (no sort) and the same rows shuffled within their passes (sorted back by time) give the
    same lag-1 autocorrelation, blocks (per row) and point noise."""
    rng = np.random.default_rng(seed)
    n = 3 * arrays.RANK_BLOCK // 2
    passes = np.repeat(np.arange(6), n // 6)
    time = np.concatenate([np.sort(rng.uniform(0, 100, n // 6)) for _ in range(6)])
    e = rng.normal(size=passes.size)
    resid = np.empty_like(e)
    resid[0] = e[0]
    for k in range(1, e.size):  # AR(1), rho 0.8: blocks are used
        resid[k] = 0.8 * resid[k - 1] + e[k]
    perm = np.lexsort((rng.permutation(passes.size), passes))  # shuffled within each pass (passes keep their order)
    first = lag1_autocorrelation(resid, passes, time)
    assert first == pytest.approx(lag1_autocorrelation(resid[perm], passes[perm], time[perm]), rel=1e-12)
    assert 0.7 < first[0] < 0.9
    assert point_noise(resid, passes, time) == point_noise(resid[perm], passes[perm], time[perm])
    a, b = serial_blocks(resid, passes, time), serial_blocks(resid[perm], passes[perm], time[perm])
    assert (a.method, a.block_rows, a.blocks) == (b.method, b.block_rows, b.blocks) and a.blocks > 1
    np.testing.assert_array_equal(a.block_id[perm], b.block_id)
    np.testing.assert_allclose(a.whiten(resid)[perm], b.whiten(resid[perm]), rtol=1e-12)
