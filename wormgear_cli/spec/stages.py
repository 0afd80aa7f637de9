"""The stage form of a drive file: ``[[stage]]`` tables listed from the motor to the output.

A drive is an ordered list of stages, each with ``kind = "worm" | "spur" | "belt"`` and the keys
of that kind (the schema as data: :data:`STAGE_FIELDS`, keys relative to the stage table, units
in the key names).  Each stage becomes an immutable record of its kind
(:class:`WormStageSpec`, :class:`SpurStageSpec`, :class:`BeltStageSpec`; typed named tuples,
cheap to create at start-up), every value in internal units (mm, rad, N, N/mm^2).

Every record also carries ``paths`` (stage key -> the TOML path it was read from, which names
the key in messages, budgets and phase tables) and ``origins`` (stage key -> ``"spec"`` written
in the file, ``"grade"`` derived from an ISO 1328 accuracy grade, ``"default"``).

The legacy two-table form (``[gear_pair]``, ``[worm_pair]``, ``[assembly]``, ``[loads]``) is the
train [worm, spur]: :data:`LEGACY_KEYS` maps each of its keys to a stage key, the one table
behind loading the old form, ``wormgear upgrade`` and the old attribute names.

Problems are reported by position and kind: ``FILE: stage 2 (spur): module_mm: expected ...``.
"""

import math
from types import MappingProxyType
from typing import Any, NamedTuple

from wormgear_cli.errors import did_you_mean
from wormgear_cli.spec.fields import (
    FACE_WIDTH,
    FORCE,
    KINEMATICS,
    MISSING,
    MODULE,
    PRESSURE_ANGLE,
    TOLERANCE,
    UNIT_SCALE,
    Field,
    check_value,
    field_,
    gear_grade_fields,
    phase_field,
    quote,
    teeth_field,
    tol_field,
    type_name,
)

#: stage kinds, in the order the docs list them
STAGE_KINDS = ("worm", "spur", "belt")
#: the most stages a drive may have
MAX_STAGES = 16
#: default stage name per kind ("gear": the paper's name of its spur stage)
DEFAULT_NAMES = {"worm": "worm", "spur": "gear", "belt": "belt"}
#: anti-backlash arrangements a kind may have (``anti_backlash``)
ANTI_BACKLASH = {"worm": ("none", "duplex"), "spur": ("none", "split_pinion"), "belt": ("none",)}


def wheel_transverse_pressure_angle(normal_pressure_angle: float, lead_angle: float) -> float:
    """alpha_2 = atan(tan(alpha_n) / cos(lambda)) [rad], the default of ``transverse_pressure_angle_deg``.

    For a 90 deg shaft angle the wheel's transverse pressure angle equals the worm's axial pressure
    angle; for a worm specified by its normal pressure angle (ZN/ZI type) tan(alpha_x) =
    tan(alpha_n) / cos(gamma) (DIN 3975).  ``normal_pressure_angle`` alpha_n and ``lead_angle``
    lambda [rad], scalars.
    """
    return math.atan(math.tan(normal_pressure_angle) / math.cos(lead_angle))


def _limit(key, attr, what):
    return field_(key, attr, "arcsec", "", f"limit on this stage's {what} at its own output shaft", lo=0.0,
                  hi=1e9, lo_open=True)


def _common(kind: str) -> tuple[Field, ...]:
    """Keys every stage has: kind, name, limits; gear meshes: load, stiffness model, anti-backlash."""
    out = [
        Field("kind", "kind", "str", "", None, "stage kind: worm, spur or belt", choices=STAGE_KINDS),
        Field("name", "name", "str", "", "derived",
              "name shown in reports (default: worm, gear or belt; numbered by position when a kind repeats)"),
    ]
    if kind in ("worm", "spur"):
        out += [
            field_("normal_force_N", "normal_force", "N", "derived",
                   "normal force F_N on the teeth (default: from [drive] output_torque_Nm through the ratios "
                   "after this stage and its pitch radius, else 0)", **FORCE),
            Field("stiffness_model", "stiffness_model", "str", "", "derived",
                  "deflection model of this mesh (default: [stiffness] model)", choices=("iso6336", "empirical")),
            Field("anti_backlash", "anti_backlash", "str", "", "none",
                  "anti-backlash arrangement: " + ("duplex (a duplex worm, adjusted axially)" if kind == "worm"
                                                   else "split_pinion (a split or spring-preloaded pinion)")
                  + " sets the clearance to residual_lost_motion_arcsec", choices=ANTI_BACKLASH[kind]),
            field_("residual_lost_motion_arcsec", "residual_lost_motion", "arcsec", 0.0,
                   "lost motion left by the anti-backlash arrangement, at this stage's output shaft (replaces "
                   "the clearance terms; the tooth deflection stays)", lo=0.0, hi=36000.0),
            field_("shaft_stiffness_Nm_per_arcmin", "shaft_stiffness", "N m/arcmin", "",
                   "torsional stiffness of the stage's output shaft from its gear (wheel) to the next stage or the "
                   "load, bearings and couplings included: a wind-up under load, 1 / (k O^2) at the output "
                   "(default: none, rigid)", lo=1e-6, hi=1e12),
        ]
    return (*out, _limit("max_transmission_error_arcsec", "max_transmission_error", "transmission error"),
            _limit("max_backlash_arcsec", "max_backlash", "backlash"))


WORM_FIELDS: tuple[Field, ...] = (
    *_common("worm"),
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

SPUR_FIELDS: tuple[Field, ...] = (
    *_common("spur"),
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

BELT_FIELDS: tuple[Field, ...] = (
    *_common("belt"),
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

#: kind -> its keys (paths relative to the stage table; order = template and reference order)
STAGE_FIELDS: dict[str, tuple[Field, ...]] = {"worm": WORM_FIELDS, "spur": SPUR_FIELDS, "belt": BELT_FIELDS}
STAGE_FIELD_BY_KEY: dict[str, dict[str, Field]] = {k: {f.path: f for f in fs} for k, fs in STAGE_FIELDS.items()}
#: kind -> its sub-tables (members)
MEMBERS = {"worm": ("worm", "wheel"), "spur": ("pinion", "gear"), "belt": ("driver", "driven")}


# --- records ------------------------------------------------------------------------------------------------
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


class Pulley(NamedTuple):
    """A pulley of a belt stage."""

    teeth: int
    eccentricity: float
    eccentricity_phase: float


class WormStageSpec(NamedTuple):
    """A worm stage: worm on the input shaft, wheel on the output shaft (internal units; ``index``
    1-based from the motor; ``paths``/``origins``: stage key -> TOML path / origin)."""

    index: int
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
    kind = "worm"

    @property
    def ratio(self) -> float:
        """Worm turns per wheel turn, z_wheel / z_worm."""
        return self.wheel.teeth / self.worm.starts

    @property
    def output_radius(self) -> float:
        """Pitch radius of the wheel [mm]."""
        return self.module * self.wheel.teeth / 2.0


class SpurStageSpec(NamedTuple):
    """A spur stage: pinion on the input shaft, gear on the output shaft."""

    index: int
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
    kind = "spur"

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


class BeltStageSpec(NamedTuple):
    """A toothed-belt stage: driving pulley on the input shaft, driven pulley on the output shaft."""

    index: int
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
    kind = "belt"

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


RECORDS = {"worm": (WormStageSpec, {"worm": Worm, "wheel": Wheel}),
           "spur": (SpurStageSpec, {"pinion": SpurGear, "gear": SpurGear}),
           "belt": (BeltStageSpec, {"driver": Pulley, "driven": Pulley})}


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


def stage_path(index: int, key: str) -> str:
    """The TOML path of a stage key: ``stage.INDEX.KEY`` (1-based index)."""
    return f"stage.{index}.{key}"


def stage_label(index: int, kind: str) -> str:
    """How messages name a stage: ``stage 2 (spur)``."""
    return f"stage {index} ({kind})"


# --- validation -----------------------------------------------------------------------------------------------


def _known_children() -> dict[str, dict[str, frozenset[str]]]:
    out: dict[str, dict[str, frozenset[str]]] = {}
    for kind, fields in STAGE_FIELDS.items():
        table: dict[str, set[str]] = {"": set()}
        for f in fields:
            head, _, tail = f.path.partition(".")
            table[""].add(head)
            if tail:
                table.setdefault(head, set()).add(tail)
        out[kind] = {k: frozenset(v) for k, v in table.items()}
    return out


#: kind -> table ("" = the stage table, or a member) -> the keys valid directly under it (built once)
_KNOWN = _known_children()

#: keys a user may reasonably try that no standard here covers -> the message (exit 2)
NOT_COVERED = {
    f"{part}.accuracy_grade": (
        "worm pairs are not covered by ISO 1328-1/-2 (cylindrical involute gears only) and no public, "
        "citable worm-gear grade system (DIN 3974) is available here; give the worm pair's tolerances "
        "explicitly (lead_error_mm, profile_error_mm, radial_composite_error_mm, ...)")
    for part in ("worm", "wheel")
}


class StageInput(NamedTuple):
    """One ``[[stage]]`` table as checked: ``values`` stage key -> internal value (or MISSING),
    ``written``: the keys the file gives, ``grade_keys``: keys set from an accuracy grade."""

    index: int
    kind: str
    values: dict
    written: frozenset
    grade_keys: frozenset


def check_stage(table, index: int, source: str, problems: list[str]) -> StageInput | None:
    """Check one ``[[stage]]`` table (position ``index``, 1-based); every problem is appended to
    ``problems`` as ``SOURCE: stage INDEX (KIND): KEY: what is expected``.  None when the table is
    not usable at all (not a table, no valid kind)."""
    where = f"{source}: stage {index}"
    if not isinstance(table, dict):
        problems.append(f"{where}: expected a table [[stage]], got {type_name(table)}")
        return None
    kind = table.get("kind")
    if kind is None:
        problems.append(f"{where}: kind: missing required key, expected one of "
                        + ", ".join(f'"{k}"' for k in STAGE_KINDS))
        return None
    err, _ = check_value(STAGE_FIELD_BY_KEY["worm"]["kind"], kind)
    if err:
        problems.append(f"{where}: kind: {err}")
        return None
    label = f"{source}: {stage_label(index, kind)}"
    _walk(table, kind, "", problems, label)
    values: dict[str, Any] = {}
    written = set()
    for f in STAGE_FIELDS[kind]:
        head, _, tail = f.path.partition(".")
        parent = table.get(head) if tail else table
        key = tail or head
        if not isinstance(parent, dict) or key not in parent or isinstance(parent[key], dict):
            if f.default is None and isinstance(parent, dict) and key not in parent:
                problems.append(f"{label}: {f.path}: missing required key, expected {f.expected()}")
            elif tail and parent is None and f.default is None:
                problems.append(f"{label}: {f.path}: missing required key, expected {f.expected()} "
                                f"(in a [stage.{head}] table)")
            values[f.path] = MISSING
            continue
        err, val = check_value(f, parent[key])
        if err:
            problems.append(f"{label}: {f.path}: {err}")
            values[f.path] = MISSING
        else:
            values[f.path] = val
            written.add(f.path)
    if values.get("name") not in (None, MISSING) and (not values["name"].isprintable() or not values["name"]):
        problems.append(f"{label}: name: expected a non-empty single-line name, got {quote(values['name'])}")
        values["name"] = MISSING
    grade_keys = _apply_grades(kind, values, problems, label)
    return StageInput(index, kind, values, frozenset(written), frozenset(grade_keys))


def _walk(table: dict, kind: str, prefix: str, problems: list[str], label: str) -> None:
    known = _KNOWN[kind].get(prefix, frozenset())
    for key, value in table.items():
        shown = key if key.isprintable() and key.strip() == key and key else quote(key)
        rel = f"{prefix}.{shown}" if prefix else shown
        if key not in known:
            if rel in NOT_COVERED and kind == "worm":
                problems.append(f"{label}: {rel}: {NOT_COVERED[rel]}")
                continue
            # a key of another kind first (it is exactly that), else the nearest key of this table, else the
            # nearest path of this kind (a misplaced key)
            hint = (_other_kind(rel, kind)
                    or did_you_mean(key, sorted(known), show=lambda m: (prefix + "." if prefix else "") + m)
                    or did_you_mean(rel, list(STAGE_FIELD_BY_KEY[kind]), cutoff=0.75))
            what = "table" if isinstance(value, dict) else "key"
            problems.append(f"{label}: {rel}: unknown {what}{hint}")
            continue
        is_member = not prefix and key in MEMBERS[kind]
        if is_member and not isinstance(value, dict):
            problems.append(f"{label}: {rel}: expected a table [stage.{rel}], got {type_name(value)}")
        elif not is_member and isinstance(value, dict):
            problems.append(f"{label}: {rel}: expected a value, got a table")
        elif isinstance(value, dict):
            _walk(value, kind, rel, problems, label)


def _other_kind(rel: str, kind: str) -> str:
    """A hint when the key belongs to another kind of stage (a spur key in a worm stage)."""
    others = [k for k in STAGE_KINDS if k != kind and rel in STAGE_FIELD_BY_KEY[k]]
    if others:
        return f" (a key of {' and '.join(others)} stages; this stage has kind = \"{kind}\")"
    return ""


def _apply_grades(kind: str, values: dict, problems: list[str], label: str) -> set[str]:
    """Fill a spur stage's pitch deviations (and profile errors) from the members' ``accuracy_grade``
    where the stage does not give them (ISO 1328-1:2013; explicit keys win).  Returns the keys set."""
    out: set[str] = set()
    if kind != "spur" or values["module_mm"] is MISSING:
        return out
    module = values["module_mm"]
    face = values["face_width_mm"]
    face = 10.0 * module if face is MISSING else face
    for member in MEMBERS["spur"]:
        grade, teeth = values[f"{member}.accuracy_grade"], values[f"{member}.teeth"]
        if grade in (MISSING, None) or teeth is MISSING:
            continue
        from wormgear_cli.physics.iso1328 import GradeError, flank_tolerances

        try:
            tol = flank_tolerances(grade, module, module * teeth, face, teeth)
        except GradeError as exc:
            problems.append(f"{label}: {member}.accuracy_grade: {exc}; give the deviations explicitly instead")
            continue
        for key, um in (("cumulative_pitch_deviation_mm", tol.F_pT), ("single_pitch_deviation_mm", tol.f_pT),
                        ("profile_error_mm", tol.F_alphaT)):
            if values[f"{member}.{key}"] is MISSING:
                values[f"{member}.{key}"] = um * 1e-3
                out.add(f"{member}.{key}")
    return out


# --- defaults, names, loads and the records -------------------------------------------------------------------


def _defaults(s: StageInput, model_default: str, label: str, problems: list[str]) -> dict:
    """The stage's values with every default and derived value filled in (key units -> internal)."""
    v = dict(s.values)
    for f in STAGE_FIELDS[s.kind]:
        if v[f.path] is not MISSING or f.default in ("derived", None):
            continue
        d = f.default
        if d == "":
            v[f.path] = None
        elif f.kind == "floats":
            v[f.path] = tuple(x * UNIT_SCALE[f.unit] for x in d)
        elif f.kind == "str":
            v[f.path] = d
        else:
            v[f.path] = float(d) * UNIT_SCALE[f.unit]
    if s.kind in ("worm", "spur"):
        if v["face_width_mm"] is MISSING and v["module_mm"] is not MISSING:
            v["face_width_mm"] = 10.0 * v["module_mm"]
        if v["stiffness_model"] is MISSING:
            v["stiffness_model"] = model_default
        if "residual_lost_motion_arcsec" in s.written and v["anti_backlash"] == "none" and \
                v["residual_lost_motion_arcsec"] not in (0.0, MISSING):
            problems.append(f"{label}: residual_lost_motion_arcsec: only with an anti-backlash arrangement; set "
                            f"anti_backlash = \"{ANTI_BACKLASH[s.kind][1]}\" or remove the key")
    if s.kind == "worm" and v["worm_shaft_temperature_rise_K"] is MISSING:
        v["worm_shaft_temperature_rise_K"] = v["mesh_temperature_rise_K"]
    if s.kind == "worm" and v["transverse_pressure_angle_deg"] is MISSING:
        an, lam = v["normal_pressure_angle_deg"], v["lead_angle_deg"]
        if MISSING not in (an, lam):
            v["transverse_pressure_angle_deg"] = wheel_transverse_pressure_angle(an, lam)
    if s.kind == "spur":
        if v["eccentricity_mm"] is MISSING:
            v["eccentricity_mm"] = v["centre_distance_error_mm"]
        for member in MEMBERS["spur"]:
            for key in ("cumulative_pitch_deviation_mm", "single_pitch_deviation_mm"):
                if v[f"{member}.{key}"] is MISSING:
                    v[f"{member}.{key}"] = 0.0
    if s.kind == "belt" and v["centre_distance_mm"] is MISSING and MISSING not in (
            v["belt_teeth"], v["pitch_mm"], v["driver.teeth"], v["driven.teeth"]):
        c = belt_centre_distance(v["belt_teeth"], v["pitch_mm"], v["driver.teeth"], v["driven.teeth"])
        if c is None:
            problems.append(f"{label}: belt_teeth: a belt of {v['belt_teeth']} x {v['pitch_mm']:g} mm is too short "
                            f"for pulleys of {v['driver.teeth']} and {v['driven.teeth']} teeth; give a longer belt")
        v["centre_distance_mm"] = c if c is not None else MISSING
    return v


def _ratio(kind: str, v: dict) -> float | None:
    members = {"worm": ("wheel.teeth", "worm.starts"), "spur": ("gear.teeth", "pinion.teeth"),
               "belt": ("driven.teeth", "driver.teeth")}[kind]
    out, inp = v[members[0]], v[members[1]]
    return None if MISSING in (out, inp) else out / inp


def _load_radius(kind: str, v: dict) -> float | None:
    """The radius [mm] that turns the torque on the stage's output shaft into its load: spur, the gear's
    base radius r cos(alpha); worm, the wheel radius times cos(alpha_n) cos(lambda) (the normal force of
    the worm mesh); belt, the driven pulley's pitch radius (the effective tension)."""
    if kind == "spur":
        need = ("module_mm", "gear.teeth", "pressure_angle_deg")
        if MISSING in (v[k] for k in need):
            return None
        return v["module_mm"] * v["gear.teeth"] / 2.0 * math.cos(v["pressure_angle_deg"])
    if kind == "worm":
        need = ("module_mm", "wheel.teeth", "normal_pressure_angle_deg", "lead_angle_deg")
        if MISSING in (v[k] for k in need):
            return None
        return (v["module_mm"] * v["wheel.teeth"] / 2.0 * math.cos(v["normal_pressure_angle_deg"])
                * math.cos(v["lead_angle_deg"]))
    if MISSING in (v["driven.teeth"], v["pitch_mm"]):
        return None
    return pulley_radius(v["driven.teeth"], v["pitch_mm"])


def _loads(stages: list[StageInput], values: list[dict], torque_nm: float | None) -> None:
    """Fill each stage's load not given in the file: the output torque T carried back to the stage's
    output shaft, T / O (O = product of the ratios after the stage; losses neglected), over its load
    radius (:func:`_load_radius`); 0 without a torque."""
    after = 1.0
    for s, v in zip(reversed(stages), reversed(values)):
        key = "effective_tension_N" if s.kind == "belt" else "normal_force_N"
        if v[key] is MISSING:
            radius = _load_radius(s.kind, v)
            v[key] = 0.0 if (torque_nm is None or not radius) else torque_nm * 1000.0 / after / radius
        ratio = _ratio(s.kind, v)
        after *= ratio if ratio else 1.0


def _names(stages: list[StageInput], source: str, problems: list[str]) -> list[str]:
    counts: dict[str, int] = {}
    for s in stages:
        counts[s.kind] = counts.get(s.kind, 0) + 1
    names = []
    for s in stages:
        given = s.values.get("name", MISSING)
        base = DEFAULT_NAMES[s.kind]
        names.append(given if given not in (MISSING, None) else (base if counts[s.kind] == 1 else f"{base}{s.index}"))
    for s, name in zip(stages, names):
        first = names.index(name)
        if stages[first].index != s.index:
            problems.append(f"{source}: {stage_label(s.index, s.kind)}: name: \"{name}\" is also the name of "
                            f"{stage_label(stages[first].index, stages[first].kind)}; give each stage its own name")
    return names


def build_stages(stages: list[StageInput], source: str, problems: list[str], model_default: str,
                 torque_nm: float | None, paths: list[dict] | None = None) -> tuple:
    """The records of checked stage tables (motor -> output), or () when ``problems`` is not empty.

    ``model_default``: ``[stiffness] model``; ``torque_nm``: ``[drive] output_torque_Nm`` (None: not
    given); ``paths``: per stage, stage key -> TOML path (default ``stage.INDEX.KEY``)."""
    names = _names(stages, source, problems)
    values = [_defaults(s, model_default, f"{source}: {stage_label(s.index, s.kind)}", problems) for s in stages]
    _loads(stages, values, torque_nm)
    if problems:
        return ()
    out = []
    for k, (s, v, name) in enumerate(zip(stages, values, names)):
        where = paths[k] if paths is not None else {f.path: stage_path(s.index, f.path) for f in STAGE_FIELDS[s.kind]}
        origins = {f.path: ("spec" if f.path in s.written else "grade" if f.path in s.grade_keys else "default")
                   for f in STAGE_FIELDS[s.kind]}
        load = "effective_tension_N" if s.kind == "belt" else "normal_force_N"
        if load not in s.written and torque_nm is not None:
            origins[load] = "spec"  # derived from the drive's output torque, a value the file gives
        out.append(make_record(s.kind, s.index, name, v, where, origins))
    return tuple(out)


def make_record(kind: str, index: int, name: str, values: dict, paths: dict, origins: dict):
    """The record of kind ``kind`` from complete ``values`` (stage key -> internal value)."""
    cls, member_classes = RECORDS[kind]
    top: dict[str, Any] = {"index": index, "name": name, "paths": MappingProxyType(dict(paths)),
                           "origins": MappingProxyType(dict(origins))}
    members: dict[str, dict] = {m: {} for m in member_classes}
    for f in STAGE_FIELDS[kind]:
        if f.path in ("kind", "name"):
            continue
        head, _, tail = f.path.partition(".")
        if tail:
            members[head][f.attr] = values[f.path]
        else:
            top[f.attr] = values[f.path]
    for m, mcls in member_classes.items():
        top[m] = mcls(**members[m])
    return cls(**top)


def record_values(record) -> dict:
    """stage key -> internal value of a stage record (the inverse of :func:`make_record`)."""
    out: dict[str, Any] = {"kind": record.kind, "name": record.name}
    for f in STAGE_FIELDS[record.kind]:
        if f.path in ("kind", "name"):
            continue
        head, _, tail = f.path.partition(".")
        out[f.path] = getattr(getattr(record, head), f.attr) if tail else getattr(record, f.attr)
    return out


# --- the legacy two-table form: the train [worm, spur] ------------------------------------------------------


def _legacy_keys() -> dict[str, tuple[str, str]]:
    worm = {
        "worm_pair.module_mm": "module_mm", "worm_pair.normal_pressure_angle_deg": "normal_pressure_angle_deg",
        "worm_pair.lead_angle_deg": "lead_angle_deg",
        "worm_pair.transverse_pressure_angle_deg": "transverse_pressure_angle_deg",
        "worm_pair.face_width_mm": "face_width_mm", "worm_pair.lead_error_mm": "lead_error_mm",
        "worm_pair.lead_error_phase_deg": "lead_error_phase_deg",
        "assembly.worm_centre_distance_error_mm": "centre_distance_error_mm",
        "assembly.worm_pair_errors_mm": "alignment_errors_mm",
        "assembly.worm_eccentricity_mm": "worm.runout_mm",
        "assembly.worm_eccentricity_phase_deg": "worm.runout_phase_deg",
        "assembly.worm_bearing_clearance_mm": "worm.bearing_clearance_mm",
        "assembly.wheel_eccentricity_mm": "wheel.runout_mm",
        "assembly.wheel_eccentricity_phase_deg": "wheel.runout_phase_deg",
        "assembly.wheel_bearing_clearance_mm": "wheel.bearing_clearance_mm",
        "loads.worm_normal_force_N": "normal_force_N",
        "requirements.max_worm_transmission_error_arcsec": "max_transmission_error_arcsec",
        "requirements.max_worm_backlash_arcsec": "max_backlash_arcsec",
        **{f"worm_pair.worm.{k}": f"worm.{k}" for k in ("starts", "profile_error_mm", "thickness_deviation_mm")},
        **{f"worm_pair.wheel.{k}": f"wheel.{k}" for k in (
            "teeth", "profile_error_mm", "thickness_deviation_mm", "radial_composite_error_mm",
            "radial_composite_phase_deg", "cumulative_pitch_deviation_mm", "cumulative_pitch_phase_deg")},
    }
    member_keys = ("teeth", "accuracy_grade", "cumulative_pitch_deviation_mm", "single_pitch_deviation_mm",
                   "cumulative_pitch_phase_deg", "single_pitch_phase_deg", "profile_error_mm",
                   "thickness_deviation_mm")
    spur = {
        **{f"gear_pair.{k}": k for k in ("module_mm", "pressure_angle_deg", "face_width_mm", "kinematics")},
        **{f"gear_pair.output_gear.{k}": f"gear.{k}" for k in member_keys},
        **{f"gear_pair.pinion.{k}": f"pinion.{k}" for k in member_keys},
        "assembly.gear_centre_distance_error_mm": "centre_distance_error_mm",
        "assembly.gear_eccentricity_mm": "eccentricity_mm",
        "assembly.gear_eccentricity_phase_deg": "eccentricity_phase_deg",
        "loads.gear_normal_force_N": "normal_force_N",
        "requirements.max_gear_transmission_error_arcsec": "max_transmission_error_arcsec",
        "requirements.max_gear_backlash_arcsec": "max_backlash_arcsec",
    }
    return {**{k: ("worm", v) for k, v in worm.items()}, **{k: ("spur", v) for k, v in spur.items()}}


#: legacy key (two-table form) -> (stage kind, stage key): the worm pair is stage 1, the spur pair stage 2
LEGACY_KEYS: dict[str, tuple[str, str]] = _legacy_keys()
#: the legacy form's train, motor -> output
LEGACY_TRAIN = ("worm", "spur")
#: (kind, stage key) -> legacy key
STAGE_TO_LEGACY: dict[tuple[str, str], str] = {v: k for k, v in LEGACY_KEYS.items()}


def is_legacy_train(stages) -> bool:
    """Whether the train is one worm stage followed by one spur stage (the legacy form's drive)."""
    return tuple(s.kind for s in stages) == LEGACY_TRAIN


def legacy_path(stages, path: str) -> str:
    """A TOML path of the stage form (``stage.2.module_mm``) as the legacy key of a [worm, spur]
    train (``gear_pair.module_mm``); other paths, and any path of another train, unchanged."""
    parts = path.split(".", 2)
    if len(parts) == 3 and parts[0] == "stage" and parts[1].isdigit() and is_legacy_train(stages):
        kind = LEGACY_TRAIN[int(parts[1]) - 1] if 1 <= int(parts[1]) <= 2 else None
        return STAGE_TO_LEGACY.get((kind, parts[2]), path)
    return path


def new_path(stages, path: str) -> str:
    """A legacy key as the stage-form path of a [worm, spur] train (``gear_pair.module_mm`` ->
    ``stage.2.module_mm``); other paths unchanged.  ``stages`` None: the legacy form's train."""
    hit = LEGACY_KEYS.get(path)
    if hit is None or (stages is not None and not is_legacy_train(stages)):
        return path
    return stage_path(LEGACY_TRAIN.index(hit[0]) + 1, hit[1])
