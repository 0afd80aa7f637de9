"""Issue 21's done-when: tables made from one measurement, loaded as the controller or the mount
loads them, judged on measurements they were not made from.

Data: :mod:`tests.support.compensation_data` (its own generator); the file is read back and
applied by :mod:`tests.support.controllers` (LinuxCNC's and EQASCOM's rules, not the writers'
code); figures from their definitions.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support import compensation_data as data
from tests.support.controllers import LinuxCncJoint, eqascom_read
from tests.support.paths import CONFIGS
from wormgear_cli.api import compensate

#: the mount: a 180-tooth RA wheel (worm period 478.7 s)
MOUNT = CONFIGS / "telescope-mount.toml"


@pytest.fixture(scope="module")
def linuxcnc_case(tmp_path_factory):
    """A table made from test 1 (seed 1): the file, the API result, and the joint that loaded it."""
    folder = tmp_path_factory.mktemp("linuxcnc")
    first = folder / "test1.csv"
    first.write_text(data.rows_csv(*data.iso_rows(seed=1)))
    result = compensate(first, "linuxcnc", orders=[1, 2, 9], output=folder / "table.comp")
    text = (folder / "table.comp").read_text()
    return result, text, LinuxCncJoint(text, file_type=1)


def _corrected(joint, angle, error, direction):
    """The error once the joint adds its correction: a correction c [deg] moves the table by c."""
    return error + joint.apply(angle, direction) * 3600.0


@pytest.mark.parametrize("rows", ["second test", "dense scan"])
def test_linuxcnc_table_shrinks_e_and_b_of_data_it_was_not_made_from(linuxcnc_case, rows):
    result, text, joint = linuxcnc_case
    assert joint.entries == 256 and not joint.errors
    angle, error, direction, _ = data.iso_rows(seed=2) if rows == "second test" else data.dense_rows(seed=3)
    e0, b0 = data.e_and_b(angle, error, direction)
    e1, b1 = data.e_and_b(angle, _corrected(joint, angle, error, direction), direction)
    assert e0 > 60.0 and b0 > 12.0  # the drive as built: orders 1, 2, 9 and lost motion
    assert e1 <= e0 / 10.0
    assert b1 <= b0 / 4.0


def test_predicted_figures_are_within_a_quarter_of_the_achieved(linuxcnc_case):
    result, text, joint = linuxcnc_case
    angle, error, direction, _ = data.iso_rows(seed=2)
    e1, b1 = data.e_and_b(angle, _corrected(joint, angle, error, direction), direction)
    assert result.method == "cross-validated"
    assert result.predicted["E"].arcsec == pytest.approx(e1, rel=0.25)
    assert result.predicted["B"].arcsec == pytest.approx(b1, rel=0.25)


def test_type_0_file_loads_to_the_same_corrections(tmp_path, linuxcnc_case):
    _, _, joint1 = linuxcnc_case
    path = tmp_path / "test1.csv"
    path.write_text(data.rows_csv(*data.iso_rows(seed=1)))
    joint0 = LinuxCncJoint(compensate(path, "linuxcnc", orders=[1, 2, 9], file_type=0).text, file_type=0)
    probe = np.linspace(-5.0, 365.0, 1001)
    for d in (1, -1):
        dirs = np.full(probe.size, d)
        assert np.allclose(joint0.apply(probe, dirs), joint1.apply(probe, dirs), atol=2e-9)


def test_table_covers_0_and_360_and_holds_beyond(linuxcnc_case):
    _, text, joint = linuxcnc_case
    nominal = [float(line.split()[0]) for line in text.splitlines()]
    assert nominal[0] == 0.0 and nominal[-1] == 360.0
    assert joint.correction(360.0, 1) == pytest.approx(joint.correction(0.0, 1), abs=1e-8)  # one turn, continuous
    assert joint.correction(400.0, 1) == joint.correction(360.0, 1)


@pytest.fixture(scope="module")
def eqmod_case(tmp_path_factory):
    folder = tmp_path_factory.mktemp("eqmod")
    path = folder / "tracking.csv"
    path.write_text(data.tracking_csv(*data.tracking_rows(seed=5)))
    result = compensate(path, "eqmod", drive=MOUNT, steps_per_worm=50133)
    return result, eqascom_read(result.text)


def test_eqmod_file_has_the_worm_period_and_the_fundamental(eqmod_case):
    result, read = eqmod_case
    assert read["period"] == round(data.SIDEREAL_DAY_S / 180.0)  # 479 s: the mount's 180-tooth worm
    assert read["steps"] == 50133
    # the fundamental of the curve EQASCOM holds, against the measured PE's (8 arcsec zero-to-peak)
    p = read["period"]
    t = np.arange(p)
    fundamental = 2.0 * abs(np.mean(read["curve"] * np.exp(-2j * math.pi * t / p)))
    assert fundamental == pytest.approx(8.0, rel=0.2)


def test_eqascom_reading_gives_back_the_curve_meant(eqmod_case):
    result, read = eqmod_case
    curve = result.core.details.curve
    meant = curve.pe * 648000.0 / math.pi
    step = abs(meant[-1] - meant[0])  # EQASCOM's drift step changes the curve by at most one second's change
    assert np.max(np.abs(read["curve"] - meant)) <= step + 1e-4
    # and the curve meant is the mount's PE (up to its mean) at the worm phase of each row
    phase = curve.reference + 2.0 * math.pi * np.arange(curve.rows) / curve.rows / curve.worm_order
    truth = data.mount_pe(phase, 180.0)
    assert np.max(np.abs(meant - (truth - truth.mean()))) < 0.6
    # motor positions run once round the worm
    assert read["positions"][0] == 0 and np.all(np.diff(read["positions"]) > 0) and read["positions"][-1] < 50133
