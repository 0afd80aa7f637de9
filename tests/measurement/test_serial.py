"""Standard errors that hold for serially correlated rows (issue 22, item 1).

The block (batch-means) sandwich is checked against statsmodels' cluster covariance (the library
oracle), and its calibration on data made here: a slow sinusoid over a partial arc with AR(1) noise,
over seeds; the scatter of the estimates is the truth the reported standard errors must match.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.measurement.test_separation import ar1
from wormgear_cli.measurement.orders import OrdersOptions, analyse_orders
from wormgear_cli.measurement.serial import (
    andrews_block_length,
    block_covariance,
    lag1_autocorrelation,
    point_noise,
    serial_blocks,
)


def test_block_covariance_is_statsmodels_cluster_covariance():
    sm = pytest.importorskip("statsmodels.regression.linear_model")  # OLS (not all of statsmodels.api)
    rng = np.random.default_rng(7)
    n = 600
    theta = np.linspace(0.0, 1.2, n)
    x = np.column_stack([np.ones(n), np.cos(40 * theta), np.sin(40 * theta), theta])
    y = x @ [1.0, 0.5, -0.3, 2.0] + ar1(rng, n, 0.7, 1.0)
    passes = np.repeat([0, 1, 2], n // 3)
    coef = np.linalg.lstsq(x, y, rcond=None)[0]
    blocks = serial_blocks(y - x @ coef, passes)
    assert blocks.method == "blocks" and blocks.blocks >= 10
    scores = np.zeros((blocks.blocks, 4))
    np.add.at(scores, blocks.block_id, x * (y - x @ coef)[:, None])
    ours = block_covariance(np.linalg.inv(x.T @ x), scores, n)
    oracle = sm.OLS(y, x).fit(cov_type="cluster", cov_kwds={"groups": blocks.block_id}).cov_params()
    assert np.allclose(ours, oracle, rtol=1e-10, atol=0)


def test_blocks_never_span_two_passes_and_follow_time():
    rng = np.random.default_rng(1)
    resid = ar1(rng, 300, 0.9, 1.0)
    passes = np.repeat([5, 2, 9], 100)  # ids in any order: the passes as they appear
    b = serial_blocks(resid, passes, block_rows=30)
    for p in (5, 2, 9):
        inside = set(b.block_id[passes == p])
        assert not inside & set(b.block_id[passes != p])
    # rows written out of time order are put in time order before blocking
    t = rng.permutation(300).astype(float)
    b2 = serial_blocks(resid, None, t, block_rows=30)
    order = np.argsort(t)
    assert np.all(np.diff(b2.block_id[order]) >= 0)


def test_white_rows_keep_the_ordinary_errors():
    rng = np.random.default_rng(2)
    theta = np.radians(np.sort(rng.uniform(0, 360, 2000)))
    y = 3.0 * np.sin(5 * theta) + rng.normal(size=theta.size)
    res = analyse_orders(theta, y, np.ones_like(theta), [5])
    assert res.serial.independent
    plain = analyse_orders(theta, y, np.ones_like(theta), [5], OrdersOptions(serial=False))
    assert res.items[0].common == plain.items[0].common  # the same numbers, bit for bit
    rho, pairs = lag1_autocorrelation(rng.normal(size=5000))
    assert abs(rho) < 0.05 and pairs == 4999


def test_andrews_rule_and_point_noise():
    # the AR(1) plug-in bandwidth grows with rho and n^(1/3)
    assert andrews_block_length(0.0, 1000) == 1
    assert andrews_block_length(0.8, 1000) < andrews_block_length(0.9, 1000) < andrews_block_length(0.9, 8000)
    assert andrews_block_length(0.8, 1000) == math.ceil(1.1447 * (4 * 0.64 / (0.04 * 3.24) * 1000) ** (1 / 3))
    rng = np.random.default_rng(3)
    steps = np.repeat(rng.normal(0, 50, 10), 200)  # offsets per pass cancel
    assert point_noise(steps + rng.normal(0, 0.5, 2000), np.repeat(np.arange(10), 200)) == pytest.approx(0.5, rel=0.08)


def test_reported_errors_match_the_scatter_over_seeds_with_correlated_rows():
    # a 20 deg scan, order 60 at 2 arcsec, AR(1) noise rho 0.9: ordinary errors are about 4x too small
    amps, se_block, se_ols = [], [], []
    theta = np.radians(np.linspace(0.0, 20.0, 1500))
    for seed in range(60):
        rng = np.random.default_rng(100 + seed)
        y = 2.0 * np.sin(60 * theta + 0.4) + ar1(rng, theta.size, 0.9, 1.0)
        res = analyse_orders(theta, y, np.ones_like(theta), [60])
        ols = analyse_orders(theta, y, np.ones_like(theta), [60], OrdersOptions(serial=False))
        assert res.serial.method == "blocks"
        amps.append(res.items[0].common[0])
        se_block.append(res.items[0].common[1])
        se_ols.append(ols.items[0].common[1])
    scatter = float(np.std(amps, ddof=1))
    # 200 seeds gave 0.88 (95 % intervals covering 2.0 in 93 %); ordinary least squares 0.22 (37 %)
    assert 0.75 < float(np.mean(se_block)) / scatter < 1.3
    assert float(np.mean(se_ols)) / scatter < 0.4
    covered = np.abs(np.asarray(amps) - 2.0) < 1.96 * np.asarray(se_block)
    assert np.mean(covered) > 0.85
