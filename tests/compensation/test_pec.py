"""A mount's PEC curve from a tracking record: drift per session, worm harmonics, cross-validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support import compensation_data as data
from wormgear_cli.compensation import pec
from wormgear_cli.units import ARCSEC


def _record(seed=0, **kw):
    a, e, t, r = data.tracking_rows(seed, **kw)
    return np.radians(a), e * ARCSEC, r


def test_the_curve_carries_the_worm_harmonics_drift_removed():
    theta, y, run = _record(sessions=3, duration_s=1300.0)
    curve = pec.pec_curve(theta, y, run, 180.0, [180.0, 360.0, 540.0, 705.0])
    assert curve.harmonics == (180.0, 360.0, 540.0) and curve.extra == (705.0,)
    assert curve.rows == 479 and curve.period_s == pytest.approx(478.69, abs=0.01)
    amp = np.hypot(curve.fit.cos, curve.fit.sin)[:3] / ARCSEC
    assert amp == pytest.approx([h[1] for h in data.PE], abs=0.1)
    assert abs(curve.pe.mean()) < 1e-15
    assert curve.cycles == pytest.approx(3 * 1298.0 / 478.69, rel=1e-3)


def test_worm_phase_zero_is_next_to_the_record():
    theta, y, run = _record()
    curve = pec.pec_curve(theta, y, run, 180.0, [180.0])
    first = pec.continuous(theta, run)[0]
    assert first <= curve.reference < first + 2 * math.pi / 180.0
    assert (curve.reference * 180.0 / (2 * math.pi)) == pytest.approx(round(curve.reference * 180.0 / (2 * math.pi)))


@pytest.mark.parametrize("seed", range(4))
def test_the_strongest_period_is_the_worm(seed):
    theta, y, run = _record(seed)
    assert pec.period_of(pec.strongest_worm_order(theta, y, run)) == pytest.approx(478.69, abs=1.5)


def test_too_short_a_record_has_no_period():
    theta, y, run = _record(duration_s=80.0)  # 1.5 cycles of the shortest period searched (60 s) need 90 s
    assert pec.strongest_worm_order(theta, y, run) is None


def test_cycles_are_left_out_one_at_a_time():
    theta, y, run = _record(duration_s=2400.0)
    th = pec.continuous(theta, run)
    folds = pec.cycle_folds(th, run, 180.0)
    assert np.unique(folds).size == 5  # 2398 s = 5.01 cycles: the last hundredth joins the fifth
    curve = pec.pec_curve(theta, y, run, 180.0, [180.0, 360.0, 540.0])
    p = pec.predict_pec(theta, y, run, curve)
    assert p.method == "cross-validated" and p.folds == 5
    assert p.before / ARCSEC == pytest.approx(15.8, abs=0.3)  # the true PE's peak-to-peak
    assert p.after / ARCSEC < 0.3  # seeing noise 0.4 arcsec over 1200 frames


def test_an_order_left_out_of_the_curve_is_what_remains():
    theta, y, run = _record(duration_s=2400.0)
    curve = pec.pec_curve(theta, y, run, 180.0, [180.0, 360.0])  # the third harmonic (1.2 arcsec) not carried
    p = pec.predict_pec(theta, y, run, curve)
    assert p.residual_orders[0][0] == 540.0
    assert p.residual_orders[0][1] / ARCSEC == pytest.approx(1.2, rel=0.15)
