"""The worm stage kind on the spec side: a worm on the stage's input shaft, its wheel on the output shaft.

Its keys as data (:data:`FIELDS`), its records (:class:`WormStageSpec` with :class:`Worm` and
:class:`Wheel`), its derived defaults, its load radius, its template's example values (the MCH50 of
the paper: its Table 1, its text for the loads, and the assumptions named in ``configs/mch50.toml``)
and its toleranced keys, gathered in :data:`KIND` (:class:`~wormgear_cli.spec.kinds.base.StageKind`).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from wormgear_cli.spec.fields import (
    FACE_WIDTH,
    MISSING,
    MODULE,
    PRESSURE_ANGLE,
    Field,
    field_,
    phase_field,
    teeth_field,
    tol_field,
)
from wormgear_cli.spec.kinds.base import Plausible, StageKind, Toleranced, limit_fields, mesh_fields

ANTI_BACKLASH = ("none", "duplex")


def wheel_transverse_pressure_angle(normal_pressure_angle: float, lead_angle: float) -> float:
    """alpha_2 = atan(tan(alpha_n) / cos(lambda)) [rad], the default of ``transverse_pressure_angle_deg``.

    For a 90 deg shaft angle the wheel's transverse pressure angle equals the worm's axial pressure
    angle; for a worm specified by its normal pressure angle (ZN/ZI type) tan(alpha_x) =
    tan(alpha_n) / cos(gamma) (DIN 3975).  ``normal_pressure_angle`` alpha_n and ``lead_angle``
    lambda [rad], scalars.
    """
    return math.atan(math.tan(normal_pressure_angle) / math.cos(lead_angle))


FIELDS: tuple[Field, ...] = (
    *mesh_fields(ANTI_BACKLASH, "duplex (a duplex worm, adjusted axially)"),
    *limit_fields(),
    field_("module_mm", "module", "mm", None, "axial module m2 (= wheel transverse module)", **MODULE,
           table1="2.5"),
    field_("normal_pressure_angle_deg", "normal_pressure_angle", "deg", None, "normal pressure angle alpha_n",
           **PRESSURE_ANGLE, table1="20"),
    field_("lead_angle_deg", "lead_angle", "deg", None, "lead angle lambda of the worm", lo=0.1, hi=45.0,
           hi_open=True, table1="3.178"),
    field_("transverse_pressure_angle_deg", "transverse_pressure_angle", "deg", "derived",
           "wheel transverse pressure angle alpha_2 (default: atan(tan alpha_n / cos lambda), DIN 3975)",
           **PRESSURE_ANGLE),
    field_("face_width_mm", "face_width", "mm", "derived", "face width of the wheel (default: 10 x module)",
           **FACE_WIDTH),
    field_("mesh_temperature_rise_K", "mesh_temperature_rise", "K", 0.0,
           "rise of the worm and the wheel above the temperature the drive was measured (calibrated) at, in "
           "operation; with the housing's it changes the centre distance and the backlash", lo=-100.0, hi=300.0),
    field_("housing_temperature_rise_K", "housing_temperature_rise", "K", 0.0,
           "rise of the housing (the bores' distance) above the calibration temperature, in operation",
           lo=-100.0, hi=300.0),
    field_("worm_shaft_temperature_rise_K", "worm_shaft_temperature_rise", "K", "derived",
           "rise of the worm shaft between its thrust bearing and the mesh (default: mesh_temperature_rise_K)",
           lo=-100.0, hi=300.0),
    tol_field("lead_error_mm", "lead_error", "worm lead error f_hL", "0.030"),
    phase_field("lead_error_phase_deg", "lead_error_phase", "phase of the lead error (once per worm turn)"),
    tol_field("centre_distance_error_mm", "centre_distance_error", "centre-distance error f_a of the worm pair",
              "0.035"),
    Field("alignment_errors_mm", "alignment_errors", "floats", "mm", (0.0,) * 6,
          "the paper's six e_i of the worm pair (shaft-position and alignment errors entering Delta j)",
          0.0, 10.0, length=6),
    Field("worm.starts", "starts", "int", "-", None, "number of worm starts (threads)", 1, 100, table1="1"),
    tol_field("worm.profile_error_mm", "profile_error", "worm profile error f_t1", "0.036"),
    tol_field("worm.thickness_deviation_mm", "thickness_deviation", "worm thickness deviation T_s1", "0.045"),
    tol_field("worm.runout_mm", "runout", "the paper's S1: radial runout of the worm (total indicator reading, "
              "2 x the eccentricity of an eccentric worm; docs/models.md)"),
    phase_field("worm.runout_phase_deg", "runout_phase", "phase of S1 (once per worm turn)"),
    tol_field("worm.bearing_clearance_mm", "bearing_clearance", "the paper's C1: radial clearance of the worm "
              "bearings"),
    tol_field("worm.axial_play_mm", "axial_play", "axial play of the worm's thrust bearing (0 when preloaded): the "
              "worm shifts by it on a reversal, an arc of the same length on the wheel's pitch circle (a constant "
              "lost motion)"),
    field_("worm.axial_stiffness_N_per_um", "axial_stiffness", "N/um", "",
           "axial stiffness of the worm's thrust bearing and shaft (preloaded): the wheel's tangential force "
           "shifts the worm axially by F / k, an arc of the wheel (default: none, rigid)", lo=1e-6, hi=1e9),
    tol_field("worm.axial_runout_mm", "axial_runout", "axial runout of the worm (face runout of its thrust "
              "shoulder, total indicator reading): the worm moves axially by half of it, sinusoidally once per "
              "worm turn, an arc of the wheel"),
    phase_field("worm.axial_runout_phase_deg", "axial_runout_phase", "phase of the axial runout (once per worm "
                "turn)"),
    field_("worm.thrust_bearing_distance_mm", "thrust_bearing_distance", "mm", 0.0,
           "axial distance from the worm's axially located (thrust) bearing to the mesh: the worm shaft grows "
           "by it x alpha_worm x its temperature rise, an arc of the wheel (a thermal drift)", lo=0.0, hi=1e5),
    teeth_field("wheel.teeth", "teeth", "teeth z3 of the worm wheel", "30"),
    tol_field("wheel.profile_error_mm", "profile_error", "wheel profile error f_t2", "0.011"),
    tol_field("wheel.thickness_deviation_mm", "thickness_deviation", "wheel thickness deviation T_s2", "0.090"),
    tol_field("wheel.radial_composite_error_mm", "radial_composite_error", "wheel radial composite error F_i",
              "0.036"),
    phase_field("wheel.radial_composite_phase_deg", "radial_composite_phase",
                "phase of the radial composite error (once per wheel turn)"),
    tol_field("wheel.cumulative_pitch_deviation_mm", "cumulative_pitch_deviation",
              "cumulative pitch deviation F_p of the wheel (budget source, once per wheel turn; part of what "
              "F_i measures, so leave 0 unless measured separately)"),
    phase_field("wheel.cumulative_pitch_phase_deg", "cumulative_pitch_phase",
                "phase of the wheel's cumulative pitch deviation (once per wheel turn)"),
    tol_field("wheel.runout_mm", "runout", "the paper's S2: radial runout of the wheel (total indicator reading, "
              "2 x the eccentricity of an eccentric wheel; docs/models.md)"),
    phase_field("wheel.runout_phase_deg", "runout_phase", "phase of S2 (once per wheel turn)"),
    tol_field("wheel.bearing_clearance_mm", "bearing_clearance", "the paper's C2: radial clearance of the wheel "
              "shaft's bearings"),
)


# typed named tuples, not frozen dataclasses: created when ``analyze`` starts (0.1 ms against 0.6 ms each;
# docs/development.md, "Start-up")


class Worm(NamedTuple):
    """The worm of a worm stage (internal units)."""

    starts: int
    profile_error: float
    thickness_deviation: float
    runout: float
    runout_phase: float
    bearing_clearance: float
    axial_play: float = 0.0
    axial_stiffness: float | None = None
    axial_runout: float = 0.0
    axial_runout_phase: float = 0.0
    thrust_bearing_distance: float = 0.0


class Wheel(NamedTuple):
    """The wheel of a worm stage (internal units)."""

    teeth: int
    profile_error: float
    thickness_deviation: float
    radial_composite_error: float
    radial_composite_phase: float
    cumulative_pitch_deviation: float
    cumulative_pitch_phase: float
    runout: float
    runout_phase: float
    bearing_clearance: float


class WormStageSpec(NamedTuple):
    """A worm stage: worm on the input shaft, wheel on the output shaft (internal units; ``index``
    1-based from the motor; ``paths``/``origins``: stage key -> TOML path / origin)."""

    index: int  # type: ignore[assignment]  # a field named as tuple.index, by design
    name: str
    normal_force: float
    stiffness_model: str
    anti_backlash: str
    residual_lost_motion: float
    max_transmission_error: float | None
    max_backlash: float | None
    module: float
    normal_pressure_angle: float
    lead_angle: float
    transverse_pressure_angle: float
    face_width: float
    lead_error: float
    lead_error_phase: float
    centre_distance_error: float
    alignment_errors: tuple
    worm: Worm
    wheel: Wheel
    paths: Any
    origins: Any
    shaft_stiffness: float | None = None
    mesh_temperature_rise: float = 0.0
    housing_temperature_rise: float = 0.0
    worm_shaft_temperature_rise: float = 0.0
    kind = "worm"  # type: ignore[misc]  # a class constant, not a field

    @property
    def ratio(self) -> float:
        """Worm turns per wheel turn, z_wheel / z_worm."""
        return self.wheel.teeth / self.worm.starts

    @property
    def output_radius(self) -> float:
        """Pitch radius of the wheel [mm]."""
        return self.module * self.wheel.teeth / 2.0


def _derive(v: dict, label: str, problems: list[str]) -> None:
    """The worm stage's derived defaults, in place: the worm shaft's temperature rise (the mesh's) and
    the wheel's transverse pressure angle (:func:`wheel_transverse_pressure_angle`)."""
    if v["worm_shaft_temperature_rise_K"] is MISSING:
        v["worm_shaft_temperature_rise_K"] = v["mesh_temperature_rise_K"]
    if v["transverse_pressure_angle_deg"] is MISSING:
        an, lam = v["normal_pressure_angle_deg"], v["lead_angle_deg"]
        if MISSING not in (an, lam):
            v["transverse_pressure_angle_deg"] = wheel_transverse_pressure_angle(an, lam)


def _load_radius(v: dict) -> float | None:
    """The wheel radius times cos(alpha_n) cos(lambda) [mm] (the normal force of the worm mesh)."""
    need = ("module_mm", "wheel.teeth", "normal_pressure_angle_deg", "lead_angle_deg")
    if MISSING in (v[k] for k in need):
        return None
    return (v["module_mm"] * v["wheel.teeth"] / 2.0 * math.cos(v["normal_pressure_angle_deg"])
            * math.cos(v["lead_angle_deg"]))


def _part_size(stage, key: str) -> tuple[float, float]:
    """(reference diameter of the wheel, pitch radius of the part ``key`` belongs to: the worm's, the
    wheel's, the smaller of the two for a key of the pair) [mm]."""
    head = key.split(".", 1)[0] if "." in key else ""
    d_wheel = stage.module * stage.wheel.teeth
    d_worm = stage.worm.starts * stage.module / math.tan(stage.lead_angle)
    return d_wheel, (d_worm / 2.0 if head == "worm" else min(d_worm, d_wheel) / 2.0 if head == "" else
                     d_wheel / 2.0)


R, S, U, T = "radial", "signed", "unknown", "allowance"

KIND = StageKind(
    name="worm", fields=FIELDS, record=WormStageSpec, members={"worm": Worm, "wheel": Wheel}, default_name="worm",
    anti_backlash=ANTI_BACKLASH, ratio_keys=("wheel.teeth", "worm.starts"), load_key="normal_force_N",
    load_radius=_load_radius, derive=_derive,
    examples={
        "module_mm": (2.5, "Table 1"), "normal_pressure_angle_deg": (20.0, "Table 1"),
        "lead_angle_deg": (3.178, "Table 1"), "face_width_mm": (37.5, "MCH50 assumption"),
        "lead_error_mm": (0.030, "Table 1"), "centre_distance_error_mm": (0.035, "Table 1"),
        "alignment_errors_mm": ((0.030, 0.030, 0.030, 0.030, 0.040, 0.040), "MCH50 assumption"),
        "normal_force_N": (85.0, "the paper's text"), "worm.starts": (1, "Table 1"),
        "worm.profile_error_mm": (0.036, "Table 1"), "worm.thickness_deviation_mm": (0.045, "Table 1"),
        "worm.runout_mm": (0.012, "MCH50 assumption"), "worm.bearing_clearance_mm": (0.010, "MCH50 assumption"),
        "wheel.teeth": (30, "Table 1"), "wheel.profile_error_mm": (0.011, "Table 1"),
        "wheel.thickness_deviation_mm": (0.090, "Table 1"), "wheel.radial_composite_error_mm": (0.036, "Table 1"),
        "wheel.runout_mm": (0.016, "MCH50 assumption"), "wheel.bearing_clearance_mm": (0.015, "MCH50 assumption"),
    },
    toleranced=(
        Toleranced("lead_error_mm", S, True),
        Toleranced("worm.profile_error_mm", U, True),
        Toleranced("worm.thickness_deviation_mm", T),
        Toleranced("wheel.profile_error_mm", U, True),
        Toleranced("wheel.thickness_deviation_mm", T),
        Toleranced("wheel.radial_composite_error_mm", R, True),
        Toleranced("centre_distance_error_mm", S),
        Toleranced("worm.runout_mm", R),
        Toleranced("worm.bearing_clearance_mm", R),
        Toleranced("wheel.runout_mm", R),
        Toleranced("wheel.bearing_clearance_mm", R),
        Toleranced("alignment_errors_mm", U, length=6),
        Toleranced("wheel.cumulative_pitch_deviation_mm", R),
    ),
    listed=(("lead_error_mm", "wheel.radial_composite_error_mm", "wheel.cumulative_pitch_deviation_mm"), ()),
    plausible=(
        Plausible("lead_error_mm", "F_pT", 10.0, "radius"),
        Plausible("centre_distance_error_mm", "F_rT", 10.0, "depth"),
        Plausible("alignment_errors_mm", "F_rT", 10.0, "depth"),
        *(Plausible(f"{m}.profile_error_mm", "F_alphaT", 10.0, "depth") for m in ("worm", "wheel")),
        *(Plausible(f"{m}.thickness_deviation_mm", "tooth", 0.2, "tooth") for m in ("worm", "wheel")),
        *(Plausible(f"{m}.{key}", "F_rT", 10.0, "depth") for m in ("worm", "wheel")
          for key in ("runout_mm", "bearing_clearance_mm")),
        Plausible("worm.axial_play_mm", "F_rT", 10.0, "depth"),
        Plausible("worm.axial_runout_mm", "F_rT", 10.0, "depth"),
        Plausible("wheel.radial_composite_error_mm", "F_i2T", 10.0, "depth"),
        Plausible("wheel.cumulative_pitch_deviation_mm", "F_pT", 10.0, "radius"),
    ),
    part_size=_part_size,
)
