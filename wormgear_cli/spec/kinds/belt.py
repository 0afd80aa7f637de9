"""The toothed-belt stage kind on the spec side: a driving pulley on the stage's input shaft, a driven
pulley on the output shaft, a belt between them.

Its keys as data (:data:`FIELDS`), its records (:class:`BeltStageSpec` with two :class:`Pulley`), the
belt's geometry (:func:`pulley_radius`, :func:`belt_centre_distance`), its derived centre distance,
its load radius, its template's example values (an EQ6-class telescope mount's motor reduction,
``configs/eq6-belt-worm.toml``: a 12 -> 47 tooth reduction, the 47:12 that with a 180-tooth worm
wheel gives the 705 motor turns per RA turn EQMOD mounts report; belt and error sizes marked as
assumptions) and its toleranced keys, gathered in :data:`KIND`.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from wormgear_cli.spec.fields import FORCE, MISSING, Field, field_, phase_field, teeth_field, tol_field
from wormgear_cli.spec.kinds.base import Plausible, StageKind, Toleranced, limit_fields

FIELDS: tuple[Field, ...] = (
    *limit_fields(),
    field_("pitch_mm", "pitch", "mm", None, "belt tooth pitch p (GT2: 2, HTD 3M: 3, MXL: 2.032)", lo=0.5,
           hi=50.0),
    Field("belt_teeth", "belt_teeth", "int", "-", None, "teeth of the belt (its length / p)", 10, 10000),
    field_("centre_distance_mm", "centre_distance", "mm", "derived",
           "pulley centre distance C (default: from the belt length, C = (b + sqrt(b^2 - 2 (D - d)^2)) / 4 with "
           "b = L - pi (D + d) / 2)", lo=0.1, hi=1e5),
    tol_field("backlash_mm", "backlash", "lost motion on the pitch line between belt and pulley teeth, both "
              "meshes together"),
    tol_field("pitch_error_mm", "pitch_error", "the belt's cumulative pitch variation over its length (peak to "
              "peak, once per belt revolution)"),
    phase_field("pitch_error_phase_deg", "pitch_error_phase", "phase of the belt pitch error (once per belt "
                "revolution)"),
    tol_field("tooth_mesh_error_mm", "tooth_mesh_error", "pitch-line displacement at the tooth-meshing "
              "frequency (peak to peak; polygon action and meshing)"),
    phase_field("tooth_mesh_phase_deg", "tooth_mesh_phase", "phase of the tooth-meshing error"),
    field_("tensile_stiffness_N", "tensile_stiffness", "N", "",
           "tensile stiffness E A of the belt (force per unit strain, whole width); stretch of both spans as "
           "torsional compliance (default: none, a rigid belt)", lo=1.0, hi=1e9),
    field_("effective_tension_N", "effective_tension", "N", "derived",
           "effective tension (tight minus slack span) under the process load (default: from [drive] "
           "output_torque_Nm through the ratios after this stage and the driven pulley's radius, else 0)",
           **FORCE),
    teeth_field("driver.teeth", "teeth", "teeth of the driving pulley (on the stage's input shaft)", "", lo=8),
    tol_field("driver.eccentricity_mm", "eccentricity", "eccentricity of the driving pulley on its shaft"),
    phase_field("driver.eccentricity_phase_deg", "eccentricity_phase", "phase of the driving pulley's "
                "eccentricity (once per turn of its shaft)"),
    teeth_field("driven.teeth", "teeth", "teeth of the driven pulley (on the stage's output shaft)", "", lo=8),
    tol_field("driven.eccentricity_mm", "eccentricity", "eccentricity of the driven pulley on its shaft"),
    phase_field("driven.eccentricity_phase_deg", "eccentricity_phase", "phase of the driven pulley's "
                "eccentricity (once per turn of its shaft)"),
)


class Pulley(NamedTuple):
    """A pulley of a belt stage."""

    teeth: int
    eccentricity: float
    eccentricity_phase: float


class BeltStageSpec(NamedTuple):
    """A toothed-belt stage: driving pulley on the input shaft, driven pulley on the output shaft."""

    index: int  # type: ignore[assignment]  # a field named as tuple.index, by design
    name: str
    max_transmission_error: float | None
    max_backlash: float | None
    pitch: float
    belt_teeth: int
    centre_distance: float
    backlash: float
    pitch_error: float
    pitch_error_phase: float
    tooth_mesh_error: float
    tooth_mesh_phase: float
    tensile_stiffness: float | None
    effective_tension: float
    driver: Pulley
    driven: Pulley
    paths: Any
    origins: Any
    kind = "belt"  # type: ignore[misc]  # a class constant, not a field

    @property
    def ratio(self) -> float:
        """Driver turns per driven turn, z_driven / z_driver."""
        return self.driven.teeth / self.driver.teeth

    @property
    def output_radius(self) -> float:
        """Pitch radius of the driven pulley, z p / (2 pi) [mm]."""
        return pulley_radius(self.driven.teeth, self.pitch)

    @property
    def span_length(self) -> float:
        """Free length of each span, sqrt(C^2 - (R - r)^2) [mm]."""
        d = self.output_radius - pulley_radius(self.driver.teeth, self.pitch)
        return math.sqrt(max(self.centre_distance ** 2 - d * d, 0.0))


def pulley_radius(teeth, pitch):
    """Pitch radius of a toothed pulley, z p / (2 pi) [mm] (the belt's pitch line)."""
    return teeth * pitch / (2.0 * math.pi)


def belt_centre_distance(belt_teeth: int, pitch: float, driver_teeth: int, driven_teeth: int) -> float | None:
    """Centre distance C [mm] of a belt of ``belt_teeth`` x ``pitch`` over two pulleys, from
    L = 2 C + pi (D + d) / 2 + (D - d)^2 / (4 C):  C = (b + sqrt(b^2 - 2 (D - d)^2)) / 4,
    b = L - pi (D + d) / 2 (the belt-length relation of the belt makers' design manuals).  None
    when the belt is too short to pass round both pulleys."""
    big, small = (2.0 * pulley_radius(z, pitch) for z in (driven_teeth, driver_teeth))
    b = belt_teeth * pitch - math.pi * (big + small) / 2.0
    disc = b * b - 2.0 * (big - small) ** 2
    if b <= 0.0 or disc < 0.0:
        return None
    c = (b + math.sqrt(disc)) / 4.0
    return c if c > (big + small) / 2.0 else None


def _derive(v: dict, label: str, problems: list[str]) -> None:
    """The belt stage's derived centre distance, in place (a problem when the belt is too short)."""
    if v["centre_distance_mm"] is MISSING and MISSING not in (
            v["belt_teeth"], v["pitch_mm"], v["driver.teeth"], v["driven.teeth"]):
        c = belt_centre_distance(v["belt_teeth"], v["pitch_mm"], v["driver.teeth"], v["driven.teeth"])
        if c is None:
            problems.append(f"{label}: belt_teeth: a belt of {v['belt_teeth']} x {v['pitch_mm']:g} mm is too short "
                            f"for pulleys of {v['driver.teeth']} and {v['driven.teeth']} teeth; give a longer belt")
        v["centre_distance_mm"] = c if c is not None else MISSING


def _load_radius(v: dict) -> float | None:
    """The driven pulley's pitch radius [mm] (the effective tension)."""
    if MISSING in (v["driven.teeth"], v["pitch_mm"]):
        return None
    return pulley_radius(v["driven.teeth"], v["pitch_mm"])


def _part_size(stage, key: str) -> tuple[float, float]:
    """(pitch diameter, pitch radius) [mm] of the pulley ``key`` belongs to (the driving pulley's for a
    key of the belt)."""
    head = key.split(".", 1)[0] if "." in key else ""
    part = stage.driver if head == "driver" else stage.driven
    r = pulley_radius(part.teeth, stage.pitch) if head else pulley_radius(stage.driver.teeth, stage.pitch)
    return 2.0 * r, r


R, U = "radial", "unknown"

KIND = StageKind(
    name="belt", fields=FIELDS, record=BeltStageSpec, members={"driver": Pulley, "driven": Pulley},
    default_name="belt", anti_backlash=("none",), ratio_keys=("driven.teeth", "driver.teeth"),
    load_key="effective_tension_N", load_radius=_load_radius, derive=_derive,
    examples={
        "pitch_mm": (2.0, "assumption: a GT2 belt"),
        "belt_teeth": (80, "assumption: about 49 mm between motor and worm shaft"),
        "backlash_mm": (0.02, "assumption: GT2 profile, no tensioner play"),
        "pitch_error_mm": (0.05, "assumption: pitch variation over a 160 mm belt"),
        "tooth_mesh_error_mm": (0.002, "assumption"),
        "tensile_stiffness_N": (20000.0, "assumption: 6 mm glass-cord belt, E A ~ 20 kN; measure it"),
        "driver.teeth": (12, "EQ6 class: 47:12 motor reduction"), "driver.eccentricity_mm": (0.010, "assumption"),
        "driven.teeth": (47, "EQ6 class: 47:12 motor reduction"), "driven.eccentricity_mm": (0.015, "assumption"),
    },
    toleranced=(
        Toleranced("driver.eccentricity_mm", R),
        Toleranced("driven.eccentricity_mm", R),
        Toleranced("pitch_error_mm", R),
        Toleranced("tooth_mesh_error_mm", U),
        Toleranced("backlash_mm", R),
    ),
    listed=(("pitch_error_mm", "tooth_mesh_error_mm", "driver.eccentricity_mm", "driven.eccentricity_mm",
             "backlash_mm"), ()),
    plausible=(
        Plausible("backlash_mm", "pitch", 0.5, "pitch"),
        Plausible("pitch_error_mm", "pitch", 0.5, "radius"),
        Plausible("tooth_mesh_error_mm", "pitch", 0.25, "pitch"),
        *(Plausible(f"{m}.eccentricity_mm", "pitch", 0.5, "radius") for m in ("driver", "driven")),
    ),
    part_size=_part_size,
)
