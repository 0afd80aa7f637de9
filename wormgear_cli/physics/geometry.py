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
    worm + spur one, from its train (empty: the legacy drive's named orders);
    ``kinds``: the stage kinds from the motor to the output (empty: the legacy [worm, spur]);
    ``intermediate``: the order of the intermediate shaft, the output stage's input shaft (0:
    none apart from a worm shaft); ``worm_after``: the product of the ratios after the worm stage
    (0: no worm stage); both None for the legacy drive, where they are i_c (``gear_ratio``).

    For any train (:func:`wormgear_cli.drive.train.drive_geometry`): r_1, r_b1 and z1 are the
    output stage's output member's (spur gear, worm wheel or driven pulley), the worm values the
    last worm stage's.
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
    kinds: tuple = ()
    intermediate: float | None = None
    worm_after: float | None = None

    @property
    def intermediate_order(self) -> float:
        """Turns of the intermediate shaft per output turn (0: no such shaft apart from a worm shaft)."""
        return self.gear_ratio if self.intermediate is None else self.intermediate

    @property
    def worm_reduction(self) -> float:
        """The product of the ratios after the worm stage (i_c for the legacy drive; 0: no worm stage)."""
        return self.gear_ratio if self.worm_after is None else self.worm_after

    @property
    def base_orders(self) -> tuple:
        """The drive's shaft and mesh orders (its labels' orders; the legacy drive's 1, i_c, z1, n_w)."""
        if self.labels:
            return tuple(float(o) for o, _ in self.labels)
        return (1.0, float(self.gear_ratio), float(self.output_teeth), float(self.worm_order))
