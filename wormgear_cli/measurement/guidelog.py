"""PHD2 guide logs read as they come: the RA axis's own error, reconstructed frame by frame.

A PHD2 guide log (``PHD2_GuideLog_*.txt``) holds guiding sections, each opened by ``Guiding
Begins at <date time>``, a header (pixel scale, calibration, pointing, lock position), the column
line ``Frame,Time,mount,dx,dy,RARawDistance,...`` and one row per guide frame; ``INFO:`` lines
(dithers, lock-position changes, settling, parameter changes) are interleaved with the rows, and a
frame without a star is a ``"DROP"`` row with one more (status) column.  PHD2 only ever appends
columns, so they are found by name.

While guiding, the star's offset from the lock position (``RARawDistance``, pixels along the RA
axis of the calibration) is what the mount's error left after the corrections PHD2 already sent.
The mount's own error is put back together as

    u_i = RARawDistance_i + (lock_i - lock_0) . x_RA + s * sum_{j < i} p_j            [px]

where ``lock . x_RA`` is the lock position (camera x, y) projected on the RA axis (``xAngle`` of the
calibration: a dither or a lock-position change moves the lock, and the guider then moves the
star after it), ``p_j = +-RADuration_j / 1000 * rate`` the j-th RA pulse as pixels of star motion
(``W`` positive, ``E`` negative; also the dead-reckoning pulses PHD2 sends after a lost frame, and
manual pulses), and ``s = +1`` the sign PHD2 writes them with, checked against the data: the
right sign gives the smoother series (:func:`pulse_sign`).  The pulse rate [px/s] at the
declination guided on is, in this order of preference, ``--guide-rate`` (arc-seconds per second
of the RA axis, as at the equator), the ``Norm rates RA = ..."/s @ dec 0`` line times cos Dec /
pixel scale, and the ``xRate`` of the ``Mount`` line taken as measured at the calibration
declination (``Cal Dec``) times cos Dec / cos Cal Dec.

Pixels become arc-seconds of RA-axis rotation through the pixel scale and 1 / cos Dec (a star at
declination Dec moves cos Dec arcsec on the sky per arcsec of the axis).  The error is positive
where the axis is ahead of the sky: a positive RA offset is one PHD2 corrects with a West pulse,
which makes the axis run ahead, so the axis was behind (error = -u x scale / cos Dec).  The
offset's sign is PHD2's definition and does not depend on the pulse letters, so a log whose W/E
letters are reversed gets the same error curve.

Time becomes the RA-axis angle at the sidereal rate, 360 deg per
:data:`~wormgear_cli.units.SIDEREAL_DAY_S`.  Every session is a run of the measurement (run
number = session number, 1 for the first ``Guiding Begins``; where ``Time`` goes back inside a
section and runs on from there, a new session starts; one ``Time`` cell out of order between rows
in order, or beyond two days, is a corrupt row and refused), so several sessions are the same
mount at several hour angles:
each starts where the clock puts it (the previous session's start plus the time elapsed), or at
its logged hour angle (plus 180 deg on the east side of the pier) where that differs (a slew, a
re-centring, a meridian flip).  ``time`` is seconds since the first session read began.

Rows: a ``DROP`` row has no star; the ``Mount`` row PHD2 writes right after it with the same frame
number is the dead-reckoning pulse the guide algorithm sent meanwhile (no star position: its pulse
counts, its offset does not); ``Mount`` rows with a non-zero ``ErrorCode`` (a star warning) were
guided on and are kept; an incomplete last row (a log cut off while written) is left out.  The
pulse sign is decided once, pooled over the sessions read.

Pure parsing of a given text (the file is read by the reader layer); every problem raises
:class:`~wormgear_cli.errors.DataError` naming the line and the option that supplies what is
missing.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from datetime import datetime

import numpy as np

from wormgear_cli.errors import DataError, UsageError
from wormgear_cli.measurement.guidelog_options import GuideLogOptions
from wormgear_cli.measurement.reader import ARCSEC, Measurement, ReadOptions
from wormgear_cli.units import DEG, SIDEREAL_DAY_S

#: the start of the column line of a guiding section
COLUMN_LINE = "Frame,Time,mount,"
#: columns the reconstruction needs (found by name: PHD2 only ever appends columns)
NEEDED_COLUMNS = ("Frame", "Time", "mount", "RARawDistance", "RADuration", "RADirection")
#: declinations nearer the pole are refused [deg]: the star moves cos Dec with the axis (1/cos 80 deg = 5.8)
MAX_ABS_DEC_DEG = 80.0
#: the headers write the hour angle to 0.01 h: a session whose logged hour angle differs from the
#: clock's by more than this [h] moved since the session before
HOUR_ANGLE_TOL_H = 0.015
#: the pulse sign is taken as shown by the data when one sign's series is rougher by more than this
SIGN_MARGIN = 0.05
#: pulses a session needs before its own sign evidence is compared with the pooled decision
SIGN_MIN_PULSES = 20

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_BEGINS = "Guiding Begins at"


def looks_like_guidelog(head: str) -> bool:
    """Whether ``head`` (the first few kilobytes of a text) is a PHD2 guide log: a line starting
    ``PHD2 version``, ``Guiding Begins at``, ``Calibration Begins at`` or the column line
    ``Frame,Time,mount,``."""
    for line in head.lstrip("\ufeff").replace("\r", "\n").split("\n"):
        s = line.strip()
        if s.startswith(("PHD2 version", _BEGINS, "Calibration Begins at", COLUMN_LINE)):
            return True
    return False


# --- the sections -------------------------------------------------------------------------------------------


@dataclass
class _Section:
    """One guiding session as found in the text (1-based line numbers)."""

    line: int
    start: datetime | None
    header: list = field(default_factory=list)  # (line, text) before the column line
    columns: dict | None = None
    column_line: int = 0
    rows: list = field(default_factory=list)  # frame lines
    row_lines: list = field(default_factory=list)
    events: list = field(default_factory=list)  # (rows before it, line, text) of the INFO lines


def _start_time(line: str) -> datetime | None:
    try:
        return datetime.strptime(line.strip()[len(_BEGINS):].strip(), "%Y-%m-%d %H:%M:%S")
    except ValueError:
        return None


#: a line that does not start with a digit (everything but frame rows), after its newline: the regex
#: engine jumps from newline to newline
_NOT_A_ROW = re.compile(r"\n(?![0-9])([^\n]*)")


def _scan(text: str) -> list[_Section]:
    """The guiding sections of the log, in file order (calibration sections and text outside a
    section left out).  The frame rows between two other lines are taken as one block."""
    sections: list[_Section] = []
    cur: _Section | None = None
    text = "\n" + text  # every line after a newline
    line_no, pos = 1, 1  # the line that starts at text[pos]
    for m in _NOT_A_ROW.finditer(text):
        if m.start() > pos:
            line_no = _rows(text[pos:m.start()], line_no, cur)
        cur = _line(m.group(1), line_no, cur, sections)
        line_no, pos = line_no + 1, m.end() + 1
    if pos < len(text):
        _rows(text[pos:], line_no, cur)
    return [sec for sec in sections if sec.columns is not None]


def _rows(block: str, line_no: int, cur: _Section | None) -> int:
    """File the lines of ``block`` (each starting with a digit) from line ``line_no`` on: frame rows
    of a section after its column line, header lines before it; the next line number."""
    lines = block.split("\n")
    if cur is not None and cur.columns is not None:
        cur.rows += lines
        cur.row_lines += range(line_no, line_no + len(lines))
    elif cur is not None:
        cur.header += [(line_no + k, line.strip()) for k, line in enumerate(lines)]
    return line_no + len(lines)


def _line(line: str, i: int, cur: _Section | None, sections: list[_Section]) -> _Section | None:
    """File line ``i`` (not a frame row); the section current after it."""
    s = line.strip()
    if s.startswith(_BEGINS):
        cur = _Section(i, _start_time(s))
        sections.append(cur)
    elif s.startswith(("Calibration Begins at", "Guiding Ends at")):
        cur = None
    elif s.startswith(COLUMN_LINE):
        if cur is None or cur.columns is not None:  # frames without a "Guiding Begins" line
            cur = _Section(i, None)
            sections.append(cur)
        cur.columns = {c.strip(): k for k, c in enumerate(s.split(","))}
        cur.column_line = i
    elif cur is not None and s.startswith("INFO:"):
        if cur.columns is not None:
            cur.events.append((len(cur.rows), i, s))
    elif cur is not None and cur.columns is None and s:
        cur.header.append((i, s))
    return cur


def _find(header: list, pattern: str) -> tuple[int, re.Match] | None:
    """(line, match) of the first header line matching ``pattern``."""
    rx = re.compile(pattern)
    for line, text in header:
        m = rx.search(text)
        if m:
            return line, m
    return None


#: numbers in headers and INFO lines beyond this (or not finite) are taken as damage and not used
_SANE = 1e9


def _num(text: str) -> float | None:
    """``text`` as a number, or None when it is not finite or beyond :data:`_SANE`."""
    value = float(text)
    return value if math.isfinite(value) and abs(value) < _SANE else None


def _value(header: list, pattern: str) -> float | None:
    found = _find(header, pattern)
    return None if found is None else _num(found[1].group(1))


# --- per-session parameters ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Params:
    """What converts one session's pixels and pulses: ``scale`` [arcsec/px], ``dec`` [deg],
    ``rate`` [px/s of star motion per second of RA pulse at ``dec``] and how each was found;
    ``x_angle`` [rad] and ``lock`` (camera px) for the lock shifts; the pointing (hour angle [h],
    pier side) for the session's place on the RA axis."""

    scale: float
    scale_how: str
    dec: float
    dec_how: str
    rate: float
    rate_how: str
    x_angle: float | None
    lock: tuple[float, float] | None
    hour_angle: float | None
    pier: str | None


def _scale(sec: _Section, opts: GuideLogOptions, where: str) -> tuple[float | None, str, str | None]:
    """(pixel scale [arcsec/px] or None, how, problem)."""
    found = _find(sec.header, r"Pixel scale = (\S+?)(?: arc-sec/px|,|$)")
    logged = None
    if found is not None:
        try:
            logged = _num(found[1].group(1))
        except ValueError:
            logged = None
    if opts.pixel_scale is not None:
        said = "" if logged is None else f"; the log says {logged:g}"
        return opts.pixel_scale, f'{opts.pixel_scale:g}"/px from --pixel-scale{said}', None
    if logged is not None and logged > 0:
        return logged, f'{logged:g}"/px', None
    size = _value(sec.header, rf"pixel size = ({_NUMBER}) um")
    binning = _value(sec.header, rf"Binning = ({_NUMBER})")
    focal = _value(sec.header, rf"Focal length = ({_NUMBER}) mm")
    hint = ""
    if size and focal:
        hint = f" (the log's pixel size and focal length give {206.265 * size * (binning or 1) / focal:.3g})"
    elif size:
        hint = (f"; with the log's pixel size {size:g} um and binning {binning or 1:g}: "
                f"{206.265 * size * (binning or 1):.4g} / focal length [mm]")
    state = ("not in the log" if found is None else "unspecified" if found[1].group(1) == "unspecified"
             else f"unreadable ({found[1].group(1)!r})")
    return None, "", (f"{where}: the pixel scale is {state}; give it with --pixel-scale ARCSEC_PER_PX "
                      f"(206.265 x pixel size [um] x binning / focal length [mm]){hint}")


def _dec(sec: _Section, opts: GuideLogOptions, where: str) -> tuple[float | None, str, str | None]:
    """(declination [deg] or None, how, problem)."""
    found = _find(sec.header, rf"\bDec = ({_NUMBER}) deg")
    logged = None if found is None else _num(found[1].group(1))
    if opts.dec_deg is not None:
        dec, how = opts.dec_deg, f"Dec {opts.dec_deg:g} deg from --dec-deg"
    elif logged is not None:
        dec, how = logged, f"Dec {logged:g} deg"
    else:
        state = "not in the log" if found is None else f"unreadable ({found[1].group(1)!r})"
        return None, "", (f"{where}: the declination is {state}; give it with --dec-deg DEG (the declination of "
                          "the guide star)")
    if abs(dec) > 90.0:
        return None, "", (f"{where}: the logged declination {dec:g} is not in [-90, 90] degrees; give the right "
                          "one with --dec-deg DEG")
    if abs(dec) > MAX_ABS_DEC_DEG:
        fix = "" if opts.dec_deg is not None else "; if the logged value is wrong, give the right one with --dec-deg"
        return None, "", (f"{where}: declination {dec:g} deg is within {90 - MAX_ABS_DEC_DEG:g} deg of the pole: "
                          f"the star moves only cos Dec = {math.cos(dec * DEG):.3f} arcsec per arcsec of the RA "
                          f"axis, too little to measure its error; guide on a star nearer the equator{fix}")
    return dec, how, None


def _rate(sec: _Section, opts: GuideLogOptions, scale: float | None, dec: float | None, where: str):
    """(pulse rate [px/s at ``dec``] or None, how, problem); see the module doc for the order."""
    if scale is None or dec is None:
        return None, "", None
    cosd = math.cos(dec * DEG)
    if opts.guide_rate is not None:
        return (opts.guide_rate * cosd / scale,
                f'--guide-rate {opts.guide_rate:g}"/s x cos Dec / pixel scale', None)
    logged_scale = _value(sec.header, rf"Pixel scale = ({_NUMBER}) arc-sec/px")
    norm = _value(sec.header, rf'Norm rates RA = ({_NUMBER})"/s @ dec 0')
    cal_dec = _value(sec.header, rf"Cal Dec = ({_NUMBER})")
    if norm is not None and logged_scale and cal_dec is not None:
        return norm * cosd / logged_scale, f'Norm rates RA {norm:g}"/s x cos Dec / {logged_scale:g}"/px', None
    x_rate = _value(sec.header, rf"xRate = ({_NUMBER})")
    if x_rate is not None and x_rate > 0:
        if cal_dec is not None and abs(cal_dec) < 90.0:
            return (x_rate * cosd / math.cos(cal_dec * DEG),
                    f"xRate {x_rate:g} px/s x cos Dec / cos Cal Dec {cal_dec:g} deg", None)
        return x_rate, f"xRate {x_rate:g} px/s as logged (calibration declination unknown)", None
    speed = _value(sec.header, rf"RA Guide Speed = ({_NUMBER}) a-s/s")
    hint = f"; the log states RA Guide Speed = {speed:g} a-s/s" if speed else ""
    return None, "", (f"{where}: no RA calibration in the log (no xRate or Norm rates line); give the RA guide "
                      "rate with --guide-rate ARCSEC_PER_S (arc-seconds per second of pulse at the equator, "
                      f"e.g. 7.52 for 0.5x sidereal){hint}")


def _params(sec: _Section, number: int, opts: GuideLogOptions, name: str) -> tuple[_Params | None, list[str]]:
    """The session's conversion parameters, or None and the problems (each naming the option)."""
    where = f"{name}:{sec.line}: session {number}"
    scale, scale_how, p1 = _scale(sec, opts, where)
    dec, dec_how, p2 = _dec(sec, opts, where)
    rate, rate_how, p3 = _rate(sec, opts, scale, dec, where)
    problems = [p for p in (p1, p2, p3) if p]
    if problems:
        return None, problems
    assert scale is not None and dec is not None  # (each comes with a problem when it is missing)
    x_angle = _value(sec.header, rf"xAngle = ({_NUMBER})")
    lock = _find(sec.header, rf"Lock position = ({_NUMBER}), ({_NUMBER})")
    lock_x, lock_y = (None, None) if lock is None else (_num(lock[1].group(1)), _num(lock[1].group(2)))
    hour = _value(sec.header, rf"Hour angle = ({_NUMBER}) hr")
    pier = _find(sec.header, r"Pier side = (East|West)")
    return _Params(scale, scale_how, dec, dec_how, rate, rate_how,
                   None if x_angle is None else x_angle * DEG,
                   None if lock_x is None or lock_y is None else (lock_x, lock_y),
                   hour if hour is not None and abs(hour) <= 24.0 else None,
                   None if pier is None else pier[1].group(1)), []


# --- the frames of a session --------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Frames:
    """One session's rows as arrays, in row order.

    ``time`` [s since the section began]; ``measured``: rows with a star position (``Mount`` rows
    that are not dead-reckoning steps); ``drop``: frames without a star; ``dead``: the ``Mount``
    rows PHD2 writes for the dead-reckoning pulse after a lost frame (same frame number as the
    ``DROP`` row before it, no star position: their pulse counts, their offset does not);
    ``raw`` [px] (NaN where not measured); ``pulse_ms`` signed RA pulse (+ West, - East);
    ``flagged``: measured rows with a star warning code (ErrorCode not 0); ``cut``: the line of an
    incomplete last row left out (0: none)."""

    time: np.ndarray
    measured: np.ndarray
    drop: np.ndarray
    dead: np.ndarray
    raw: np.ndarray
    pulse_ms: np.ndarray
    lines: np.ndarray
    flagged: int
    cut: int


def _numbers(values, lines: np.ndarray, name: str, column: str) -> np.ndarray:
    """``values`` (a sequence of text cells) as floats; a DataError naming the line and column of
    the first that is not a finite number."""
    try:
        out = np.fromiter(map(float, values), dtype=float, count=len(values))
        if np.all(np.isfinite(out)):
            return out
    except ValueError:
        pass
    for v, line in zip(values, lines.tolist()):
        try:
            ok = math.isfinite(float(v))
        except ValueError:
            ok = False
        if not ok:
            raise DataError(f"{name}:{line}: column {column}: expected a number, got {v.strip()!r}") from None
    raise AssertionError("unreachable")  # pragma: no cover


#: RADirection letter -> sign of the pulse (West positive, as PHD2 moves a positive RA offset)
_SIGN = {"W": 1.0, "E": -1.0, "": 0.0}


def _cells(sec: _Section, name: str) -> tuple[dict, tuple | None, np.ndarray, int]:
    """The section's cells of :data:`NEEDED_COLUMNS` (a tuple of text cells per column name, over
    the rows), the rest of each row after them (None when no row has more), the rows' line numbers
    and the line of an incomplete last row left out (0: none)."""
    cols = sec.columns
    assert cols is not None  # (the sections read have their column line)
    missing = [c for c in NEEDED_COLUMNS if c not in cols]
    if missing:
        raise DataError(f"{name}:{sec.column_line}: the column line lacks {', '.join(missing)}; expected PHD2's "
                        "Frame,Time,mount,dx,dy,RARawDistance,DECRawDistance,RAGuideDistance,...")
    need = max(cols[c] for c in NEEDED_COLUMNS) + 1
    cells = [r.split(",", need) for r in sec.rows]  # the cells read, then the rest of the row in one piece
    lines = sec.row_lines
    cut = 0
    if cells and len(cells[-1]) < need:  # the last row of a log cut off while PHD2 wrote it
        cut = lines[-1]
        cells, lines = cells[:-1], lines[:-1]
    lengths = np.fromiter(map(len, cells), dtype=np.int64, count=len(cells))
    short = np.flatnonzero(lengths < need)
    if short.size:
        k = int(short[0])
        raise DataError(f"{name}:{lines[k]}: expected at least {need} cells as in the column line "
                        f"(line {sec.column_line}), got {lengths[k]}")
    columns = list(zip(*cells))  # as many as the shortest row has
    read = {c: columns[cols[c]] if columns else () for c in NEEDED_COLUMNS}
    return read, columns[need] if len(columns) > need else None, np.asarray(lines, dtype=np.int64), cut


def _flagged(sec: _Section, rest: tuple | None, idx: np.ndarray) -> int:
    """Rows ``idx`` whose ErrorCode (a star warning) is not 0, from the rest of each row."""
    assert sec.columns is not None  # (the sections read have their column line)
    j = sec.columns.get("ErrorCode")
    need = max(sec.columns[c] for c in NEEDED_COLUMNS) + 1
    if j is None or rest is None or j < need:
        return 0
    if j == max(sec.columns.values()):  # the last column, as PHD2 writes it: the end of a guide-step row
        codes = [rest[k].rpartition(",")[2] for k in idx.tolist()]
    else:
        codes = [(rest[k].split(",")[j - need:j - need + 1] or [""])[0] for k in idx.tolist()]
    return sum(1 for c in codes if c.strip() not in ("", "0"))


def _frames(sec: _Section, name: str) -> _Frames:
    """Parse the rows of a section (see :class:`_Frames`)."""
    cells, rest, lines, cut = _cells(sec, name)
    kind = cells["mount"]
    n = len(kind)
    drop, mount = np.zeros(n, dtype=bool), np.ones(n, dtype=bool)
    for k in [k for k, word in enumerate(kind) if word != '"Mount"']:  # DROP rows, or spelled another way
        word = kind[k].strip().strip('"')
        if word == "AO":
            raise DataError(f"{name}:{lines[k]}: adaptive-optics steps (\"AO\" rows): the corrections of an AO "
                            "cannot be added back from the log; this reader takes logs of mount guiding only")
        if word not in ("Mount", "DROP"):
            raise DataError(f"{name}:{lines[k]}: column mount: expected \"Mount\" or \"DROP\", got {word!r}")
        drop[k], mount[k] = word == "DROP", word == "Mount"
    time = _numbers(cells["Time"], lines, name, "Time")
    frame = cells["Frame"]
    dead = np.zeros(n, dtype=bool)
    for k in np.flatnonzero(drop[:-1] & mount[1:]).tolist():  # the row after a DROP row, same frame number
        dead[k + 1] = frame[k + 1].strip() == frame[k].strip()
    measured = mount & ~dead
    idx = np.flatnonzero(measured)
    raw = np.full(n, np.nan)
    raw[idx] = _numbers(_pick(cells["RARawDistance"], idx), lines[idx], name, "RARawDistance")
    rows = np.flatnonzero(mount)
    col = _pick(cells["RADuration"], rows)
    dur = _numbers(col if all(col) else [c or "0" for c in col], lines[rows], name, "RADuration")
    col = _pick(cells["RADirection"], rows)
    sign = np.fromiter((_SIGN.get(c, math.nan) for c in col), dtype=float, count=rows.size)
    odd = np.flatnonzero(np.isnan(sign) | ((sign == 0) & (dur != 0)))
    for k in odd.tolist():
        sign[k] = _SIGN.get(col[k].strip(), math.nan)  # a letter with spaces round it
        if math.isnan(sign[k]) or (sign[k] == 0 and dur[k] != 0):
            raise DataError(f"{name}:{lines[rows[k]]}: column RADirection: expected W or E with a pulse of "
                            f"{dur[k]:g} ms, got {col[k].strip()!r}")
    pulse = np.zeros(n)
    pulse[rows] = sign * dur
    return _Frames(time, measured, drop, dead, raw, pulse, lines, _flagged(sec, rest, idx), cut)


def _fast_frames(sec: _Section) -> _Frames | None:
    """:func:`_frames` of a well-formed section, the numbers converted by numpy's C reader (no
    Python object per cell); None when anything is out of the ordinary (the exact path then
    finds it and names the line)."""
    cols, rows = sec.columns, sec.rows
    assert cols is not None  # (the sections read have their column line)
    if not rows or any(c not in cols for c in NEEDED_COLUMNS):
        return None
    need = max(cols[c] for c in NEEDED_COLUMNS) + 1
    if rows[-1].count(",") < need - 1:  # a cut last row
        return None
    drops = [k for k, r in enumerate(rows) if '"Mount"' not in r]
    head = [rows[k].split(",", need) for k in drops]
    if any(len(c) < need or c[cols["mount"]] != '"DROP"' for c in head):
        return None
    n = len(rows)
    mount = np.ones(n, dtype=bool)
    mount[drops] = False
    idx = np.flatnonzero(mount)
    if not idx.size:  # no guide step at all: the exact path (numpy's reader warns on no rows)
        return None
    chosen = rows if not drops else [rows[k] for k in idx.tolist()]
    use = [cols["Time"], cols["RARawDistance"], cols["RADuration"]] + (
        [cols["ErrorCode"]] if "ErrorCode" in cols else [])
    try:
        num = np.loadtxt(chosen, delimiter=",", usecols=use, comments=None, quotechar='"', ndmin=2)
        letters = np.loadtxt(chosen, delimiter=",", usecols=cols["RADirection"], dtype="U8", comments=None,
                             quotechar='"', ndmin=1)
        drop_time = np.array([float(c[cols["Time"]]) for c in head])
    except ValueError:
        return None
    sign = (letters == "W").astype(float) - (letters == "E")
    if (not np.all(np.isfinite(num)) or not np.all(np.isfinite(drop_time)) or num.shape[0] != idx.size
            or np.any((sign == 0) & ((letters != "") | (num[:, 2] != 0)))):
        return None
    time = np.empty(n)
    time[idx] = num[:, 0]
    time[drops] = drop_time
    drop = ~mount
    dead = np.zeros(n, dtype=bool)
    for k, c in zip(drops, head):  # the row after a DROP row with its frame number: dead reckoning
        if k + 1 < n and mount[k + 1]:
            dead[k + 1] = rows[k + 1].split(",", 1)[0].strip() == c[cols["Frame"]].strip()
    measured = mount & ~dead
    raw = np.full(n, np.nan)
    raw[idx] = num[:, 1]
    raw[~measured] = np.nan
    pulse = np.zeros(n)
    pulse[idx] = sign * num[:, 2]
    flagged = 0
    if num.shape[1] > 3:
        code = np.zeros(n)
        code[idx] = num[:, 3]
        flagged = int(np.count_nonzero(code[measured]))
    return _Frames(time, measured, drop, dead, raw, pulse, np.asarray(sec.row_lines, dtype=np.int64), flagged, 0)


def _pick(col: tuple, idx: np.ndarray):
    """The cells of ``col`` at the rows ``idx``."""
    return col if idx.size == len(col) else [col[k] for k in idx.tolist()]


#: longest a guiding section's Time runs [s]: PHD2 counts it from 'Guiding Begins' and starts a log each night
MAX_SECTION_S = 2.0 * 86400.0


#: most rows of a run of corrupt ``Time`` cells told from a clock restart: rows that jumped ahead and
#: then gave way to the clock running on from where it was before them
SPIKE_ROWS = 20


def _check_times(frames: _Frames, name: str) -> None:
    """A DataError at the first row whose ``Time`` is a corrupt cell: beyond :data:`MAX_SECTION_S`; a
    row that steps back while the next runs on from before it (a dip); or up to :data:`SPIKE_ROWS`
    rows that jump ahead, the clock then running on from where it was before them (a spike).  A
    clock that goes back below every earlier row of the section and runs on from there (a frame
    or more) is a restart, split by :func:`_split_restarts`."""
    t = frames.time
    n = t.shape[0]
    bad: tuple[int, str] | None = None
    over = np.flatnonzero(t > MAX_SECTION_S)
    steps = np.diff(t)
    step = float(np.median(steps[steps > 0])) if np.any(steps > 0) else 0.0
    for i in np.flatnonzero(steps < 0).tolist():  # row i + 1 steps back from row i
        if over.size and over[0] < i - SPIKE_ROWS:
            break
        a = float(t[i + 1])
        if i == 0:  # the section's first frame ahead of the rest: no clock restarts after one frame
            bad = (0, f"at most {a:.15g} s (the next row's)")
            break
        if i + 2 < n and t[i + 2] >= t[i]:  # a dip: the clock runs on from before it
            bad = (i + 1, f"between {t[i]:.15g} and {t[i + 2]:.15g} s (the rows around it)")
            break
        below = np.flatnonzero(t[max(0, i - SPIKE_ROWS):i + 1] <= a)
        k = max(0, i - SPIKE_ROWS) + int(below[-1]) if below.size else -1
        # rows k+1 .. i jumped ahead and the clock ran on meanwhile, returning about that many exposures
        # after row k (a restart returns to the section's start instead)
        if k >= 0 and a - t[k] >= 0.5 * (i - k + 1) * step:
            bad = (k + 1, f"between {t[k]:.15g} and {a:.15g} s (the rows around {'it' if k + 1 == i else 'them'})")
            break
    if over.size and (bad is None or over[0] < bad[0]):
        bad = (int(over[0]), f"at most {MAX_SECTION_S:.0f} s (two days) after 'Guiding Begins'")
    if bad is None:
        return
    k, expected = bad
    raise DataError(f"{name}:{int(frames.lines[k])}: column Time: {t[k]:.15g} s, expected {expected}: PHD2's clock "
                    "runs on by about an exposure a row within a section; a corrupt row: correct or delete the line")


def _split_restarts(sec: _Section, frames: _Frames) -> list[_Section]:
    """The section itself, or its parts where ``Time`` goes back (each part a session of its own)."""
    back = np.flatnonzero(frames.time[1:] < frames.time[:-1]) + 1
    if not back.size:
        return [sec]
    bounds = [0, *back.tolist(), len(frames.time)]
    parts = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        last = b == bounds[-1]  # an INFO line between two parts belongs to the later one
        events = [(k - a, line, text) for k, line, text in sec.events if a <= k <= b and (k < b or last)]
        parts.append(_Section(sec.line if a == 0 else int(frames.lines[a]), sec.start if a == 0 else None,
                              sec.header, sec.columns, sec.column_line, sec.rows[a:b], sec.row_lines[a:b], events))
    return parts


# --- lock shifts, pulses and the pulse sign -----------------------------------------------------------------

_NEW_LOCK = re.compile(rf"new lock pos = ({_NUMBER}), ({_NUMBER})")
_DITHER = re.compile(rf"^INFO: DITHER by ({_NUMBER}), ({_NUMBER})")
_SHIFT = re.compile(rf"^INFO: LOCK SHIFT, enabled = (\d)(?:.*\(({_NUMBER}),({_NUMBER})\) px/hr)?")
_MANUAL = re.compile(r"^INFO: Manual guide \(Mount\) (East|West) (\d+) ms")


@dataclass(frozen=True)
class _Events:
    """What a session's INFO lines did: the lock's shift along RA per row [px] (relative to the lock
    at the start), manual RA pulses (rows before each, signed ms), and counts for the notes."""

    shift: np.ndarray
    manual: tuple
    dithers: int
    lock_moves: int
    shifting: bool
    unplaced: tuple  # lines of lock changes that could not be put on the RA axis


def _events(sec: _Section, p: _Params, time: np.ndarray) -> _Events:
    """Lock shifts along RA (dithers, lock-position changes, lock-shift rates) and manual pulses."""
    n = time.shape[0]
    projected = p.x_angle is not None and p.lock is not None
    cx, sy = (math.cos(p.x_angle), math.sin(p.x_angle)) if projected and p.x_angle is not None else (0.0, 0.0)

    def ra(x, y):
        return x * cx + y * sy

    ra0 = ra(*p.lock) if projected and p.lock is not None else 0.0
    segments = [(0, ra0, 0.0, 0.0)]  # (first row, RA of the lock [px], at time [s], RA rate [px/s])
    manual, unplaced = [], []
    dithers = moves = 0
    shifting = False
    for k, line, text in sec.events:
        t = float(time[min(k, n) - 1]) if k > 0 and n else 0.0
        first, base, t0, rate = segments[-1]
        now = base + rate * (t - t0)
        m = _DITHER.match(text)
        dithers += m is not None
        lock = _NEW_LOCK.search(text)
        numbers = [_num(g) for g in (m.groups() if m else ()) + (lock.groups() if lock else ())]
        if None in numbers:  # a damaged line
            unplaced.append(line)
            continue
        if lock is not None:
            if projected:
                target = ra(float(lock.group(1)), float(lock.group(2)))
                moves += m is None and abs(target - now) > 1e-3
                segments.append((k, target, t, rate))
            elif m is not None:  # no calibration angle: the dither's own RA part
                segments.append((k, now + float(m.group(1)), t, rate))
            else:
                unplaced.append(line)
            continue
        m = _SHIFT.match(text)
        if m is not None and m.group(2) is not None and None in (_num(m.group(2)), _num(m.group(3))):
            unplaced.append(line)
            continue
        if m is not None:
            on = m.group(1) == "1" and m.group(2) is not None
            shifting |= on
            new_rate = ra(float(m.group(2)), float(m.group(3))) / 3600.0 if on and projected else 0.0
            if on and not projected:
                unplaced.append(line)
            segments.append((k, now, t, new_rate))
            continue
        m = _MANUAL.match(text)
        if m is not None:
            manual.append((k, (1.0 if m.group(1) == "West" else -1.0) * float(m.group(2))))
    firsts = np.array([s[0] for s in segments])
    which = np.searchsorted(firsts, np.arange(n), side="right") - 1
    seg = np.array([s[1:] for s in segments])
    shift = seg[which, 0] + seg[which, 2] * (time - seg[which, 1]) - ra0
    return _Events(shift, tuple(manual), dithers, moves, shifting, tuple(unplaced))


def _pulses_before(frames: _Frames, manual: tuple) -> np.ndarray:
    """Signed RA pulse time sent before each row [ms] (+ West): the rows' own pulses and manual ones."""
    n = frames.time.shape[0]
    before = np.zeros(n)
    before[1:] = np.cumsum(frames.pulse_ms)[:-1]
    if manual:
        extra = np.zeros(n + 1)
        for k, ms in manual:
            extra[min(k, n)] += ms
        before += np.cumsum(extra)[:n]
    return before


def sign_roughness(base, pulses) -> tuple[float, float, int]:
    """Roughness of the reconstruction with either pulse sign: (R+, R-, number of pulses).

    ``base`` (n,) [px]: the star's offset with the lock shifts added back, measured frames in
    order; ``pulses`` (n,) [px]: the RA correction sent before each frame, cumulated, with the sign
    PHD2 writes.  R+- = sum |diff(base +- pulses)| over the frame-to-frame steps across which a
    pulse was sent (the other steps are the same either way).  With the right sign a step is the
    mount's own change plus seeing; with the wrong one it carries twice the pulse, so the right
    sign gives the smaller sum (the guider's pulses answer the seeing of the frame before, which
    makes the wrong sign rougher still).  The sum of absolute steps (not of squares) keeps a few
    wild frames from deciding.
    """
    d0 = np.diff(np.asarray(base, dtype=float))
    ds = np.diff(np.asarray(pulses, dtype=float))
    hit = ds != 0
    return float(np.abs(d0[hit] + ds[hit]).sum()), float(np.abs(d0[hit] - ds[hit]).sum()), int(hit.sum())


def pulse_sign(plus: float, minus: float, margin: float = SIGN_MARGIN) -> tuple[int, float, bool]:
    """(sign, how much rougher the other sign is (relative), decided by the data) from the
    roughness of :func:`sign_roughness`: +1 (as PHD2 writes the pulses) unless -1 is smoother
    by more than ``margin``; ``decided`` False when the two are within ``margin`` of each other."""
    lo = min(plus, minus)
    if lo <= 0.0 and max(plus, minus) <= 0.0:
        return 1, 0.0, False
    rel = (max(plus, minus) - lo) / lo if lo > 0 else math.inf
    if rel <= margin:
        return 1, rel, False
    return (1 if plus <= minus else -1), rel, True


# --- sessions on the RA axis --------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Session:
    """One session ready to convert: its measured frames' ``time`` [s, section clock], ``base``
    (offset + lock shift) [px] and ``pulses`` (cumulated RA pulses before each, PHD2's sign) [px]."""

    number: int
    sec: _Section
    params: _Params
    frames: _Frames
    events: _Events
    time: np.ndarray
    base: np.ndarray
    pulses: np.ndarray


def _session(number: int, sec: _Section, frames: _Frames, p: _Params) -> _Session:
    ev = _events(sec, p, frames.time)
    before = _pulses_before(frames, ev.manual) / 1000.0 * p.rate
    m = frames.measured
    return _Session(number, sec, p, frames, ev, frames.time[m], frames.raw[m] + ev.shift[m], before[m])


def _axis_angle(p: _Params) -> float | None:
    """The RA axis's angle [rad] from the logged hour angle (+180 deg east of the pier), or None."""
    if p.hour_angle is None:
        return None
    return (15.0 * p.hour_angle + (180.0 if p.pier == "East" else 0.0)) * DEG


def _place(sessions: list[_Session]) -> tuple[list[float], list[float], list[str]]:
    """Start time [s after the first session's start] and start angle [rad] of each session, and
    notes on the sessions placed by their logged hour angle or by neither clock nor hour angle.

    A session starts where the clock puts it (the previous start plus the elapsed time at the
    sidereal rate) unless its logged hour angle differs from that by more than
    :data:`HOUR_ANGLE_TOL_H` (the mount moved: a slew, a re-centring, a meridian flip); then at
    its logged hour angle.  Without a start time (a clock restart) the session continues after the
    previous one."""
    rate = 2.0 * math.pi / SIDEREAL_DAY_S
    times, angles, notes = [], [], []
    for k, s in enumerate(sessions):
        logged = _axis_angle(s.params)
        if k == 0:
            times.append(0.0)
            angles.append(logged if logged is not None else 0.0)
            continue
        prev = sessions[k - 1]
        ref = next((j for j in range(k - 1, -1, -1) if sessions[j].sec.start is not None), None)
        prev_end = times[-1] + float(prev.frames.time[-1]) if prev.frames.time.size else times[-1]
        if s.sec.start is not None and ref is not None:
            ref_start = sessions[ref].sec.start
            assert ref_start is not None  # (ref is a session with a start time)
            t0 = times[ref] + (s.sec.start - ref_start).total_seconds()
            if t0 >= prev_end - 1.0:
                clock = angles[ref] + rate * (t0 - times[ref])
                times.append(t0)
                if logged is not None and abs(_wrap(logged - clock)) > HOUR_ANGLE_TOL_H * 15.0 * DEG:
                    angles.append(clock + _wrap(logged - clock))
                    notes.append(f"session {s.number} starts at its logged hour angle {s.params.hour_angle:+.2f} h"
                                 f"{' (east of the pier)' if s.params.pier == 'East' else ''}: the mount moved since "
                                 f"session {prev.number}")
                else:
                    angles.append(clock)
                continue
        step = float(np.median(np.diff(prev.frames.time))) if prev.frames.time.size > 1 else 1.0
        times.append(prev_end + step)
        angles.append(angles[-1] + rate * (prev_end + step - times[-2]))
        notes.append(f"session {s.number} (line {s.sec.line}) has no start time after the previous session's end: "
                     "placed right after it, its phase on the RA axis unknown")
    return times, angles, notes


def _wrap(a: float) -> float:
    """``a`` [rad] into (-pi, pi]."""
    return -((-a + math.pi) % (2.0 * math.pi) - math.pi)


# --- the reader ---------------------------------------------------------------------------------------------


def _found_sessions(text: str, name: str) -> tuple[list[tuple[_Section, _Frames]], list[str]]:
    """Every session of the log in file order (a section whose clock restarts is split), with
    notes on the restarts and cut rows."""
    if text.startswith("\ufeff"):
        text = text[1:]
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    sections = _scan(text)
    if not sections:
        raise DataError(f"{name}: no guiding frames: expected a PHD2 guide log with 'Guiding Begins at ...' "
                        f"sections and the column line {COLUMN_LINE}dx,dy,RARawDistance,...")
    found, notes = [], []
    for sec in sections:
        frames = _fast_frames(sec) or _frames(sec, name)
        if frames.cut:
            notes.append(f"line {frames.cut}: an incomplete last row of a section left out")
        _check_times(frames, name)
        parts = _split_restarts(sec, frames)
        if len(parts) == 1:
            found.append((sec, frames))
            continue
        for k, part in enumerate(parts):
            if k:
                notes.append(f"line {part.line}: Time starts again without a 'Guiding Begins' line: read as a new "
                             f"session (number {len(found) + 1})")
            found.append((part, _fast_frames(part) or _frames(part, name)))
    return found, notes


def _selected(found: list, opts: GuideLogOptions) -> list[int]:
    """Session numbers to read (1-based)."""
    if not opts.sessions:
        return list(range(1, len(found) + 1))
    out = []
    for k in opts.sessions:
        if k > len(found):
            starts = ", ".join(str(sec.line) for sec, _ in found[:8]) + (", ..." if len(found) > 8 else "")
            raise UsageError(f"--session {k}: the log has {len(found)} session{'s' if len(found) != 1 else ''} "
                             f"(starting at line{'s' if len(found) != 1 else ''} {starts})")
        if k not in out:
            out.append(k)
    return sorted(out)


def read_guidelog(text: str, name: str = "<guide log>", options: GuideLogOptions | None = None) -> Measurement:
    """The RA axis's own error from a PHD2 guide log (see the module doc).

    Parameters
    ----------
    text : str
        The whole log.
    name : str
        How the log is named in messages (its path).
    options : GuideLogOptions or None
        Sessions to read and values the log lacks.

    Returns
    -------
    Measurement
        One row per guide frame with a star: ``angle`` [rad] the RA axis's angle (hour angle,
        +180 deg east of the pier, advancing at the sidereal rate), ``error`` [rad] the axis's
        error (positive: ahead of the sky), ``run`` the session number, ``time`` [s] since the
        first session read began, ``direction`` +1; ``notes`` say what was done, ``warnings``
        what looks wrong.

    Raises
    ------
    DataError
        No guiding frames; a malformed row; a session without pixel scale, declination or RA
        calibration (naming ``--pixel-scale``, ``--dec-deg``, ``--guide-rate``); a declination
        nearer the pole than :data:`MAX_ABS_DEC_DEG`; adaptive-optics rows.
    UsageError
        ``--session`` beyond the sessions in the log.
    """
    opts = options or GuideLogOptions()
    found, notes = _found_sessions(text, name)
    problems, sessions, empty = [], [], []
    for number in _selected(found, opts):
        sec, frames = found[number - 1]
        p, probs = _params(sec, number, opts, name)
        problems += probs
        if p is None:
            continue
        if not frames.measured.any():
            empty.append(number)
            continue
        sessions.append(_session(number, sec, frames, p))
    if problems:
        if sessions:  # some sessions have what they need
            ok = ", ".join(str(s.number) for s in sessions[:5]) + (", ..." if len(sessions) > 5 else "")
            problems.append(f"{name}: session{'s' if len(sessions) > 1 else ''} {ok} can be read as "
                            f"{'they are' if len(sessions) > 1 else 'it is'}: --session {sessions[0].number}")
        raise DataError(problems)
    if sum(s.time.size for s in sessions) < 2:
        raise DataError(f"{name}: fewer than two guide frames with a star in the session"
                        f"{'s' if len(found) != 1 else ''} read; at least two are needed")
    plus = minus = 0.0
    for s in sessions:
        r = sign_roughness(s.base, s.pulses)
        plus, minus = plus + r[0], minus + r[1]
    sign, rel, decided = pulse_sign(plus, minus)
    times, angles, place_notes = _place(sessions)
    angle, error, run, time = [], [], [], []
    for s, t0, a0 in zip(sessions, times, angles):
        p = s.params
        u = s.base + sign * s.pulses
        error.append(-u * (p.scale / math.cos(p.dec * DEG)) * ARCSEC)
        angle.append(a0 + 2.0 * math.pi * s.time / SIDEREAL_DAY_S)
        time.append(t0 + s.time)
        run.append(np.full(s.time.size, s.number, dtype=np.int64))
    warnings = _warnings(sessions, sign, rel, decided, plus + minus > 0)
    notes = (_notes(found, sessions, empty, sign, rel, decided, plus + minus > 0) + place_notes + notes
             + [w for s in sessions for w in _event_notes(s)])
    n = sum(s.time.size for s in sessions)
    col_index = sessions[0].sec.columns
    assert col_index is not None  # (the sections read have their column line)
    return Measurement(
        source=name, angle=np.concatenate(angle), error=np.concatenate(error), direction=np.ones(n),
        run=np.concatenate(run), load=np.zeros(n), temperature=np.full(n, 20.0), time=np.concatenate(time),
        present=frozenset({"run", "time_s"}),
        header=tuple(sorted(col_index, key=col_index.__getitem__)), comments=(),
        notes=tuple(notes), warnings=tuple(warnings), input_format="phd2", run_drift=True,
        columns=(("angle_deg", "Time"), ("error_arcsec", "RARawDistance"), ("run", "Guiding Begins"),
                 ("time_s", "Time")))


def read_phd2(text: str, name: str, options: ReadOptions) -> Measurement:
    """The input format's entry point (:mod:`wormgear_cli.measurement.readers`): :func:`read_guidelog`
    with ``options.guidelog``.  UsageError for the options of tables (``--map``, ``--error-unit``,
    ``--angle-unit``): a guide log's columns and units are PHD2's."""
    table = [o for o, given in (("--map", options.column_map), ("--error-unit", options.error_unit),
                                ("--angle-unit", options.angle_unit)) if given]
    if table:
        raise UsageError(f"{', '.join(table)}: for tables; {name} is a PHD2 guide log, whose columns and units are "
                         "PHD2's (its options: --session, --pixel-scale, --dec-deg, --guide-rate)")
    return read_guidelog(text, name, options.guidelog)


# --- what was done, in words --------------------------------------------------------------------------------


def _rougher(rel: float) -> str:
    return "much rougher" if not math.isfinite(rel) else f"{100 * rel:.0f} % rougher"


def _plural(k: int, word: str, many: str | None = None) -> str:
    return f"{k} {word if k == 1 else (many or word + 's')}"


def _span(values: list[float], fmt: str, unit: str) -> str:
    lo, hi = min(values), max(values)
    return f"{lo:{fmt}}{unit}" if f"{lo:{fmt}}" == f"{hi:{fmt}}" else f"{lo:{fmt}} to {hi:{fmt}}{unit}"


def _notes(found, sessions: list[_Session], empty: list[int], sign: int, rel: float, decided: bool,
           pulsed: bool) -> list[str]:
    """The notes of :func:`read_guidelog`: sessions, frames, conversion, pulse sign, lock shifts."""
    nums = [s.number for s in sessions]
    lines = ", ".join(str(s.sec.line) for s in sessions[:6]) + (", ..." if len(sessions) > 6 else "")
    if len(nums) == len(found):
        out = [f"PHD2 guide log: {_plural(len(nums), 'session')} read as run{'s' if len(nums) > 1 else ''} "
               f"{nums[0]}{f'..{nums[-1]}' if len(nums) > 1 else ''} (line{'s' if len(nums) > 1 else ''} {lines})"]
    else:
        out = [f"PHD2 guide log: session{'s' if len(nums) > 1 else ''} {', '.join(map(str, nums))} of {len(found)} "
               f"read (line{'s' if len(nums) > 1 else ''} {lines}), each a run numbered as its session"]
    if empty:
        out.append(f"session{'s' if len(empty) > 1 else ''} {', '.join(map(str, empty))} without a frame with a "
                   "star: left out")
    fr = [s.frames for s in sessions]
    used, drop, dead = sum(s.time.size for s in sessions), sum(int(f.drop.sum()) for f in fr), sum(
        int(f.dead.sum()) for f in fr)
    text = f"{_plural(used, 'guide frame')} with a star used"
    if drop:
        text += f"; {_plural(drop, 'frame')} without a star (DROP) left out"
    if dead:
        text += f", the {_plural(dead, 'dead-reckoning pulse')} PHD2 sent after them added back"
    flagged = sum(f.flagged for f in fr)
    if flagged:
        text += f"; {_plural(flagged, 'frame')} with a star warning code (ErrorCode not 0) kept, PHD2 guided on them"
    out.append(text)
    p0 = sessions[0].params
    conv = (f"pixels to RA-axis arcsec: pixel scale {p0.scale_how} / cos Dec ({p0.dec_how}); RA pulses added back "
            f"at {p0.rate:.4g} px/s ({p0.rate_how})")
    if len({(s.params.scale, s.params.dec, s.params.rate) for s in sessions}) > 1:
        arcsec_px = '"/px'
        conv += (f"; per session: pixel scale {_span([s.params.scale for s in sessions], 'g', arcsec_px)}, Dec "
                 f"{_span([s.params.dec for s in sessions], 'g', ' deg')}, rate "
                 f"{_span([s.params.rate for s in sessions], '.4g', ' px/s')}")
    out.append(conv)
    if not pulsed:
        out.append("no RA pulses in the sessions read (guide output off?): the star's offsets are the mount's error")
    elif sign > 0:
        out.append("RA pulses added back with the sign PHD2 writes (a West pulse moves the star towards -RA)"
                   + (f": the opposite sign gives a {_rougher(rel)} series" if decided else ""))
    else:
        out.append(f"RA pulses added back with the sign opposite to the W/E letters: PHD2's own sign gives a "
                   f"{_rougher(rel)} series")
    dithers = sum(s.events.dithers for s in sessions)
    moves = sum(s.events.lock_moves for s in sessions)
    shifts = np.concatenate([s.events.shift for s in sessions])
    if dithers or moves:
        what = " and ".join(x for x in (_plural(dithers, "dither") if dithers else "",
                                       _plural(moves, "lock-position change") if moves else "") if x)
        out.append(f"{what}: the lock's shift along RA ({shifts.min():+.2f} to {shifts.max():+.2f} px) added back")
    manual = sum(len(s.events.manual) for s in sessions)
    if manual:
        out.append(f"{_plural(manual, 'manual RA pulse')} added back")
    first = sessions[0].params
    start = (f"starting at the logged hour angle {first.hour_angle:+.2f} h"
             + (" (east of the pier: +180 deg)" if first.pier == "East" else "")
             if first.hour_angle is not None else "starting at 0 (no hour angle in the log)")
    out.append(f"time to RA-axis angle at the sidereal rate (360 deg per {SIDEREAL_DAY_S:.2f} s), {start}")
    return out


def _event_notes(s: _Session) -> list[str]:
    if s.events.shifting:
        return [f"session {s.number}: lock-position shift (tracking a moving target) on: the lock's motion along "
                "RA added back"]
    return []


def _warnings(sessions: list[_Session], sign: int, rel: float, decided: bool, pulsed: bool) -> list[str]:
    """Warnings: lock changes not added back; the pulse sign (reversed letters, no clear answer, a
    session that disagrees)."""
    out = []
    for s in sessions:
        lines = s.events.unplaced
        if lines:
            out.append(f"session {s.number}: lock-position change{'s' if len(lines) > 1 else ''} at line"
                       f"{'s' if len(lines) > 1 else ''} {', '.join(map(str, lines[:3]))}"
                       f"{' and more' if len(lines) > 3 else ''} could not be put on the RA axis (a damaged line, "
                       "or no xAngle or lock position in the session's header): not added back")
    if not pulsed:
        return out
    if sign < 0:
        out.append("the RA pulses move the star the way opposite to their W/E letters (the series is smoother with "
                   "the sign reversed, used here); check the mount's RA direction setting")
    elif not decided:
        out.append(f"the RA pulse sign could not be confirmed from the data (either sign gives a series within "
                   f"{100 * SIGN_MARGIN:.0f} % of the other's roughness): PHD2's sign used")
    for s in sessions:
        plus, minus, count = sign_roughness(s.base, s.pulses)
        own, own_rel, own_decided = pulse_sign(plus, minus)
        if count >= SIGN_MIN_PULSES and own_decided and own != sign and len(sessions) > 1:
            out.append(f"session {s.number} (line {s.sec.line}) alone shows the other pulse sign "
                       f"({100 * own_rel:.0f} % smoother): its RA corrections may not have moved the mount as logged")
    return out
