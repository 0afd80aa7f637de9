"""The strongest orders of the data (issue 22, items 5, 6 and 9): a scan up to the Nyquist limit.

Data are made here from the formulas (sinusoids at chosen orders, random-walk drift, white and
AR(1) noise); the right values are what was put in, and the resolution arithmetic of the
sampling (360 deg / span, pi / spacing).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.measurement.test_separation import SIDEREAL_S, ar1
from tests.support.examples import examples
from wormgear_cli.cli import app
from wormgear_cli.measurement.dominant import ScanOptions, _harmonic_columns, _Scan, cos_sin, dominant_orders


def test_a_dense_scan_finds_order_8_and_nothing_made_up():
    rng = np.random.default_rng(5)
    theta = np.radians(np.arange(3600) / 10.0)
    y = 10.0 * np.sin(8 * theta + 0.4) + 0.5 * rng.normal(size=theta.size)
    dom = dominant_orders(theta, y)
    assert dom.scanned == (1.0, 1800.0)  # Nyquist of a 0.1 deg spacing
    assert [p.order for p in dom.significant] == [8.0]
    top = dom.strongest
    assert top.amplitude == pytest.approx(10.0, abs=0.05) and top.group == (8.0, 8.0)
    assert top.amplitude_stderr < 0.05
    assert dom.residual_rms == pytest.approx(0.5, rel=0.1)


def test_order_705_beyond_30_and_beyond_the_drive_orders():
    # a mount's motor gear: 705 cycles per RA turn on a dense full-turn scan; 2 arcsec on 0.3 noise
    rng = np.random.default_rng(2)
    theta = np.radians(np.arange(20000) * 360.0 / 20000)
    y = 2.0 * np.sin(705 * theta) + 6.0 * np.sin(180 * theta + 1.0) + 0.3 * rng.normal(size=theta.size)
    dom = dominant_orders(theta, y, options=ScanOptions(labels=((180.0, "worm"), (705.0, "motor gear"))))
    got = {p.order: p for p in dom.significant}
    assert set(got) == {180.0, 705.0}
    assert got[705.0].amplitude == pytest.approx(2.0, abs=0.02) and got[705.0].label == "motor gear"
    assert dom.peaks[0].order == 180.0  # strongest first


@pytest.mark.parametrize("seed", range(4))
def test_a_guide_log_arc_reports_the_worm_period_with_its_group(seed):
    # 8.3 deg of RA (33 min at 2 s), 8 arcsec at order 180 (478.7 s), a random-walk drift and AR(1) seeing
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 1990.0, 2.0)
    theta = 0.3 + 2.0 * math.pi * t / SIDEREAL_S
    y = (8.0 * np.sin(180 * theta + rng.uniform(0, 6)) + np.cumsum(rng.normal(0, 0.3, t.size))
         + ar1(rng, t.size, 0.6, 0.5))
    dom = dominant_orders(theta, y, time=t)
    top = dom.strongest
    lo, hi = top.group
    assert top.significant and lo <= 180.0 <= hi
    assert dom.resolution == pytest.approx(360.0 / math.degrees(np.ptp(theta)), rel=1e-6)
    assert hi - lo < 1.2 * dom.resolution  # one resolution element wide: 180 and 181 are one group
    assert top.amplitude == pytest.approx(8.0, abs=5 * top.amplitude_stderr + 0.3)
    assert top.period_s == pytest.approx(SIDEREAL_S / top.order, rel=1e-6)
    assert SIDEREAL_S / hi <= 478.7 <= SIDEREAL_S / lo
    assert dom.seconds_per_turn == pytest.approx(SIDEREAL_S, rel=1e-6)
    assert dom.slow.kind == "angle" and dom.slow.degree == 3


def test_a_drift_is_a_trend_with_its_size_not_a_string_of_harmonics():
    # pure drift over 15 deg of arc: no significant order in 20 seeds but at most 2; the slow part has a size
    named = 0
    for seed in range(20):
        rng = np.random.default_rng(50 + seed)
        t = np.arange(0.0, 3600.0, 2.0)
        theta = 2.0 * math.pi * t / SIDEREAL_S
        y = np.cumsum(rng.normal(0, 0.5, t.size)) + 0.3 * rng.normal(size=t.size)
        dom = dominant_orders(theta, y, time=t)
        named += len(dom.significant)
        assert dom.slow.size > 1.0
    assert named <= 2


def test_the_scan_stops_at_the_nyquist_limit_of_the_targets():
    theta = np.radians(np.arange(24) * 15.0)
    dom = dominant_orders(np.tile(theta, 3), np.tile(np.sin(5 * theta), 3))
    assert dom.nyquist == pytest.approx(12.0) and dom.scanned == (1.0, 12.0)
    assert dom.strongest.order == 5.0 and dom.strongest.amplitude == pytest.approx(1.0, abs=1e-9)


def test_both_directions_scan_common_and_differential_together():
    rng = np.random.default_rng(4)
    theta = np.radians(np.tile(np.sort(rng.uniform(0, 360, 600)), 2))
    d = np.repeat([1.0, -1.0], 600)
    y = 3.0 * d * np.sin(8 * theta) + 1.0 * np.sin(3 * theta) - 20.0 * d + 0.1 * rng.normal(size=1200)
    dom = dominant_orders(theta, y, direction=d)
    top = dom.strongest
    assert top.order == 8.0 and top.differential == pytest.approx(3.0, abs=0.03) and top.amplitude < 0.05
    assert {p.order for p in dom.significant} == {3.0, 8.0}


def test_too_few_rows_say_so():
    dom = dominant_orders(np.radians([0.0, 10.0, 20.0]), [1.0, 2.0, 3.0])
    assert dom.peaks == () and "too few rows" in dom.note


def test_measure_reports_dominant_and_the_order_left_out(runner, tmp_path):
    rng = np.random.default_rng(5)
    angles = np.arange(3600) / 10.0
    err = 10.0 * np.sin(np.radians(8 * angles) + 0.4) + 0.5 * rng.normal(size=angles.size)
    path = tmp_path / "scan.csv"
    path.write_text("angle_deg,error_arcsec\n" + "".join(f"{a:.3f},{e:.4f}\n" for a, e in zip(angles, err)))
    res = runner.invoke(app, ["measure", str(path), "-f", "json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    peaks = doc["dominant"]["peaks"]
    assert peaks[0]["order"] == 8.0 and peaks[0]["amplitude"] == pytest.approx(10.0, abs=0.05)
    note = next(n for n in doc["notes"] if n.startswith("the residual of the fit"))
    assert "the strongest content of the data lies outside the orders fitted: order 8 (9.98 arcsec)" in note
    assert "--orders 1,2,3,4,8" in note
    # fitted at order 8, the residual is the noise and the note goes
    res = runner.invoke(app, ["measure", str(path), "-f", "json", "--orders", "1,2,3,4,8"])
    doc = json.loads(res.stdout)
    assert not any(n.startswith("the residual of the fit") for n in doc["notes"])
    assert doc["orders"]["residual_rms"] == pytest.approx(0.5, rel=0.1)


def test_repeated_targets_give_the_row_least_squares():
    # 40 targets x 30 runs x 2 directions: the scan reduces the rows to (angle, direction) units; the
    # amplitudes must be those of an ordinary least-squares fit on every row (numpy's lstsq, the oracle)
    rng = np.random.default_rng(12)
    targets = np.sort(rng.uniform(0, 2 * math.pi, 40))
    theta = np.tile(np.concatenate([targets, targets[::-1]]), 30)
    d = np.tile(np.repeat([1.0, -1.0], 40), 30)
    y = 4.0 * np.sin(3 * theta + 0.5) + 1.5 * d * np.cos(7 * theta) - 2.0 * d + 0.4 * rng.normal(size=theta.size)
    dom = dominant_orders(theta, y, direction=d)
    got = {p.order: p for p in dom.significant}
    assert set(got) == {3.0, 7.0}
    x = np.column_stack([np.ones_like(theta), d] + [f(k * theta) * m for k in (3.0, 7.0)
                                                    for m in (1.0, d) for f in (np.cos, np.sin)])
    coef = np.linalg.lstsq(x, y, rcond=None)[0]
    assert got[3.0].amplitude == pytest.approx(math.hypot(coef[2], coef[3]), rel=1e-9)
    assert got[7.0].differential == pytest.approx(math.hypot(coef[8], coef[9]), rel=1e-9)
    resid = y - x @ coef
    assert dom.residual_rms == pytest.approx(float(np.sqrt(np.mean(resid**2))), rel=1e-9)


# -- the scan's trigonometry: the fast forms against np.cos / np.sin taken directly ----------------------

@settings(max_examples=examples(40), deadline=None)
@given(lo=st.floats(0.01, 5000.0), step=st.floats(1e-3, 50.0), count=st.integers(64, 700),
       arc=st.floats(0.01, 6.3), rows=st.integers(3, 60))
def test_cos_sin_of_an_even_grid_is_the_direct_values(lo, step, count, arc, rows):
    # the scan's grid (lo + step * j) by the angle-addition formulas: within a few units in the last
    # place of the largest phase, as the direct form's own rounding of k * theta
    theta = np.linspace(0.0, arc, rows)
    orders = lo + step * np.arange(count)
    cos, sin = cos_sin(theta, orders)
    phase = np.multiply.outer(theta, orders)
    tol = 64 * np.finfo(float).eps * max(1.0, float(np.max(phase)))
    assert cos.shape == sin.shape == (rows, count)
    assert np.max(np.abs(cos - np.cos(phase))) <= tol and np.max(np.abs(sin - np.sin(phase))) <= tol


def test_cos_sin_of_uneven_or_few_orders_is_exactly_the_direct_form():
    theta = np.linspace(0.0, 2.0, 50)
    for orders in (np.arange(10.0), np.sort(np.random.default_rng(1).uniform(1.0, 90.0, 200))):
        cos, sin = cos_sin(theta, orders)
        assert np.array_equal(cos, np.cos(np.multiply.outer(theta, orders)))
        assert np.array_equal(sin, np.sin(np.multiply.outer(theta, orders)))


@pytest.mark.parametrize("both", [False, True])
@pytest.mark.parametrize("reduced", [False, True])
def test_harmonic_columns_are_the_scans_columns_at_each_harmonic(both, reduced):
    # the refinement's harmonics (h = 1, 2, 3 from one cos and sin) against the scan's own columns at h k
    rng = np.random.default_rng(3)
    n = 40
    theta = np.sort(rng.uniform(0.0, 0.7, n))
    d = np.where(rng.uniform(size=n) < 0.5, 1.0, -1.0) if both else None
    sw = np.sqrt(rng.integers(1, 5, n).astype(float)) if reduced else None
    scan = _Scan(theta, rng.normal(size=n), np.ones((n, 1)), np.arange(1.0, 5.0), 0.7, False, d, sw=sw)
    for series in ([1], [1, 2, 3], [1, 3], [2]):
        got = _harmonic_columns(scan, 213.7, series)
        want = np.hstack([scan.trig(h * 213.7) for h in series])
        assert got.shape == want.shape
        assert np.max(np.abs(got - want)) <= 1e-12
