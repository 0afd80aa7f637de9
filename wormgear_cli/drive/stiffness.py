"""Tooth deflection of each gear mesh of a train under its load, by the stage's deflection model.

The spec layer gives each worm and spur stage its normal force F_N (written, or carried back from
the drive's output torque) and its model (``stiffness_model``, default ``[stiffness] model``);
the drive-level ``[stiffness]`` factors and ``[materials]`` moduli apply to every stage.

* ``iso6336``: delta = F_t / (b c') with ISO 6336-1's single stiffness c' = c'_th C_M C_R C_B
  (E / E_steel).  Spur: c'_th of the pair (z_pinion, z_gear), F_t = F_N cos(alpha), E = the spur
  gears' modulus.  Worm (no standard worm-mesh stiffness exists): the wheel as a gear of
  z / cos^3(lambda) teeth against a rack (the worm in its axial section), F_t = F_N cos(alpha_n)
  cos(lambda), E = 2 E_worm E_wheel / (E_worm + E_wheel).  Which slot of q' the rack takes: ISO
  6336-1's fit is written for a pinion (z_n1, the member of fewer teeth) and a wheel (z_n2), and the
  standard treats a mating member of unbounded tooth count (an internal gear) by setting z_n2 to
  infinity; so the rack takes the wheel's slot and the worm wheel the pinion's,
  q' = C1 + C2 / z_n,wheel (the other way round, C3 / z_n,wheel, gives a 3-7 % softer mesh for
  z = 30..90).  Below a line load F_t K_A / b of 100 N/mm c' is scaled by
  ((F_t K_A / b) / 100)^0.25 (ISO 6336-1:2006 clause 9, method B).
* ``empirical``: the paper's delta = A1 F_N / ((eps + 1)^B (lambda2 + 1)^C E b).  The contact ratio
  eps is ``[stiffness] contact_ratio`` when given, else a spur stage's own standard eps_alpha and,
  for a worm stage, that of the drive's last spur stage (the paper applies one eps to both meshes)
  or, without a spur stage, the wheel's against a rack.

Units: forces [N], lengths [mm], deflections [mm].
"""

from __future__ import annotations

import math

import numpy as np

from wormgear_cli.physics import deformation


def tangential_force(stage, normal_force):
    """F_t [N] of a mesh: spur F_N cos(alpha); worm F_N cos(alpha_n) cos(lambda) (wheel plane)."""
    if stage.kind == "spur":
        return normal_force * math.cos(stage.pressure_angle)
    return normal_force * math.cos(stage.normal_pressure_angle) * math.cos(stage.lead_angle)


def line_load(spec, stage) -> float:
    """F_t K_A / b [N/mm] of a gear mesh at its spec load (ISO 6336-1)."""
    return tangential_force(stage, stage.normal_force) * spec.stiffness.iso_ka / stage.face_width


def modulus(spec, stage) -> float:
    """The mesh's equivalent Young's modulus [N/mm^2]: spur gears' E; worm pair 2 E1 E2 / (E1 + E2)."""
    mat = spec.materials
    if stage.kind == "spur":
        return mat.gear_elastic_modulus
    return deformation.combined_modulus(mat.worm_elastic_modulus, mat.wheel_elastic_modulus)


def contact_ratio(spec, stage, stages=None) -> float:
    """eps of the empirical form for ``stage`` (module docstring)."""
    given = spec.stiffness.contact_ratio
    if given is not None:
        return given
    spurs = [s for s in (stages if stages is not None else spec.stages) if s.kind == "spur"]
    ref = stage if stage.kind == "spur" else (spurs[-1] if spurs else None)
    if ref is not None:
        return float(deformation.spur_contact_ratio(ref.gear.teeth, ref.pinion.teeth, ref.pressure_angle))
    return float(deformation.rack_contact_ratio(stage.wheel.teeth / math.cos(stage.lead_angle) ** 3,
                                                stage.transverse_pressure_angle))


def single_stiffness(spec, stage) -> float:
    """ISO 6336-1 c' [N/(mm um)] of the mesh at full line load."""
    st = spec.stiffness
    if stage.kind == "spur":
        c_th = deformation.iso6336_theoretical_stiffness(stage.pinion.teeth, stage.gear.teeth)
    else:
        # the wheel in the pinion's slot (z_n1), the worm as a rack in the wheel's (z_n2 = infinity): module docstring
        c_th = deformation.iso6336_theoretical_stiffness(stage.wheel.teeth / math.cos(stage.lead_angle) ** 3, np.inf)
    return deformation.iso6336_single_stiffness(c_th, st.iso_cm, st.iso_cr, st.iso_cb, 0.0, modulus(spec, stage))


def deflection(spec, stage, force=None, linear_at_spec_load: bool = False, stages=None):
    """delta [mm] of a worm or spur stage's mesh at normal force ``force`` [N] (default: the stage's
    own; arrays allowed).  ``linear_at_spec_load``: ISO 6336-1's low-load reduction of c' taken at
    the stage's own load and held, so the deflection is linear in ``force`` (the compliance about
    the operating point; a stage without load uses the unreduced c'); otherwise c' follows the force.
    ``stages``: the train whose spur stage sets the empirical form's contact ratio (default the
    spec's)."""
    f = stage.normal_force if force is None else force
    st = spec.stiffness
    if stage.stiffness_model == "empirical":
        return deformation.empirical_deflection(f, modulus(spec, stage), stage.face_width,
                                                contact_ratio(spec, stage, stages), st.empirical_lambda2,
                                                st.empirical_a1, st.empirical_b, st.empirical_c)
    c = single_stiffness(spec, stage)
    ft = tangential_force(stage, f)
    if linear_at_spec_load:
        k = float(deformation.iso6336_low_load_factor(line_load(spec, stage)))
        return deformation.iso6336_deflection(ft, stage.face_width, c * (k if k > 0.0 else 1.0))
    return deformation.iso6336_loaded_deflection(ft, stage.face_width, c, st.iso_ka)
