"""Statistics of the samples: yield interval, percentiles, sensitivity indices (hand formulas)."""

from __future__ import annotations

import numpy as np
import pytest

from wormgear_cli.tolerance.statistics import PERCENTILES, bin_index, binomial_yield, describe, first_order_indices


@pytest.mark.parametrize("n", [10, 1000, 100_000])
def test_clopper_pearson_closed_forms_at_the_ends(n):
    # k = 0: high = 1 - (alpha/2)^(1/n);  k = n: low = (alpha/2)^(1/n)  (Clopper & Pearson 1934)
    none = binomial_yield(0, n)
    assert none.low == 0.0 and none.high == pytest.approx(1 - 0.025 ** (1 / n), rel=1e-9)
    every = binomial_yield(n, n)
    assert every.high == 1.0 and every.low == pytest.approx(0.025 ** (1 / n), rel=1e-9)


def test_verdicts():
    y = binomial_yield(990, 1000)  # interval about 0.9817 .. 0.9952
    assert y.verdict(0.98) == "pass"
    assert y.verdict(0.99) == "undecided"
    assert y.verdict(0.996) == "fail"


def test_describe_percentiles_of_a_known_sequence():
    # 0, 1, ..., 10000: linear interpolation puts percentile q at 100 q
    d = describe(np.arange(10_001, dtype=float))
    assert list(d["percentiles"]) == list(PERCENTILES)
    assert d["percentiles"]["99.73"] == pytest.approx(9973.0)
    assert d["percentiles"]["max"] == 10_000.0
    assert d["mean"] == 5000.0
    assert d["std"] == pytest.approx(np.sqrt(10_001 * 10_002 / 12), rel=1e-12)  # discrete uniform, n - 1


def test_bin_index_edges():
    idx = bin_index(np.array([0.0, 0.0199, 0.02, 0.5, 1.0]), 0.0, 1.0, 50)
    assert idx.tolist() == [0, 0, 1, 25, 49]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_first_order_indices_of_a_linear_model(seed):
    # Y = 2 X1 + X2 + 0 X3, X ~ U(0, 1) independent: S1 = 4/5, S2 = 1/5, S3 = 0
    rng = np.random.default_rng(seed)
    x = rng.random((3, 200_000))
    y = 2 * x[0] + x[1]
    s, rest = first_order_indices({f"x{i}": bin_index(x[i], 0, 1) for i in range(3)}, y)
    assert s["x0"] == pytest.approx(0.8, abs=0.01)
    assert s["x1"] == pytest.approx(0.2, abs=0.01)
    assert s["x2"] == pytest.approx(0.0, abs=0.002)
    assert rest == pytest.approx(0.0, abs=0.01)


def test_first_order_indices_leave_the_interaction_in_the_remainder():
    # Y = X1 X2 with X ~ U(-1, 1): E[Y | Xi] = 0, so both first-order indices are 0, all in the remainder
    rng = np.random.default_rng(3)
    x = rng.uniform(-1, 1, (2, 200_000))
    s, rest = first_order_indices({f"x{i}": bin_index(x[i], -1, 1) for i in range(2)}, x[0] * x[1])
    assert max(s.values()) < 0.005
    assert rest > 0.99


def test_constant_metric_has_no_indices():
    assert first_order_indices({"x": np.zeros(10, np.uint8)}, np.ones(10)) is None


@pytest.mark.parametrize("seed", [0, 1])
def test_second_pass_percentiles_equal_the_in_memory_ones(monkeypatch, seed):
    # beyond IN_MEMORY_SAMPLES only a histogram is kept and a second pass collects the order
    # statistics: same numbers as holding every value (and as numpy's percentile, to rounding)
    from wormgear_cli.tolerance import statistics

    rng = np.random.default_rng(seed)
    blocks = [rng.normal(5.0, 2.0, 1000) for _ in range(7)] + [np.array([-3.0, 0.0, 12.5])]
    full = np.concatenate(blocks)
    held = statistics.OrderStatistics()
    for b in blocks:
        held.add(b)
    monkeypatch.setattr(statistics, "IN_MEMORY_SAMPLES", 1500)
    streamed = statistics.OrderStatistics()
    for b in blocks:
        streamed.add(b)
    assert streamed.needs_second_pass and not held.needs_second_pass
    streamed.start_second_pass()
    for b in blocks:
        streamed.collect(b)
    assert streamed.percentiles() == held.percentiles()
    ref = np.percentile(full, [50, 90, 95, 99, 99.73])
    assert list(held.percentiles().values())[:-1] == pytest.approx(ref, rel=1e-14)
    assert held.percentiles()["max"] == full.max()


def test_large_run_second_pass_gives_the_same_report(monkeypatch):
    from tests.support.paths import MCH50
    from wormgear_cli.spec.loader import load_spec
    from wormgear_cli.tolerance import engine, statistics

    s = engine.setup(load_spec(MCH50), engine.Options(samples=3000, seed=9, metrics="all"))
    held = engine.run(s)
    monkeypatch.setattr(statistics, "IN_MEMORY_SAMPLES", 1000)
    streamed = engine.run(s)
    assert streamed.described == held.described


# --- mutation-testing round 2 (issue 13): hand-worked ANOVA, small-n percentiles, boundaries --------

from wormgear_cli.tolerance.statistics import BinSums, Moments, Yield  # noqa: E402

# y = 0.01 * [1, 2, 3, 5, 7, 9]: n 6, mean 0.045, SST = 1e-4 * (3.5^2 + 2.5^2 + 1.5^2 + 0.5^2 + 2.5^2 + 4.5^2)
# = 47.5e-4.  Column "a" bins [0, 0, 0, 1, 1, 2] (bin 3 empty): bin means 2, 6, 9 (x 0.01), b = 3 occupied,
# SSB = 1e-4 (3 * 2.5^2 + 2 * 1.5^2 + 1 * 4.5^2) = 43.5e-4, MSW = (47.5 - 43.5)e-4 / (6 - 3) = 1.3333e-4,
# S_a = (43.5 - 2 * 1.3333) / 47.5 = 40.8333 / 47.5 = 0.8596491.
Y6 = 0.01 * np.array([1.0, 2.0, 3.0, 5.0, 7.0, 9.0])
BINS_A = np.array([0, 0, 0, 1, 1, 2], np.uint8)


def _sums(columns, y, centre, nbins=4, chunks=((0, 3), (3, 6))):
    """BinSums and Moments fed in two chunks about ``centre`` (the run adds block by block)."""
    m, s = Moments(centre), BinSums(list(columns), ["y"], nbins)
    for a, b in chunks:
        m.add(y[a:b])
        s.add({c: idx[a:b] for c, idx in columns.items()}, {"y": y[a:b] - centre})
    return s, m


def test_moments_of_two_chunks_by_hand():
    # mean 0.045, sample sd sqrt(47.5e-4 / 5) = 0.0308221
    _, m = _sums({"a": BINS_A}, Y6, 0.0)
    assert m.n == 6 and m.mean == pytest.approx(0.045, rel=1e-12)
    assert m.std == pytest.approx(0.0308221, rel=1e-6)


@pytest.mark.parametrize("centre", [0.0, 0.045, 0.1])
def test_first_order_index_by_hand_one_way_anova(centre):
    # a one-bin column (all in bin 0) first: no between-bin variance, index 0, the next column still counted
    s, m = _sums({"flat": np.zeros(6, np.uint8), "a": BINS_A}, Y6, centre)
    idx, rest = s.indices("y", m)
    assert idx["flat"] == 0.0
    assert idx["a"] == pytest.approx(0.8596491, rel=1e-6)
    assert rest == pytest.approx(1 - 0.8596491, rel=1e-5)


def test_indices_summing_above_one_are_scaled_to_one():
    # column "b" bins [0, 0, 0, 1, 1, 1]: means 2 and 7 (x 0.01): SSB = 1e-4 * 6 * 2.5^2 = 37.5e-4,
    # MSW = 10e-4 / 4 = 2.5e-4, S_b = (37.5 - 2.5) / 47.5 = 0.7368421.  S_a + S_b = 1.5964912 > 1:
    # scaled to 0.5384615 and 0.4615385 (= 0.8596491 / 1.5964912, 0.7368421 / 1.5964912), remainder 0
    s, m = _sums({"a": BINS_A, "b": np.array([0, 0, 0, 1, 1, 1], np.uint8)}, Y6, 0.0)
    idx, rest = s.indices("y", m)
    assert idx["a"] == pytest.approx(0.5384615, rel=1e-6) and idx["b"] == pytest.approx(0.4615385, rel=1e-6)
    assert rest == 0.0


def test_every_sample_in_its_own_bin_gives_no_index():
    # n = 3 = b: no within-bin degrees of freedom, so no estimate (index 0, all in the remainder)
    y = np.array([1.0, 2.0, 4.0])
    out = first_order_indices({"x": np.array([0, 1, 2], np.uint8)}, y, nbins=4)
    assert out == ({"x": 0.0}, 1.0)


def test_percentiles_of_four_values_by_hand():
    # sorted 1, 2, 3, 4; h = 3 q / 100: 50 -> 1.5 -> 2.5; 90 -> 2.7 -> 3.7; 95 -> 2.85 -> 3.85;
    # 99 -> 2.97 -> 3.97; 99.73 -> 2.9919 -> 3.9919; max 4.  mean 2.5, sd sqrt(5/3) = 1.2909944
    d = describe(np.array([4.0, 1.0, 3.0, 2.0]))
    assert d["percentiles"] == pytest.approx({"50": 2.5, "90": 3.7, "95": 3.85, "99": 3.97, "99.73": 3.9919,
                                              "max": 4.0}, rel=1e-12)
    assert d["mean"] == 2.5 and d["std"] == pytest.approx(1.2909944, rel=1e-7)


def test_order_key_preserves_the_order_of_floats():
    v = np.array([-1e300, -2.0, -1.0, -0.5, 0.5, 1.0, 2.0, 1e300])
    from wormgear_cli.tolerance.statistics import _order_key

    k = _order_key(v)
    assert np.all(np.diff(k) > 0)  # each pair differs in sign or exponent, i.e. in the top 20 bits
    assert k.min() >= 0 and k.max() < 2**20


@pytest.mark.parametrize("loc", [-5.0, 0.0])
def test_second_pass_with_negative_values(monkeypatch, loc):
    from wormgear_cli.tolerance import statistics

    rng = np.random.default_rng(4)
    blocks = [rng.normal(loc, 2.0, 700) for _ in range(5)]
    held = statistics.OrderStatistics()
    for b in blocks:
        held.add(b)
    monkeypatch.setattr(statistics, "IN_MEMORY_SAMPLES", 1000)
    streamed = statistics.OrderStatistics()
    for b in blocks:
        streamed.add(b)
    streamed.start_second_pass()
    for b in blocks:
        streamed.collect(b)
    assert streamed.percentiles() == held.percentiles()
    ref = np.percentile(np.concatenate(blocks), [50, 90, 95, 99, 99.73])
    assert list(streamed.percentiles().values())[:-1] == pytest.approx(ref, rel=1e-14)


def test_verdict_boundaries():
    # pass: the whole interval at or above the target; fail: wholly below; touching the top: undecided
    y = Yield(990, 1000, 0.99, 0.98, 0.995)
    assert y.verdict(0.98) == "pass"
    assert y.verdict(0.995) == "undecided"
    assert y.verdict(0.9951) == "fail"


def test_yield_fields_and_level_by_hand():
    # k = n = 50 at 90 %: low = (0.05)^(1/50) = 0.9417 (Clopper-Pearson closed form), high 1
    y = binomial_yield(50, 50, 0.90)
    assert (y.k, y.n, y.value, y.high, y.level) == (50, 50, 1.0, 1.0, 0.90)
    assert y.low == pytest.approx(0.05 ** (1 / 50), rel=1e-9)
    z = binomial_yield(3, 4)
    assert (z.k, z.n, z.value, z.level) == (3, 4, 0.75, 0.95)


def test_bin_index_off_zero_and_a_degenerate_interval():
    # [1, 3] in 4 bins of 0.5: 0.5 (below) -> 0, 1.0 -> 0, 1.5 -> 1, 2.9 -> 3, 3.0 (top edge) -> 3, 3.5 -> 3
    idx = bin_index(np.array([0.5, 1.0, 1.5, 2.9, 3.0, 3.5]), 1.0, 3.0, 4)
    assert idx.tolist() == [0, 0, 1, 3, 3, 3] and idx.dtype == np.uint8
    flat = bin_index(np.array([0.5, 0.7]), 1.0, 1.0, 4)
    assert flat.tolist() == [0, 0] and flat.dtype == np.uint8
