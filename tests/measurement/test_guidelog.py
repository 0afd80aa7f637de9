"""PHD2 guide logs read as they come (wormgear_cli.measurement.guidelog).

Real logs (tests/data/telescope/README.md): the reader's reconstruction is compared with one
written here (the csv module, the dithers' own RA values from their INFO lines, the rate rule of
the README), and amplitudes fitted here by numpy's least squares on that independent
reconstruction with the README's right answers.  Constructed logs (tests/support/guidelog_synth.py,
the forward physics of a guided mount): the reconstruction is the true axis error within the
seeing.
"""

from __future__ import annotations

import csv
import math
import re

import numpy as np
import pytest

from tests.support import guidelog_synth as synth
from tests.support.paths import DATA
from wormgear_cli.errors import DataError, UsageError
from wormgear_cli.measurement.guidelog import (
    GuideLogOptions,
    looks_like_guidelog,
    pulse_sign,
    read_guidelog,
    sign_roughness,
)

TELESCOPE = DATA / "telescope"
CGE, G11, EQ6 = (TELESCOPE / f for f in ("cge-pro-180.guidelog.txt", "losmandy-g11-360.guidelog.txt",
                                          "eq6-ppec-19-sessions.guidelog.txt"))
SIDEREAL = 86164.09


# --- an independent reconstruction (no code of the reader) --------------------------------------------------


def _number(pattern: str, text: str) -> float | None:
    m = re.search(pattern, text)
    return None if m is None else float(m.group(1))


def independent(path, session: int = 1):
    """(time [s], reconstructed RA offset u [px], pixel scale, Dec) of one session, by another route:
    sessions split at 'Guiding Begins', rows through csv.reader, the lock shifts summed from the
    DITHER lines' own RA value, pulses at the README's rate."""
    text = path.read_bytes().decode().replace("\r\n", "\n")
    block = text.split("Guiding Begins at")[session]
    head, body = block.split("Frame,Time,mount,", 1)
    scale = _number(r"Pixel scale = ([\d.]+)", head)
    dec = _number(r"Dec = ([-\d.]+) deg", head)
    norm = _number(r'Norm rates RA = ([\d.]+)"/s', head)
    if norm is not None:
        rate = norm * math.cos(math.radians(dec)) / scale
    else:
        rate = (_number(r"xRate = ([\d.]+)", head) * math.cos(math.radians(dec))
                / math.cos(math.radians(_number(r"Cal Dec = ([-\d.]+)", head))))
    times, us = [], []
    lock_ra = pulses = 0.0
    last_drop = None
    for row in csv.reader(body.split("\n")[1:]):
        if not row:
            continue
        if row[0].startswith("INFO: DITHER by"):
            lock_ra += float(row[0].split("by")[1])
            continue
        if row[0].startswith("Guiding Ends"):
            break
        if not row[0][:1].isdigit():
            continue
        if row[2] == "DROP":
            last_drop = row[0]
            continue
        if row[0] != last_drop:  # a dead-reckoning row (same frame as the DROP before it) is no measurement
            times.append(float(row[1]))
            us.append(float(row[5]) + lock_ra + pulses)
        if row[9] and int(row[9]):
            pulses += (1.0 if row[10] == "W" else -1.0) * int(row[9]) / 1000.0 * rate
    return np.array(times), np.array(us), scale, dec


def lstsq_amplitudes(t, y, orders):
    """Zero-to-peak amplitudes at ``orders`` of a cubic in time plus sinusoids in 2 pi t / sidereal day."""
    x = 2.0 * (t - t.min()) / np.ptp(t) - 1.0
    theta = 2.0 * math.pi * t / SIDEREAL
    cols = [np.ones_like(t), x, x * x, x ** 3]
    for k in orders:
        cols += [np.cos(k * theta), np.sin(k * theta)]
    coef = np.linalg.lstsq(np.column_stack(cols), y, rcond=None)[0]
    return np.hypot(coef[4::2], coef[5::2])


def read(path, **options):
    return read_guidelog(path.read_text(), str(path), GuideLogOptions(**options))


# --- the three real logs -------------------------------------------------------------------------------------

REAL = [
    # path, session, orders, right answers (README), tolerance of each
    (CGE, 1, (180, 360, 540), (8.28, 0.79, 1.14), (0.1, 0.02, 0.02)),
    (G11, 1, (360, 720), (4.07, 1.63), (0.1, 0.02)),
    (G11, 1, (180, 360, 720), (0.82, 4.11, 1.64), (0.02, 0.1, 0.02)),
    (EQ6, 3, (180, 360, 705), (2.34, 0.78, 0.10), (0.1, 0.02, 0.02)),
]


@pytest.mark.parametrize("path, session, orders, right, tol", REAL, ids=lambda v: getattr(v, "name", None))
def test_real_logs_give_their_right_answers(path, session, orders, right, tol):
    t, u, scale, dec = independent(path, session)
    arcsec = -u * scale / math.cos(math.radians(dec))
    got = lstsq_amplitudes(t, arcsec, orders)
    assert np.all(np.abs(got - right) <= tol), f"orders {orders}: {np.round(got, 3)}, expected {right} +/- {tol}"
    m = read(path, sessions=(session,))
    # the reader's reconstruction is the independent one (the lock shifts agree to the logs' 3 decimals)
    assert len(m) == t.size
    np.testing.assert_allclose(m.error_arcsec, arcsec, atol=0.01)
    np.testing.assert_allclose(m.time - m.time[0], t - t[0], atol=1e-9)
    np.testing.assert_allclose(np.diff(m.angle), 2.0 * math.pi * np.diff(t) / SIDEREAL, rtol=1e-6)
    assert set(m.run.tolist()) == {session}


def test_cge_log_notes_say_what_was_done():
    m = read(CGE)
    notes = "\n".join(m.notes)
    assert "1 session read as run 1 (line 1)" in notes
    assert "3520 guide frames with a star used" in notes
    assert "533 frames with a star warning code" in notes
    assert "xRate 12.346 px/s x cos Dec / cos Cal Dec 7.3 deg" in notes
    assert "3 dithers: the lock's shift along RA (-4.00 to +2.00 px) added back" in notes
    assert "the opposite sign gives a" in notes
    assert m.warnings == ()


def test_eq6_log_every_session_a_run():
    m = read(EQ6)
    assert sorted(set(m.run.tolist())) == list(range(1, 20))
    notes = "\n".join(m.notes)
    assert "175 frames without a star (DROP) left out, the 174 dead-reckoning pulses" in notes
    assert "Norm rates RA 7" in notes
    assert "session 5 starts at its logged hour angle -0.25 h" in notes  # re-centred (RA 20.95 -> 20.91 h)
    assert "session 6 starts at its logged hour angle +0.19 h (east of the pier)" in notes  # meridian flip
    # sessions 3 and 4 follow on the clock: the angle at the start of 4 is 3's plus the elapsed time
    s3, s4 = m.run == 3, m.run == 4
    gap = m.time[s4][0] - m.time[s3][0]
    assert m.angle[s4][0] - m.angle[s3][0] == pytest.approx(2 * math.pi * gap / SIDEREAL, rel=1e-7)
    # each session read alone gives the same errors as within the whole log
    alone = read(EQ6, sessions=(4,))
    np.testing.assert_allclose(alone.error, m.error[s4], rtol=0, atol=1e-15)


# --- constructed logs ---------------------------------------------------------------------------------------


def check_truth(m, truth, rig, skip_time=False):
    """The reconstruction is the true axis error within the seeing, every frame."""
    error, session, time, angle = truth.arrays()
    assert len(m) == error.size
    assert m.run.tolist() == session.tolist()
    diff = m.error_arcsec - error
    noise = rig.seeing * rig.scale / math.cos(math.radians(rig.dec))
    assert abs(diff.mean()) < 4 * noise / math.sqrt(diff.size) + 0.01
    assert 0.8 * noise < diff.std() < 1.2 * noise
    if not skip_time:
        np.testing.assert_allclose(m.time, time, atol=1e-3)
        np.testing.assert_allclose(np.mod(m.angle - angle + math.pi, 2 * math.pi) - math.pi, 0, atol=1e-6)


@pytest.mark.parametrize("name", sorted(synth.CONSTRUCTED))
def test_constructed_files_are_up_to_date(name):
    assert (TELESCOPE / "constructed" / f"{name}.guidelog.txt").read_text() == synth.constructed(name)[0]


@pytest.mark.parametrize("name", ["several-sessions", "dither-storm", "no-version-header", "drop-frames",
                                  "reversed-letters"])
def test_constructed_logs_give_the_true_error(name):
    text, truth = synth.constructed(name)
    check_truth(read_guidelog(text, name), truth, synth.CONSTRUCTED[name][1])


def test_several_sessions_third_after_a_meridian_flip():
    text, truth = synth.constructed("several-sessions")
    m = read_guidelog(text, "several")
    assert "session 3 starts at its logged hour angle +0.35 h (east of the pier)" in "\n".join(m.notes)
    assert not any("session 2 starts" in n for n in m.notes)  # the second follows on the clock
    one = read_guidelog(text, "several", GuideLogOptions(sessions=(2,)))
    assert set(one.run.tolist()) == {2}
    assert "session 2 of 3 read" in one.notes[0]


def test_time_restart_is_a_new_session():
    text, truth = synth.constructed("time-restart")
    m = read_guidelog(text, "restart")
    check_truth(m, truth, synth.CONSTRUCTED["time-restart"][1], skip_time=True)
    assert any("Time starts again without a 'Guiding Begins' line" in n for n in m.notes)
    assert np.all(np.diff(m.time) > 0)  # placed after the first session


def test_dither_storm_every_shift_added_back():
    text, _ = synth.constructed("dither-storm")
    m = read_guidelog(text, "storm")
    assert any(n.startswith("29 dithers: the lock's shift along RA") for n in m.notes)


def test_drop_frames_left_out_dead_reckoning_pulses_added_back():
    text, _ = synth.constructed("drop-frames")
    m = read_guidelog(text, "drops")
    assert any("12 frames without a star (DROP) left out, the 12 dead-reckoning pulses" in n for n in m.notes)


def test_reversed_letters_found_from_the_data():
    text, _ = synth.constructed("reversed-letters")
    m = read_guidelog(text, "reversed")
    assert any("sign opposite to the W/E letters" in n for n in m.notes)
    assert any("opposite to their W/E letters" in w for w in m.warnings)


def test_unspecified_pixel_scale_names_the_option():
    text, truth = synth.constructed("unspecified-pixel-scale")
    with pytest.raises(DataError) as err:
        read_guidelog(text, "log.txt")
    message = str(err.value)
    assert message.startswith("log.txt:3: session 1: the pixel scale is unspecified; give it with --pixel-scale")
    assert "pixel size 3.8 um and binning 1: 783.8 / focal length [mm]" in message
    m = read_guidelog(text, "log.txt", GuideLogOptions(pixel_scale=1.2))
    check_truth(m, truth, synth.CONSTRUCTED["unspecified-pixel-scale"][1])
    assert any('1.2"/px from --pixel-scale' in n for n in m.notes)


def test_xrate_without_norm_rates_scaled_from_the_calibration_declination():
    text, truth = synth.make_log([synth.Session(synth.START, frames=200)], synth.Rig(log_rate="xrate", cal_dec=30.0))
    check_truth(read_guidelog(text, "x"), truth, synth.Rig())


def test_missing_declination_and_calibration_name_their_options():
    rig = synth.Rig(log_dec=False, log_rate="none")
    text, truth = synth.make_log([synth.Session(synth.START, frames=200)], rig)
    with pytest.raises(DataError) as err:
        read_guidelog(text, "log.txt")
    assert [p.split(";")[0] for p in err.value.problems] == [
        "log.txt:3: session 1: the declination is not in the log"]
    with pytest.raises(DataError) as err:
        read_guidelog(text, "log.txt", GuideLogOptions(dec_deg=25.0))
    assert err.value.problems[0].startswith("log.txt:3: session 1: no RA calibration in the log")
    assert "--guide-rate ARCSEC_PER_S" in err.value.problems[0]
    assert "the log states RA Guide Speed = 7.5 a-s/s" in err.value.problems[0]
    m = read_guidelog(text, "log.txt", GuideLogOptions(dec_deg=25.0, guide_rate=7.52))
    check_truth(m, truth, rig)


def test_declination_near_the_pole_refused():
    text, _ = synth.make_log([synth.Session(synth.START, frames=50)], synth.Rig(dec=84.0))
    with pytest.raises(DataError, match=r"declination 84 deg is within 10 deg of the pole"):
        read_guidelog(text, "log.txt")


def test_options_checked():
    for kwargs, option in (({"sessions": (0,)}, "--session 0"), ({"pixel_scale": -1.0}, "--pixel-scale -1.0"),
                           ({"dec_deg": 95.0}, "--dec-deg 95.0"), ({"guide_rate": math.nan}, "--guide-rate nan")):
        with pytest.raises(UsageError, match=option):
            GuideLogOptions(**kwargs)
    with pytest.raises(UsageError, match=r"--session 4: the log has 3 sessions \(starting at lines 3, "):
        read_guidelog(synth.constructed("several-sessions")[0], "x", GuideLogOptions(sessions=(4,)))


# --- hand-made logs: what PHD2 writes that the generator does not -------------------------------------------

HEAD = """Guiding Begins at 2026-01-05 22:00:00
Pixel scale = 2.00 arc-sec/px, Binning = 1, Focal length = 400 mm
Mount = M, connected, guiding enabled, xAngle = 0.0, xRate = 4.000, yAngle = 90.0, yRate = 4.000, parity = +/+
RA Guide Speed = 7.5 a-s/s, Dec Guide Speed = 7.5 a-s/s, Cal Dec = 0.0, Last Cal Issue = None, Timestamp = x
RA = 1.00 hr, Dec = 0.0 deg, Hour angle = 0.00 hr, Pier side = West, Rotator pos = N/A
Lock position = 100.000, 100.000, Star position = 100.000, 100.000, HFD = 2.00 px
Frame,Time,mount,dx,dy,RARawDistance,DECRawDistance,RAGuideDistance,DECGuideDistance,RADuration,RADirection,\
DECDuration,DECDirection,XStep,YStep,StarMass,SNR,ErrorCode
"""


def row(frame, time, raw, ms=0, letter="", mount='"Mount"'):
    return f"{frame},{time:.3f},{mount},{raw:.3f},0.000,{raw:.3f},0.000,0.000,0.000,{ms},{letter},0,,,,100,20.00,0\n"


def test_manual_pulses_and_lock_shift_rate_added_back():
    # rate 4 px/s at Dec 0 (xAngle 0: the RA axis is camera x); a manual West pulse of 500 ms moves
    # the star by -2 px; a lock shift of 720 px/hr along x moves the lock 0.2 px/s
    text = (HEAD + row(1, 1.0, 0.0) + "INFO: Manual guide (Mount) West 500 ms\n" + row(2, 2.0, -2.0)
            + "INFO: LOCK SHIFT, enabled = 1 RA,Dec rate (1.00,0.00) arc-sec/hr (720.00,0.00) px/hr\n"
            + row(3, 3.0, -2.2) + row(4, 5.0, -2.6)
            + "INFO: LOCK SHIFT, enabled = 0 \n" + row(5, 7.0, -2.6))
    m = read_guidelog(text, "hand")
    np.testing.assert_allclose(m.error_arcsec, [0.0] * 5, atol=1e-9)
    assert any("1 manual RA pulse added back" in n for n in m.notes)
    assert any("lock-position shift (tracking a moving target)" in n for n in m.notes)


def test_malformed_rows_name_their_line():
    with pytest.raises(DataError, match=r"^hand:9: column RARawDistance: expected a number, got 'x'$"):
        read_guidelog(HEAD + row(1, 1.0, 0.1) + row(2, 2.0, 0.1).replace("0.100,0.000,0.100", "0.100,0.000,x"),
                      "hand")
    with pytest.raises(DataError, match=r"^hand:8: expected at least 11 cells"):
        read_guidelog(HEAD + "1,1.000,\"Mount\",0.1\n" + row(2, 2.0, 0.1) + row(3, 3.0, 0.1), "hand")
    with pytest.raises(DataError, match=r"^hand:9: column RADirection: expected W or E with a pulse of 20 ms"):
        read_guidelog(HEAD + row(1, 1.0, 0.1) + row(2, 2.0, 0.1, 20, "N"), "hand")
    with pytest.raises(DataError, match=r'^hand:8: adaptive-optics steps \("AO" rows\)'):
        read_guidelog(HEAD + row(1, 1.0, 0.1, mount='"AO"') + row(2, 2.0, 0.1), "hand")
    with pytest.raises(DataError, match=r"^hand: no guiding frames"):
        read_guidelog("angle_deg,error_arcsec\n0,1\n", "hand")


def test_cut_last_row_left_out():
    m = read_guidelog(HEAD + row(1, 1.0, 0.1) + row(2, 2.0, 0.2) + "3,3.0", "hand")
    assert len(m) == 2
    assert "line 10: an incomplete last row of a section left out" in m.notes


def test_looks_like_guidelog():
    for path in (CGE, G11, EQ6, *sorted((TELESCOPE / "constructed").glob("*.txt"))):
        assert looks_like_guidelog(path.read_text()[:4096])
    for path in sorted((DATA / "field").glob("*.csv")):
        assert not looks_like_guidelog(path.read_text(encoding="utf-8-sig")[:4096])


# --- the pulse sign -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("seeing", [0.05, 0.3, 1.0])
def test_pulse_sign_found_over_seeds_even_in_bad_seeing(seeing):
    """The right sign wins on every seed, from good seeing to seeing that swamps the periodic error."""
    for seed in range(8):
        for reversed_letters in (False, True):
            rig = synth.Rig(seeing=seeing, letters_reversed=reversed_letters)
            text, truth = synth.make_log([synth.Session(synth.START, frames=150)], rig, seed=seed)
            m = read_guidelog(text, "s")
            flipped = any("opposite to their W/E letters" in w for w in m.warnings)
            assert flipped == reversed_letters
            assert np.std(m.error_arcsec - truth.arrays()[0]) < 1.3 * seeing * rig.scale / math.cos(
                math.radians(rig.dec))


def test_pulse_sign_rules():
    assert pulse_sign(10.0, 20.0) == (1, 1.0, True)
    assert pulse_sign(20.0, 10.0) == (-1, 1.0, True)
    assert pulse_sign(10.0, 10.4) == (1, pytest.approx(0.04), False)  # within the margin: PHD2's sign
    assert pulse_sign(0.0, 0.0) == (1, 0.0, False)
    # base steps that cancel the pulses exactly (right sign): R+ = 0
    assert sign_roughness([0.0, -1.0, -1.5], [0.0, 1.0, 1.5]) == (0.0, 3.0, 2)


def test_calibration_section_and_log_lines_around_the_guiding_ignored():
    calibration = ("PHD2 version 2.6.14 [Windows], Log version 2.5. Log enabled at 2026-01-05 21:50:00\n\n"
                   "Calibration Begins at 2026-01-05 21:55:00\nEquipment Profile = p\nDirection,Step,dx,dy,x,y,Dist\n"
                   "West,1,1.234,-0.567,969.357,606.889,1.358\n"
                   "West calibration complete. Angle = 0.0 deg, Rate = 4.000 px/sec, Parity = Even\n"
                   "Calibration complete, mount = M.\n\n")
    tail = "Guiding Ends at 2026-01-05 22:01:00\n\nLog Summary: calcnt:1 gcnt:1 gdur:60 gacnt:0\nLog closed at x\n"
    text = calibration + HEAD + row(1, 1.0, 0.25) + row(2, 2.0, 0.5) + tail
    for variant in (text, "\ufeff" + text.replace("\n", "\r\n"), text.replace("\n", "\r")):
        m = read_guidelog(variant, "cal")
        np.testing.assert_allclose(m.error_arcsec, [-0.5, -1.0])  # 2"/px at Dec 0, the axis behind
        assert m.notes[0] == "PHD2 guide log: 1 session read as run 1 (line 10)"


def test_a_session_without_pixel_scale_names_the_sessions_that_can_be_read():
    text = synth.constructed("several-sessions")[0]
    first, rest = text.split("Pixel scale = 1.20 arc-sec/px", 1)
    text = first + "Pixel scale = unspecified" + rest
    with pytest.raises(DataError) as err:
        read_guidelog(text, "log.txt")
    assert err.value.problems[0].startswith("log.txt:3: session 1: the pixel scale is unspecified")
    assert err.value.problems[1] == "log.txt: sessions 2, 3 can be read as they are: --session 2"
    assert len(read_guidelog(text, "log.txt", GuideLogOptions(sessions=(2, 3)))) == 400


from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

_DROPS_TEXT = synth.constructed("drop-frames")[0]


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cut=st.integers(0, len(_DROPS_TEXT)), where=st.integers(0, len(_DROPS_TEXT) - 1),
       junk=st.sampled_from(["", ",", "\n", "x", "-", "\"", "9", "1e999", "INFO: DITHER by 1e999, 0, new lock pos = nan, 1\n",
                             "INFO: SET LOCK POSITION, new lock pos = 1e999, 1\n", "Dec = 1e999 deg\n",
                             "INFO: LOCK SHIFT, enabled = 1 X,Y rate (1,1) pixels/hr (1e999,0.00) px/hr\n",
                             "1,2,3\n", "Guiding Begins at 2026-13-45 99:99:99\n", "Frame,Time,mount\n", "\r"]))
def test_damaged_logs_raise_only_data_errors(cut, where, junk):
    """Cut short, or with a character or a line spliced in anywhere: a Measurement or a DataError naming
    the problem, never another exception."""
    text = _DROPS_TEXT[:where] + junk + _DROPS_TEXT[where:cut] if where < cut else _DROPS_TEXT[:cut]
    try:
        m = read_guidelog(text, "damaged")
    except DataError as exc:
        assert str(exc).startswith("damaged")
    else:
        assert np.all(np.isfinite(m.error)) and np.all(np.isfinite(m.angle)) and np.all(np.diff(m.time) >= -1e-9)


def test_consistency_fast_and_exact_row_paths():
    """The C-reader path and the exact path give the same frames on every test log; a log the fast
    path declines (Mount unquoted, letters padded, empty ErrorCode) reads the same by the exact path."""
    from wormgear_cli.measurement import guidelog as g

    paths = [CGE, G11, EQ6, *sorted((TELESCOPE / "constructed").glob("*.txt"))]
    for path in paths:
        for sec in g._scan(path.read_text().replace("\r\n", "\n")):
            fast, exact = g._fast_frames(sec), g._frames(sec, "x")
            assert fast is not None
            for name in ("time", "measured", "drop", "dead", "pulse_ms", "lines"):
                np.testing.assert_array_equal(getattr(fast, name), getattr(exact, name))
            np.testing.assert_array_equal(fast.raw, exact.raw)
            assert (fast.flagged, fast.cut) == (exact.flagged, exact.cut)
    text = synth.constructed("drop-frames")[0]
    odd = re.sub(r',"Mount",(.*),([EW]),', r',Mount,\1, \2 ,', text).replace(",12000,45.00,0\n", ",12000,45.00,\n")
    assert odd != text
    assert all(g._fast_frames(sec) is None for sec in g._scan(odd))
    a, b = read_guidelog(text, "x"), read_guidelog(odd, "x")
    np.testing.assert_array_equal(a.error, b.error)
    np.testing.assert_array_equal(a.angle, b.angle)
