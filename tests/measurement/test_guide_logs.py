"""Two real PHD2 guide logs (tests/data/telescope/, from ../shared/cases/telescope: OpenPHDGuiding's
performance datasets 05 and 07): the strongest period and the orders a short arc cannot separate.

The mount's RA error is rebuilt here from the log's columns, independently of the project's readers:
RARawDistance plus every RA correction already sent (duration x xRate, signed by direction) plus the
RA lock shifts of dithers, in pixels, times the pixel scale over cos(Dec); the signs are those that give
the smoother series.  The RA axis turns once per sidereal day (86 164.09 s), so the order of a period P
is 86 164.09 / P.  Right values (the cases' README): CGE Pro, worm 180 teeth (478.7 s), order 180 about
8.3 arcsec, 180 and 181 not separable on its 8.3 deg arc; Losmandy G11, 360 teeth (239.3 s), order 360
about 4.1 arcsec, 720 about 1.6.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from tests.support.paths import ROOT
from wormgear_cli.measurement.dominant import dominant_orders
from wormgear_cli.measurement.orders import OrdersOptions, analyse_orders

LOGS = ROOT / "tests" / "data" / "telescope"
SIDEREAL_S = 86164.09


def ra_error(path):
    """(time [s], RA-axis angle [rad], mount RA error [arcsec]) of the first guiding section."""
    head, rows, dithers = {}, [], []
    for line in path.read_text(errors="replace").splitlines():
        if line.startswith("Guiding Ends"):
            break
        for key, pattern in (("scale", r"Pixel scale = ([0-9.]+)"), ("xrate", r"xRate = ([0-9.]+)"),
                             ("dec", r"^Dec = ([-0-9.]+) deg")):
            m = re.search(pattern, line)
            if m:
                head[key] = float(m.group(1))
        m = re.match(r"INFO: DITHER by ([-0-9.]+), ", line)
        if m:
            dithers.append((len(rows), float(m.group(1))))
        cells = line.split(",")
        if line[:1].isdigit() and len(cells) > 10 and cells[2] == '"Mount"':
            sign = {"E": 1.0, "W": -1.0}.get(cells[10], 0.0)
            rows.append((float(cells[1]), float(cells[5]), sign * float(cells[9] or 0.0)))
    t, raw, pulse = (np.array(c) for c in zip(*rows))
    shift = np.zeros(t.size)
    for i, amount in dithers:
        shift[i:] += amount
    sent = np.concatenate([[0.0], np.cumsum(pulse / 1000.0 * head["xrate"])[:-1]])
    best = min((raw + a * sent + b * shift for a in (1, -1) for b in (1, -1)), key=lambda e: np.sum(np.diff(e) ** 2))
    return t, 2.0 * math.pi * t / SIDEREAL_S, best * head["scale"] / math.cos(math.radians(head["dec"]))


def test_cge_pro_strongest_period_is_the_worm_and_180_181_are_one_group():
    t, theta, err = ra_error(LOGS / "cge-pro-180.guidelog.txt")
    dom = dominant_orders(theta, err, time=t)
    top = dom.strongest
    lo, hi = top.group
    assert top.significant and lo <= 180.0 <= hi and lo <= 181.0 <= hi
    assert top.period_s == pytest.approx(478.7, rel=0.02)
    assert dom.resolution == pytest.approx(360.0 / 8.3, rel=0.02)  # an 8.3 deg arc
    res = analyse_orders(theta, err, np.ones_like(theta), [180, 181], OrdersOptions(time=t))
    assert [it.status for it in res.items] == ["ambiguous", "ambiguous"]
    (carrier,) = [it for it in res.items if it.fitted]
    amp, se, _ = carrier.common
    assert abs(amp - 8.28) < 2.0 * se  # the README's 8.28 from another reconstruction of the same log
    assert "8.268 deg arc" in res.items[0].reason and "a full turn would separate them" in res.items[0].reason
    assert not res.serial.independent  # guide-log rows are serially correlated


def test_losmandy_strongest_period_and_its_harmonic():
    t, theta, err = ra_error(LOGS / "losmandy-g11-360.guidelog.txt")
    dom = dominant_orders(theta, err, time=t)
    assert dom.strongest.period_s == pytest.approx(239.3, rel=0.02)
    near = {round(p.order / 360.0) for p in dom.significant if abs(p.order / 360.0 - round(p.order / 360.0)) < 0.05}
    assert {1, 2} <= near  # 360 and its 2nd harmonic 720
    res = analyse_orders(theta, err, np.ones_like(theta), [360, 720], OrdersOptions(time=t))
    by = {it.order: it for it in res.items}
    assert abs(by[360.0].common[0] - 4.07) < 3.0 * by[360.0].common[1]
    assert abs(by[720.0].common[0] - 1.63) < 3.0 * by[720.0].common[1]
