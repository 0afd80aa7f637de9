"""The spur stage of a train: the paper's Delta phi_cc and Delta phi_ch (or the involute reading),
its sources at the output.

Pinion (radius R1, z2 teeth) on the stage's input shaft, gear (R2, z1) on its output shaft.  At
the gear shaft (:mod:`wormgear_cli.physics.spur`), by ``kinematics``:

* ``paper``: Delta phi_cc(phi) = (R1+R2)/(2R2) F(l, phi) + delta1 sin(alpha + lambda1)/R2 at its
  maximum over the pinion angle phi; Delta phi_ch = 2 Delta C1 / (m1 z1) with
  Delta C1 = 2 Delta e tan(alpha) |sin phi| + 2 delta1.  The stage's TE is the paper's figure (the
  curve's maximum); its source in the budget is the curve's periodic part (the maximum less the
  curve's mean, ``Source.offset``, which shifts every position alike and is reported apart).
* ``involute``: an eccentricity e gives TE e / r_b2 at the pinion's order, a centre-distance error
  Delta a a backlash 2 Delta a tan(alpha) and no TE, the thickness allowances add to the backlash.

With ``anti_backlash = "split_pinion"`` (a split or spring-preloaded pinion) the clearance terms of
the backlash are replaced by the stated residual lost motion; the deflection stays.

Sources at the output (A = the product of the ratios after the stage, O_p = A z1 / z2 the pinion
shaft's order): the eccentricity Delta e at O_p (paper: the kinematic Delta phi_cc curve at the
pinion angle O_p theta + psi, / A; involute: e / r_b2 / A); the full budget's pitch deviations,
each a once-per-turn TE of peak-to-peak F_p / r at its shaft carried to the output (gear
F_p / (2 R2) / A at A, pinion F_p / (2 R1) / O_p at O_p) and the single pitch deviations f_p at
the mesh order z1 A.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np

from wormgear_cli.drive import stiffness
from wormgear_cli.drive.records import Clearance, Source, StageResult, Static, sine, sine_source
from wormgear_cli.physics import spur as model
from wormgear_cli.spec.stages import record_values

#: the paper's names of the spur stage's TE and backlash
SYMBOLS = ("Delta phi_cc", "Delta phi_ch")
#: what sits on the stage's input and output shaft
MEMBER_NAMES = ("pinion", "gear")


def teeth(stage) -> tuple[int, int]:
    """(teeth of the gear, teeth of the pinion): the stage's ratio as whole numbers."""
    return stage.gear.teeth, stage.pinion.teeth


def mesh_orders(stage, after: float, of: str) -> list[tuple[float, str, str]]:
    """(order at the output, kind, label) of the stage's meshes: the spur mesh at z_gear per gear turn."""
    return [(stage.gear.teeth * after, "mesh", f"spur mesh{of}")]


def base_circle(stage) -> tuple[float, int]:
    """(base radius [mm], teeth) of the gear."""
    return stage.module * stage.gear.teeth * math.cos(stage.pressure_angle) / 2.0, stage.gear.teeth


def tooth_deflection(spec, stage, stages) -> float:
    """The mesh's tooth deflection under the stage's load [mm] (:func:`~wormgear_cli.drive.stiffness.deflection`)."""
    return float(stiffness.deflection(spec, stage, stages=stages))


def radii(stage) -> tuple[float, float]:
    """(R1 pinion, R2 gear) pitch radii [mm]."""
    return stage.module * stage.pinion.teeth / 2.0, stage.module * stage.gear.teeth / 2.0


def base_radius(stage) -> float:
    """r_b2 = m z1 cos(alpha) / 2, the gear's base radius [mm]."""
    return stage.module * stage.gear.teeth * math.cos(stage.pressure_angle) / 2.0


def paper_te_max(r1, r2, de, alpha, deflection):
    """The paper's Delta phi_cc at its maximum: (value [rad], pinion angle at it [rad]) of
    :func:`~wormgear_cli.physics.spur.gear_te_max_fast`.  One drive's (scalar arguments) is kept: its
    evaluation, its sources and its totals ask for the same two maxima (with and without the tooth
    deflection), and a command analyses a drive more than once (the budget, the report); arrays of
    sampled drives are computed each time."""
    if all(np.ndim(a) == 0 for a in (r1, r2, de, alpha, deflection)):
        return _kept_te_max(float(r1), float(r2), float(de), float(alpha), float(deflection))
    return model.gear_te_max_fast(r1, r2, de, alpha, deflection)


@functools.lru_cache(maxsize=256)
def _kept_te_max(r1: float, r2: float, de: float, alpha: float, deflection: float) -> tuple:
    value, phi = model.gear_te_max_fast(r1, r2, de, alpha, deflection)
    value.setflags(write=False)  # shared by every caller: read only
    phi.setflags(write=False)
    return value, phi


def values(stage):
    """``value(key)`` -> the stage's own value of a stage key (internal units); the eccentricity is the
    one the kinematics uses (:attr:`~wormgear_cli.spec.stages.SpurStageSpec.model_eccentricity`)."""

    table = record_values(stage)
    table["eccentricity_mm"] = stage.model_eccentricity
    return table.__getitem__


def totals(stage, deflection, value=None, te_max=None) -> tuple:
    """(TE, backlash) at the gear shaft [rad] at tooth deflection ``deflection`` [mm], from ``value(key)``
    (default the stage's own values; arrays of sampled drives allowed): the paper's Delta phi_cc at its
    maximum over the pinion angle and Delta phi_ch, or the involute reading (module docstring); with a
    split pinion the backlash is the deflection's part plus the stated residual.  ``te_max(de)``: the
    paper's maximum as a function of Delta e alone (an interpolant for many samples; default exact)."""
    v = value or values(stage)
    r1, r2 = radii(stage)
    de, alpha = v("eccentricity_mm"), stage.pressure_angle
    if stage.kinematics == "paper":
        te = te_max(de) if te_max is not None else paper_te_max(r1, r2, de, alpha, deflection)[0]
        bl = model.gear_backlash_max(stage.module, stage.gear.teeth, de, alpha, deflection)
        bl_def = model.pitch_arc_to_angle(2.0 * deflection, stage.module, stage.gear.teeth)
    else:
        inv = model.involute_stage(r2, alpha, de, v("centre_distance_error_mm"), deflection,
                                   v("gear.thickness_deviation_mm") + v("pinion.thickness_deviation_mm"))
        te, bl, bl_def = inv.te_eccentricity + inv.te_deformation, inv.backlash, inv.backlash_deformation
    if stage.anti_backlash != "none":
        bl = 0.0 + bl_def + float(stage.residual_lost_motion)
    return te, bl + shaft_windup(stage)


def sampled_totals(stage, deflection, value, spec, te_max=None) -> tuple:
    """(TE, backlash) at the gear shaft [rad] of sampled drives (:func:`totals`; ``te_max`` the paper
    kinematics' interpolant of the TE maximum): every model's entry for the tolerance analysis."""
    return totals(stage, deflection, value, te_max)


def shaft_windup(stage) -> float:
    """The gear shaft's wind-up under the gear's torque F_N r_b2, both ways [rad at the gear shaft]:
    2 F_N r_b2 / k_s (0 without a torsional stiffness k_s)."""
    if not stage.shaft_stiffness:
        return 0.0
    return 2.0 * stage.normal_force * base_radius(stage) / 1000.0 / stage.shaft_stiffness


def evaluate(spec, stage, t, deflection: float) -> StageResult:
    """The stage's TE and backlash at the gear shaft, with their parts."""
    r_pinion, r_gear = radii(stage)
    de, alpha, m, z1 = stage.model_eccentricity, stage.pressure_angle, stage.module, stage.gear.teeth
    bl_thk = 0.0
    if stage.kinematics == "paper":
        _, phi_star = paper_te_max(r_pinion, r_gear, de, alpha, deflection)
        te_kin_only, _ = paper_te_max(r_pinion, r_gear, de, alpha, 0.0)
        te_kin = model.gear_kinematic_te(phi_star, r_pinion, r_gear, de, alpha)
        te_def = model.gear_deformation_te(phi_star, r_pinion, r_gear, de, alpha, deflection)
        bl = model.gear_backlash_max(m, z1, de, alpha, deflection)
        bl_def = model.pitch_arc_to_angle(2.0 * deflection, m, z1)
    else:
        inv = model.involute_stage(r_gear, alpha, de, stage.centre_distance_error, deflection,
                                   stage.gear.thickness_deviation + stage.pinion.thickness_deviation)
        phi_star = 0.5 * np.pi  # e sin(phi) peaks at a quarter turn of the pinion
        te_kin_only = te_kin = inv.te_eccentricity
        te_def, bl = inv.te_deformation, inv.backlash
        bl_def, bl_thk = inv.backlash_deformation, inv.backlash_thickness
    te_max = te_kin + te_def
    if stage.anti_backlash == "none":
        bl_parts = {"eccentricity": float(bl - bl_def - bl_thk), "deformation": float(bl_def),
                    "thickness": float(bl_thk)}
    else:
        bl_parts = {"deformation": float(bl_def), "residual": float(stage.residual_lost_motion)}
    if stage.shaft_stiffness:  # the gear shaft's wind-up under the gear's torque F_N r_b2, both ways
        bl_parts["shaft_compliance"] = shaft_windup(stage)
    backlash = float(totals(stage, deflection)[1])
    info = {
        "kinematics": stage.kinematics,
        "line_load_N_per_mm": stiffness.line_load(spec, stage),
        "phi_at_max_deg": float(np.degrees(phi_star)),
        # the paper's "load adds ~0.11 %": increase of the maximum caused by the deflection
        # (undefined, None, when there is no eccentric part to increase: Delta e = 0)
        "load_share_pct": (float(100.0 * (te_max - te_kin_only) / te_kin_only) if te_kin_only > 0 and deflection > 0
                           else (0.0 if deflection == 0 else None)),
        "deflection_um": float(deflection * 1e3),
        "normal_force_N": float(stage.normal_force),
        "anti_backlash": stage.anti_backlash,
    }
    return StageResult(stage.index, stage.name, "spur", stage.ratio, t.after(stage), float(te_max), backlash,
                       {"eccentricity": float(te_kin), "deformation": float(te_def)}, bl_parts, info, SYMBOLS)


def _first_harmonic(curve, samples: int = 256) -> float:
    """Size of the once-per-turn Fourier component of a 2 pi-periodic ``curve(phi)``.

    Exact for the gear curve (which is smooth, so 256 samples resolve its
    harmonics far beyond the first).  For small Delta e it approaches
    Delta e sqrt(1 + 4 tan^2 alpha) / (2 R2), with mean Delta e tan(alpha) / R2.
    """
    phi = np.arange(samples) * (2.0 * np.pi / samples)
    c = 2.0 / samples * np.sum(curve(phi) * np.exp(-1j * phi))
    return float(abs(c))


def _eccentricity_source(stage, t, origin) -> Source:
    """The eccentricity Delta e of the pinion shaft (module docstring), with its lost motion."""
    r1, r2 = radii(stage)
    de, alpha = stage.model_eccentricity, stage.pressure_angle
    o_p, after = t.before(stage), t.after(stage)
    keys: tuple[str, ...] = ("eccentricity_mm", "centre_distance_error_mm")
    curve_at: Callable | None
    lost_clear = stage.anti_backlash == "none"
    if stage.kinematics == "paper":
        def curve(theta, phase):
            return model.gear_kinematic_te(o_p * theta + phase, r1, r2, de, alpha) / after

        def lost(theta, phase):
            return de * math.tan(alpha) * (1.0 + np.sin(o_p * theta + phase)) / r2 / after

        def size(v):  # the periodic part's peak (the curve less its mean) as a function of Delta e
            e = v("eccentricity_mm")
            return (paper_te_max(r1, r2, e, alpha, 0.0)[0] - model.gear_kinematic_mean(r1, r2, e, alpha)) \
                / after

        def curve_at_paper(v, theta, phase):  # the curve of sampled drives (Delta e an array)
            return model.gear_kinematic_te(o_p * theta + phase, r1, r2, v("eccentricity_mm"), alpha) / after

        def lost_size(v):  # Delta e tan(alpha) (1 + sin) / R2, never negative (no clipping needed)
            c = v("eccentricity_mm") * (math.tan(alpha) / r2) / after
            return c, c, 1.0, False

        curve_at = curve_at_paper
        amp = _first_harmonic(lambda phi: model.gear_kinematic_te(phi, r1, r2, de, alpha)) / after
        offset = float(model.gear_kinematic_mean(r1, r2, de, alpha)) / after
        peak = float(paper_te_max(r1, r2, de, alpha, 0.0)[0]) / after - offset
    else:
        # involute: e / r_b at the pinion's order, i.e. e / r_b2 at the gear (models.gear.involute_stage);
        # the static part of the lost motion (centre distance, thickness allowances) is constant
        r_b = base_radius(stage)
        amp = peak = de / r_b / after
        offset = 0.0
        curve = sine(amp, o_p)
        static = (2.0 * stage.centre_distance_error * math.tan(alpha)
                  + stage.gear.thickness_deviation + stage.pinion.thickness_deviation)
        keys = ("eccentricity_mm",)

        def lost(theta, phase):
            return (static + de * math.tan(alpha) * (1.0 + np.sin(o_p * theta + phase))) / r2 / after

        counts = 1.0 if de == stage.eccentricity else 0.0  # involute: only an eccentricity the spec states

        def size(v):
            return counts * v("eccentricity_mm") / r_b / after

        curve_at = None

        def lost_size(v):  # (2 Delta a tan(alpha) + E_sn1 + E_sn2 + e tan(alpha) (1 + sin)) / R2, clipped at 0
            c = counts * v("eccentricity_mm") * (math.tan(alpha) / r2)
            fixed = (2.0 * math.tan(alpha) * v("centre_distance_error_mm") + v("gear.thickness_deviation_mm")
                     + v("pinion.thickness_deviation_mm"))
            return (c + fixed / r2) / after, c / after, 1.0, True
    return Source("gear_eccentricity", stage.paths["eccentricity_phase_deg"], o_p, amp, stage.eccentricity_phase,
                  curve, lost if lost_clear else None, stage.name, "shaft", tuple(stage.paths[k] for k in keys), peak,
                  stage.index, "spur", "pinion", origin(stage, keys), keys, size, 0,
                  lost_size if lost_clear else None, curve_at, offset)


def sources(spec, stage, t, deflection: float, result: StageResult, origin) -> tuple[list, list, list]:
    """(periodic sources, static terms, constant clearances) of the stage at the output (module
    docstring); ``result``: the stage's :func:`evaluate`.  ``origin(stage, keys)``: the origin of a
    size read from ``keys``."""
    r1, r2 = radii(stage)
    o_p, after = t.before(stage), t.after(stage)
    mesh = float(stage.gear.teeth) * after
    gear_name = "output_gear" if stage.index == len(t.stages) else "gear"
    ident = {"stage_index": stage.index, "stage_kind": "spur"}

    def pitch(member, name, key, order, kind, radius, per, tier):
        k = f"{member}.{key}_deviation_mm"
        phase_key = f"{member}.{key}_phase_deg"

        def size(v):
            return v(k) / (2.0 * radius) / per
        part = getattr(stage, member)
        amp = size(lambda _: getattr(part, f"{key}_deviation"))
        return sine_source(f"{name}_{key}", stage.paths[phase_key], order, amp, getattr(part, f"{key}_phase"),
                           stage.name, kind, (stage.paths[k],), part=member, origin=origin(stage, (k,)),
                           size_keys=(k,), size=size, tier=tier, **ident)

    out = [
        _eccentricity_source(stage, t, origin),
        pitch("gear", gear_name, "cumulative_pitch", after, "shaft", r2, after, 1),
        pitch("pinion", "pinion", "cumulative_pitch", o_p, "shaft", r1, o_p, 1),
        # single pitch deviation f_p: a tooth-to-tooth TE of peak-to-peak f_p on that gear's pitch circle, at
        # the mesh order z1 A (both gears: z2 O_p = z1 A)
        pitch("gear", gear_name, "single_pitch", mesh, "mesh", r2, after, 2),
        pitch("pinion", "pinion", "single_pitch", mesh, "mesh", r1, o_p, 2),
    ]
    static = [Static("gear_deflection", result.te_parts["deformation"] / after, stage.name, stage.index, "spur",
                     origin(stage, ("normal_force_N",)), (stage.paths["normal_force_N"],))]
    clear = [] if stage.anti_backlash == "none" else [
        Clearance("gear_residual_lost_motion", float(stage.residual_lost_motion) / after, stage.name, stage.index,
                  "spur")]
    return out, static, clear


def compliance(spec, stage, t, deflection: float) -> tuple[float, float]:
    """(process lag, wind-up per N m of output torque) at the output: paper, delta1 on the pitch arc
    (its Delta phi_ch); involute, along the line of action, 1 / r_b2; the gear's torque T / A gives the
    normal force T / (A r_b2) (ISO 6336-1's c' held at the spec's load); with the gear shaft's
    torsional stiffness k_s its wind-up adds (1 / (k_s O^2) at the output)."""
    after = t.after(stage)
    r_b = base_radius(stage)
    angle_per_mm = (1.0 / radii(stage)[1] if stage.kinematics == "paper" else 1.0 / r_b) / after
    unit = stiffness.deflection(spec, stage, 1.0, linear_at_spec_load=True)
    lag, per_nm = float(deflection * angle_per_mm), float(unit * (1000.0 / after / r_b) * angle_per_mm)
    if stage.shaft_stiffness:  # the gear shaft: T / (k A) per direction, 1 / (k A^2) per N m at the output
        k = stage.shaft_stiffness
        lag, per_nm = lag + stage.normal_force * r_b / 1000.0 / k / after, per_nm + 1.0 / (k * after * after)
    return lag, per_nm
