"""``wormgear compensate`` on a PHD2 guide log as it comes, to an EQMOD PEC file (issue 20 with issue 21).

The log goes through the reader registry as it does for ``measure``; the worm period is the drive's
(``--drive``) or, without one, the strongest period ``measure`` finds (one definition for both
commands).  Right answers: the peak to peak of a least-squares fit written here on an independent
reconstruction of the log (tests/measurement/test_guidelog.py), and the EQMOD file read back the way
EQASCOM reads it (tests/support/controllers.py).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.measurement.test_guidelog import independent
from tests.support import compensation_data as data
from tests.support.controllers import eqascom_read
from tests.support.paths import CONFIGS, DATA
from wormgear_cli import api
from wormgear_cli.cli import app

LOGS = DATA / "telescope"
CGE = LOGS / "cge-pro-180.guidelog.txt"
G11 = LOGS / "losmandy-g11-360.guidelog.txt"
EQ6 = LOGS / "eq6-ppec-19-sessions.guidelog.txt"
SIDEREAL = 86164.0905


def run(runner, *args):
    return runner.invoke(app, ["compensate", *map(str, args)])


def fitted_pp(path, worm: float, harmonics: int = 3, session: int = 1) -> float:
    """Peak to peak over one worm period of the worm harmonics of a least-squares fit (cubic in time +
    sinusoids at worm x 1..harmonics) on the log's independent reconstruction."""
    t, u, scale, dec = independent(path, session)
    y = -u * scale / math.cos(math.radians(dec))
    x = 2.0 * (t - t.min()) / np.ptp(t) - 1.0
    theta = 2.0 * math.pi * t / SIDEREAL
    cols = [np.ones_like(t), x, x * x, x ** 3] + [f(h * worm * theta) for h in range(1, harmonics + 1)
                                                  for f in (np.cos, np.sin)]
    coef = np.linalg.lstsq(np.column_stack(cols), y, rcond=None)[0]
    phi = np.linspace(0.0, 2.0 * math.pi, 20001)
    curve = sum(coef[2 + 2 * h] * np.cos(h * phi) + coef[3 + 2 * h] * np.sin(h * phi)
                for h in range(1, harmonics + 1))
    return float(np.ptp(curve))


def test_a_raw_log_to_an_eqmod_file_with_the_mount_spec(runner, tmp_path):
    out, rep = tmp_path / "cge.pec", tmp_path / "cge.json"
    r = run(runner, CGE, "--drive", CONFIGS / "cge-pro-ra.toml", "--steps-per-worm", "50133", "-o", out,
            "--report", rep)
    assert r.exit_code == 0, r.stderr
    assert "worm order 180: period 478.689 s, 479 rows" in r.stderr
    lines = out.read_text().splitlines()
    assert lines[1:3] == ["!WormPeriod=479", "!StepsPerWorm=50133"]
    read = eqascom_read(out.read_text())
    want = fitted_pp(CGE, 180.0)
    assert np.ptp(read["curve"]) == pytest.approx(want, rel=0.02)
    doc = json.loads(rep.read_text())
    assert doc["pec"]["peak_to_peak_before"] == pytest.approx(want, rel=0.02)
    assert doc["pec"]["worm_order"] == 180.0


@pytest.mark.parametrize("path, worm, session", [(CGE, 180.0, None), (G11, 360.0, None), (EQ6, 180.0, "3")])
def test_without_a_drive_the_worm_is_measures_strongest_period(runner, tmp_path, path, worm, session):
    out = tmp_path / "m.pec"
    extra = ["--session", session] if session else []
    r = run(runner, path, "-o", out, *extra)
    assert r.exit_code == 0, r.stderr
    assert "(the strongest period found in the record)" in r.stderr
    doc = api.measure(path, sessions=None if session is None else int(session))
    top = doc.dominant[0].order
    assert abs(top - worm) <= 1.0  # README: the worm's order +- 1
    period = SIDEREAL / top
    assert f"period {period:.6g} s, {round(period)} rows" in r.stderr
    assert out.read_text().splitlines()[1] == f"!WormPeriod={round(period)}"


def test_the_api_takes_a_log_and_its_session(tmp_path):
    c = api.compensate(EQ6, "eqmod", drive=CONFIGS / "eq6-belt-worm.toml", sessions=[3], steps_per_worm=50133,
                       output=tmp_path / "eq6.pec")
    assert c.format == "eqmod" and c.orders[0] == 180.0
    assert (tmp_path / "eq6.pec").read_text() == c.text
    assert c.measured["PE_pp"].arcsec == pytest.approx(fitted_pp(EQ6, 180.0, session=3), rel=0.05)
    assert c.predicted["PE_pp"].arcsec < c.measured["PE_pp"].arcsec / 2


def test_guide_log_options_reach_the_reader(runner, tmp_path):
    path = LOGS / "constructed" / "unspecified-pixel-scale.guidelog.txt"
    r = run(runner, path, "-o", tmp_path / "x.pec")
    assert r.exit_code == 2 and "--pixel-scale ARCSEC_PER_PX" in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "x.pec").exists()
    r = run(runner, EQ6, "--session", "20", "-o", tmp_path / "x.pec")
    assert r.exit_code == 2 and r.stderr.startswith("error: --session 20: the log has 19 sessions")


@pytest.mark.parametrize("seed", range(3))
def test_a_tracking_table_without_a_drive_finds_the_worm(runner, tmp_path, seed):
    """The same strongest-period scan on a tracking table (not a guide log)."""
    rec = tmp_path / "track.csv"
    rec.write_text(data.tracking_csv(*data.tracking_rows(seed)))
    r = run(runner, rec, "-f", "eqmod")
    assert r.exit_code == 0, r.stderr
    period = float(r.stderr.split(": period ")[1].split(" s")[0])
    assert period == pytest.approx(478.69, abs=1.5)


def test_a_record_too_short_for_any_period_names_the_options(runner, tmp_path):
    rec = tmp_path / "short.csv"
    rec.write_text(data.tracking_csv(*data.tracking_rows(seed=1, duration_s=80.0)))
    r = run(runner, rec, "-f", "eqmod")
    assert r.exit_code == 2 and "Traceback" not in r.stderr
    assert r.stderr.endswith("give --worm-period or --drive\n")
