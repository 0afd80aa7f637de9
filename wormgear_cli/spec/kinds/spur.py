"""The spur stage kind on the spec side: a pinion on the stage's input shaft, a gear on the output shaft.

Its keys as data (:data:`FIELDS`; ISO 1328-1 accuracy grades per member), its records
(:class:`SpurStageSpec` with two :class:`SpurGear`), its derived defaults, its load radius, its
template's example values (the MCH50 of the paper: its Table 1 and text) and its toleranced keys,
gathered in :data:`KIND` (:class:`~wormgear_cli.spec.kinds.base.StageKind`).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from wormgear_cli.spec.fields import (
    FACE_WIDTH,
    KINEMATICS,
    MISSING,
    MODULE,
    PRESSURE_ANGLE,
    TOLERANCE,
    Field,
    field_,
    gear_grade_fields,
    phase_field,
    teeth_field,
    tol_field,
)
from wormgear_cli.spec.kinds.base import Plausible, StageKind, Toleranced, limit_fields, mesh_fields

ANTI_BACKLASH = ("none", "split_pinion")
#: the members, input shaft's first
MEMBERS = ("pinion", "gear")

FIELDS: tuple[Field, ...] = (
    *mesh_fields(ANTI_BACKLASH, "split_pinion (a split or spring-preloaded pinion)"),
    *limit_fields(),
    field_("module_mm", "module", "mm", None, "module m1 of the spur pair", **MODULE, table1="2.5"),
    field_("pressure_angle_deg", "pressure_angle", "deg", None, "pressure angle alpha", **PRESSURE_ANGLE,
           table1="20"),
    field_("face_width_mm", "face_width", "mm", "derived", "face width b of the spur mesh (default: 10 x module)",
           **FACE_WIDTH),
    Field("kinematics", "kinematics", "str", "", "paper",
          "spur kinematics: paper (the paper's Delta phi_cc/Delta phi_ch as printed) or involute "
          "(eccentricity e -> TE e/r_b; centre-distance error -> backlash 2 Delta a tan(alpha), no TE; "
          "tooth-thickness allowances in the backlash; see docs/budget.md)", choices=KINEMATICS),
    tol_field("centre_distance_error_mm", "centre_distance_error", "centre-distance error of the spur pair",
              "0.030"),
    field_("eccentricity_mm", "eccentricity", "mm", "derived",
           "the paper's Delta e, eccentricity of the pinion shaft (default: centre_distance_error_mm under the "
           "paper kinematics, 0 under the involute one)", **TOLERANCE),
    phase_field("eccentricity_phase_deg", "eccentricity_phase", "phase of Delta e (once per pinion turn)"),
    teeth_field("pinion.teeth", "teeth", "teeth z2 of the pinion (the member on the stage's input shaft)", "18"),
    *gear_grade_fields("pinion", "the pinion"),
    tol_field("pinion.profile_error_mm", "profile_error", "profile error of the pinion (not used by the "
              "gear-stage equations)", "0.008"),
    tol_field("pinion.thickness_deviation_mm", "thickness_deviation",
              "tooth thickness deviation of the pinion (read by the involute kinematics)", "0.045"),
    teeth_field("gear.teeth", "teeth", "teeth z1 of the gear (the member on the stage's output shaft)", "144"),
    *gear_grade_fields("gear", "the gear"),
    tol_field("gear.profile_error_mm", "profile_error", "profile error of the gear (not used by the gear-stage "
              "equations)", "0.007"),
    tol_field("gear.thickness_deviation_mm", "thickness_deviation",
              "tooth thickness deviation of the gear (read by the involute kinematics)", "0.055"),
)


class SpurGear(NamedTuple):
    """A member of a spur stage (pinion or gear)."""

    teeth: int
    accuracy_grade: int | None
    cumulative_pitch_deviation: float
    single_pitch_deviation: float
    cumulative_pitch_phase: float
    single_pitch_phase: float
    profile_error: float
    thickness_deviation: float


class SpurStageSpec(NamedTuple):
    """A spur stage: pinion on the input shaft, gear on the output shaft."""

    index: int  # type: ignore[assignment]  # a field named as tuple.index, by design
    name: str
    normal_force: float
    stiffness_model: str
    anti_backlash: str
    residual_lost_motion: float
    max_transmission_error: float | None
    max_backlash: float | None
    module: float
    pressure_angle: float
    face_width: float
    kinematics: str
    centre_distance_error: float
    eccentricity: float
    eccentricity_phase: float
    pinion: SpurGear
    gear: SpurGear
    paths: Any
    origins: Any
    shaft_stiffness: float | None = None
    kind = "spur"  # type: ignore[misc]  # a class constant, not a field

    @property
    def ratio(self) -> float:
        """Pinion turns per gear turn, z_gear / z_pinion."""
        return self.gear.teeth / self.pinion.teeth

    @property
    def output_radius(self) -> float:
        """Pitch radius of the gear [mm]."""
        return self.module * self.gear.teeth / 2.0

    @property
    def model_eccentricity(self) -> float:
        """The Delta e the kinematics uses [mm]: paper, the key (default the centre-distance error);
        involute, only an eccentricity written in the spec (a centre-distance error is static)."""
        if self.kinematics == "paper" or self.origins.get("eccentricity_mm") == "spec":
            return self.eccentricity
        return 0.0


def _derive(v: dict, label: str, problems: list[str]) -> None:
    """The spur stage's derived defaults, in place: the eccentricity (the centre-distance error) and the
    members' pitch deviations not set by a grade (0)."""
    if v["eccentricity_mm"] is MISSING:
        v["eccentricity_mm"] = v["centre_distance_error_mm"]
    for member in MEMBERS:
        for key in ("cumulative_pitch_deviation_mm", "single_pitch_deviation_mm"):
            if v[f"{member}.{key}"] is MISSING:
                v[f"{member}.{key}"] = 0.0


def _load_radius(v: dict) -> float | None:
    """The gear's base radius r cos(alpha) [mm]."""
    need = ("module_mm", "gear.teeth", "pressure_angle_deg")
    if MISSING in (v[k] for k in need):
        return None
    return v["module_mm"] * v["gear.teeth"] / 2.0 * math.cos(v["pressure_angle_deg"])


def _part_size(stage, key: str) -> tuple[float, float]:
    """(reference diameter, pitch radius) [mm] of the member ``key`` belongs to (the pinion's radius for
    a key of the pair)."""
    head = key.split(".", 1)[0] if "." in key else ""
    part = stage.pinion if head == "pinion" else stage.gear
    d = stage.module * part.teeth
    return d, (stage.module * stage.pinion.teeth / 2.0 if head == "" else d / 2.0)


R, S, U, T = "radial", "signed", "unknown", "allowance"

KIND = StageKind(
    name="spur", fields=FIELDS, record=SpurStageSpec, members={"pinion": SpurGear, "gear": SpurGear},
    default_name="gear", anti_backlash=ANTI_BACKLASH, ratio_keys=("gear.teeth", "pinion.teeth"),
    load_key="normal_force_N", load_radius=_load_radius, derive=_derive,
    examples={
        "module_mm": (2.5, "Table 1"), "pressure_angle_deg": (20.0, "Table 1"),
        "face_width_mm": (50.0, "MCH50 assumption"), "kinematics": ("paper", "the paper's equations"),
        "centre_distance_error_mm": (0.030, "Table 1"), "normal_force_N": (666.0, "the paper's text"),
        "pinion.teeth": (18, "Table 1"), "pinion.profile_error_mm": (0.008, "Table 1"),
        "pinion.thickness_deviation_mm": (0.045, "Table 1"), "gear.teeth": (144, "Table 1"),
        "gear.profile_error_mm": (0.007, "Table 1"), "gear.thickness_deviation_mm": (0.055, "Table 1"),
    },
    toleranced=(
        Toleranced("eccentricity_mm", R, True),
        Toleranced("gear.cumulative_pitch_deviation_mm", R, True),
        Toleranced("pinion.cumulative_pitch_deviation_mm", R, True),
        Toleranced("gear.single_pitch_deviation_mm", U, True),
        Toleranced("pinion.single_pitch_deviation_mm", U, True),
        # read only by the involute reading (physics.spur.involute_stage)
        Toleranced("centre_distance_error_mm", S, kinematics="involute"),
        Toleranced("gear.thickness_deviation_mm", T, kinematics="involute"),
        Toleranced("pinion.thickness_deviation_mm", T, kinematics="involute"),
    ),
    listed=(tuple(f"{m}.{k}" for m in ("gear", "pinion") for k in (
        "cumulative_pitch_deviation_mm", "single_pitch_deviation_mm", "profile_error_mm", "thickness_deviation_mm")),
        ("centre_distance_error_mm", "eccentricity_mm")),
    plausible=(
        Plausible("centre_distance_error_mm", "F_rT", 10.0, "depth"),
        *(Plausible(f"{m}.profile_error_mm", "F_alphaT", 10.0, "depth") for m in MEMBERS),
        *(Plausible(f"{m}.thickness_deviation_mm", "tooth", 0.2, "tooth") for m in MEMBERS),
        Plausible("eccentricity_mm", "F_rT", 10.0, "depth"),
        *(Plausible(f"{m}.cumulative_pitch_deviation_mm", "F_pT", 10.0, "radius") for m in MEMBERS),
        *(Plausible(f"{m}.single_pitch_deviation_mm", "f_pT", 10.0, "radius") for m in MEMBERS),
    ),
    part_size=_part_size,
)
