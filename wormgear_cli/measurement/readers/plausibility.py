"""Whether the sizes read fit the units used: advice where a unit was assumed, never against one the
file states.

A unit is *stated* when the header says it (``error (deg)``), an instrument's unit row gives it, an
option names it, or the error is formed from stated positions (actual - target).  A stated unit is
never argued against: a faulty resolver really is off by degrees.  Where the unit was assumed (the
canonical ``error_arcsec`` with no option), an error whose peak-to-peak lies outside
:data:`PLAUSIBLE_ERROR_P2P` gets the unit that would bring it inside.  Either way an error beyond the
usual size is said once, in the same words whatever its size (6 deg and 19 deg alike).  Pure numpy.
"""

from __future__ import annotations

import numpy as np

from wormgear_cli.measurement.reader import ERROR_UNITS
from wormgear_cli.units import RAD_PER_UNIT

#: peak-to-peak error that a positioning measurement plausibly has [arcsec]: 0.05" .. 2 deg
PLAUSIBLE_ERROR_P2P = (0.05, 7200.0)


def _p2p_text(p2p_arcsec: float) -> str:
    deg = p2p_arcsec / 3600.0
    return f"{p2p_arcsec:.6g} arcsec ({deg:.4g} deg)" if deg >= 0.1 else f"{p2p_arcsec:.4g} arcsec"


def plausibility(angle: np.ndarray, error: np.ndarray, angle_unit: str, error_unit: str, has_error: bool,
                 error_stated: bool = False, angle_stated: bool = False) -> list[str]:
    """Warnings when the sizes suggest the columns are in another unit than the one assumed.

    Parameters
    ----------
    angle, error : ndarray [rad], shape (n,)
        As read (converted with ``angle_unit`` / ``error_unit``).
    angle_unit, error_unit : str
        The units used.
    has_error : bool
        Whether the file had an error column.
    error_stated, angle_stated : bool
        Whether the error's / the angle's unit is stated (then no unit is proposed for it; see
        :func:`size_note`).

    Returns
    -------
    list of str
        One sentence per suspicion with the likely fix: an assumed error unit whose peak-to-peak lies
        outside :data:`PLAUSIBLE_ERROR_P2P` when a different unit of :data:`ERROR_UNITS` would bring it
        inside (e.g. degrees or radians read as arcsec); angles read in degrees that all lie within
        +/-2 pi and spread over more than 1 "degree" with at least 8 distinct values (radians read as
        degrees); assumed degrees that are all whole numbers, at least 8 distinct, the largest above 720
        (encoder counts read as degrees).
    """
    out = []
    arc = RAD_PER_UNIT["arcsec"]
    if has_error and error.size and not error_stated:
        p2p = float(np.ptp(error)) / arc
        lo, hi = PLAUSIBLE_ERROR_P2P
        if p2p > 0 and not lo <= p2p <= hi:
            raw = p2p * arc / RAD_PER_UNIT[error_unit]
            fits = [(abs(np.log(raw * RAD_PER_UNIT[u] / arc / 20.0)), u) for u in ERROR_UNITS
                    if u != error_unit and lo <= raw * RAD_PER_UNIT[u] / arc <= hi]
            if fits:
                u = min(fits)[1]
                fix = f"--error-unit {u}"
                out.append(f"the errors span {p2p:.4g} arcsec peak to peak read as {error_unit}, implausible for a "
                           f"positioning error; if the column is in {u}, use {fix}")
    if angle_unit == "deg" and angle.size and not angle_stated:
        out += _angle_warnings(angle)
    return out


#: rows looked at a time (the checks hold no copy of a column)
_BLOCK = 1 << 16


def _distinct_at_least(angle: np.ndarray, k: int, of) -> bool:
    """Whether ``of(angle)`` has at least ``k`` distinct values (judged block by block, stopping early)."""
    seen = np.empty(0)
    for a in range(0, angle.shape[0], _BLOCK):
        seen = np.unique(np.concatenate([seen, of(angle[a:a + _BLOCK])]))
        if seen.size >= k:
            return True
    return False


def _angle_warnings(angle: np.ndarray) -> list[str]:
    """Radians or encoder counts read as degrees (see :func:`plausibility`); the figures of the whole
    column in degrees without a copy of it (degrees are monotone: the extremes are the extremes')."""
    out = []
    lo, hi = float(np.degrees(angle.min())), float(np.degrees(angle.max()))
    top, span = max(abs(lo), abs(hi)), hi - lo
    if top <= 2 * np.pi + 1e-9 and span > 1.0 and _distinct_at_least(angle, 8, np.degrees):
        out.append(f"the angles all lie within +/-2 pi and span {span:.3g} deg: if they are "
                   "radians, use --angle-unit rad")

    def whole(a):
        deg = np.degrees(a)
        return np.round(deg)

    if top > 720.0 and all(np.all(np.abs(np.degrees(angle[a:a + _BLOCK]) - whole(angle[a:a + _BLOCK])) < 1e-9)
                           for a in range(0, angle.shape[0], _BLOCK)) and _distinct_at_least(angle, 8, whole):
        out.append(f"the angles are whole numbers from {lo:.0f} to {hi:.0f} read as "
                   "degrees: if they are encoder counts, convert them to degrees (counts x 360 / counts per "
                   "turn); the tool does not read counts")
    return out


def size_note(error: np.ndarray, error_unit: str, how: str) -> str | None:
    """A sentence when a stated error unit gives an error beyond the usual size of a positioning error
    (above :data:`PLAUSIBLE_ERROR_P2P`), else None.  ``how``: how the unit is stated ("as the header
    states", ...).  The same words for every size: the data are taken as stated."""
    if not error.size:
        return None
    p2p = float(np.ptp(error)) / RAD_PER_UNIT["arcsec"]
    if p2p <= PLAUSIBLE_ERROR_P2P[1]:
        return None
    return (f"the errors span {_p2p_text(p2p)} peak to peak, far beyond a positioning error's usual size; read in "
            f"{error_unit} {how} (a faulty encoder or resolver, or a reading lag, can be off by degrees)")
