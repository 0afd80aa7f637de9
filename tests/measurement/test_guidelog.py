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
    times, us, sent = [], [], []
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
            sent.append(pulses)
        if row[9] and int(row[9]):
            pulses += (1.0 if row[10] == "W" else -1.0) * int(row[9]) / 1000.0 * rate
    independent.sent = np.array(sent)  # the cumulated pulses before each frame [px], for the sign check
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
    assert GuideLogOptions(sessions=2) == GuideLogOptions(sessions=[2]) == GuideLogOptions(sessions=(2,))
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


@pytest.mark.parametrize("path, session, expected", [
    (CGE, 1, [
        "PHD2 guide log: 1 session read as run 1 (line 1)",
        "3520 guide frames with a star used; 533 frames with a star warning code (ErrorCode not 0) kept, PHD2 "
        "guided on them",
        'pixels to RA-axis arcsec: pixel scale 0.55"/px / cos Dec (Dec 22 deg); RA pulses added back at 11.54 px/s '
        "(xRate 12.346 px/s x cos Dec / cos Cal Dec 7.3 deg)",
        "RA pulses added back with the sign PHD2 writes (a West pulse moves the star towards -RA): the opposite "
        "sign gives a {} % rougher series",
        "3 dithers: the lock's shift along RA (-4.00 to +2.00 px) added back",
        "time to RA-axis angle at the sidereal rate (360 deg per 86164.09 s), starting at the logged hour angle "
        "+0.88 h (east of the pier: +180 deg)"]),
    (EQ6, 3, [
        "PHD2 guide log: session 3 of 19 read (line 85), each a run numbered as its session",
        "607 guide frames with a star used; 4 frames without a star (DROP) left out, the 4 dead-reckoning pulses "
        "PHD2 sent after them added back",
        'pixels to RA-axis arcsec: pixel scale 1.05"/px / cos Dec (Dec 31.6 deg); RA pulses added back at 5.678 '
        'px/s (Norm rates RA 7"/s x cos Dec / 1.05"/px)',
        "RA pulses added back with the sign PHD2 writes (a West pulse moves the star towards -RA): the opposite "
        "sign gives a {} % rougher series",
        "1 dither: the lock's shift along RA (-2.00 to +0.00 px) added back",
        "time to RA-axis angle at the sidereal rate (360 deg per 86164.09 s), starting at the logged hour angle "
        "-2.78 h"]),
])
def test_notes_word_for_word(path, session, expected):
    """The notes of two real logs, checked by hand: 11.54 = 12.346 cos 22 / cos 7.3, 5.678 = 7.0 cos 31.6 / 1.05;
    the roughness of the other sign from the independent reconstruction."""
    t, u, _, _ = independent(path, session)
    sent = independent.sent
    step = np.diff(sent) != 0
    d = np.diff(u - sent)  # the offsets with the lock shifts, without the pulses
    plus, minus = np.abs(d + np.diff(sent))[step].sum(), np.abs(d - np.diff(sent))[step].sum()
    expected = [n.format(round(100 * (minus - plus) / plus)) for n in expected]
    m = read(path, sessions=(session,))
    assert list(m.notes) == expected
    assert m.warnings == ()


def guided(u, events=None, header=HEAD, rate=4.0, letters=("W", "E")):
    """A hand-made session: the star's true offset ``u`` [px] per frame (1 s apart), a guider sending
    the whole measured offset back each frame (rounded to ms at ``rate`` px/s), ``events`` {frame index:
    (INFO line, lock shift [px] it makes, pulse [px] it sends)} before that frame.  Returns the text."""
    out, sent, lock = [header], 0.0, 0.0
    for i, ui in enumerate(u):
        t = float(i + 1)
        line, dlock, dpulse = (events or {}).get(i, (None, 0.0, 0.0))
        if line:
            out.append(line + "\n")
            lock += dlock(t) if callable(dlock) else dlock
            sent += dpulse
        raw = ui - sent - lock
        ms = int(round(abs(raw) / rate * 1000))
        letter = (letters[0] if raw > 0 else letters[1]) if ms else ""
        out.append(row(i + 1, t, raw, ms, letter))
        sent += math.copysign(ms / 1000 * rate, raw) if ms else 0.0
    return "".join(out)


U = [0.0, 0.5, 1.0, 1.2, 1.0, 0.8, 0.5, 0.2, -0.3, -0.6, -0.4, 0.0, 0.3, 0.7]


def test_hand_log_manual_pulses_both_ways_and_lock_moves():
    events = {3: ("INFO: Manual guide (Mount) East 250 ms", 0.0, -1.0),
              6: ("INFO: Manual guide (Mount) West 500 ms", 0.0, 2.0),
              9: ("INFO: SET LOCK POSITION, new lock pos = 100.700, 100.000", 0.7, 0.0)}
    m = read_guidelog(guided(U, events), "hand")
    np.testing.assert_allclose(m.error_arcsec, -2.0 * np.array(U), atol=2e-3)
    assert "2 manual RA pulses added back" in m.notes
    assert "1 lock-position change: the lock's shift along RA (+0.00 to +0.70 px) added back" in m.notes
    assert m.warnings == ()


def test_hand_log_lock_shift_from_the_start_and_without_calibration_angle():
    shift = "INFO: LOCK SHIFT, enabled = 1 RA,Dec rate (1.00,0.00) arc-sec/hr (720.00,0.00) px/hr"
    # the lock moves 0.2 px/s from the first frame's clock (t = 0) on: by 0.2 px at frame 1 (t = 1 s)
    events = {0: (shift, 0.2, 0.0), **dict.fromkeys(range(1, 14), ("INFO: SETTLING STATE CHANGE, x", 0.2, 0.0))}
    m = read_guidelog(guided(U, events), "hand")
    np.testing.assert_allclose(m.error_arcsec, -2.0 * np.array(U), atol=2e-3)
    # no xAngle: a dither's own RA value is added back; a lock change or a lock shift cannot be placed
    head = HEAD.replace("xAngle = 0.0, ", "")
    dither = "INFO: DITHER by 0.600, 0.300, new lock pos = 100.600, 100.300"
    m = read_guidelog(guided(U, {5: (dither, 0.6, 0.0)}, head), "hand")
    np.testing.assert_allclose(m.error_arcsec, -2.0 * np.array(U), atol=2e-3)
    m = read_guidelog(guided(U, {5: ("INFO: SET LOCK POSITION, new lock pos = 101.000, 100.000", 1.0, 0.0),
                                 7: (shift, 0.0, 0.0)}, head), "hand")
    assert m.warnings == ("session 1: lock-position changes at lines 13, 16 could not be put on the RA axis (a "
                          "damaged line, or no xAngle or lock position in the session's header): not added back",)


def test_hand_log_reversed_letters_and_undecided_sign():
    m = read_guidelog(guided(U, letters=("E", "W")), "hand")
    np.testing.assert_allclose(m.error_arcsec, -2.0 * np.array(U), atol=2e-3)
    assert "RA pulses added back with the sign opposite to the W/E letters: PHD2's own sign gives a 26 % rougher " \
           "series" in m.notes  # sum of |steps| after a pulse: 3.8 px (the true |du|), 4.8 px with the letters
    still = read_guidelog(guided([1.0] * 5, letters=("E", "W")), "hand")  # the mount still: no roughness at all
    assert "RA pulses added back with the sign opposite to the W/E letters: PHD2's own sign gives a much rougher " \
           "series" in still.notes
    flat = read_guidelog(HEAD + row(1, 1.0, 0.1) + row(2, 2.0, 0.1), "hand")
    assert "no RA pulses in the sessions read (guide output off?): the star's offsets are the mount's error" \
        in flat.notes


def test_pulse_sign_edges():
    assert pulse_sign(0.0, 5.0) == (1, math.inf, True)
    assert pulse_sign(5.0, 0.0) == (-1, math.inf, True)
    assert pulse_sign(0.1, 0.3) == (1, pytest.approx(2.0), True)
    assert pulse_sign(10.0, 10.5)[2] is False and pulse_sign(10.0, 10.51)[2] is True  # the 5 % margin
    assert pulse_sign(10.0, 10.51, margin=0.1)[2] is False


def test_time_restart_placed_after_the_first_session():
    text, truth = synth.constructed("time-restart")
    m = read_guidelog(text, "restart")
    first, second = m.run == 1, m.run == 2
    step = np.median(np.diff(m.time[first]))
    assert m.time[second][0] == pytest.approx(m.time[first][-1] + step + m.time[second][0] - m.time[second][0],
                                              abs=step * 1.1)
    # one clock through both: the angle runs with the time at the sidereal rate
    np.testing.assert_allclose(m.angle - 2 * math.pi * m.time / SIDEREAL, m.angle[0] - 2 * math.pi * m.time[0] / SIDEREAL,
                               atol=1e-9)
    assert "session 2 (line 218) has no start time after the previous session's end: placed right after it, its " \
           "phase on the RA axis unknown" in m.notes
    assert "line 218: Time starts again without a 'Guiding Begins' line: read as a new session (number 2)" in m.notes


def test_rate_and_declination_edges():
    text = synth.make_log([synth.Session(synth.START, frames=100)], synth.Rig(log_rate="xrate"))[0]
    m = read_guidelog(text.replace("Cal Dec = 5.0", "Cal Dec = Unknown"), "x")
    assert any("(xRate 6.243 px/s as logged (calibration declination unknown))" in n for n in m.notes)
    slow = synth.make_log([synth.Session(synth.START, frames=100)], synth.Rig(log_rate="xrate", guide_speed=0.6))
    check_truth(read_guidelog(*slow[:1], "x"), slow[1], synth.Rig())  # an xRate below 1 px/s
    ok = synth.make_log([synth.Session(synth.START, frames=50)], synth.Rig(dec=80.0))[0]
    assert len(read_guidelog(ok, "x")) == 50  # 80 deg is the limit, still read
    with pytest.raises(DataError) as err:
        read_guidelog(ok, "x", GuideLogOptions(dec_deg=85.0))
    assert err.value.problems == ["x:3: session 1: declination 85 deg is within 10 deg of the pole: the star moves "
                                  "only cos Dec = 0.087 arcsec per arcsec of the RA axis, too little to measure its "
                                  "error; guide on a star nearer the equator"]
    with pytest.raises(DataError, match=r"equator; if the logged value is wrong, give the right one with --dec-deg$"):
        read_guidelog(ok.replace("Dec = 80.0 deg", "Dec = 81.0 deg"), "x")
    uncalibrated = synth.make_log([synth.Session(synth.START, frames=50)], synth.Rig(log_rate="none"))[0]
    with pytest.raises(DataError) as err:
        read_guidelog(uncalibrated.replace("RA Guide Speed = 7.5 a-s/s, ", ""), "x")
    assert err.value.problems[0].endswith("(arc-seconds per second of pulse at the equator, e.g. 7.52 for 0.5x "
                                          "sidereal)")


def test_pixel_scale_hints():
    text = synth.constructed("unspecified-pixel-scale")[0]
    with pytest.raises(DataError) as err:
        read_guidelog(text.replace("Binning = 1, Focal length = unspecified", "Binning = 2, Focal length = 2800 mm"),
                      "x")
    assert err.value.problems[0].endswith("(the log's pixel size and focal length give 0.56)")
    with pytest.raises(DataError) as err:
        read_guidelog(text.replace("Binning = 1,", "Binning = 2,"), "x")
    assert err.value.problems[0].endswith("with the log's pixel size 3.8 um and binning 2: 1568 / focal length [mm]")
    with pytest.raises(DataError) as err:
        read_guidelog(text.replace("Pixel scale = unspecified, ", ""), "x")
    assert "the pixel scale is not in the log; give it with --pixel-scale" in err.value.problems[0]
    logged = synth.constructed("no-version-header")[0]
    m = read_guidelog(logged, "x", GuideLogOptions(pixel_scale=0.5))
    assert m.notes[2].startswith('pixels to RA-axis arcsec: pixel scale 0.5"/px from --pixel-scale; the log says 1.2 ')


def test_options_edges_and_detection():
    GuideLogOptions(pixel_scale=0.5, guide_rate=0.5, dec_deg=-90.0, sessions=(1,))
    for kwargs in ({"sessions": (True,)}, {"pixel_scale": 0.0}, {"guide_rate": 0.0}, {"dec_deg": 90.5}):
        with pytest.raises(UsageError):
            GuideLogOptions(**kwargs)
    with pytest.raises(UsageError, match="^--pixel-scale 0.0: expected a positive number of arc-seconds per pixel$"):
        GuideLogOptions(pixel_scale=0.0)
    with pytest.raises(UsageError, match="^--guide-rate -1: expected a positive number of arc-seconds per second$"):
        GuideLogOptions(guide_rate=-1)
    for head in ("Calibration Begins at 2026-01-01 20:00:00\nx", "\ufeffPHD2 version 2.6.14, Log version 2.5.",
                 "x\r Frame,Time,mount,dx,dy", "\r\nGuiding Begins at 2026"):
        assert looks_like_guidelog(head), head
    for head in ("phd2 version", "Frame,Time", "angle_deg,error_arcsec\n0,1", "Guiding Ends at x"):
        assert not looks_like_guidelog(head), head


def test_sessions_listed_in_the_message_of_a_session_beyond_them():
    text = synth.constructed("several-sessions")[0]
    nine = text + "".join(text.split("\n", 2)[2] for _ in range(3))  # 3 + 9 sessions, no version lines between
    with pytest.raises(UsageError) as err:
        read_guidelog(nine, "x", GuideLogOptions(sessions=(13,)))
    assert str(err.value).startswith("--session 13: the log has 12 sessions (starting at lines 3, ")
    assert str(err.value).endswith(", ...)")
    with pytest.raises(UsageError, match=r"^--session 2: the log has 1 session \(starting at line 1\)$"):
        read_guidelog(synth.constructed("no-version-header")[0], "x", GuideLogOptions(sessions=2))


def test_measurement_record_of_a_guide_log():
    m = read(CGE)
    assert m.source == str(CGE)
    assert m.present == frozenset({"run", "time_s"}) and m.derived == frozenset()
    assert m.header[:6] == ("Frame", "Time", "mount", "dx", "dy", "RARawDistance") and len(m.header) == 18
    assert m.comments == () and m.rows == ()
    assert dict(m.columns) == {"angle_deg": "Time", "error_arcsec": "RARawDistance", "run": "Guiding Begins",
                               "time_s": "Time"}
    assert m.run.dtype == np.int64
    np.testing.assert_array_equal(m.direction, 1.0)
    np.testing.assert_array_equal(m.load, 0.0)
    np.testing.assert_array_equal(m.temperature, 20.0)
    assert m.units == (("angle", "deg"), ("error", "arcsec"))


def test_sessions_without_a_star_left_out_and_too_few_frames():
    lost = 'INFO: x\n1,1.000,"DROP",,,,,,,,,,,,,0,0.00,5,"No star found"\n'
    text = HEAD + lost.replace("INFO: x\n", "") + "Guiding Ends at x\n\n" + HEAD + row(1, 1.0, 0.1) + row(2, 2.0, 0.2)
    m = read_guidelog(text, "two")
    assert "session 1 without a frame with a star: left out" in m.notes
    assert set(m.run.tolist()) == {2}
    with pytest.raises(DataError, match=r"^one: fewer than two guide frames with a star in the session read; at "
                                        r"least two are needed$"):
        read_guidelog(HEAD + row(1, 1.0, 0.1), "one")
    with pytest.raises(DataError, match=r"in the sessions read"):
        read_guidelog(text.replace(row(2, 2.0, 0.2), ""), "two")


def test_rows_without_error_code_column_and_a_drop_at_the_end():
    head = HEAD.replace(",StarMass,SNR,ErrorCode", ",StarMass,SNR")
    rows = "".join(row(i, float(i), 0.1 * i).rsplit(",", 1)[0] + "\n" for i in (1, 2, 3))
    drop = '4,4.000,"DROP",,,,,,,,,,,,,0,0.00,5,"No star found"\n'
    m = read_guidelog(head + rows + drop, "old")
    np.testing.assert_allclose(m.error_arcsec, [-0.2, -0.4, -0.6])
    assert "3 guide frames with a star used; 1 frame without a star (DROP) left out" in m.notes
    # the exact path (Mount unquoted) counts the star warnings, wherever the ErrorCode column is
    flagged = (HEAD + row(1, 1.0, 0.1) + row(2, 2.0, 0.2)[:-2] + "3\n" + row(3, 3.0, 0.3)).replace('"Mount"', "Mount")
    assert any("1 frame with a star warning code" in n for n in read_guidelog(flagged, "f").notes)
    moved = flagged.replace("SNR,ErrorCode", "ErrorCode,SNR").replace(",20.00,3\n", ",3,20.00\n").replace(
        ",20.00,0\n", ",0,20.00\n")
    assert any("1 frame with a star warning code" in n for n in read_guidelog(moved, "f").notes)


def test_restart_parts_keep_their_info_lines_and_a_damaged_line_does_not_stop_the_rest():
    dither = "INFO: DITHER by 0.500, 0.000, new lock pos = 100.500, 100.000"
    first = guided(U)
    second = guided(U[:6], {3: (dither, 0.5, 0.0)}, header="")  # Time starts again, a dither in the second part
    m = read_guidelog(first + second, "parts")
    assert m.run.tolist() == [1] * 14 + [2] * 6
    np.testing.assert_allclose(m.error_arcsec, -2.0 * np.array(U + U[:6]), atol=2e-3)
    # a dither between the two parts (before the second part's first row) belongs to the second
    between = guided(U[:6], {0: (dither, 0.5, 0.0)}, header="")
    m = read_guidelog(first + between, "parts")
    np.testing.assert_allclose(m.error_arcsec, -2.0 * np.array(U + U[:6]), atol=2e-3)
    damaged = "INFO: SET LOCK POSITION, new lock pos = 1e999, 100.000"
    m = read_guidelog(guided(U, {2: (damaged, 0.0, 0.0), 5: (dither, 0.5, 0.0)}), "damaged")
    np.testing.assert_allclose(m.error_arcsec, -2.0 * np.array(U), atol=2e-3)
    assert len(m.warnings) == 1 and "line 10" in m.warnings[0]


# --- a corrupt Time cell ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("cell", "command"), [("99999999", "measure"), ("0.5", "measure"),
                                               ("99999999", "compensate")])
def test_one_corrupt_time_cell_is_refused_naming_its_line(runner, tmp_path, cell, command):
    """Line 30 of the CGE log (frame 14, Time 6.996 s) with a corrupt Time: it had split the log into two
    sessions (the second placed 1.667e+06 min on) and given worm order 185 instead of 180.9, exit 0."""
    from wormgear_cli.cli import app

    lines = CGE.read_text(encoding="utf-8").split("\n")
    assert lines[29].startswith("14,6.996,")
    lines[29] = lines[29].replace("14,6.996,", f"14,{cell},", 1)
    path = tmp_path / "corrupt.guidelog.txt"
    path.write_text("\n".join(lines), encoding="utf-8")
    args = [command, str(path)] + (["-f", "eqmod", "-o", str(tmp_path / "pec.txt")] if command == "compensate" else [])
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    assert result.stderr == (f"error: {path}:30: column Time: {cell} s, expected between 6.566 and 7.624 s (the rows "
                             "around it): PHD2's clock runs on by about an exposure a row within a section; a corrupt "
                             "row: correct or delete the line\n")
    assert not (tmp_path / "pec.txt").exists()


def test_a_run_of_corrupt_time_cells_is_refused_and_a_restart_with_one_frame_is_read(runner, tmp_path):
    """Breaker trial: two corrupt cells in a row (lines 1001-1002 of the CGE log at 9001.63 and 9002.22 s)
    slipped past a check of single cells and moved the worm period to 452.9 s, exit 0; a genuine clock
    restart followed by one frame had been refused as corrupt."""
    from wormgear_cli.cli import app

    lines = CGE.read_text(encoding="utf-8").split("\n")
    for n, cell in ((1001, "9001.63"), (1002, "9002.22")):
        cells = lines[n - 1].split(",")
        cells[1] = cell
        lines[n - 1] = ",".join(cells)
    path = tmp_path / "two.guidelog.txt"
    path.write_text("\n".join(lines), encoding="utf-8")
    result = runner.invoke(app, ["measure", str(path)])
    assert result.exit_code == 2
    assert result.stderr.startswith(f"error: {path}:1001: column Time: 9001.63 s, expected between 527.614 and "
                                    "528.916 s (the rows around them): ")
    lines = CGE.read_text(encoding="utf-8").split("\n")[:2016]
    frame = next(line for line in lines if '"Mount"' in line).split(",")
    frame[0], frame[1] = "1", "0.512"
    path = tmp_path / "restart.guidelog.txt"
    path.write_text("\n".join([*lines, ",".join(frame), "Guiding Ends at 2020-01-01 00:00:00", ""]), encoding="utf-8")
    result = runner.invoke(app, ["measure", str(path), "-f", "json"])
    assert result.exit_code == 0, result.stderr


def test_a_corrupt_time_at_either_end_of_a_section_is_refused():
    rows = [row(k, 0.5 * k, 0.1) for k in range(1, 5)]
    with pytest.raises(DataError, match=r"^hand:8: column Time: 9 s, expected at most 1 s \(the next row's\): "):
        read_guidelog(HEAD + rows[0].replace("1,0.500,", "1,9,", 1) + "".join(rows[1:]), "hand")
    # the last frame back below the section's start: a clock restart followed by one frame (breaker
    # trial: it had been refused), read as a session of its own
    m = read_guidelog(HEAD + "".join(rows[:3]) + rows[3].replace("4,2.000,", "4,0.1,", 1), "hand")
    assert m.run.tolist() == [1, 1, 1, 2]
    with pytest.raises(DataError, match=r"^hand:11: column Time: 200000 s, expected at most 172800 s \(two days\) "
                                        r"after 'Guiding Begins'"):
        read_guidelog(HEAD + "".join(rows[:3]) + rows[3].replace("4,2.000,", "4,200000,", 1), "hand")
