"""The toothed-belt stage of a train: its transmission error, lost motion and sources at the output.

A driving pulley (z_d teeth, pitch radius r = z_d p / (2 pi)) on the stage's input shaft, a driven
pulley (z_D, R) on its output shaft, a belt of z_b teeth of pitch p; ratio i = z_D / z_d.  The belt
is inextensible except for the stretch of its spans; every error is a displacement x of the belt's
pitch line, which turns the driven pulley by x / R, i.e. x / (R A) at the output (A = the product
of the ratios after the stage).  Sources, each at its order at the output:

* pulley eccentricity e (either pulley): the pulley's centre orbits its axis, moving the belt along
  its spans by e sin(turn + psi): amplitude e / (R A), once per turn of that pulley's shaft (order
  O_d = i A for the driver, A for the driven).  Kagotani, M. and Ueda, H., "Transmission Error Due
  to Resonance in Synchronous Belt Drive With Eccentric Pulley", ASME J. Mech. Des. 139(12),
  123301 (2017), measure this once-per-pulley-turn error (and its growth at span resonance, not
  modelled here).
* tooth meshing: belt climbing and polygon action at every tooth engagement, a peak-to-peak
  pitch-line displacement f_m at the tooth-mesh order z_D A (Kagotani, M. and Ueda, H.,
  "Transmission Error in Synchronous Belt With Resonance Under Installation Tension", ASME J. Mech.
  Des. 134(6), 061003 (2012): an error with the period of one pulley pitch).
* the belt's cumulative pitch variation F_b over its length, once per belt revolution: order
  z_D A / z_b, not a whole number in general (the belt's and pulleys' manufacturing errors and
  the belt-pulley backlash as causes of a toothed-belt drive's positioning error: Proceedings of
  the JSME Kansai Branch 2004.79, paper 7-33).

Lost motion: the belt-pulley tooth clearance on the pitch line, c / (R A), constant.  Compliance:
each span of free length L = sqrt(C^2 - (R - r)^2) is a spring E A / L; preloaded, both spans carry
a torque change (one tightens, one slackens) while the slack span stays tight, so the driven
pulley's torsional stiffness is k = 2 E A R^2 / L, and an effective tension T_e (tight minus
slack) stretches the drive by x = T_e L / (2 E A) (the tooth-belt elongation dL = F L / (E A) of
the belt makers' design manuals, shared by the two spans).  Tooth deflection is neglected.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from wormgear_cli.drive.records import Clearance, StageResult, Static, sine_source
from wormgear_cli.spec.stages import record_values

#: what sits on the stage's input and output shaft
MEMBER_NAMES = ("driving pulley", "driven pulley")


def teeth(stage) -> tuple[int, int]:
    """(teeth of the driven pulley, teeth of the driving pulley): the stage's ratio as whole numbers."""
    return stage.driven.teeth, stage.driver.teeth


def mesh_orders(stage, after: float, of: str) -> list[tuple[float, str, str]]:
    """(order at the output, kind, label) of the stage's meshes: the belt's tooth mesh at z_driven per
    driven turn, and once per belt revolution (order z_driven / z_belt per driven turn)."""
    return [(stage.driven.teeth * after, "mesh", f"belt tooth mesh{of}"),
            (stage.driven.teeth * after / stage.belt_teeth, "belt", f"belt revolution{of}")]


def base_circle(stage) -> tuple[float, int]:
    """(radius [mm], teeth) of the driven pulley (its pitch radius: a belt acts on its pitch line)."""
    return stage.output_radius, stage.driven.teeth


def tooth_deflection(spec, stage, stages) -> float:
    """0: a belt's teeth do not deflect in this model (its stretch is the belt's compliance)."""
    return 0.0


def stretch(stage, tension) -> float:
    """x = T L / (2 E A) [mm] on the pitch line under an effective tension ``tension`` [N]; 0 for a
    rigid belt (no ``tensile_stiffness_N``)."""
    if not stage.tensile_stiffness:
        return 0.0
    return tension * stage.span_length / (2.0 * stage.tensile_stiffness)


def _amplitudes(stage, after: float) -> list[tuple]:
    """(name, phase key, size key, order, scale, kind, part, phase, tier) per source;
    amplitude at the output = value(size key) x scale."""
    r, a = stage.output_radius, after
    o_d, o_mesh = stage.ratio * a, stage.driven.teeth * a
    return [
        ("driver_pulley_eccentricity", "driver.eccentricity_phase_deg", "driver.eccentricity_mm", o_d, 1.0 / (r * a),
         "shaft", "driver", stage.driver.eccentricity_phase, 1),
        ("driven_pulley_eccentricity", "driven.eccentricity_phase_deg", "driven.eccentricity_mm", a, 1.0 / (r * a),
         "shaft", "driven", stage.driven.eccentricity_phase, 1),
        ("belt_pitch_error", "pitch_error_phase_deg", "pitch_error_mm", o_mesh / stage.belt_teeth, 0.5 / (r * a),
         "belt", "belt", stage.pitch_error_phase, 1),
        ("belt_tooth_mesh", "tooth_mesh_phase_deg", "tooth_mesh_error_mm", o_mesh, 0.5 / (r * a), "mesh", "belt",
         stage.tooth_mesh_phase, 2),
    ]


def periodic_size(stage, value):
    """The periodic part of the stage's TE at the driven pulley's shaft [rad]: the sum over orders of the
    root-sum-square of the sources at one order (sources of one order add as vectors, different orders
    peak together somewhere in a turn), from ``value(key)`` (numbers or arrays of sampled drives)."""
    by_order: dict[float, Any] = {}
    for _, _, key, order, scale, *_ in _amplitudes(stage, 1.0):
        amp = value(key) * scale
        by_order[order] = by_order.get(order, 0.0) + amp * amp
    return sum(np.sqrt(s) for s in by_order.values())


def totals(stage, value=None) -> tuple:
    """(TE, backlash) at the driven pulley's shaft [rad]: TE = stretch + :func:`periodic_size`;
    backlash = clearance + 2 stretch (``value(key)``: default the stage's own values; arrays allowed)."""
    v = value or record_values(stage).__getitem__
    r = stage.output_radius
    s = stretch(stage, stage.effective_tension) / r
    return s + periodic_size(stage, v), v("backlash_mm") / r + 2.0 * s


def sampled_totals(stage, deflection, value, spec, te_max=None) -> tuple:
    """(TE, backlash) at the driven pulley's shaft [rad] of sampled drives (:func:`totals`): every
    model's entry for the tolerance analysis."""
    return totals(stage, value)


def evaluate(spec, stage, t, deflection: float = 0.0) -> StageResult:
    """The stage's TE and backlash at the driven pulley's shaft (:func:`totals`), with their parts."""
    r = stage.output_radius
    periodic = periodic_size(stage, record_values(stage).__getitem__)
    s = stretch(stage, stage.effective_tension) / r
    clearance = stage.backlash / r
    te, bl = totals(stage)
    info = {"effective_tension_N": float(stage.effective_tension), "stretch_um": float(s * r * 1e3),
            "span_length_mm": float(stage.span_length), "centre_distance_mm": float(stage.centre_distance)}
    return StageResult(stage.index, stage.name, "belt", stage.ratio, t.after(stage), float(te), float(bl),
                       {"stretch": float(s), "periodic": float(periodic)},
                       {"clearance": float(clearance), "stretch": float(2.0 * s)}, info)


def sources(spec, stage, t, deflection: float, result: StageResult, origin) -> tuple[list, list, list]:
    """(periodic sources, static terms, constant clearances) of the stage at the output (module
    docstring).  ``origin(stage, keys)``: the origin of a size read from ``keys``."""
    after = t.after(stage)
    own = record_values(stage)
    out = []
    for name, phase_key, key, order, scale, kind, part, phase, tier in _amplitudes(stage, after):
        def size(v, key=key, scale=scale):
            return v(key) * scale
        out.append(sine_source(name, stage.paths[phase_key], order, float(size(own.__getitem__)), phase, stage.name,
                               kind, (stage.paths[key],), part=part, origin=origin(stage, (key,)), size_keys=(key,),
                               size=size, tier=tier, stage_index=stage.index, stage_kind="belt"))
    static = [Static("belt_stretch", result.te_parts["stretch"] / after, stage.name, stage.index, "belt",
                     origin(stage, ("effective_tension_N", "tensile_stiffness_N")),
                     (stage.paths["effective_tension_N"], stage.paths["tensile_stiffness_N"]))]
    r = stage.output_radius
    clear = [Clearance("belt_backlash", result.backlash_parts["clearance"] / after, stage.name, stage.index, "belt",
                       ("backlash_mm",), lambda v: v("backlash_mm") / r / after)]
    return out, static, clear


def compliance(spec, stage, t, deflection: float = 0.0) -> tuple[float, float]:
    """(process lag, wind-up per N m of output torque) at the output: the stretch under the stage's
    effective tension, and under the tension 1 N m / (A R) of a unit output torque, each / (R A)."""
    after, r = t.after(stage), stage.output_radius
    return (float(stretch(stage, stage.effective_tension) / r / after),
            float(stretch(stage, 1000.0 / after / r) / r / after))
