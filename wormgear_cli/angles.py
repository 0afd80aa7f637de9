"""Angles that carry their unit: :class:`Angle` (one value) and :class:`AngleArray` (many).

Every angle of the core is a float in radians; these two types wrap such
values for the Python API (:mod:`wormgear_cli.api`) so a result never has
to be read together with a separate ``unit`` argument.

Conventions (decided once, documented in docs/api.md):

* The stored value is in radians: ``float(angle)`` and
  ``numpy.asarray(angles)`` give radians, like every core function takes.
* Read a value in a unit with an attribute (``.rad``, ``.deg``,
  ``.arcmin``, ``.arcsec``, ``.urad``) or ``.to(unit)``; the units and
  their factors are :data:`wormgear_cli.units.RAD_PER_UNIT` (no second
  definition).
* Comparisons are between angles only: ``Angle < Angle`` works,
  ``Angle < 50`` raises TypeError (50 what?) and ``Angle == 50`` is False.
* Arithmetic keeps the unit where it is meaningful: angle +/- angle,
  angle * number, angle / number give angles; angle / angle gives a float.
* The repr shows arcsec, 4 significant digits (``Angle(53.08 arcsec)``):
  readable, not exact; use ``.rad`` for the exact value.
* In f-strings the format spec applies to the number and the unit follows:
  ``f"{a:.2f}"`` gives ``53.59 arcsec``, ``f"{a:.4f deg}"`` ``0.0149 deg``.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from wormgear_cli.units import RAD_PER_UNIT

#: unit shown by repr and str
DISPLAY_UNIT = "arcsec"


def _factor(unit: str) -> float:
    try:
        return RAD_PER_UNIT[unit]
    except KeyError:
        raise ValueError(f"unknown angle unit {unit!r}, expected one of {', '.join(RAD_PER_UNIT)}") from None


class Angle:
    """One angle.

    Parameters
    ----------
    value : float
        The angle in ``unit``.
    unit : str
        One of ``rad``, ``deg``, ``arcmin``, ``arcsec``, ``urad`` (default ``rad``).

    Raises
    ------
    ValueError
        Unknown unit.

    Examples
    --------
    >>> a = Angle(90, "arcmin")
    >>> a.deg
    1.5
    >>> a
    Angle(5400 arcsec)
    >>> round(a.to("urad"), 3)
    26179.939
    >>> Angle(1, "deg") > Angle(59, "arcmin")
    True
    """

    __slots__ = ("_rad",)

    def __init__(self, value: float, unit: str = "rad"):
        self._rad = float(value) * _factor(unit)

    # --- values in units ---------------------------------------------------------------------------------------
    @property
    def rad(self) -> float:
        """The angle [rad]."""
        return self._rad

    @property
    def deg(self) -> float:
        """The angle [deg]."""
        return self._rad / RAD_PER_UNIT["deg"]

    @property
    def arcmin(self) -> float:
        """The angle [arcmin]."""
        return self._rad / RAD_PER_UNIT["arcmin"]

    @property
    def arcsec(self) -> float:
        """The angle [arcsec]."""
        return self._rad / RAD_PER_UNIT["arcsec"]

    @property
    def mrad(self) -> float:
        """The angle [mrad]."""
        return self._rad / RAD_PER_UNIT["mrad"]

    @property
    def urad(self) -> float:
        """The angle [urad]."""
        return self._rad / RAD_PER_UNIT["urad"]

    def to(self, unit: str) -> float:
        """The angle as a float in ``unit`` (rad, deg, arcmin, arcsec, urad)."""
        return self._rad / _factor(unit)

    # --- conversions -------------------------------------------------------------------------------------------
    def __float__(self) -> float:
        return self._rad

    def __repr__(self) -> str:
        return f"Angle({self.to(DISPLAY_UNIT):.4g} {DISPLAY_UNIT})"

    def __str__(self) -> str:
        return f"{self.to(DISPLAY_UNIT):.4g} {DISPLAY_UNIT}"

    def __format__(self, spec: str) -> str:
        """f-strings: ``f"{a:.2f}"`` is ``53.59 arcsec``; a unit ends the spec to choose another
        (``f"{a:.4f deg}"`` is ``0.0149 deg``, ``f"{a:urad}"`` is ``259.8 urad``).  The number is
        formatted as a float with the rest of the spec (``.4g`` when empty); the unit always
        follows it, so a value is never printed without its unit."""
        head, _, last = spec.rpartition(" ") if " " in spec else ("", "", spec)
        if last in RAD_PER_UNIT:
            number, unit = head, last
        elif head:
            raise ValueError(f"format spec {spec!r}: unknown angle unit {last!r}, expected one of "
                             f"{', '.join(RAD_PER_UNIT)}")
        else:
            number, unit = spec, DISPLAY_UNIT
        return f"{format(self.to(unit), number or '.4g')} {unit}"

    def __hash__(self) -> int:
        return hash(("Angle", self._rad))

    def __bool__(self) -> bool:
        return self._rad != 0.0

    # --- comparisons: with angles only --------------------------------------------------------------------------
    def __eq__(self, other):
        if isinstance(other, Angle):
            return self._rad == other._rad
        return NotImplemented

    def _other(self, other) -> float:
        if isinstance(other, Angle):
            return other._rad
        raise TypeError(f"an Angle compares with an Angle, not {type(other).__name__}; "
                        "write e.g. Angle(50, 'arcsec') or compare angle.arcsec")

    def __lt__(self, other):
        return self._rad < self._other(other)

    def __le__(self, other):
        return self._rad <= self._other(other)

    def __gt__(self, other):
        return self._rad > self._other(other)

    def __ge__(self, other):
        return self._rad >= self._other(other)

    def isclose(self, other: Angle, rel: float = 1e-9, abs_rad: float = 0.0) -> bool:
        """``math.isclose`` on the two values [rad]."""
        return math.isclose(self._rad, self._other(other), rel_tol=rel, abs_tol=abs_rad)

    # --- arithmetic ---------------------------------------------------------------------------------------------
    def __add__(self, other):
        return Angle(self._rad + self._other(other)) if isinstance(other, Angle) else NotImplemented

    def __sub__(self, other):
        return Angle(self._rad - self._other(other)) if isinstance(other, Angle) else NotImplemented

    def __mul__(self, k):
        return Angle(self._rad * float(k)) if isinstance(k, numbers.Real) else NotImplemented

    __rmul__ = __mul__

    def __truediv__(self, other):
        if isinstance(other, Angle):
            return self._rad / other._rad
        return Angle(self._rad / float(other)) if isinstance(other, numbers.Real) else NotImplemented

    def __neg__(self):
        return Angle(-self._rad)

    def __abs__(self):
        return Angle(abs(self._rad))


class AngleArray:
    """Many angles: a numpy array [rad] with its unit attached.

    Indexing with an integer gives an :class:`Angle`, with a slice or mask an
    :class:`AngleArray`; ``numpy.asarray(a)`` gives the values [rad].
    ``min``, ``max``, ``mean``, ``ptp`` and ``rms`` give angles.

    Parameters
    ----------
    values : array_like
        The angles in ``unit``.
    unit : str
        As for :class:`Angle` (default ``rad``).

    Examples
    --------
    >>> a = AngleArray([10.0, -20.0, 30.0], "arcsec")
    >>> a.max()
    Angle(30 arcsec)
    >>> a.ptp().arcsec
    50.0
    >>> a.arcsec.tolist()
    [10.0, -20.0, 30.0]
    >>> len(a), a[1]
    (3, Angle(-20 arcsec))
    """

    __slots__ = ("_rad",)

    def __init__(self, values, unit: str = "rad"):
        self._rad = np.asarray(values, dtype=float) * _factor(unit)

    @property
    def rad(self) -> np.ndarray:
        """The angles [rad]."""
        return self._rad

    @property
    def deg(self) -> np.ndarray:
        """The angles [deg]."""
        return self.to("deg")

    @property
    def arcmin(self) -> np.ndarray:
        """The angles [arcmin]."""
        return self.to("arcmin")

    @property
    def arcsec(self) -> np.ndarray:
        """The angles [arcsec]."""
        return self.to("arcsec")

    @property
    def urad(self) -> np.ndarray:
        """The angles [urad]."""
        return self.to("urad")

    def to(self, unit: str) -> np.ndarray:
        """The angles as a float array in ``unit``."""
        return self._rad / _factor(unit)

    @property
    def shape(self) -> tuple:
        return self._rad.shape

    def __len__(self) -> int:
        return len(self._rad)

    def __getitem__(self, index):
        v = self._rad[index]
        return Angle(float(v)) if np.ndim(v) == 0 else AngleArray(v)

    def __iter__(self):
        return (Angle(float(v)) for v in self._rad.ravel())

    def __array__(self, dtype=None, copy=None):
        return self._rad if dtype is None else self._rad.astype(dtype)

    def __eq__(self, other):
        if isinstance(other, AngleArray):
            return bool(np.array_equal(self._rad, other._rad))
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]  # arrays compare by value and are not hashable

    def min(self) -> Angle:
        """Smallest angle."""
        return Angle(float(np.min(self._rad)))

    def max(self) -> Angle:
        """Largest angle."""
        return Angle(float(np.max(self._rad)))

    def mean(self) -> Angle:
        """Arithmetic mean."""
        return Angle(float(np.mean(self._rad)))

    def ptp(self) -> Angle:
        """Peak to peak: max - min."""
        return Angle(float(np.ptp(self._rad)))

    def rms(self) -> Angle:
        """Root mean square."""
        return Angle(float(np.sqrt(np.mean(self._rad * self._rad))))

    def __repr__(self) -> str:
        v = self.to(DISPLAY_UNIT).ravel()
        body = ", ".join(f"{x:.4g}" for x in v[:4]) + (", ..." if v.size > 4 else "")
        shape = "" if self._rad.ndim == 1 else f", shape={self._rad.shape}"
        return f"AngleArray([{body}] {DISPLAY_UNIT}, n={self._rad.size}{shape})"
