"""Whole-drive analysis: the paper's stage models applied to a :class:`Spec`.

No I/O.  :func:`analyze` returns an :class:`Analysis` holding every angle in
radians; :meth:`Analysis.report` converts to a unit for output, and
:meth:`Analysis.metrics` flattens it to the CSV/sweep columns.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from wormgear_cli.physics import deformation, worm
from wormgear_cli.physics import spur as gear
from wormgear_cli.units import to_unit

#: flat metric columns (CSV of analyze, columns of sweep --param); all angles
METRIC_COLUMNS = (
    "gear_transmission_error",
    "gear_backlash",
    "worm_transmission_error",
    "worm_backlash",
    "total_transmission_error",
    "total_backlash",
    "gear_te_eccentricity",
    "gear_te_deformation",
    "gear_backlash_eccentricity",
    "gear_backlash_deformation",
    "worm_te_deformation",
    "worm_te_envelope",
    "worm_backlash_deformation",
    "worm_backlash_profile",
    "worm_backlash_thickness",
    "worm_backlash_envelope",
)
#: flat non-angle columns that follow the angle columns
INFO_COLUMNS = ("gear_ratio", "gear_te_phi_deg", "gear_load_share_pct", "gear_deflection_um", "worm_deflection_um",
                "gear_te_share_pct", "gear_backlash_share_pct")


# an immutable named record built as a NamedTuple, not a frozen dataclass: it is created when
# ``analyze`` starts (0.1 ms against 0.6 ms; docs/development.md, "Start-up")
class Deflections(NamedTuple):
    """Tooth deflections [mm] and the model that produced them."""

    gear: float
    worm: float
    model: str


def geometry(spec):
    """Derived geometry used by the effect catalogue and simulation (a ``DriveGeometry``)."""
    from wormgear_cli.physics.geometry import DriveGeometry

    gp, wp = spec.gear_pair, spec.worm_pair
    z1, z2 = gp.output_gear.teeth, gp.pinion.teeth
    z3, zw = wp.wheel.teeth, wp.worm.starts
    i_c = z1 / z2
    worm_pitch_diameter = zw * wp.module / math.tan(wp.lead_angle)
    return DriveGeometry(
        output_pitch_radius=gp.module * z1 / 2.0,
        output_base_radius=gp.module * z1 * math.cos(gp.pressure_angle) / 2.0,
        wheel_pitch_radius=wp.module * z3 / 2.0,
        gear_ratio=i_c,
        worm_order=i_c * z3 / zw,
        output_teeth=z1,
        axial_pressure_angle=wp.transverse_pressure_angle,
        worm_centre_distance=(worm_pitch_diameter + wp.module * z3) / 2.0,
    )


def deflections(spec, gear_force=None, worm_force=None, linear_at_spec_load=False) -> Deflections:
    """delta1 and delta2 [mm] from the spec's loads and its selected stiffness model.

    ``gear_force``/``worm_force`` override the spec's normal forces [N]
    (arrays allowed; used by sweeps that hold torque instead of force).
    ``linear_at_spec_load``: evaluate ISO 6336-1's low-load reduction of c'
    at the spec's own loads and keep it fixed, so the deflection is linear in
    the given forces (the compliance about the operating point; a spec without
    load uses the unreduced c').  Otherwise c' follows the given forces.
    """
    st, mat = spec.stiffness, spec.materials
    f1 = spec.loads.gear_normal_force if gear_force is None else gear_force
    f2 = spec.loads.worm_normal_force if worm_force is None else worm_force
    e_gear = mat.gear_elastic_modulus  # both spur gears share one material
    e_worm = deformation.combined_modulus(mat.worm_elastic_modulus, mat.wheel_elastic_modulus)
    d1, d2 = _DEFLECTION_ADAPTERS[st.model](spec, f1, f2, e_gear, e_worm, linear_at_spec_load)
    return Deflections(float(d1) if np.ndim(d1) == 0 else d1, float(d2) if np.ndim(d2) == 0 else d2, st.model)


def gear_tangential_force(spec, normal_force):
    """F_t = F_N cos(alpha) [N] of the spur mesh."""
    return normal_force * math.cos(spec.gear_pair.pressure_angle)


def worm_tangential_force(spec, normal_force):
    """F_t = F_N cos(alpha_n) cos(lambda) [N] at the wheel (transverse, wheel plane)."""
    wp = spec.worm_pair
    return normal_force * math.cos(wp.normal_pressure_angle) * math.cos(wp.lead_angle)


def line_loads(spec) -> tuple[float, float]:
    """F_t K_A / b [N/mm] of the spur and the worm mesh at the spec's loads (ISO 6336-1)."""
    ka = spec.stiffness.iso_ka
    return (gear_tangential_force(spec, spec.loads.gear_normal_force) * ka / spec.gear_pair.face_width,
            worm_tangential_force(spec, spec.loads.worm_normal_force) * ka / spec.worm_pair.face_width)


def _empirical(spec, f1, f2, e_gear, e_worm, linear_at_spec_load=False):
    """The paper's empirical form for both meshes, with the spec's constants."""
    st = spec.stiffness
    const = (st.contact_ratio, st.empirical_lambda2, st.empirical_a1, st.empirical_b, st.empirical_c)
    return (deformation.empirical_deflection(f1, e_gear, spec.gear_pair.face_width, *const),
            deformation.empirical_deflection(f2, e_worm, spec.worm_pair.face_width, *const))


def _iso6336(spec, f1, f2, e_gear, e_worm, linear_at_spec_load=False):
    """ISO 6336-1 single stiffness for the spur mesh; for the worm mesh the wheel
    (z3 / cos^3 lambda virtual teeth) against a rack, scaled by the pair's modulus.

    Below a line load F_t K_A / b of 100 N/mm c' is scaled by ((F_t K_A / b)/100)^0.25
    (ISO 6336-1:2006 clause 9, method B; :func:`deformation.iso6336_low_load_factor`)."""
    gp, wp, st = spec.gear_pair, spec.worm_pair, spec.stiffness
    z1, z2 = gp.output_gear.teeth, gp.pinion.teeth
    c_gear = deformation.iso6336_single_stiffness(
        deformation.iso6336_theoretical_stiffness(z2, z1), st.iso_cm, st.iso_cr, st.iso_cb, 0.0, e_gear)
    zn_wheel = wp.wheel.teeth / math.cos(wp.lead_angle) ** 3
    c_worm = deformation.iso6336_single_stiffness(
        deformation.iso6336_theoretical_stiffness(np.inf, zn_wheel), st.iso_cm, st.iso_cr, st.iso_cb, 0.0, e_worm)
    ft1, ft2 = gear_tangential_force(spec, f1), worm_tangential_force(spec, f2)
    if linear_at_spec_load:
        k1, k2 = (float(deformation.iso6336_low_load_factor(w)) for w in line_loads(spec))
        k1, k2 = (k if k > 0.0 else 1.0 for k in (k1, k2))
        return (deformation.iso6336_deflection(ft1, gp.face_width, c_gear * k1),
                deformation.iso6336_deflection(ft2, wp.face_width, c_worm * k2))
    return (deformation.iso6336_loaded_deflection(ft1, gp.face_width, c_gear, st.iso_ka),
            deformation.iso6336_loaded_deflection(ft2, wp.face_width, c_worm, st.iso_ka))


def gear_eccentricity(spec) -> float:
    """The gear-stage eccentricity Delta e [mm] the chosen kinematics uses.

    ``paper``: the spec's ``assembly.gear_eccentricity_mm`` (which defaults to the
    centre-distance error, as the paper reads Table 1).  ``involute``: only an
    eccentricity written in the spec; a centre-distance error is static and gives
    backlash, not TE, so it does not default into the eccentricity."""
    if spec.gear_pair.kinematics == "paper":
        return spec.assembly.gear_eccentricity
    from wormgear_cli.spec.loader import value_origin

    return spec.assembly.gear_eccentricity if value_origin(spec, "assembly.gear_eccentricity_mm") == "spec" else 0.0


#: deflection model name (``[stiffness] model``, see models.deformation.DEFORMATION_MODELS) -> spec adapter
_DEFLECTION_ADAPTERS = {"iso6336": _iso6336, "empirical": _empirical}
assert set(_DEFLECTION_ADAPTERS) == set(deformation.DEFORMATION_MODELS)


@dataclass(frozen=True)
class Analysis:
    """Result of :func:`analyze`.  ``angles``: name -> value [rad];
    ``info``: name -> dimensionless or labelled values."""

    drive: str
    angles: dict
    info: dict

    def metrics(self, unit: str) -> dict:
        """Flat ``column -> value`` (angles in ``unit``) for CSV and sweeps."""
        out = {c: float(to_unit(self.angles[c], unit)) for c in METRIC_COLUMNS}
        out.update({c: (None if self.info[c] is None else float(self.info[c])) for c in INFO_COLUMNS})
        return out

    def report(self, unit: str) -> dict:
        """The JSON document of ``wormgear analyze`` (angles in ``unit``)."""
        a = {k: float(to_unit(v, unit)) for k, v in self.angles.items()}
        i = self.info
        return {
            "drive": self.drive,
            "unit": unit,
            "ratios": {"gear": i["gear_ratio"], "worm": i["worm_ratio"], "total": i["total_ratio"]},
            "deflection_model": i["deflection_model"],
            "stages": {
                "gear": {
                    "transmission_error": a["gear_transmission_error"],
                    "backlash": a["gear_backlash"],
                    "transmission_error_parts": {
                        "eccentricity": a["gear_te_eccentricity"],
                        "deformation": a["gear_te_deformation"],
                    },
                    "backlash_parts": {
                        "eccentricity": a["gear_backlash_eccentricity"],
                        "deformation": a["gear_backlash_deformation"],
                        "thickness": a["gear_backlash_thickness"],
                    },
                    "kinematics": i["kinematics"],
                    "line_load_N_per_mm": i["gear_line_load_N_per_mm"],
                    "phi_at_max_deg": i["gear_te_phi_deg"],
                    "load_share_pct": i["gear_load_share_pct"],
                    "deflection_um": i["gear_deflection_um"],
                    "contribution": {
                        "transmission_error": a["gear_transmission_error"],
                        "backlash": a["gear_backlash"],
                        "transmission_error_pct": i["gear_te_share_pct"],
                        "backlash_pct": i["gear_backlash_share_pct"],
                    },
                },
                "worm": {
                    "transmission_error": a["worm_transmission_error"],
                    "backlash": a["worm_backlash"],
                    "transmission_error_parts": {
                        "deformation": a["worm_te_deformation"],
                        "envelope_halfwidth": a["worm_te_envelope"],
                        "lower_bound": a["worm_te_deformation"] - a["worm_te_envelope"],
                    },
                    "backlash_parts": {
                        "deformation": a["worm_backlash_deformation"],
                        "profile": a["worm_backlash_profile"],
                        "thickness": a["worm_backlash_thickness"],
                        "envelope_halfwidth": a["worm_backlash_envelope"],
                        "lower_bound": a["worm_backlash"] - 2.0 * a["worm_backlash_envelope"],
                    },
                    "deflection_um": i["worm_deflection_um"],
                    "line_load_N_per_mm": i["worm_line_load_N_per_mm"],
                    "contribution": {
                        "transmission_error": a["worm_transmission_error"] / i["gear_ratio"],
                        "backlash": a["worm_backlash"] / i["gear_ratio"],
                        "transmission_error_pct": 100.0 - i["gear_te_share_pct"],
                        "backlash_pct": 100.0 - i["gear_backlash_share_pct"],
                    },
                },
            },
            "total": {
                "transmission_error": a["total_transmission_error"],
                "backlash": a["total_backlash"],
            },
        }


# an immutable named record built as a NamedTuple, not a frozen dataclass: it is created when
# ``analyze`` starts (0.1 ms against 0.6 ms; docs/development.md, "Start-up")
class WormStage(NamedTuple):
    """The worm stage at the wheel shaft [rad], and its parts on the wheel's pitch circle [mm]
    (arrays when the deflection is one): ``transmission_error`` Delta phi_wc, ``backlash``
    Delta phi_wh; ``te_halfwidth`` h, ``backlash_halfwidth`` h_j; ``backlash_deformation``,
    ``backlash_profile``, ``backlash_thickness`` (the central backlash's parts)."""

    transmission_error: object
    backlash: object
    te_halfwidth: float
    backlash_halfwidth: float
    backlash_deformation: object
    backlash_profile: float
    backlash_thickness: float


def worm_stage(spec, deflection) -> WormStage:
    """The paper's worm stage of ``spec`` at tooth deflection ``deflection`` [mm] (delta2; scalar
    or array): its TE and backlash at the wheel shaft with their parts (paper's Delta phi_wc and
    Delta phi_wh equations; :mod:`wormgear_cli.physics.worm`).  The one definition that ``analyze``
    and the torque-held ``sweep`` use."""
    wp, asm = spec.worm_pair, spec.assembly
    lam, a2 = wp.lead_angle, wp.transverse_pressure_angle
    m2, z3 = wp.module, wp.wheel.teeth
    h_te = worm.worm_te_halfwidth(wp.lead_error, asm.worm_eccentricity, asm.worm_bearing_clearance,
                                  wp.wheel.radial_composite_error, asm.wheel_eccentricity,
                                  asm.wheel_bearing_clearance, lam, a2)
    wte = worm.worm_te(deflection, h_te, m2, z3)
    j_def, j_prof, j_thk = worm.worm_backlash_central(deflection, wp.worm.profile_error, wp.wheel.profile_error,
                                                      wp.worm.thickness_deviation, wp.wheel.thickness_deviation, lam)
    h_j = worm.worm_backlash_halfwidth(wp.worm.profile_error, wp.wheel.profile_error, wp.worm.thickness_deviation,
                                       wp.wheel.thickness_deviation, sum(e * e for e in asm.worm_pair_errors),
                                       wp.lead_error, asm.worm_centre_distance_error,
                                       wp.wheel.radial_composite_error, lam, a2)
    wbl = worm.worm_backlash(j_def + j_prof + j_thk, h_j, m2, z3)
    return WormStage(wte, wbl, h_te, h_j, j_def, j_prof, j_thk)


def analyze(spec) -> Analysis:
    """The paper's two-stage model for one drive.

    Stage values are at each stage's own output shaft (as the paper reports
    them); totals at the output: Delta phi_c = Delta phi_cc + Delta phi_wc / i_c
    and Delta phi_h = Delta phi_ch + Delta phi_wh / i_c with i_c = z1/z2.
    """
    gp, wp, asm = spec.gear_pair, spec.worm_pair, spec.assembly
    z1, z2 = gp.output_gear.teeth, gp.pinion.teeth
    r_gear, r_pinion = gp.module * z1 / 2.0, gp.module * z2 / 2.0
    i_c = z1 / z2
    de, alpha = gear_eccentricity(spec), gp.pressure_angle
    defl = deflections(spec)

    # --- gear stage -------------------------------------------------------------
    bl_thk = 0.0
    if gp.kinematics == "paper":
        _, phi_star = gear.gear_te_max_fast(r_pinion, r_gear, de, alpha, defl.gear)
        te_kin_only, _ = gear.gear_te_max_fast(r_pinion, r_gear, de, alpha, 0.0)
        te_kin_part = gear.gear_kinematic_te(phi_star, r_pinion, r_gear, de, alpha)
        te_def_part = gear.gear_deformation_te(phi_star, r_pinion, r_gear, de, alpha, defl.gear)
        bl = gear.gear_backlash_max(gp.module, z1, de, alpha, defl.gear)
        bl_def = gear.pitch_arc_to_angle(2.0 * defl.gear, gp.module, z1)
    else:
        inv = gear.involute_stage(r_gear, alpha, de, asm.gear_centre_distance_error, defl.gear,
                                  gp.output_gear.thickness_deviation + gp.pinion.thickness_deviation)
        phi_star = 0.5 * np.pi  # e sin(phi) peaks at a quarter turn of the pinion
        te_kin_only = te_kin_part = inv.te_eccentricity
        te_def_part = inv.te_deformation
        bl = inv.backlash
        bl_def, bl_thk = inv.backlash_deformation, inv.backlash_thickness
    te_max = te_kin_part + te_def_part

    # --- worm stage -------------------------------------------------------------
    m2, z3 = wp.module, wp.wheel.teeth
    ws = worm_stage(spec, defl.worm)
    wte, wbl, h_te, h_j = ws.transmission_error, ws.backlash, ws.te_halfwidth, ws.backlash_halfwidth
    j_def, j_prof, j_thk = ws.backlash_deformation, ws.backlash_profile, ws.backlash_thickness

    def arc(x):
        return float(gear.pitch_arc_to_angle(x, m2, z3))

    total_te = te_max + wte / i_c
    total_bl = bl + wbl / i_c
    angles = {
        "gear_transmission_error": float(te_max),
        "gear_backlash": float(bl),
        "worm_transmission_error": float(wte),
        "worm_backlash": float(wbl),
        "total_transmission_error": float(total_te),
        "total_backlash": float(total_bl),
        "gear_te_eccentricity": float(te_kin_part),
        "gear_te_deformation": float(te_def_part),
        "gear_backlash_eccentricity": float(bl - bl_def - bl_thk),
        "gear_backlash_deformation": float(bl_def),
        "gear_backlash_thickness": float(bl_thk),
        "worm_te_deformation": arc(defl.worm),
        "worm_te_envelope": arc(h_te),
        "worm_backlash_deformation": arc(j_def),
        "worm_backlash_profile": arc(j_prof),
        "worm_backlash_thickness": arc(j_thk),
        "worm_backlash_envelope": arc(h_j),
    }
    info = {
        "gear_ratio": i_c,
        "worm_ratio": z3 / wp.worm.starts,
        "total_ratio": i_c * z3 / wp.worm.starts,
        "deflection_model": defl.model,
        "kinematics": gp.kinematics,
        "gear_line_load_N_per_mm": line_loads(spec)[0],
        "worm_line_load_N_per_mm": line_loads(spec)[1],
        "gear_te_phi_deg": float(np.degrees(phi_star)),
        # the paper's "load adds ~0.11 %": increase of the maximum caused by the deflection
        # (undefined, None, when there is no eccentric part to increase: Delta e = 0)
        "gear_load_share_pct": (float(100.0 * (te_max - te_kin_only) / te_kin_only) if te_kin_only > 0 and defl.gear > 0
                                else (0.0 if defl.gear == 0 else None)),
        "gear_deflection_um": float(defl.gear * 1e3),
        "worm_deflection_um": float(defl.worm * 1e3),
        "gear_te_share_pct": _pct(te_max, total_te),
        "gear_backlash_share_pct": _pct(bl, total_bl),
    }
    return Analysis(spec.drive.name, angles, info)


def _pct(part, whole) -> float:
    return float(100.0 * part / whole) if whole > 0 else 0.0
