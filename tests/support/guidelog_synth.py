"""PHD2 guide logs made from a known mount error (the forward physics the reader inverts).

A mount whose RA axis runs ahead of the sky by ``e(T)`` arcsec of axis rotation (periodic error
plus a drift) is guided by a simple proportional guider, as PHD2 does: every frame the star's
offset from the lock position is measured (with seeing), a pulse of ``aggression x offset`` is
sent (West for a positive offset) and moves the star back by its duration times the true rate.
The log is written as PHD2 writes it: sections, headers, the column line, frame rows, DROP rows
and the dead-reckoning row after them, INFO lines for dithers.  The truth (the axis error at every
frame with a star) comes back with the text, so a test can compare the reader's reconstruction
with it.  Nothing here uses the reader's code.

Conventions (PHD2's): the RA offset in mount coordinates is positive where a West pulse takes the
star back; a West pulse makes the axis run ahead, so an axis ahead of the sky by e arcsec puts the
star at -e cos(Dec) / scale pixels; the lock position's RA part is its projection on the RA axis
of the calibration (angle ``x_angle``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from datetime import datetime, timedelta

import numpy as np

SIDEREAL_DAY = 86164.0905


@dataclass(frozen=True)
class Mount:
    """The mount's own error: ``terms`` (order, amplitude [arcsec of axis, zero-to-peak], phase
    [rad]) as A sin(k theta + phase) of the RA axis angle theta, plus ``drift`` [arcsec/s]."""

    terms: tuple = ((180.0, 5.0, 0.3), (360.0, 1.0, 1.1))
    drift: float = 0.004

    def error(self, theta: np.ndarray, t: np.ndarray) -> np.ndarray:
        out = self.drift * t
        for k, a, ph in self.terms:
            out = out + a * np.sin(k * theta + ph)
        return out


@dataclass(frozen=True)
class Session:
    """One guiding session: ``start`` (wall clock), ``frames``, ``exposure`` [s] between frames,
    ``hour_angle`` at the start [h], ``pier`` side; ``dithers``: frame indices after which the
    lock moves by (dRA, dDec) px (tuples (index, dra, ddec)); ``drops``: frame indices without a
    star; ``header``: write the session's ``Guiding Begins`` line and header (False: the frames
    follow the previous session's, their Time starting again)."""

    start: datetime
    frames: int = 300
    exposure: float = 2.0
    hour_angle: float = -1.0
    pier: str = "West"
    dithers: tuple = ()
    drops: tuple = ()
    header: bool = True


@dataclass(frozen=True)
class Rig:
    """The guiding set-up and how the log states it.

    ``scale`` [arcsec/px], ``dec`` [deg], ``guide_speed`` [arcsec/s of axis, at the equator]
    (the true pulse rate), ``cal_dec`` [deg] the calibration declination; ``log_rate``: how the
    header states the rate: ``"norm"`` (a ``Norm rates`` line), ``"xrate"`` (only the Mount line's
    xRate, at the calibration declination), ``"none"`` (not calibrated); ``log_scale`` False:
    ``Pixel scale = unspecified``; ``log_dec`` False: ``Dec = Unknown``; ``letters_reversed``: the
    log's W/E letters are the opposite of the pulses sent; ``version_header``: the ``PHD2
    version`` line at the top; ``seeing`` [px RMS] of each measured offset; ``aggression``,
    ``min_move`` [px] of the guider; ``x_angle`` [deg]."""

    scale: float = 1.2
    dec: float = 25.0
    guide_speed: float = 7.52
    cal_dec: float = 5.0
    log_rate: str = "norm"
    log_scale: bool = True
    log_dec: bool = True
    letters_reversed: bool = False
    version_header: bool = True
    seeing: float = 0.15
    aggression: float = 0.7
    min_move: float = 0.15
    x_angle: float = -81.6


@dataclass
class Truth:
    """Per frame with a star: the axis error [arcsec], the session number (1-based), the time
    [s since the first session's start] and the axis angle [rad]."""

    error: list = field(default_factory=list)
    session: list = field(default_factory=list)
    time: list = field(default_factory=list)
    angle: list = field(default_factory=list)

    def arrays(self):
        return (np.array(self.error), np.array(self.session), np.array(self.time), np.array(self.angle))


def _header(rig: Rig, s: Session, lock) -> list[str]:
    scale = f"{rig.scale:.2f} arc-sec/px" if rig.log_scale else "unspecified"
    px_per_s_at_cal = rig.guide_speed * math.cos(math.radians(rig.cal_dec)) / rig.scale
    px_per_s_here = rig.guide_speed * math.cos(math.radians(rig.dec)) / rig.scale
    out = [f"Guiding Begins at {s.start:%Y-%m-%d %H:%M:%S}",
           "Equipment Profile = synthetic",
           "Dither = both axes, Dither scale = 1.000, Image noise reduction = none, Guide-frame time lapse = 0",
           f"Pixel scale = {scale}, Binning = 1, Focal length = {'unspecified' if not rig.log_scale else '400 mm'}",
           "Camera = Synthetic camera, gain = 50, full size = 1280 x 960, no dark, no defect map, pixel size = 3.8 um",
           f"Exposure = {int(s.exposure * 1000)} ms"]
    if rig.log_rate == "none":
        out.append("Mount = Synthetic mount, connected, guiding enabled, not calibrated")
    else:
        rate = px_per_s_here if rig.log_rate == "norm" else px_per_s_at_cal
        out.append(f"Mount = Synthetic mount, connected, guiding enabled, xAngle = {rig.x_angle:.1f}, "
                   f"xRate = {rate:.3f}, yAngle = {rig.x_angle + 90:.1f}, yRate = 5.000, parity = +/+")
    if rig.log_rate == "norm":
        norm = rig.guide_speed
        out.append(f'Norm rates RA = {norm:.1f}"/s @ dec 0, Dec = 7.0"/s; ortho.err. = 0.5 deg')
    out += ["X guide algorithm = Hysteresis, Hysteresis = 0.100, Aggression = 0.700, Minimum move = 0.150",
            "Y guide algorithm = Resist Switch, Minimum move = 0.150 Aggression = 100% FastSwitch = enabled",
            "Max RA duration = 2500, Max DEC duration = 2500, DEC guide mode = Auto",
            f"RA Guide Speed = {rig.guide_speed:.1f} a-s/s, Dec Guide Speed = 7.5 a-s/s, Cal Dec = "
            f"{rig.cal_dec:.1f}, Last Cal Issue = None, Timestamp = 1/1/2026 9:00:00 PM"]
    dec = f"{rig.dec:.1f} deg" if rig.log_dec else "Unknown"
    out.append(f"RA = 20.00 hr, Dec = {dec}, Hour angle = {s.hour_angle:.2f} hr, Pier side = {s.pier}, "
               "Rotator pos = N/A, Alt = 50.0 deg, Az = 120.0 deg")
    out.append(f"Lock position = {lock[0]:.3f}, {lock[1]:.3f}, Star position = {lock[0]:.3f}, {lock[1]:.3f}, "
               "HFD = 3.00 px")
    out.append("Frame,Time,mount,dx,dy,RARawDistance,DECRawDistance,RAGuideDistance,DECGuideDistance,RADuration,"
               "RADirection,DECDuration,DECDirection,XStep,YStep,StarMass,SNR,ErrorCode")
    return out


def _pulse(g: float, rate: float, rig: Rig) -> tuple[int, str]:
    """(duration [ms], letter as logged) of a guide distance ``g`` [px] at the logged ``rate`` [px/s]."""
    ms = min(int(round(abs(g) / rate * 1000.0)), 2500) if g else 0
    letter = ("W" if g > 0 else "E") if ms else ""
    if ms and rig.letters_reversed:
        letter = "E" if letter == "W" else "W"
    return ms, letter


def _session_lines(rig: Rig, mount: Mount, s: Session, number: int, t0: float, theta0: float, rng,
                   truth: Truth) -> list[str]:
    """The rows (and INFO lines) of one session; appends the truth of its measured frames."""
    c, sn = math.cos(math.radians(rig.x_angle)), math.sin(math.radians(rig.x_angle))
    cosd = math.cos(math.radians(rig.dec))
    true_rate = rig.guide_speed * cosd / rig.scale  # px/s of star motion per second of pulse
    logged_rate = true_rate  # PHD2 sizes pulses with its (here exact) calibrated rate
    lock_ra = 0.0
    sent = 0.0  # px of star motion the pulses sent so far have caused (West positive)
    out, drops, dithers = [], set(s.drops), {d[0]: d[1:] for d in s.dithers}
    lock = np.array([500.0, 400.0])
    times = np.cumsum(s.exposure + rng.uniform(-0.05, 0.05, s.frames))
    for i, t in enumerate(times, start=1):
        theta = theta0 + 2.0 * math.pi * t / SIDEREAL_DAY
        e = float(mount.error(np.array([theta]), np.array([t0 + t]))[0])
        star = -e * cosd / rig.scale - sent  # the star's RA offset from the start lock [px]
        if i in drops:
            out.append(f'{i},{t:.3f},"DROP",,,,,,,,,,,,,0,0.00,5,"No star found"')
            g = 0.4  # dead reckoning: the guide algorithm's guess, sent as a pulse
            ms, letter = _pulse(g, logged_rate, rig)
            out.append(f'{i},{t + 0.05:.3f},"Mount",0.000,0.000,{g:.3f},0.000,{g:.3f},0.000,{ms},{letter},0,,,,'
                       f"5000,40.00,5")
            sent += math.copysign(ms / 1000.0 * true_rate, g)
            continue
        raw = star - lock_ra + rng.normal(0.0, rig.seeing)
        truth.error.append(e)
        truth.session.append(number)
        truth.time.append(t0 + t)
        truth.angle.append(theta)
        g = rig.aggression * raw if abs(raw) > rig.min_move else 0.0
        ms, letter = _pulse(g, logged_rate, rig)
        dec_raw = rng.normal(0.0, 0.2)
        dx, dy = raw * c - dec_raw * sn, raw * sn + dec_raw * c
        out.append(f'{i},{t:.3f},"Mount",{dx:.3f},{dy:.3f},{raw:.3f},{dec_raw:.3f},{g:.3f},0.000,{ms},{letter},'
                   f"0,,,,12000,45.00,0")
        sent += math.copysign(ms / 1000.0 * true_rate, g) if ms else 0.0
        if i in dithers:
            dra, ddec = dithers[i]
            lock = lock + np.array([dra * c - ddec * sn, dra * sn + ddec * c])
            lock_ra += dra
            out.append(f"INFO: SET LOCK POSITION, new lock pos = {lock[0] - dra * c + ddec * sn:.3f}, "
                       f"{lock[1] - dra * sn - ddec * c:.3f}")
            out.append(f"INFO: DITHER by {dra:.3f}, {ddec:.3f}, new lock pos = {lock[0]:.3f}, {lock[1]:.3f}")
            out.append("INFO: SETTLING STATE CHANGE, Settling started")
    return out


def make_log(sessions: list[Session], rig: Rig = Rig(), mount: Mount = Mount(), seed: int = 0,
             slews: tuple = ()) -> tuple[str, Truth]:
    """The log text of ``sessions`` and the truth.  The RA axis's angle runs at the sidereal rate from
    the first session's hour angle; a session listed in ``slews`` (1-based) starts where its own
    hour angle says (the mount moved), the others where the clock puts them (their logged hour
    angles are made consistent with it)."""
    rng = np.random.default_rng(seed)
    truth = Truth()
    lines = []
    if rig.version_header:
        lines += [f"PHD2 version 2.6.14 [Windows], Log version 2.5. Log enabled at {sessions[0].start:%Y-%m-%d %H:%M:%S}",
                  ""]
    first = sessions[0].start
    theta_start = None
    prev = None
    for number, s in enumerate(sessions, start=1):
        t0 = (s.start - first).total_seconds()
        clock_theta = None if theta_start is None else theta_start + 2 * math.pi * t0 / SIDEREAL_DAY
        if clock_theta is None or number in slews:
            ha = s.hour_angle
            theta0 = math.radians(15.0 * ha + (180.0 if s.pier == "East" else 0.0))
            if theta_start is None:
                theta_start = theta0
        else:
            theta0 = clock_theta
            ha = (math.degrees(theta0) - (180.0 if s.pier == "East" else 0.0)) / 15.0
            s = replace(s, hour_angle=ha)
        if s.header:
            lines += _header(rig, s, (500.0, 400.0))
        elif prev is None:
            raise ValueError("the first session needs a header")
        lines += _session_lines(rig, mount, s, number, t0, theta0, rng, truth)
        if number == len(sessions) or sessions[number].header:
            last = s.start + timedelta(seconds=s.frames * s.exposure + 1)
            lines += [f"Guiding Ends at {last:%Y-%m-%d %H:%M:%S}", ""]
        prev = s
    return "\n".join(lines) + "\n", truth


START = datetime(2026, 3, 1, 21, 0, 0)


def _storm(frames: int = 300, every: int = 10, size: float = 3.0, seed: int = 7) -> tuple:
    rng = np.random.default_rng(seed)
    return tuple((i, float(round(rng.uniform(-size, size), 3)), float(round(rng.uniform(-size, size), 3)))
                 for i in range(every, frames, every))


#: the constructed logs of tests/data/telescope/constructed: name -> (sessions, rig, slews)
CONSTRUCTED = {
    "several-sessions": ([Session(START, frames=200), Session(START + timedelta(minutes=12), frames=200),
                          Session(START + timedelta(minutes=40), frames=200, hour_angle=0.35, pier="East")],
                         Rig(), (3,)),
    "time-restart": ([Session(START, frames=200), Session(START + timedelta(seconds=404), frames=200, header=False)],
                     Rig(), ()),
    "dither-storm": ([Session(START, frames=300, dithers=_storm())], Rig(), ()),
    "no-version-header": ([Session(START, frames=200)], Rig(version_header=False), ()),
    "drop-frames": ([Session(START, frames=200, drops=tuple(range(15, 200, 16)))], Rig(), ()),
    "unspecified-pixel-scale": ([Session(START, frames=200)], Rig(log_scale=False, log_rate="xrate"), ()),
    "reversed-letters": ([Session(START, frames=200)], Rig(letters_reversed=True), ()),
}


def constructed(name: str) -> tuple[str, Truth]:
    """The text and truth of a constructed log (:data:`CONSTRUCTED`)."""
    sessions, rig, slews = CONSTRUCTED[name]
    return make_log(sessions, rig, seed=sorted(CONSTRUCTED).index(name) + 1, slews=slews)


if __name__ == "__main__":  # python -m tests.support.guidelog_synth FOLDER: write the constructed logs
    import sys
    from pathlib import Path

    folder = Path(sys.argv[1])
    folder.mkdir(parents=True, exist_ok=True)
    for name in CONSTRUCTED:
        (folder / f"{name}.guidelog.txt").write_text(constructed(name)[0], newline="\n")
