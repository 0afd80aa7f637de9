"""The derived geometry of a drive that the effect catalogue, the simulation and the budget share.

Its own small module so that ``analyze`` (which needs the geometry for the budget's
orders) does not import the whole effect catalogue at start-up.
"""

from __future__ import annotations

from typing import NamedTuple


# an immutable named record built as a NamedTuple, not a frozen dataclass: it is created when
# ``analyze`` starts (0.1 ms against 0.6 ms; docs/development.md, "Start-up")
class DriveGeometry(NamedTuple):
    """Derived quantities of a drive that the effect signatures need.

    Attributes (internal units): ``output_pitch_radius`` r_1 [mm],
    ``output_base_radius`` r_b1 [mm], ``wheel_pitch_radius`` [mm],
    ``gear_ratio`` i_c = z1/z2 [-], ``worm_order`` n_w = i_c z3 / z_worm [-]
    (worm revolutions per output revolution), ``output_teeth`` z1,
    ``axial_pressure_angle`` alpha_x [rad], ``worm_centre_distance`` a [mm],
    ``worm_starts`` z_worm (the worm mesh is at z_worm n_w; 1: worm shaft and mesh coincide),
    ``labels``: ((order, label), ...) of every shaft and mesh of a drive other than the legacy
    worm + spur one, from its train (empty: the legacy drive's named orders).
    """

    output_pitch_radius: float
    output_base_radius: float
    wheel_pitch_radius: float
    gear_ratio: float
    worm_order: float
    output_teeth: int
    axial_pressure_angle: float
    worm_centre_distance: float
    worm_starts: int = 1
    labels: tuple = ()
