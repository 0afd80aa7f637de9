"""The writer registry and the three formats: what each program's reader requires of the file."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from tests.support.controllers import LinuxCncJoint, eqascom_read
from wormgear_cli.compensation.pec import HarmonicFit, PecCurve
from wormgear_cli.compensation.table import CorrectionTable, TableGrid
from wormgear_cli.errors import UsageError
from wormgear_cli.output import writers
from wormgear_cli.output.writers import WriteOptions

ARCSEC = math.pi / 648000.0


def _table(points=256, scale=20.0):
    a = TableGrid(points).angles_deg()
    th = np.radians(a)
    return CorrectionTable(a, -scale * ARCSEC * np.sin(th), scale * ARCSEC * (0.5 - np.cos(2 * th)))


def _curve(rows=479):
    t = np.arange(rows)
    pe = 8.0 * ARCSEC * np.sin(2 * math.pi * t / rows + 0.4)
    fit = HarmonicFit(np.array([180.0]), np.zeros(1), np.zeros(1), np.zeros(0))
    return PecCurve(180.0, 478.69, rows, (180.0,), (), 0.0, pe, fit, 5.0)


def test_registry_names_formats_and_their_file_endings():
    assert writers.names() == ("linuxcnc", "eqmod", "csv")
    assert writers.names(writers.PEC_CURVE) == ("eqmod",)
    assert writers.for_path("out/Table.COMP").name == "linuxcnc"
    assert writers.for_path("x.tbl").name == "linuxcnc"
    assert writers.for_path("pec.pec").name == "eqmod"
    assert writers.for_path("t.csv", writers.CORRECTION_TABLE).name == "csv"
    assert writers.for_path("t.txt") is None and writers.for_path(None) is None
    assert writers.extensions() == {".comp": "linuxcnc", ".tbl": "linuxcnc", ".pec": "eqmod", ".csv": "csv"}
    with pytest.raises(UsageError, match=r"unknown format 'linuxcn' \(did you mean linuxcnc\?\)"):
        writers.get("linuxcn")


@pytest.mark.parametrize("name", list(writers.WRITERS))
def test_every_writer_module_writes_what_it_accepts(name):
    w = writers.get(name)
    text = w.write(_curve() if w.accepts == writers.PEC_CURVE else _table())
    assert text.endswith("\n") and "\r" not in text and "nan" not in text.lower()


def test_linuxcnc_type_1_is_three_numbers_per_line_and_nothing_else():
    text = writers.get("linuxcnc").write(_table(), WriteOptions(file_type=1))
    lines = text.splitlines()
    assert len(lines) == 256
    assert all(re.fullmatch(r"-?\d+\.\d{6} -?\d+\.\d{9} -?\d+\.\d{9}", line) for line in lines)
    nominal = [float(line.split()[0]) for line in lines]
    assert nominal[0] == 0.0 and nominal[-1] == 360.0 and all(np.diff(nominal) > 0)
    joint = LinuxCncJoint(text, 1)
    assert joint.entries == 256 and not joint.errors  # every line read: no header to stop at
    assert float(lines[0].split()[2]) == pytest.approx(20.0 * (0.5 - 1.0) / 3600.0, abs=1e-9)
    assert "-0.000000000" not in text


def test_linuxcnc_type_0_holds_the_positions_reached():
    t = _table()
    one = [list(map(float, line.split())) for line in writers.get("linuxcnc").write(t, WriteOptions()).splitlines()]
    zero = [list(map(float, line.split())) for line in
            writers.get("linuxcnc").write(t, WriteOptions(file_type=0)).splitlines()]
    for (n1, f1, r1), (n0, f0, r0) in zip(one, zero):
        assert n0 == n1 and f0 == pytest.approx(n1 - f1, abs=2e-9) and r0 == pytest.approx(n1 - r1, abs=2e-9)


def test_linuxcnc_refuses_more_than_256_lines():
    with pytest.raises(ValueError, match="at most 256 lines"):
        writers.get("linuxcnc").write(_table(257))


def test_linuxcnc_instructions_are_the_ini_lines():
    lines = writers.get("linuxcnc").instructions(WriteOptions(file_type=0, path="a.comp"))
    assert lines[1:] == ["COMP_FILE = a.comp", "COMP_FILE_TYPE = 0"] and lines[0].startswith("[JOINT_n]")


def test_eqmod_file_as_eqascom_reads_it():
    text = writers.get("eqmod").write(_curve(), WriteOptions(steps_per_worm=50133, caption="my mount"))
    lines = text.splitlines()
    assert lines[0] == "# my mount"
    assert lines[1:3] == ["!WormPeriod=479", "!StepsPerWorm=50133"]
    data = [line for line in lines[3:] if not line.startswith("#")]
    assert len(data) == 479
    assert all(re.fullmatch(r"\d+ \d+ -?\d+\.\d{4}", line) for line in data)  # single spaces
    read = eqascom_read(text)
    assert read["period"] == 479 and read["steps"] == 50133
    assert read["positions"][-1] == 478 * 50133 // 479
    assert np.max(np.abs(read["curve"] - _curve().pe / ARCSEC)) < 0.11  # one second's change, and 4 decimals


def test_eqmod_without_steps_has_no_steps_line():
    text = writers.get("eqmod").write(_curve(), WriteOptions())
    assert "!StepsPerWorm" not in text and text.splitlines()[1] == "!WormPeriod=479"
    assert [line.split()[1] for line in text.splitlines()[3:6]] == ["0", "1", "2"]


@pytest.mark.parametrize("unit, factor", [("arcsec", 1.0), ("urad", ARCSEC * 1e6), ("deg", 1 / 3600.0)])
def test_csv_header_and_values_in_the_unit(unit, factor):
    text = writers.get("csv").write(_table(5), WriteOptions(unit=unit))
    lines = text.splitlines()
    assert lines[0] == f"angle_deg,correction_forward_{unit},correction_reverse_{unit}"
    rows = [list(map(float, line.split(","))) for line in lines[1:]]
    assert [r[0] for r in rows] == [0.0, 90.0, 180.0, 270.0, 360.0]
    assert rows[1][1] == pytest.approx(-20.0 * factor, rel=1e-11)


def test_no_negative_zero_and_the_values_exact():
    a = np.array([0.0, 180.0, 360.0])
    tiny = np.array([-1e-14, -1e-14, 0.0])
    t = CorrectionTable(a, np.array([-1e-14, 2e-5, -0.0]), np.array([0.0, -3e-5, 1e-4]))
    lines = writers.get("linuxcnc").write(t, WriteOptions()).splitlines()
    assert lines[0] == "0.000000 0.000000000 0.000000000"
    assert lines[1] == f"180.000000 {2e-5 * 180 / math.pi:.9f} {-3e-5 * 180 / math.pi:.9f}"
    csv_lines = writers.get("csv").write(CorrectionTable(a, -0.0 * tiny, tiny * 0.0), WriteOptions()).splitlines()
    assert csv_lines[1:] == ["0,0,0", "180,0,0", "360,0,0"]
    curve = _curve(4)
    curve = PecCurve(180.0, 4.0, 4, (180.0,), (), 2 * math.pi + 0.5, np.array([-1e-12, 1e-5, -2e-5, 0.0]),
                     curve.fit, 1.0)
    text = writers.get("eqmod").write(curve, WriteOptions())
    assert text.splitlines()[0] == "# PEC curve by wormgear compensate"
    assert f"RA axis at {math.degrees(0.5):.4f} deg in the record" in text
    assert text.splitlines()[3:] == ["0 0 0.0000", f"1 1 {1e-5 / ARCSEC:.4f}", f"2 2 {-2e-5 / ARCSEC:.4f}",
                                     "3 3 0.0000"]


def test_writers_without_instructions_have_none_and_messages_are_exact():
    assert writers.get("csv").instructions() == []
    assert writers.get("linuxcnc").instructions()[1] == "COMP_FILE = FILE"
    assert writers.get("eqmod").instructions()[0].startswith("EQASCOM: PEC > load FILE,")
    assert writers.get("eqmod").instructions(WriteOptions(path="p.pec")) == [
        "EQASCOM: PEC > load p.pec, then enable PEC (gain 1, phase 0 to begin with)"]
    with pytest.raises(UsageError) as e:
        writers.get("bogus")
    assert e.value.problems == ["--format: unknown format 'bogus'; expected one of linuxcnc, eqmod, csv"]
    with pytest.raises(ValueError, match="^COMP_FILE_TYPE is 0 or 1$"):
        writers.get("linuxcnc").write(_table(), WriteOptions(file_type=2))


def test_csv_reverse_column_is_the_reverse_correction():
    t = _table(5)
    rows = [list(map(float, line.split(","))) for line in
            writers.get("csv").write(t, WriteOptions()).splitlines()[1:]]
    assert [r[2] for r in rows] == pytest.approx(list(t.reverse / ARCSEC), rel=1e-11, abs=1e-9)
    assert [r[1] for r in rows] == pytest.approx(list(t.forward / ARCSEC), rel=1e-11, abs=1e-9)
