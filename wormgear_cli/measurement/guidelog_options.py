"""What a PHD2 guide log may leave out, and which of its sessions to read: :class:`GuideLogOptions`.

A module of its own so that the reading options of every input format
(:class:`~wormgear_cli.measurement.reader.ReadOptions`) can carry it without importing the reader
(:mod:`wormgear_cli.measurement.guidelog`), which imports the record module.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wormgear_cli.errors import UsageError

#: the name of the input format of PHD2 guide logs (:data:`wormgear_cli.measurement.readers.FORMATS`)
GUIDE_FORMAT = "phd2"
#: the one sentence on ISO 230-2 for a guide log
ISO_NOT_APPLICABLE = ("ISO 230-2 figures are not applicable to a guide log: every frame is at its own angle, no "
                      "target is visited twice; the periodic error is the mount's figure")


def is_guide_log(m) -> bool:
    """Whether the measurement ``m`` was read from a PHD2 guide log (ISO 230-2 and the checks of
    targets and directions do not apply to it)."""
    return getattr(m, "input_format", "") == GUIDE_FORMAT


@dataclass(frozen=True)
class GuideLogOptions:
    """What a guide log may leave out, and which sessions to read (the CLI's option names in brackets).

    Parameters
    ----------
    sessions : tuple of int (or one int)
        Sessions to read, numbered from 1 in file order (``--session N``); empty: all.
    pixel_scale : float or None
        Guide-camera pixel scale [arcsec/px] (``--pixel-scale``); wins over the log's.
    dec_deg : float or None
        Declination guided on [deg] (``--dec-deg``); wins over the log's.
    guide_rate : float or None
        RA guide rate [arcsec of RA axis per second of pulse, i.e. sky arcsec/s at the equator]
        (``--guide-rate``); wins over the log's calibration.

    Raises
    ------
    UsageError
        A value out of range (naming the option).
    """

    sessions: tuple[int, ...] = ()
    pixel_scale: float | None = None
    dec_deg: float | None = None
    guide_rate: float | None = None

    def __post_init__(self):
        if isinstance(self.sessions, (int, np.integer)) and not isinstance(self.sessions, bool):
            object.__setattr__(self, "sessions", (int(self.sessions),))  # one session given as a number
        else:
            object.__setattr__(self, "sessions", tuple(self.sessions))
        problems = []
        for k in self.sessions:
            if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
                problems.append(f"--session {k}: expected a session number, 1 for the first")
        for value, option, what in ((self.pixel_scale, "--pixel-scale", "arc-seconds per pixel"),
                                    (self.guide_rate, "--guide-rate", "arc-seconds per second")):
            if value is not None and not (math.isfinite(value) and value > 0):
                problems.append(f"{option} {value}: expected a positive number of {what}")
        if self.dec_deg is not None and not (math.isfinite(self.dec_deg) and abs(self.dec_deg) <= 90.0):
            problems.append(f"--dec-deg {self.dec_deg}: expected a declination in [-90, 90] degrees")
        if problems:
            raise UsageError(problems)

    @property
    def given(self) -> tuple[str, ...]:
        """The options set (as the CLI names them), in the CLI's order."""
        return tuple(name for name, value in (("--session", self.sessions), ("--pixel-scale", self.pixel_scale),
                                              ("--dec-deg", self.dec_deg), ("--guide-rate", self.guide_rate))
                     if value not in ((), None))
