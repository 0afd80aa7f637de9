"""The guide-log parts of ``measure``: the worm period, the periodic error as astronomers quote it, the
sessions, the parts of the mount each strong period belongs to, and the verdict line.

A PHD2 guide log (:mod:`wormgear_cli.measurement.guidelog`) is the RA axis's error at every guide
frame, each session a run with an offset and a drift of its own.  Its figure of merit is the periodic
error (PE): the peak-to-peak range of the error over one worm cycle with the drift removed
(:func:`~wormgear_cli.measurement.periodic_error.periodic_error`).  The worm's order (cycles per RA
turn) comes from the mount's drive spec (``--drive``: the worm shaft's turns per output turn, the
wheel's teeth over the worm's starts) or, without one, from the strongest period found
(:func:`~wormgear_cli.measurement.dominant.dominant_orders`).  The drive's other shafts and meshes
(a motor gear, a belt) that the frames resolve are fitted alongside so they do not leak into the
worm's curve; without a drive, the other significant periods found are.

ISO 230-2 figures do not apply (no target is visited twice: every frame is at its own angle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from wormgear_cli.measurement.guidelog_options import ISO_NOT_APPLICABLE, is_guide_log  # noqa: F401 (re-exported)
from wormgear_cli.units import SIDEREAL_DAY_S

if TYPE_CHECKING:  # the record's type only: the module itself is imported where it is used
    from wormgear_cli.measurement.periodic_error import PeriodicError

#: worm harmonics of the periodic error (the worm order and its next three multiples)
PE_HARMONICS = 4
#: points of the smoothed curve over one worm period in the document
CURVE_POINTS = 120
@dataclass(frozen=True)
class MountParts:
    """What a drive spec says about a mount: ``worm`` (order, label) of its (last) worm shaft or None,
    ``wheel_teeth`` and ``starts`` of that worm stage, and ``parts``: (order, label) of every shaft
    and mesh (:func:`wormgear_cli.drive.train.orders`, fundamentals only)."""

    worm: tuple | None
    wheel_teeth: int | None
    starts: int | None
    parts: tuple


def mount_parts(spec) -> MountParts:
    """The :class:`MountParts` of a loaded drive spec."""
    from wormgear_cli.drive.train import of, orders, shaft_label  # lazy: keeps drive.train off `measure`'s start-up

    t = of(spec)
    worms = [s for s in t.stages if s.kind == "worm"]
    parts = tuple((float(o.order), o.label) for o in orders(t))
    if not worms:
        return MountParts(None, None, None, parts)
    w = worms[-1]
    return MountParts((float(t.before(w)), shaft_label(t, w.index - 1)), int(w.wheel.teeth), int(w.worm.starts),
                      parts)


@dataclass(frozen=True)
class Session:
    """One session (run) of a guide log as the periodic error sees it: ``number``, ``frames``,
    ``start_s`` [s since the first session], ``duration_s``, ``start_angle`` [rad, RA axis],
    ``drift_p2p`` (peak to peak of its fitted offset-free drift) and ``rms_detrended`` (its error
    with the drift removed, RMS) [rad]."""

    number: int
    frames: int
    start_s: float
    duration_s: float
    start_angle: float
    drift_p2p: float
    rms_detrended: float


@dataclass(frozen=True)
class GuideResult:
    """The periodic error of a guide log (:func:`guide_periodic_error`).

    ``periodic``: the :class:`~wormgear_cli.measurement.periodic_error.PeriodicError` (angles in
    rad) or None (then ``note`` says why); ``worm_from``: where the worm order came from (a sentence);
    ``worm_label``: the drive's name for the worm shaft (None without a drive); ``extra``: (order,
    label or None) of each order fitted alongside; ``sessions``: tuple of :class:`Session`."""

    periodic: PeriodicError | None
    worm_from: str
    worm_label: str | None
    extra: tuple
    sessions: tuple
    note: str = ""


def _resolvable(order: float, longest: float, nyquist: float) -> bool:
    """Whether ``order`` [cycles/rev] has at least one period over the longest run [rad] and lies below
    the Nyquist limit of the frames."""
    return order * longest >= 2.0 * math.pi and order <= nyquist


def guide_periodic_error(m, dominant, mount: MountParts | None = None,
                         harmonics: int = PE_HARMONICS, orders=None) -> GuideResult:
    """The periodic error of the guide log ``m`` (a :class:`~wormgear_cli.measurement.reader.Measurement`).

    ``dominant``: its :class:`~wormgear_cli.measurement.dominant.Dominant` (scanned with a drift per
    run); ``mount``: the :class:`MountParts` of ``--drive`` (None: the worm order is the lowest of
    ``orders`` (``--orders``) the sessions resolve, else the strongest period found).  The worm
    harmonics are the first ``harmonics`` multiples below the Nyquist limit."""
    # lazy: keeps measurement.periodic_error off `measure`'s start-up
    from wormgear_cli.measurement.periodic_error import periodic_error

    nyquist = dominant.nyquist if dominant is not None and math.isfinite(dominant.nyquist) else math.inf
    longest = longest_run(m.angle, m.run)
    label = None
    if mount is not None and mount.worm is not None:
        order, label = mount.worm
        starts = "" if mount.starts == 1 else f" / {mount.starts} starts"
        worm_from = f"the drive's worm ({mount.wheel_teeth}-tooth wheel{starts})"
    elif orders and any(_resolvable(k, longest / 2.0, nyquist) for k in orders):
        # two periods in a session at least: one period beside a session's cubic drift is not a curve
        order = min(k for k in orders if _resolvable(k, longest / 2.0, nyquist))
        worm_from = "the lowest of the orders asked for with two periods in a session"
    elif dominant is not None and dominant.significant:
        order = dominant.significant[0].order
        worm_from = "the strongest period found" + (" (the drive has no worm)" if mount is not None else
                                                    " (give the mount with --drive for the wheel's tooth count)")
    else:
        why = "no period stands out of the noise" if dominant is not None and dominant.peaks else "nothing to scan"
        return GuideResult(None, "", None, (), (), f"no periodic error: {why} and no drive spec names the worm")
    if not _resolvable(order, longest, nyquist):
        return GuideResult(None, worm_from, label, (), (),
                           f"no periodic error: the worm's period ({SIDEREAL_DAY_S / order:.4g} s) is longer than the "
                           "longest session" if order * longest < 2 * math.pi else
                           "no periodic error: the worm's period is shorter than two frames")
    h = max(1, min(harmonics, int(math.floor(nyquist / order + 1e-9))))
    extra = _extra_orders(order, h, mount, dominant, longest, nyquist)
    pe = periodic_error(m.angle, m.error, order, time=m.time, run=m.run, harmonics=h,
                        extra_orders=[k for k, _ in extra], axis_period_s=SIDEREAL_DAY_S)
    kept = [(k, lab) for k, lab in extra if np.any(np.abs(pe.orders[h:] - k) <= 1e-9 * k)]
    return GuideResult(pe, worm_from, label, tuple(kept), _sessions(m, pe))


def _extra_orders(order: float, h: int, mount: MountParts | None, dominant, longest: float,
                  nyquist: float) -> list:
    """(order, label) fitted beside the worm: the drive's other shafts and meshes the frames resolve, or,
    without a drive, the other significant periods found (neither near a worm harmonic)."""
    worm = order * np.arange(1, h + 1)
    if mount is not None:
        cands = [(k, lab) for k, lab in mount.parts]
        near = 1e-9
    else:
        cands = [(p.order, None) for p in (dominant.significant if dominant is not None else ())]
        near = dominant.resolution / 2.0 if dominant is not None else 1e-9
    out: list = []
    for k, lab in cands:
        tol = near * (k if mount is not None else 1.0)
        if np.any(np.abs(worm - k) <= max(tol, 1e-9 * k)) or any(abs(k - o) <= max(tol, 1e-9 * k) for o, _ in out):
            continue
        if _resolvable(k, longest, nyquist):
            out.append((float(k), lab))
    return out


def longest_run(angle: np.ndarray, run: np.ndarray) -> float:
    """The longest run's span of the RA axis [rad] (``angle`` [rad] and ``run`` per row)."""
    keys = np.unique(run, return_inverse=True)[1].reshape(-1)
    lo = np.full(int(keys.max()) + 1, np.inf)
    hi = np.full(lo.shape, -np.inf)
    np.minimum.at(lo, keys, angle)
    np.maximum.at(hi, keys, angle)
    return float(np.max(hi - lo))


def _sessions(m, pe) -> tuple:
    """The :class:`Session` of every run, in file order."""
    out = []
    numbers, first = np.unique(m.run, return_index=True)
    for number in numbers[np.argsort(first)]:
        rows = m.run == number
        t = m.time[rows]
        drift = pe.drift[rows]
        detrended = m.error[rows] - drift
        out.append(Session(int(number), int(rows.sum()), float(t.min()), float(np.ptp(t)),
                           float(m.angle[rows][np.argmin(t)]), float(np.ptp(drift)),
                           float(np.sqrt(np.mean(detrended ** 2)))))
    return tuple(out)


def guide_verdict(m, guide: GuideResult | None) -> str:
    """The verdict line's head for a guide log: sessions, frames, time and RA-axis span, worm cycles."""
    runs = len(np.unique(m.run))
    minutes = sum(float(np.ptp(m.time[m.run == r])) for r in np.unique(m.run)) / 60.0
    span = sum(float(np.ptp(m.angle[m.run == r])) for r in np.unique(m.run))
    head = (f"{m.source}: PHD2 guide log, {runs} session{'s' if runs != 1 else ''}, {len(m)} frames over "
            f"{minutes:.4g} min ({math.degrees(span):.4g} deg of the RA axis")
    pe = None if guide is None else guide.periodic
    if pe is not None:
        head += f", {pe.cycles:.3g} worm cycles"
    return head + ")"


def guide_doc(guide: GuideResult | None, a) -> dict | None:
    """The ``periodic_error`` section of measure's document (angles through ``a``: rad -> the unit)."""
    if guide is None:
        return None
    if guide.periodic is None:
        return {"note": guide.note, "worm_order": None}
    pe = guide.periodic
    h = pe.harmonics
    step = max(1, pe.curve.shape[0] // CURVE_POINTS)

    def entry(i: int, label) -> dict:
        k = float(pe.orders[i])
        return {"order": k, "period_s": SIDEREAL_DAY_S / k, "label": label, "amplitude": a(pe.amplitude[i]),
                "amplitude_stderr": a(pe.amplitude_stderr[i]), "phase_deg": math.degrees(pe.phase[i]),
                "identifiable": bool(pe.identifiable[i])}

    return {
        "note": guide.note,
        "worm_order": pe.order,
        "worm_period_s": pe.period_s,
        "worm_from": guide.worm_from,
        "worm_label": guide.worm_label,
        "cycles": pe.cycles,
        "peak_to_peak": a(pe.peak_to_peak),
        "method": (f"least squares on every frame: the worm order and {h - 1} harmonic{'s' if h != 2 else ''}, the "
                   "orders fitted alongside, and per session an offset and a drift (a cubic in time); peak to peak "
                   "of the fitted worm harmonics over one worm period"),
        "standard_errors": pe.standard_errors,
        "rms": {"raw": a(pe.rms_raw), "drift_removed": a(pe.rms_detrended),
                "worm_removed": a(pe.rms_without_worm), "residual": a(pe.rms_residual)},
        "harmonics": [dict(entry(i, None), harmonic=i + 1) for i in range(h)],
        "fitted_alongside": [entry(h + j, lab) for j, (_, lab) in enumerate(guide.extra)],
        "curve": {"phase": pe.curve_phase[::step].tolist(),
                  "time_s": (pe.curve_phase[::step] * pe.period_s).tolist(),
                  "error": [a(x) for x in pe.curve[::step]]},
        "sessions": [{"session": s.number, "frames": s.frames, "start_s": s.start_s, "duration_s": s.duration_s,
                      "start_angle_deg": math.degrees(s.start_angle), "drift_peak_to_peak": a(s.drift_p2p),
                      "rms_drift_removed": a(s.rms_detrended)} for s in guide.sessions],
    }
