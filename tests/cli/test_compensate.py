"""``wormgear compensate``: exit codes, where the file and the messages go, format inference, report."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from tests.support import compensation_data as data
from tests.support.paths import CONFIGS, MCH50
from wormgear_cli.cli import app

MOUNT = CONFIGS / "telescope-mount.toml"


@pytest.fixture(scope="module")
def test_csv(tmp_path_factory):
    path = tmp_path_factory.mktemp("comp") / "test.csv"
    path.write_text(data.rows_csv(*data.iso_rows(seed=1)))
    return path


def run(runner, *args):
    return runner.invoke(app, ["compensate", *map(str, args)])


def test_table_to_stdout_and_how_to_load_it_on_stderr(runner, test_csv):
    r = run(runner, test_csv, "--format", "linuxcnc", "--orders", "1,2,9")
    assert r.exit_code == 0, r.stderr
    assert len(r.stdout.splitlines()) == 256 and r.stdout.startswith("0.000000 ")
    assert "load: COMP_FILE = FILE" in r.stderr and "load: COMP_FILE_TYPE = 1" in r.stderr
    assert "predicted after correction (a repeat of this test, cross-validated over 5 runs; 5-95 %):" in r.stderr
    assert "wrote" not in r.stderr


def test_format_from_the_file_ending_and_report(runner, test_csv, tmp_path):
    out, rep = tmp_path / "a.tbl", tmp_path / "a.json"
    r = run(runner, test_csv, "-o", out, "--orders", "1,2,9", "--type", "0", "--report", rep, "--unit", "urad")
    assert r.exit_code == 0, r.stderr
    assert f"load: COMP_FILE = {out}" in r.stderr and "COMP_FILE_TYPE = 0" in r.stderr
    assert r.stderr.endswith(f"wrote {out}\nwrote {rep}\n")
    doc = json.loads(rep.read_text())
    assert doc["format"] == "linuxcnc" and doc["unit"] == "urad" and doc["kind"] == "correction table"
    assert doc["orders"] == {"source": "--orders", "requested": [1.0, 2.0, 9.0]}
    assert doc["prediction"]["method"] == "cross-validated" and doc["prediction"]["runs_left_out"] == 5
    after, before = doc["prediction"]["after"]["E"], doc["prediction"]["before"]["E"]
    assert after["low_5pct"] < after["median"] < after["high_95pct"] < before / 10
    assert doc["load"] == ["[JOINT_n]    (the rotary joint's section)", f"COMP_FILE = {out}", "COMP_FILE_TYPE = 0"]


def test_csv_in_the_unit_asked(runner, test_csv):
    r = run(runner, test_csv, "-f", "csv", "--orders", "1,2,9", "--points", "37", "-u", "arcmin")
    assert r.exit_code == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == "angle_deg,correction_forward_arcmin,correction_reverse_arcmin" and len(lines) == 38


def test_a_correction_beyond_the_limit_is_exit_1_with_the_file_written(runner, test_csv, tmp_path):
    out = tmp_path / "t.comp"
    r = run(runner, test_csv, "-o", out, "--orders", "1,2,9", "--max-correction", "20")
    assert r.exit_code == 1
    assert "warning: the largest correction, 37.7" in r.stderr and "exceeds --max-correction 20 arcsec" in r.stderr
    assert out.exists()


def test_eqmod_from_a_tracking_record(runner, tmp_path):
    rec = tmp_path / "track.csv"
    rec.write_text(data.tracking_csv(*data.tracking_rows(seed=5)))
    r = run(runner, rec, "-o", tmp_path / "mount.pec", "--drive", MOUNT, "--steps-per-worm", "50133")
    assert r.exit_code == 0, r.stderr
    assert "worm order 180: period 478.689 s, 479 rows" in r.stderr
    assert "PE peak-to-peak: 15.8 arcsec as measured" in r.stderr
    assert (tmp_path / "mount.pec").read_text().splitlines()[1:3] == ["!WormPeriod=479", "!StepsPerWorm=50133"]


def test_a_record_shorter_than_a_worm_period_is_refused(runner, tmp_path):
    rec = tmp_path / "short.csv"
    rec.write_text(data.tracking_csv(*data.tracking_rows(seed=5, duration_s=300.0)))
    r = run(runner, rec, "-f", "eqmod", "--drive", MOUNT)
    assert r.exit_code == 2
    assert r.stderr == (f"error: {rec}: the record covers 298 s of tracking, less than one worm period "
                        "(478.7 s, order 180): no PEC curve can be made from it\n")


@pytest.mark.parametrize("args, message", [
    (["--format", "bogus"], "error: Invalid value for '--format' / '-f': 'bogus' is not one of 'linuxcnc', 'eqmod', 'csv'; see 'wormgear compensate --help'\n"),
    (["-o", "x.txt"], "error: --format: give one of linuxcnc, eqmod, csv (or an -o file ending in .comp (linuxcnc), "
                      ".tbl (linuxcnc), .pec (eqmod), .csv (csv))\n"),
    (["-f", "linuxcnc", "--points", "300"], "error: --points: expected an integer in [2, 256], got 300\n"),
    (["-f", "csv", "--range", "0-360"], "error: --range: expected START:END in deg, e.g. 0:360, got '0-360'\n"),
    (["-f", "linuxcnc", "--type", "2"], "error: --type: expected 0 or 1 (LinuxCNC COMP_FILE_TYPE), got 2\n"),
    (["-f", "linuxcnc", "--max-correction", "-1"], "error: --max-correction: expected a positive number\n"),
])
def test_usage_mistakes_are_one_line_and_exit_2(runner, test_csv, tmp_path, args, message):
    r = runner.invoke(app, ["compensate", str(test_csv), *args], catch_exceptions=False)
    assert r.exit_code == 2
    assert r.stderr == message
    assert not (tmp_path / "x.txt").exists()


def test_never_overwrites_the_input(runner, test_csv):
    r = run(runner, test_csv, "-f", "csv", "-o", test_csv)
    assert r.exit_code == 2  # refused before any work: no summary lines first
    assert r.stderr == f"error: {test_csv}: refusing to overwrite the input file; choose another -o\n"


def test_help_has_an_example(runner):
    r = run(runner, "--help")
    assert r.exit_code == 0 and "Example: wormgear compensate test.csv --orders 1,2,9 -o table.comp" in r.stdout


FIELD = CONFIGS.parent / "tests" / "data" / "field"


def test_field_partial_span_finds_its_order_and_says_the_range(runner, tmp_path):
    """tests/data/field/partial-span-order144.csv: 11 deg of a scan with an order-144 error (its README)."""
    rep = tmp_path / "r.json"
    args = [FIELD / "partial-span-order144.csv", "-f", "csv", "--points", "1000", "--report", rep]
    r = run(runner, *args, "--range", "0:360")
    assert r.exit_code == 0, r.stderr
    assert "beyond the table's 0 to 360 deg (--range): the controller holds the end values there" in r.stderr
    r = run(runner, *args)  # by default the measured arc, rounded out to whole degrees: -11 to 1
    assert r.exit_code == 0, r.stderr
    assert "1000 points, -11 to 1 deg" in r.stderr and "less than the table's" not in r.stderr
    doc = json.loads(rep.read_text())
    assert doc["orders"]["requested"] == [144.0]
    assert "as measured:  E_forward 20" in r.stderr and "A_forward -" in r.stderr
    before, after = doc["prediction"]["before"]["E_forward"], doc["prediction"]["after"]["E_forward"]["median"]
    assert after < before / 100
    assert doc["prediction"]["method"] == "in-sample" and "in-sample, optimistic" in r.stderr


def test_field_directions_not_stated_are_warned_about(runner):
    r = run(runner, FIELD / "no-direction-column.csv", "-f", "csv")
    assert r.exit_code == 0, r.stderr
    assert "warning: no direction column: every row is taken as forward" in r.stderr
    assert "warning: forward and reverse visits cannot be told apart" in r.stderr
    # the figures of mixed directions are withheld, as measure withholds them (not E_forward of a mixture)
    assert "ISO 230-2 figures withheld, as measured and predicted" in r.stderr
    assert not [line for line in r.stderr.splitlines() if line.startswith(("as measured:", "predicted after"))]


def test_a_mount_record_under_two_worm_cycles_is_not_cross_validated(runner, tmp_path):
    data = tmp_path / "short.csv"
    data.write_text(_mount_rows(lambda t: t < 900))  # 1.5 worm cycles in one session
    r = run(runner, data, "-f", "eqmod", "--drive", FIELD / "telescope-mount.toml")
    assert r.exit_code == 0, r.stderr
    assert "1.5 worm cycles recorded" in r.stderr and "as measured, not predicted" in r.stderr
    assert "warning: the record holds 1.5 worm cycles: fewer than two" in r.stderr


def test_a_record_of_sessions_short_beside_the_worm_period_is_refused(runner):
    """The field case's two sessions of 5 minutes beside a 10-minute worm period: each session's cubic
    drift looks like a piece of the curve, whose standard error is 75 % of the curve itself (it came
    out at 200 arcsec peak to peak from a record whose order 144 measure finds small).  Refused, naming
    the sessions' length and the worm period (it had been written with a warning about cycles only)."""
    r = run(runner, FIELD / "time-restarts-no-run.csv", "-f", "eqmod", "--drive", FIELD / "telescope-mount.toml")
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr == (f"error: {FIELD / 'time-restarts-no-run.csv'}: the record does not determine a PEC curve: the "
                        "curve's standard error is 45 arcsec RMS over the worm cycle, 75% of the curve itself (59.7 "
                        "arcsec RMS); the sessions (the longest 325.3 s) are short beside the worm period (598.4 s), "
                        "so each session's drift looks like a piece of the curve; record sessions of at least a worm "
                        "period, or fit fewer harmonics (--harmonics)\n")


def test_a_record_too_sparse_for_its_pec_curve_is_refused(runner, tmp_path):
    """Six rows over a worm cycle cannot fix three harmonics and a cubic drift (10 terms): a
    least-squares curve through them is any curve at all (it came out at 1e15 arcsec)."""
    data = tmp_path / "few.csv"
    data.write_text("angle_deg,error_arcsec\n0,1\n0.5,2\n1,3\n1.5,1\n2,2\n2.5,3\n")
    out = tmp_path / "few.pec"
    r = run(runner, data, "--drive", FIELD / "telescope-mount.toml", "-f", "eqmod", "-o", out)
    assert r.exit_code == 2 and not out.exists()
    assert r.stderr == (f"error: {data}: 6 rows cannot give a PEC curve of 10 terms (orders 144, 288, 432 and a "
                        "drift per session; the rows tell 6 apart): at least 20 rows spread over the worm cycle "
                        "are needed; record longer or more often, or fit fewer orders (--harmonics, --orders)\n")


def test_a_file_name_of_another_format_names_the_endings_that_work(runner, test_csv, tmp_path):
    r = run(runner, test_csv, "-o", tmp_path / "x.json")
    assert r.exit_code == 2
    assert r.stderr.endswith("not json; name the file .comp (linuxcnc) or .pec (eqmod) or .csv (csv)\n")
    r = run(runner, test_csv, "-f", "linuxcnc", "-o", tmp_path / "x.pec")  # an EQMOD name for a LinuxCNC table
    assert r.exit_code == 2 and not (tmp_path / "x.pec").exists()
    assert r.stderr.endswith("the file name says eqmod, but --format linuxcnc was given; drop --format or name the "
                             "file .comp\n")


def test_a_record_with_fewer_than_two_rows_a_term_is_refused_even_when_it_has_full_rank(runner, tmp_path):
    """14 rows over 1.5 worm cycles tell the 10 terms apart (rank 10) but leave 4 degrees of freedom:
    the curve would pass near every reading, noise included.  Two rows a term at least."""
    data = tmp_path / "thin.csv"
    angles = np.linspace(0.0, 3.75, 14)
    data.write_text("angle_deg,error_arcsec\n" + "".join(f"{a:.4f},{3 * np.sin(np.radians(144 * a)):.4f}\n"
                                                        for a in angles))
    r = run(runner, data, "--drive", FIELD / "telescope-mount.toml", "-f", "eqmod", "-o", tmp_path / "thin.pec")
    assert r.exit_code == 2 and not (tmp_path / "thin.pec").exists()
    assert "14 rows cannot give a PEC curve of 10 terms" in r.stderr and "the rows tell 10 apart" in r.stderr


def _mount_rows(keep) -> str:
    """A tracking record of the field mount (worm order 144, 598.4 s): 5 arcsec at the worm and 1
    at twice it, a row every 2 s for 6000 s, the rows where ``keep(t)``."""
    t = np.arange(0.0, 6000.0, 2.0)
    t = t[keep(t)]
    angle = 360.0 * t / 86164.0905
    error = 5.0 * np.sin(np.radians(144 * angle)) + np.sin(np.radians(288 * angle) + 0.5)
    return "angle_deg,error_arcsec,time_s\n" + "".join(f"{a:.6f},{e:.4f},{s:g}\n" for a, e, s in zip(angle, error, t))


def test_a_record_of_pieces_at_one_worm_phase_is_refused(runner, tmp_path):
    """A minute of every ten (about one worm period) reaches a tenth of the worm cycle: the curve
    elsewhere is the fit's extrapolation (it came out at 1.4e4 arcsec peak to peak).  The whole
    record makes the curve (10.3 arcsec)."""
    data, whole = tmp_path / "pieces.csv", tmp_path / "whole.csv"
    data.write_text(_mount_rows(lambda t: t % 600 < 60))
    whole.write_text(_mount_rows(lambda t: t >= 0))
    r = run(runner, data, "--drive", FIELD / "telescope-mount.toml", "-o", tmp_path / "pieces.pec")
    assert r.exit_code == 2 and not (tmp_path / "pieces.pec").exists()
    assert "equal parts of the worm cycle (period 598.4 s) without a reading" in r.stderr
    r = run(runner, whole, "--drive", FIELD / "telescope-mount.toml", "-o", tmp_path / "whole.pec")
    assert r.exit_code == 0, r.stderr


def test_a_record_missing_a_quarter_of_every_worm_cycle_is_refused(runner, tmp_path):
    """Pieces of 450 s every 600 s leave the same 150 s (a quarter of the 598.4 s worm period, drifting
    only 16 s over the record) unread in every session: 2 of the 12 parts of the cycle have no row.
    A few empty parts refuse as surely as most of them."""
    data = tmp_path / "gaps.csv"
    data.write_text(_mount_rows(lambda t: t % 600 < 450))
    r = run(runner, data, "--drive", FIELD / "telescope-mount.toml", "-o", tmp_path / "gaps.pec")
    assert r.exit_code == 2 and not (tmp_path / "gaps.pec").exists()
    assert "the rows leave 2 of 12 equal parts of the worm cycle (period 598.4 s) without a reading" in r.stderr


def test_short_sessions_covering_every_worm_phase_give_no_pec_curve(runner, tmp_path):
    """Breaker trial: ten 100 s sessions of a 16 arcsec peak-to-peak worm error (period 478.7 s), their
    starts spread over the cycle so that every phase is read: the curve had come out at 99 arcsec
    peak to peak with '6.31 left' promised.  200 s sessions give one within 10 % here, with a warning
    (its standard error is 25 % of it); 500 s sessions (a worm period) one within 2 %, with none."""
    period = 86164.0905 / 180

    def record(duration):
        rng = np.random.default_rng(0)
        rows = []
        for r in range(10):
            t = r * 0.55 * period * duration / 100 + np.arange(0.0, duration, 2.0)
            e = 8.0 * np.sin(2 * np.pi * t / period + 0.3) + rng.normal(0.0, 0.3, t.size)
            rows += [f"{360 * s / 86164.0905:.7f},{x:.4f},{s:.1f},{r + 1}\n" for s, x in zip(t, e)]
        path = tmp_path / f"s{duration}.csv"
        path.write_text("angle_deg,error_arcsec,time_s,run\n" + "".join(rows))
        return path

    r = run(runner, record(100), "-f", "eqmod", "--worm-period", "478.689", "-o", tmp_path / "s100.pec")
    assert r.exit_code == 2 and not (tmp_path / "s100.pec").exists()
    assert "the record does not determine a PEC curve" in r.stderr and "the longest 98 s" in r.stderr
    r = run(runner, record(200), "-f", "eqmod", "--worm-period", "478.689", "-o", tmp_path / "s200.pec")
    assert r.exit_code == 0 and "warning: the PEC curve is uncertain: the curve's standard error is" in r.stderr
    assert "25% of the curve itself" in r.stderr
    pe = [float(line.split()[-1]) for line in (tmp_path / "s200.pec").read_text().splitlines() if line[:1].isdigit()]
    assert abs(max(pe) - min(pe) - 16.0) < 1.6
    out = tmp_path / "s500.pec"
    r = run(runner, record(500), "-f", "eqmod", "--worm-period", "478.689", "-o", out)
    assert r.exit_code == 0 and "the PEC curve is uncertain" not in r.stderr, r.stderr
    pe = [float(line.split()[-1]) for line in out.read_text().splitlines() if line and line[0].isdigit()]
    assert len(pe) == 479 and abs(max(pe) - min(pe) - 16.0) < 0.32


def test_a_worm_period_shorter_than_a_minute_is_not_taken_from_a_record(runner, tmp_path):
    """Nine minutes of the CGE log: its strongest period is 15 s (not a worm): refused, asking for
    --worm-period or --drive, instead of a 15 s PEC curve."""
    lines = (CONFIGS.parent / "tests" / "data" / "telescope" / "cge-pro-180.guidelog.txt").read_text().splitlines()
    log = tmp_path / "short.txt"
    log.write_text("\n".join(lines[:1000]) + "\n")
    r = run(runner, log, "-o", tmp_path / "short.pec")
    assert r.exit_code == 2 and "no period of 60 s or longer stands out" in r.stderr


def test_one_target_at_a_whole_degree_gets_a_table_a_degree_either_side(runner, tmp_path):
    r = run(runner, FIELD / "one-position-backlash.csv", "-f", "csv", "-o", tmp_path / "ob.csv")
    assert r.exit_code == 0, r.stderr
    assert "table: 361 points, -1 to 1 deg" in r.stderr


def test_the_pe_left_counts_the_worm_harmonics_the_curve_does_not_carry(runner, tmp_path):
    """The mount's PE has 1.0 and 1.2 arcsec at the worm's 2nd and 3rd harmonics (tests/support).
    A curve of the fundamental only leaves them on the sky: the PE left must be about the
    peak-to-peak of the two together (4.13 arcsec, computed in the test), not the fundamental's
    small remainder."""
    rec = tmp_path / "track.csv"
    rec.write_text(data.tracking_csv(*data.tracking_rows(seed=5)))
    r = run(runner, rec, "-o", tmp_path / "mount.pec", "--drive", MOUNT, "--harmonics", "1")
    assert r.exit_code == 0, r.stderr
    left = float(re.search(r"arcsec as measured, ([0-9.]+) arcsec left", r.stderr).group(1))
    u = np.linspace(0.0, 2.0 * np.pi, 100_001)
    harmonics = 1.0 * np.sin(2 * u + 1.0) + 1.2 * np.sin(3 * u + 2.0)  # data.PE's 2nd and 3rd
    assert left == pytest.approx(float(np.ptp(harmonics)), rel=0.15)
    r = run(runner, rec, "-o", tmp_path / "mount3.pec", "--drive", MOUNT)  # all three carried: little left
    assert float(re.search(r"arcsec as measured, ([0-9.]+) arcsec left", r.stderr).group(1)) < 1.0


def test_one_direction_gives_the_same_correction_in_both_columns(runner, tmp_path):
    """Forward runs only, with the per-target means added (orders 1 and 2 leave order 9 at the
    targets): the reverse column repeats the forward one, as the warning says (the means had gone
    into the forward column alone)."""
    a, e, d, r = data.iso_rows(3)
    fwd = d > 0
    rec = tmp_path / "fwd.csv"
    rec.write_text(data.rows_csv(a[fwd], e[fwd], d[fwd], r[fwd]))
    r = run(runner, rec, "--orders", "1,2", "-f", "csv", "-o", tmp_path / "t.csv")
    assert r.exit_code == 0, r.stderr
    assert "per-target means of the residual are added" in r.stderr
    rows = [line.split(",") for line in (tmp_path / "t.csv").read_text().splitlines()[1:]]
    assert [row[1] for row in rows] == [row[2] for row in rows]


def test_the_largest_orders_left_are_listed_largest_first(runner, test_csv, tmp_path):
    r = run(runner, test_csv, "--orders", "1,2", "-o", tmp_path / "t.comp")
    line = next(ln for ln in r.stderr.splitlines() if ln.startswith("largest orders left:"))
    amplitudes = [float(a) for a in re.findall(r"\(([-0-9.e+]+)\)", line)]
    assert len(amplitudes) >= 2 and amplitudes == sorted(amplitudes, reverse=True)


@pytest.mark.parametrize(("args", "message"), [
    (("-f", "csv", "--steps-per-worm", "100"), "--steps-per-worm is an option of a mount's PEC curve (--format "
                                               "eqmod), not of the csv file being written"),
    (("-f", "csv", "--type", "0"), "--type is an option of LinuxCNC's table (--format linuxcnc), not of the csv "
                                   "file being written"),
    (("-f", "linuxcnc", "--worm-period", "600"), "--worm-period is an option of a mount's PEC curve (--format "
                                                 "eqmod), not of the linuxcnc file being written"),
    (("-f", "eqmod", "--points", "100"), "--points is an option of a table (--format linuxcnc or csv), not of the "
                                         "eqmod file being written"),
    (("-f", "eqmod", "--range", "0:90"), "--range is an option of a table (--format linuxcnc or csv), not of the "
                                         "eqmod file being written"),
])
def test_an_option_the_file_has_no_use_for_is_refused_not_ignored(runner, tmp_path, args, message):
    """An option that would change nothing in the file written is refused before the data is read
    (the data here is not even a measurement)."""
    given = tmp_path / "not-read.csv"
    given.write_text("not,a,measurement\n")
    r = run(runner, given, *args, "-o", tmp_path / "out.x")
    assert r.exit_code == 2 and list(tmp_path.iterdir()) == [given]
    assert r.stderr == f"error: {message}; drop it or choose that format (--format, or the -o file's ending)\n"


@pytest.mark.parametrize("fmt", ["csv", "linuxcnc"])
def test_harmonics_with_a_table_and_no_drive_is_refused_not_ignored(runner, tmp_path, fmt):
    """--harmonics counts the harmonics of the drive's orders or of a PEC curve's worm order: a table
    without --drive had been written byte for byte as without it (even --harmonics 3, the default)."""
    given = tmp_path / "not-read.csv"
    given.write_text("not,a,measurement\n")
    for n in ("7", "3"):
        r = run(runner, given, "-f", fmt, "--harmonics", n, "-o", tmp_path / "out.x")
        assert r.exit_code == 2 and list(tmp_path.iterdir()) == [given]
        assert r.stderr == (f"error: --harmonics applies with --drive (the harmonics of its shafts and meshes) or to "
                            f"a mount's PEC curve (--format eqmod), not to the {fmt} table being written without "
                            "--drive; drop it, give --drive, or choose that format (--format, or the -o file's "
                            "ending)\n")


def test_harmonics_with_the_drive_changes_the_orders_fitted(runner, test_csv, tmp_path):
    """With --drive it applies: one harmonic of each shaft and mesh order instead of the default 3."""
    r1 = run(runner, test_csv, "-f", "csv", "--drive", MCH50, "--harmonics", "1", "-o", tmp_path / "h1.csv")
    r3 = run(runner, test_csv, "-f", "csv", "--drive", MCH50, "-o", tmp_path / "h3.csv")
    assert r1.exit_code == 0 and r3.exit_code == 0
    assert "(MCH50 rotary table, 1 harmonics))" in r1.stderr and "(MCH50 rotary table, 3 harmonics))" in r3.stderr


def test_a_worm_period_taken_from_the_record_says_how_little_the_record_fixes_it(runner, tmp_path):
    """The CGE log's 4.2 worm cycles cannot tell its strongest period (476.2 s) from 449-507 s (the group
    measure reports as order 170 to 192); the mount's 180-tooth wheel gives 478.7 s.  Written, with a
    warning asking for the mount's own; with the drive, no such warning."""
    log = CONFIGS.parent / "tests" / "data" / "telescope" / "cge-pro-180.guidelog.txt"
    r = run(runner, log, "-o", tmp_path / "found.pec")
    assert r.exit_code == 0 and (tmp_path / "found.pec").exists()
    assert ("warning: the worm period, 476.2 s, is the strongest in the record, which cannot tell it from 449.2 to "
            "506.7 s (4.2 worm cycles): a PEC curve of a period even 1 % off is half a cycle out of phase after 50 "
            "worm turns; give the mount's own, --drive or --worm-period\n") in r.stderr
    r = run(runner, log, "--drive", CONFIGS / "cge-pro-ra.toml", "-o", tmp_path / "drive.pec")
    assert r.exit_code == 0 and "is the strongest in the record" not in r.stderr
    assert "!WormPeriod=479" in (tmp_path / "drive.pec").read_text()


def test_an_order_the_table_cannot_carry_is_a_warning_only_when_something_is_lost(runner, tmp_path):
    """New-user trial: on a noise-free synth test of MCH50, orders 288 and 720 (fitted at 7e-06 and
    3e-05 arcsec, the model's round-off) were 'left out' with a warning each, beside the real loss of
    the 15.7 arcsec worm mesh (240).  Now only 240 is a warning; the others a note saying why."""
    data = tmp_path / "synth.csv"
    assert runner.invoke(app, ["synth", str(CONFIGS / "mch50.toml"), "-o", str(data), "--seed", "1"]).exit_code == 0
    r = run(runner, data, "--drive", CONFIGS / "mch50.toml", "-o", tmp_path / "t.comp")
    assert r.exit_code == 0, r.stderr
    warned = [line for line in r.stderr.splitlines() if line.startswith("warning: order")]
    assert len(warned) == 1 and warned[0].startswith("warning: order 240 ") and "15.7 arcsec amplitude stays" in warned[0]
    for k in (288, 720):
        assert re.search(rf"note: order {k} has a period .* so it is left out; its amplitude, [0-9.e-]+ arcsec, is "
                         r"negligible \(under a thousandth of the largest order's, 39.6 arcsec\)", r.stderr)
