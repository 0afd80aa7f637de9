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
    from tests.conftest import MCH50
    from wormgear_cli.spec import load_spec
    from wormgear_cli.tolerance import engine, statistics

    s = engine.setup(load_spec(MCH50), engine.Options(samples=3000, seed=9, metrics="all"))
    held = engine.run(s)
    monkeypatch.setattr(statistics, "IN_MEMORY_SAMPLES", 1000)
    streamed = engine.run(s)
    assert streamed.described == held.described
