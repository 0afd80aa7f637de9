"""A correction table: the model evaluated at evenly spaced points, and how a controller applies it.

A controller such as LinuxCNC keeps one correction per table point and direction, interpolates
linearly between points and holds the end values outside the table (no wrap at 360 deg).  The
correction is added to the commanded position, so it is minus the error.  A table of N points
over a range R has a spacing R / (N - 1); an order whose period 360 / k deg spans fewer than
:data:`MIN_SPACINGS` spacings cannot be carried: its samples would trace a slower alias and add
error instead of removing it (256 points over 360 deg cannot correct a worm order of 240), so
such orders are left out of the table and said so.  Pure numpy.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from wormgear_cli.errors import UsageError

#: an order is carried when its period spans at least this many table spacings
MIN_SPACINGS = 4.0
#: decimals of the table angles [deg] (1e-6 deg = 0.0036 arcsec)
ANGLE_DECIMALS = 6
#: evaluation points per table interval when the interpolation loss is measured
LOSS_POINTS_PER_INTERVAL = 16
#: most points of a table (a bound on memory and file size)
MAX_POINTS = 1_000_000


@dataclass(frozen=True)
class TableGrid:
    """Where a table has its points: ``points`` evenly spaced from ``start_deg`` to
    ``end_deg`` [deg], both ends included."""

    points: int
    start_deg: float = 0.0
    end_deg: float = 360.0

    def check(self, most: int | None = None, option: str = "--points") -> None:
        """UsageError unless 2 <= points <= ``most`` and start < end (finite)."""
        most = MAX_POINTS if most is None else most
        if not 2 <= self.points <= most:
            raise UsageError(f"{option}: expected an integer in [2, {most}], got {self.points}")
        if not (math.isfinite(self.start_deg) and math.isfinite(self.end_deg) and self.start_deg < self.end_deg):
            raise UsageError(f"--range: expected START:END in deg with START < END, got "
                             f"{self.start_deg:g}:{self.end_deg:g}")
        if abs(self.start_deg) > 1e6 or abs(self.end_deg) > 1e6:
            raise UsageError("--range: the ends must lie within +/-1e6 deg")
        angles = self.angles_deg()
        if not np.all(np.diff(angles) > 0):
            raise UsageError(f"--points {self.points} over {self.start_deg:g}..{self.end_deg:g} deg: points closer "
                             f"than 1e-{ANGLE_DECIMALS} deg; use fewer points or a wider range")

    @property
    def spacing_deg(self) -> float:
        return (self.end_deg - self.start_deg) / (self.points - 1)

    def angles_deg(self) -> np.ndarray:
        """The table angles [deg], rounded to :data:`ANGLE_DECIMALS` (the values written)."""
        return np.round(np.linspace(self.start_deg, self.end_deg, self.points), ANGLE_DECIMALS) + 0.0


def parse_range(text: str) -> tuple[float, float]:
    """``"0:360"`` -> (0.0, 360.0) [deg]; UsageError otherwise."""
    parts = text.split(":")
    try:
        lo, hi = (float(p) for p in parts)
    except ValueError:
        raise UsageError(f"--range: expected START:END in deg, e.g. 0:360, got {text!r}") from None
    return lo, hi


@dataclass(frozen=True)
class CorrectionTable:
    """Corrections at the table points: ``angle_deg`` (N,) [deg]; ``forward`` and
    ``reverse`` (N,) [rad], the value added to the command when moving forward (positive)
    or in reverse, = minus the error; ``both``: the reverse direction was measured
    (otherwise ``reverse`` repeats ``forward``)."""

    angle_deg: np.ndarray
    forward: np.ndarray
    reverse: np.ndarray
    both: bool = True

    def __len__(self) -> int:
        return self.angle_deg.shape[0]

    @property
    def largest(self) -> float:
        """Largest |correction| in either direction [rad]."""
        return float(max(np.max(np.abs(self.forward)), np.max(np.abs(self.reverse))))


def build_table(model, grid: TableGrid) -> CorrectionTable:
    """``model`` (anything with ``error(theta, direction)`` [rad]) evaluated at the grid's angles."""
    angles = grid.angles_deg()
    theta = np.radians(angles)
    fwd = -model.error(theta, np.ones_like(theta))
    rev = -model.error(theta, -np.ones_like(theta))
    return CorrectionTable(angles, fwd + 0.0, rev + 0.0, bool(getattr(getattr(model, "plan", None), "both", True)))


def apply_table(table: CorrectionTable, theta, direction) -> np.ndarray:
    """The correction [rad] a controller adds at angles ``theta`` [rad] moving in ``direction``:
    linear interpolation between the table points per direction, end values held outside."""
    deg = np.degrees(np.asarray(theta, dtype=float))
    d = np.asarray(direction, dtype=float)
    return np.where(d > 0, np.interp(deg, table.angle_deg, table.forward),
                    np.interp(deg, table.angle_deg, table.reverse))


def uncarried(orders: Sequence[float], spacing_deg: float) -> list[float]:
    """The orders whose period (360 / k deg) spans fewer than :data:`MIN_SPACINGS` table spacings."""
    return [float(k) for k in orders if k > 0 and 360.0 / k < MIN_SPACINGS * spacing_deg]


def interpolation_loss(model, table: CorrectionTable) -> float:
    """Largest difference [rad] between the model's correction and the table's linear
    interpolation between its points, over both directions (evaluated at
    :data:`LOSS_POINTS_PER_INTERVAL` points per interval)."""
    n = min((len(table) - 1) * LOSS_POINTS_PER_INTERVAL + 1, 2_000_000)
    theta = np.radians(np.linspace(table.angle_deg[0], table.angle_deg[-1], n))
    worst = 0.0
    for sign in (1.0, -1.0):
        d = np.full(n, sign)
        gap = -model.error(theta, d) - apply_table(table, theta, d)
        worst = max(worst, float(np.max(np.abs(gap))))
    return worst
