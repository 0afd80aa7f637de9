"""Angle units.  Internally every angle is in radians.

1 arcsec = pi / 648000 rad = 4.8481 urad.  The paper's constant 6.875
converts a micrometre of arc on a pitch circle of diameter m*z millimetres
into arcminutes: 6.875 = 2 * (180*60/pi) / 1000.
"""

from __future__ import annotations

import math

#: radians per one unit
RAD_PER_UNIT: dict[str, float] = {
    "rad": 1.0,
    "deg": math.pi / 180.0,
    "arcmin": math.pi / (180.0 * 60.0),
    "arcsec": math.pi / (180.0 * 3600.0),
    "mrad": 1e-3,
    "urad": 1e-6,
}

#: one second of arc [rad]
ARCSEC = RAD_PER_UNIT["arcsec"]
#: radians per degree
DEG = RAD_PER_UNIT["deg"]

#: units offered on the command line (``--unit``)
ANGLE_UNITS = ("deg", "arcmin", "arcsec", "urad")

#: the paper's constant: arcmin per (um / (mm * teeth)); 2*180*60/(pi*1000)
PAPER_ARCMIN_CONSTANT = 2.0 * 180.0 * 60.0 / (math.pi * 1000.0)


def to_unit(value_rad, unit: str):
    """Convert an angle [rad] (scalar or array) to ``unit``."""
    return value_rad / RAD_PER_UNIT[unit]


def from_unit(value, unit: str):
    """Convert an angle in ``unit`` to [rad]."""
    return value * RAD_PER_UNIT[unit]


#: one sidereal day [s]: the time an equatorial mount's RA axis takes to turn once while tracking the stars
#: (23 h 56 min 4.0905 s; a worm of z teeth on the RA wheel turns in SIDEREAL_DAY_S / z)
SIDEREAL_DAY_S = 86164.0905
