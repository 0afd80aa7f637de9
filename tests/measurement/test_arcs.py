"""Arcs and turns (issue 22, items 7 and 8): a full turn of random angles, and a tilting axis
measured over 90 deg with repeated bidirectional ISO 230-2 runs.

The data are made here: the tilting axis' error is an output-gear runout e / r_b sin(theta + psi)
(e = 9 um on a base radius of 169.1 mm: 10.98 arcsec), a lost motion, white noise and a thermal
drift in time across the runs; the right values are those put in.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from wormgear_cli.cli import app
from wormgear_cli.measurement.coverage import coverage
from wormgear_cli.measurement.orders import OrdersOptions, analyse_orders

ARCSEC = math.pi / 180 / 3600
RUNOUT_ARCSEC = 0.009 / 169.1 / ARCSEC  # 9 um on a 169.1 mm base radius


def test_random_angles_over_a_turn_are_a_full_turn(runner, tmp_path):
    rng = np.random.default_rng(8)
    angles = rng.uniform(0.0, 360.0, 4000)
    err = 5.0 * np.sin(np.radians(angles) + 0.2) + 0.3 * rng.normal(size=4000)
    cov = coverage(np.radians(angles))
    assert cov.full_turn and math.degrees(cov.largest_gap) < 2.0
    path = tmp_path / "random.csv"
    path.write_text("angle_deg,error_arcsec\n" + "".join(f"{a:.5f},{e:.4f}\n" for a, e in zip(angles, err)))
    doc = json.loads(runner.invoke(app, ["measure", str(path), "--orders", "1", "-f", "json"]).stdout)
    item = doc["orders"]["items"][0]
    assert item["status"] == "fitted" and item["common"]["amplitude"] == pytest.approx(5.0, abs=0.03)
    assert doc["coverage"]["full_turn"] and "full turn" in doc["verdict"]
    assert not any("not a full turn" in n for n in doc["notes"])


def test_a_real_gap_still_makes_a_partial_arc():
    # a third of the turn missing is an arc, whatever the spacing of the rest
    rng = np.random.default_rng(1)
    cov = coverage(np.radians(rng.uniform(0.0, 240.0, 4000)))
    assert not cov.full_turn and math.degrees(cov.span) == pytest.approx(240.0, abs=0.5)
    # judged against the period of the slowest order asked for (order 1 unless a slower one is asked): a 30 deg
    # hole is under a tenth of order 1's period, a 40 deg hole is not, but is under a tenth of order 0.5's
    assert coverage(np.radians(np.linspace(0.0, 330.0, 3000))).full_turn
    th = np.radians(np.linspace(0.0, 320.0, 3000))
    assert not coverage(th).full_turn and coverage(th, orders=[0.5, 3.0]).full_turn


def tilting_axis(seed, drift_arcsec=6.0, runs=5):
    """An ISO 230-2 cycle over 0..90 deg: 19 jittered targets, runs of forward then reverse passes."""
    rng = np.random.default_rng(seed)
    targets = np.clip(np.linspace(0.0, 90.0, 19) + rng.uniform(-1.0, 1.0, 19), 0.0, 90.0)
    targets[0], targets[-1] = 0.0, 90.0
    psi = rng.uniform(0.0, 2 * math.pi)
    rows = []
    t = 0.0
    for run in range(1, runs + 1):
        for d, seq in ((1, targets), (-1, targets[::-1])):
            for a in seq:
                rows.append((a, d, run, t))
                t += 10.0
    a, d, run, t = (np.array(c) for c in zip(*rows))
    total = t.max()
    err = (RUNOUT_ARCSEC * np.sin(np.radians(a) + psi) - 4.0 * d
           + drift_arcsec * (t / total) ** 2 + 0.3 * rng.normal(size=a.size))
    return a, err, d, run, t


@pytest.mark.parametrize("seed", range(4))
def test_a_tilting_axis_gets_its_runout_from_repeated_passes(seed):
    a, err, d, run, t = tilting_axis(seed)
    res = analyse_orders(np.radians(a), err, d, [1, 4, 5], OrdersOptions(passes=run, time=t))
    items = {it.order: it for it in res.items}
    assert res.slow.kind == "time" and res.slow.traversals == 10
    one = items[1.0]
    assert one.status in ("fitted", "ambiguous") and one.fitted  # never "beyond span" or absorbed
    amp, se, _ = one.common
    assert abs(amp - RUNOUT_ARCSEC) < 4 * se + 0.3
    # the drift in time is fitted apart, with its size (6 arcsec over the test)
    assert res.slow.size == pytest.approx(6.0, abs=1.0)


def test_one_pass_over_the_arc_keeps_the_trend_over_the_arc():
    a, err, d, run, t = tilting_axis(0, runs=1)
    sel = d > 0
    res = analyse_orders(np.radians(a[sel]), err[sel], d[sel], [1], OrdersOptions(passes=run[sel], time=t[sel]))
    assert res.slow.kind == "angle" and res.items[0].status == "beyond span"


def test_measure_says_what_stands_for_the_slow_part(runner, tmp_path):
    a, err, d, run, t = tilting_axis(2)
    path = tmp_path / "tilt.csv"
    path.write_text("angle_deg,error_arcsec,direction,run,time_s\n" + "".join(
        f"{x:.4f},{e:.4f},{int(dd)},{int(r)},{tt:g}\n" for x, e, dd, r, tt in zip(a, err, d, run, t)))
    doc = json.loads(runner.invoke(app, ["measure", str(path), "--orders", "1", "-f", "json"]).stdout)
    note = next(n for n in doc["notes"] if n.startswith("the data cover 90 deg"))
    assert "the arc is traversed 10 times, so the slow part is a drift in time (a cubic in time_s" in note
    assert doc["orders"]["slow_part"]["kind"] == "time"
    assert doc["orders"]["items"][0]["common"]["amplitude"] == pytest.approx(RUNOUT_ARCSEC, abs=1.0)
