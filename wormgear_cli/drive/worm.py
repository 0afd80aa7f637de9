"""The worm stage of a train: the paper's Delta phi_wc and Delta phi_wh, its sources at the output.

Index 1 is the worm (on the stage's input shaft), index 2 the wheel (on its output shaft).  At the
wheel shaft (:mod:`wormgear_cli.physics.worm`):

    Delta phi_wc = 2 (delta2 + h) / (m2 z3),  h = 1/2 sqrt(f_hL^2 + (S1^2 + C1^2)/cos^2(lambda) + F_i^2
                                                       + (S2^2 + C2^2)/cos^2(alpha_2))
    Delta phi_wh = 2 (Delta j_central + h_j) / (m2 z3)

S1 and S2 are radial runouts (total indicator readings); for an eccentric member S = 2 e, so the
paper's term S2 / (2 cos(alpha_2)) on the wheel's pitch circle is e / r_b,wheel at the wheel: the
involute rule of the spur stage and of the effect catalogue (docs/models.md, "Runout and
eccentricity").  With ``anti_backlash = "duplex"`` (a duplex worm set axially) the clearance terms
of Delta j are replaced by the stated residual lost motion; the deflection stays.

Sources at the output (A = the product of the ratios after the stage, r_w the wheel's pitch radius,
O_w = A z3 / z_worm the worm shaft's order): the lead error f_hL / 2 and the worm runout
sqrt(S1^2 + C1^2) / (2 cos(lambda)) at O_w; the radial composite error F_i / 2 and the wheel runout
sqrt(S2^2 + C2^2) / (2 cos(alpha_2)) at A; each / (r_w A): the paper's +/- half-width term by term.
The wheel's cumulative pitch deviation F_p / (2 r_w) / A at A (the full budget).
"""

import math
from typing import Any, NamedTuple

import numpy as np

from wormgear_cli.drive import stiffness
from wormgear_cli.drive.records import Clearance, StageResult, Static, sine_source
from wormgear_cli.physics import thermal
from wormgear_cli.physics import worm as model
from wormgear_cli.physics.spur import pitch_arc_to_angle
from wormgear_cli.spec.stages import record_values

#: the paper's names of the worm stage's TE and backlash
SYMBOLS = ("Delta phi_wc", "Delta phi_wh")
#: what sits on the stage's input and output shaft
MEMBER_NAMES = ("worm", "wheel")


def teeth(stage) -> tuple[int, int]:
    """(teeth of the wheel, starts of the worm): the stage's ratio as whole numbers."""
    return stage.wheel.teeth, stage.worm.starts


def mesh_orders(stage, after: float, of: str) -> list[tuple[float, str, str]]:
    """(order at the output, kind, label) of the stage's meshes: the worm mesh at z_wheel per wheel turn."""
    return [(stage.wheel.teeth * after, "mesh", f"worm mesh{of}")]


def base_circle(stage) -> tuple[float, int]:
    """(base radius [mm], teeth) of the wheel (in its transverse plane)."""
    return stage.module * stage.wheel.teeth * math.cos(stage.transverse_pressure_angle) / 2.0, stage.wheel.teeth


def tooth_deflection(spec, stage, stages) -> float:
    """The mesh's tooth deflection under the stage's load [mm] (:func:`~wormgear_cli.drive.stiffness.deflection`)."""
    return float(stiffness.deflection(spec, stage, stages=stages))


class WormParts(NamedTuple):
    """The paper's worm stage at the wheel shaft [rad], and its parts on the wheel's pitch circle [mm]
    (arrays when an input is one): ``transmission_error`` Delta phi_wc, ``backlash`` Delta phi_wh;
    ``te_halfwidth`` h, ``backlash_halfwidth`` h_j; ``backlash_deformation``, ``backlash_profile``,
    ``backlash_thickness`` (the central backlash's parts)."""

    transmission_error: Any
    backlash: Any
    te_halfwidth: Any
    backlash_halfwidth: Any
    backlash_deformation: Any
    backlash_profile: Any
    backlash_thickness: Any


def values(stage):
    """``value(key)`` -> the stage's own value of a stage key (internal units)."""
    table = record_values(stage)
    return table.__getitem__


def paper(stage, deflection, value=None) -> WormParts:
    """The paper's worm stage at tooth deflection ``deflection`` [mm] (delta2; scalar or array).
    ``value(key)``: the tolerances by stage key (default the stage's own; arrays of sampled drives
    allowed, ``alignment_errors_mm`` a sequence of six)."""
    v = value or values(stage)
    lam, a2 = stage.lead_angle, stage.transverse_pressure_angle
    m2, z3 = stage.module, stage.wheel.teeth
    f_hl, fi = v("lead_error_mm"), v("wheel.radial_composite_error_mm")
    h_te = model.worm_te_halfwidth(f_hl, v("worm.runout_mm"), v("worm.bearing_clearance_mm"), fi, v("wheel.runout_mm"),
                                   v("wheel.bearing_clearance_mm"), lam, a2)
    wte = model.worm_te(deflection, h_te, m2, z3)
    ft1, ft2 = v("worm.profile_error_mm"), v("wheel.profile_error_mm")
    ts1, ts2 = v("worm.thickness_deviation_mm"), v("wheel.thickness_deviation_mm")
    j_def, j_prof, j_thk = model.worm_backlash_central(deflection, ft1, ft2, ts1, ts2, lam)
    e_sq = sum(e * e for e in v("alignment_errors_mm"))
    h_j = model.worm_backlash_halfwidth(ft1, ft2, ts1, ts2, e_sq, f_hl, v("centre_distance_error_mm"), fi, lam, a2)
    wbl = model.worm_backlash(j_def + j_prof + j_thk, h_j, m2, z3)
    return WormParts(wte, wbl, h_te, h_j, j_def, j_prof, j_thk)


def additions(spec, stage) -> tuple[dict, dict]:
    """What the stage adds beyond the paper's equations, at the wheel shaft [rad]: (backlash additions,
    TE additions), each only when the spec gives it a size (docs/models.md, "Beyond the paper"):

    * ``axial_play``: the thrust bearing's axial play c_a.  The worm's axial section is a rack: an
      axial shift x of the worm turns the wheel by the arc x on its pitch circle (the lead maps it one
      to one), so a play c_a is a lost motion c_a / r_w;
    * ``axial_compliance``: a preloaded thrust bearing of axial stiffness k_a yields F_a / k_a under the
      axial force F_a = the wheel's tangential force F_N cos(alpha_n) cos(lambda); both ways: 2 F_a / (k_a r_w);
    * ``shaft_compliance``: the wheel shaft's torsional stiffness k_s under the wheel's torque
      T = F_a r_w: 2 T / k_s;
    * ``thermal``: the backlash change of the mesh and housing warmed by different amounts,
      2 Delta a tan(alpha_2) / r_w with Delta a = a alpha_H dT_H - (r_1 alpha_1 + r_2 alpha_2) dT_mesh
      (:func:`wormgear_cli.physics.thermal.centre_distance_growth`; negative: it closes);
    * TE ``thermal_drift``: the worm shaft's axial growth between its thrust bearing and the mesh,
      L alpha_worm dT_shaft / r_w (:func:`wormgear_cli.physics.thermal.axial_growth`), a drift of the
      output against the calibration (its size).
    """

    r_w, w = stage.output_radius, stage.worm
    force = float(stiffness.tangential_force(stage, stage.normal_force))
    bl, te = {}, {}
    if w.axial_play:
        bl["axial_play"] = w.axial_play / r_w
    if w.axial_stiffness:
        bl["axial_compliance"] = 2.0 * force / w.axial_stiffness / r_w
    if stage.shaft_stiffness:
        bl["shaft_compliance"] = 2.0 * force * r_w / 1000.0 / stage.shaft_stiffness
    mat = spec.materials
    if stage.mesh_temperature_rise or stage.housing_temperature_rise:
        r1 = stage.worm.starts * stage.module / math.tan(stage.lead_angle) / 2.0
        da = thermal.centre_distance_growth(r1 + r_w, r1, r_w, mat.housing_expansion, mat.worm_expansion,
                                            mat.wheel_expansion, stage.housing_temperature_rise,
                                            stage.mesh_temperature_rise, stage.mesh_temperature_rise)
        bl["thermal"] = 2.0 * da * math.tan(stage.transverse_pressure_angle) / r_w
    growth = thermal.axial_growth(w.thrust_bearing_distance, mat.worm_expansion, stage.worm_shaft_temperature_rise)
    if growth:
        te["thermal_drift"] = abs(growth) / r_w
    return bl, te


def totals(stage, deflection, value=None, spec=None) -> tuple:
    """(TE, backlash) at the wheel shaft [rad] of the stage at tooth deflection ``deflection`` [mm], from
    ``value(key)`` (default the stage's own values; arrays of sampled drives allowed): the paper's
    Delta phi_wc and Delta phi_wh, or with a duplex worm the deflection's part of Delta phi_wh plus the
    stated residual lost motion (what ``analyze`` reports and ``tolerance`` samples).  With ``spec``
    (the drive-level settings) the stage's additions beyond the paper (:func:`additions`, not
    sampled) are added; the backlash never below zero (a mesh warmed shut binds)."""
    p = paper(stage, deflection, value)
    if stage.anti_backlash == "none":
        te, bl = p.transmission_error, p.backlash
    else:
        arc = pitch_arc_to_angle(p.backlash_deformation, stage.module, stage.wheel.teeth)
        te, bl = p.transmission_error, 0.0 + arc + float(stage.residual_lost_motion)
    if spec is None:
        return te, bl
    extra_bl, extra_te = additions(spec, stage)
    return te + sum(extra_te.values()), np.maximum(bl + sum(extra_bl.values()), 0.0)


def sampled_totals(stage, deflection, value, spec, te_max=None) -> tuple:
    """(TE, backlash) at the wheel shaft [rad] of sampled drives (:func:`totals` with its additions
    beyond the paper, which are not sampled): every model's entry for the tolerance analysis."""
    return totals(stage, deflection, value, spec)  # the worm stage's one definition


def evaluate(spec, stage, t, deflection: float) -> StageResult:
    """The stage's TE and backlash at the wheel shaft, with their parts (``spec``: the drive-level
    settings; ``t``: the train); the parts beyond the paper (:func:`additions`) only when given."""
    p = paper(stage, deflection)

    def arc(x):
        return float(pitch_arc_to_angle(x, stage.module, stage.wheel.teeth))

    extra_bl, extra_te = additions(spec, stage)
    te_parts = {"deformation": arc(deflection), "envelope": arc(p.te_halfwidth), **extra_te}
    if stage.anti_backlash == "none":
        bl_parts = {"deformation": arc(p.backlash_deformation), "profile": arc(p.backlash_profile),
                    "thickness": arc(p.backlash_thickness), "envelope": arc(p.backlash_halfwidth), **extra_bl}
    else:
        bl_parts = {"deformation": arc(p.backlash_deformation), "residual": float(stage.residual_lost_motion),
                    **extra_bl}
    backlash = float(totals(stage, deflection, spec=spec)[1])  # never negative: a mesh warmed shut binds
    info = {"deflection_um": float(deflection * 1e3), "line_load_N_per_mm": stiffness.line_load(spec, stage),
            "normal_force_N": float(stage.normal_force), "anti_backlash": stage.anti_backlash,
            "starts": stage.worm.starts}
    return StageResult(stage.index, stage.name, "worm", stage.ratio, t.after(stage),
                       float(p.transmission_error) + sum(extra_te.values()), backlash, te_parts, bl_parts, info,
                       SYMBOLS)


def _runout(runout, clearance, angle):
    """sqrt(S^2 + C^2) / cos(angle) [mm] (math.hypot for numbers, numpy's for arrays)."""
    if np.ndim(runout) == 0 and np.ndim(clearance) == 0:
        return math.hypot(runout, clearance) / math.cos(angle)
    return np.hypot(runout, clearance) / math.cos(angle)


def sources(spec, stage, t, deflection: float, result: StageResult, origin) -> tuple[list, list, list]:
    """(periodic sources, static terms, constant clearances) of the stage at the output (module
    docstring); ``result``: the stage's :func:`evaluate`.  ``origin(stage, keys)``: the origin of a
    size read from ``keys``."""
    after = t.after(stage)
    r_w = stage.output_radius
    to_out = 1.0 / (r_w * after)
    n_w = t.before(stage)
    lam, a2 = stage.lead_angle, stage.transverse_pressure_angle
    ident = {"stage_index": stage.index, "stage_kind": "worm"}
    own = values(stage)

    def src(name, key_phase, order, size, keys, part, phase, tier=0, lost=None, lost_size=None):
        amp = float(size(own))
        return sine_source(name, stage.paths[key_phase], order, amp, phase, stage.name, "shaft",
                           tuple(stage.paths[k] for k in keys), lost, part=part, origin=origin(stage, keys),
                           size_keys=keys, size=size, tier=tier, lost_size=lost_size, **ident)

    clears = stage.anti_backlash == "none"
    lost = _lost_motion(stage, after, to_out, own) if clears else None

    def lost_size(v):  # constant where its causes are, varying with F_i (:func:`lost_motion_terms`)
        constant, amplitude = lost_motion_terms(stage, paper(stage, 0.0, v), v)
        return constant, amplitude, to_out, True

    out = [
        src("worm_lead_error", "lead_error_phase_deg", n_w, lambda v: v("lead_error_mm") * (0.5 * to_out),
            ("lead_error_mm",), "worm", stage.lead_error_phase),
        src("worm_eccentricity", "worm.runout_phase_deg", n_w,
            lambda v: _runout(v("worm.runout_mm"), v("worm.bearing_clearance_mm"), lam) * (0.5 * to_out),
            ("worm.runout_mm", "worm.bearing_clearance_mm"), "worm", stage.worm.runout_phase),
        src("wheel_radial_composite", "wheel.radial_composite_phase_deg", after,
            lambda v: v("wheel.radial_composite_error_mm") * (0.5 * to_out), ("wheel.radial_composite_error_mm",),
            "wheel", stage.wheel.radial_composite_phase, lost=lost, lost_size=lost_size if clears else None),
        src("wheel_eccentricity", "wheel.runout_phase_deg", after,
            lambda v: _runout(v("wheel.runout_mm"), v("wheel.bearing_clearance_mm"), a2) * (0.5 * to_out),
            ("wheel.runout_mm", "wheel.bearing_clearance_mm"), "wheel", stage.wheel.runout_phase),
        src("wheel_cumulative_pitch", "wheel.cumulative_pitch_phase_deg", after,
            lambda v: v("wheel.cumulative_pitch_deviation_mm") / (2.0 * r_w) / after,
            ("wheel.cumulative_pitch_deviation_mm",), "wheel", stage.wheel.cumulative_pitch_phase, tier=1),
    ]
    if stage.worm.axial_runout:  # an axial motion a/2 sin(worm turn), an arc of the wheel (listed when given)
        out.append(src("worm_axial_runout", "worm.axial_runout_phase_deg", n_w,
                       lambda v: v("worm.axial_runout_mm") * (0.5 * to_out), ("worm.axial_runout_mm",), "worm",
                       stage.worm.axial_runout_phase, tier=1))
    static = [Static("worm_deflection", result.te_parts["deformation"] / after,
                     stage.name, stage.index, "worm", origin(stage, ("normal_force_N",)),
                     (stage.paths["normal_force_N"],))]
    keys = ("worm.thrust_bearing_distance_mm", "worm_shaft_temperature_rise_K")
    if "thermal_drift" in result.te_parts:
        static.append(Static("worm_thermal_drift", result.te_parts["thermal_drift"] / after, stage.name, stage.index,
                             "worm", origin(stage, keys), tuple(stage.paths[k] for k in keys), "thermal"))
    clear = [] if stage.anti_backlash == "none" else [
        Clearance("worm_residual_lost_motion", float(stage.residual_lost_motion) / after, stage.name, stage.index,
                  "worm")]
    for part, name in (("axial_play", "worm_axial_play"), ("thermal", "worm_thermal_backlash")):
        if part in result.backlash_parts:  # constant lost motion (the compliances are compliance())
            clear.append(Clearance(name, result.backlash_parts[part] / after, stage.name, stage.index, "worm"))
    return out, static, clear


def lost_motion_terms(stage, parts: WormParts, value=None) -> tuple:
    """(constant, amplitude) of the worm stage's clearance on the wheel's pitch circle [mm] at no load:
    L(theta) = max(constant + amplitude sin(A theta + psi_Fi), 0) (arrays of sampled drives allowed).

    What varies over a turn and what does not: the wheel's radial composite deviation F_i is the
    change of the working centre distance over one wheel turn (double-flank test, peak to peak), so
    the centre distance swings by +/- F_i / 2 and the circumferential backlash by
    +/- 2 (F_i / 2) tan(alpha_2) = +/- F_i tan(alpha_2) (reference facts: j_t = 2 Delta a tan alpha),
    once per wheel turn.  Everything else in the paper's Delta j (profile and thickness errors, the
    six alignment errors e_i, the lead error, the centre-distance error f_a) is a property of the
    assembled pair that does not turn with the wheel: a constant.  The largest clearance stays the
    paper's bound Delta j_central + h_j (analyze's Delta phi_wh without the deflection), reached
    where the runout opens the mesh most; the smallest is 2 F_i tan(alpha_2) below it.
    ``parts``: :func:`paper` at deflection 0; ``value``: the stage's values (default its own)."""
    v = value or values(stage)
    amplitude = v("wheel.radial_composite_error_mm") * math.tan(stage.transverse_pressure_angle)
    top = parts.backlash_profile + parts.backlash_thickness + parts.backlash_halfwidth
    return top - amplitude, amplitude


def _lost_motion(stage, after: float, to_out: float, own):
    """max(constant + amplitude sin(A theta + psi), 0) / r_w / A  [rad] at the output
    (:func:`lost_motion_terms`): the paper's clearance, constant where its causes are, varying once
    per wheel turn with the wheel's runout (F_i).  Clipped at zero: a clearance cannot be negative."""
    constant, amplitude = (float(x) for x in lost_motion_terms(stage, paper(stage, 0.0, own), own))
    return lambda theta, phase: np.maximum(constant + amplitude * np.sin(after * theta + phase), 0.0) * to_out


def compliance(spec, stage, t, deflection: float) -> tuple[float, float]:
    """(process lag, wind-up per N m of output torque) at the output [rad, rad/(N m)]: the deflection
    along the flanks, delta2 / (cos(lambda) r_w), per direction; the wheel's torque T / A gives the
    normal force T / (A r_w cos(alpha_n) cos(lambda)) (ISO 6336-1's c' held at the spec's load).  With
    a thrust bearing's axial stiffness k_a and the wheel shaft's torsional stiffness k_s
    (:func:`additions`) their wind-up adds: F_a / (k_a r_w A) and T_wheel / (k_s A) per direction,
    1 / (k_a r_w^2 A^2) and 1 / (k_s A^2) per N m of output torque."""
    after, r_w = t.after(stage), stage.output_radius
    angle_per_mm = 1.0 / (math.cos(stage.lead_angle) * r_w * after)
    unit = stiffness.deflection(spec, stage, 1.0, linear_at_spec_load=True)
    force_per_nm = 1000.0 / after / (r_w * math.cos(stage.normal_pressure_angle) * math.cos(stage.lead_angle))
    lag, per_nm = float(deflection * angle_per_mm), float(unit * force_per_nm * angle_per_mm)
    force = float(stiffness.tangential_force(stage, stage.normal_force))  # the wheel's, the worm's axial force
    if stage.worm.axial_stiffness:
        k = stage.worm.axial_stiffness
        lag, per_nm = lag + force / k / (r_w * after), per_nm + 1000.0 / (after * r_w) / k / (r_w * after)
    if stage.shaft_stiffness:
        k = stage.shaft_stiffness
        lag, per_nm = lag + force * r_w / 1000.0 / k / after, per_nm + 1.0 / (k * after * after)
    return lag, per_nm
