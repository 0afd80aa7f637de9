"""Tooth deflection under load: delta1 (spur mesh) and delta2 (worm mesh).

Two models, selected by ``[stiffness] model`` in the drive spec:

* ``"iso6336"`` (default): ISO 6336-1 single-tooth stiffness c', delta =
  F_t / (b c').  Linear in load.
* ``"empirical"``: the paper's form delta = A1 F_N / ((eps+1)^B (lambda2+1)^C E b)
  with overridable constants.  Also linear in load.

Units: forces [N], lengths [mm], moduli [N/mm^2]; deflections are returned
in [mm].
"""

from __future__ import annotations

import numpy as np

#: Young's modulus of steel used by ISO 6336 as the reference [N/mm^2]
E_STEEL = 206_000.0

#: ISO 6336-1 coefficients C1..C9 of the theoretical single stiffness
ISO6336_Q_COEFFICIENTS = (0.04723, 0.15551, 0.25791, -0.00635, -0.11654, -0.00193, -0.24188, 0.00529, 0.00182)

#: the registry of deflection models: name -> (function, the spec keys it reads)
DEFORMATION_MODELS: dict[str, dict] = {}


def combined_modulus(e1, e2):
    """E = 2 E1 E2 / (E1 + E2)  [N/mm^2]: the pair's equivalent modulus (ISO 6336-1)."""
    return 2.0 * e1 * e2 / (e1 + e2)


def iso6336_theoretical_stiffness(zn1, zn2, x1=0.0, x2=0.0):
    """c'_th = 1 / q'  [N/(mm um)], ISO 6336-1 method B.

    q' = C1 + C2/zn1 + C3/zn2 + C4 x1 + C5 x1/zn1 + C6 x2 + C7 x2/zn2 + C8 x1^2 + C9 x2^2

    Parameters
    ----------
    zn1, zn2 : virtual numbers of teeth [-], > 0; ``np.inf`` for a rack
    x1, x2 : profile shift coefficients [-], -0.5 <= x <= 0.6 (the fit's range)

    Check: zn = 17.8/108 (TR 6336-30 example, x1 = 0.145, x2 = 0) gives ~17.86.
    """
    c = ISO6336_Q_COEFFICIENTS
    q = (c[0] + c[1] / zn1 + c[2] / zn2 + c[3] * x1 + c[4] * x1 / zn1 + c[5] * x2 + c[6] * x2 / zn2
         + c[7] * x1**2 + c[8] * x2**2)
    return 1.0 / q


def iso6336_single_stiffness(c_th, cm=0.8, cr=1.0, cb=0.975, helix_angle=0.0, modulus=E_STEEL):
    """c' = c'_th C_M C_R C_B cos(beta) (E / E_steel)  [N/(mm um)] (ISO 6336-1).

    Parameters
    ----------
    c_th : theoretical single stiffness [N/(mm um)]
    cm : C_M, measured-vs-theory correction [-] (0.8)
    cr : C_R, gear blank factor [-] (1 for solid blanks)
    cb : C_B, basic rack factor [-] (0.975 for the standard rack)
    helix_angle : beta [rad] (0 for spur gears)
    modulus : the pair's equivalent modulus E [N/mm^2]; the E/E_steel scaling
        for other materials is the ISO practice, unconfirmed for bronze.
    """
    return c_th * cm * cr * cb * np.cos(helix_angle) * (modulus / E_STEEL)


#: line load F_t K_A / b [N/mm] at and above which ISO 6336-1 applies c' as computed
ISO6336_FULL_LINE_LOAD = 100.0


def iso6336_low_load_factor(line_load):
    """((F_t K_A / b) / 100)^0.25 below 100 N/mm, else 1  [-] (ISO 6336-1:2006, clause 9, method B).

    ISO 6336-1 gives c' = c'_th C_M C_R C_B cos(beta) for F_t K_A / b >= 100 N/mm
    and, below that line load, the same value multiplied by
    ((F_t K_A / b) / 100)^0.25: at light load the teeth do not bear over the full
    face and the mesh is softer.  (Confirmed against an independent open
    implementation of ISO 6336-1; the exponent is 0.25, not a linear scaling.)

    Parameters
    ----------
    line_load : F_t K_A / b [N/mm], >= 0 (arrays broadcast)
    """
    w = np.maximum(np.asarray(line_load, dtype=float), 0.0)
    return np.minimum(w / ISO6336_FULL_LINE_LOAD, 1.0) ** 0.25


def iso6336_loaded_deflection(tangential_force, face_width, single_stiffness, application_factor=1.0):
    """delta = F_t / (b c'(F_t))  [mm] with the low-load reduction of c' applied.

    c'(F_t) = c' * :func:`iso6336_low_load_factor` (F_t K_A / b); so for line
    loads below 100 N/mm delta = F_t / (b c') * (100 b / (F_t K_A))^0.25, i.e.
    it grows as F_t^0.75, and it is 0 at F_t = 0.

    Parameters
    ----------
    tangential_force : F_t [N], >= 0 (arrays broadcast)
    face_width : b [mm], > 0
    single_stiffness : c' at full line load [N/(mm um)], > 0
    application_factor : K_A [-], > 0 (ISO 6336-1 application factor)
    """
    ft = np.asarray(tangential_force, dtype=float)
    factor = iso6336_low_load_factor(ft * application_factor / face_width)
    safe = np.where(factor > 0.0, factor, 1.0)
    return np.where(factor > 0.0, iso6336_deflection(ft, face_width, single_stiffness) / safe, 0.0)


def iso6336_deflection(tangential_force, face_width, single_stiffness):
    """delta = F_t / (b c')  [mm], deflection in the single-pair zone.

    Parameters
    ----------
    tangential_force : F_t [N], >= 0
    face_width : b [mm], > 0
    single_stiffness : c' [N/(mm um)], > 0

    The result is converted from um to mm.  Linear in load: doubling F_t
    doubles delta.
    """
    return tangential_force / (face_width * single_stiffness) * 1e-3


def empirical_deflection(normal_force, modulus, face_width, contact_ratio, lambda2, a1, b, c):
    """delta = A1 F_N / ((eps + 1)^B (lambda2 + 1)^C E b)  [mm], the paper's empirical form.

    Parameters
    ----------
    normal_force : F_N [N], >= 0
    modulus : E [N/mm^2], > 0
    face_width : b [mm], > 0
    contact_ratio : eps [-], 1 <= eps < 3 for spur gears
    lambda2 : the paper's second geometry parameter [-], >= 0 (not defined
        in the paper; default 0 removes its factor)
    a1, b, c : the empirical constants A1, B, C [-]

    The paper gives neither the constants nor the meaning of lambda2; see
    :data:`wormgear_cli.spec.loader` defaults for the chosen values and why.
    Linear in load.
    """
    return a1 * normal_force / ((contact_ratio + 1.0) ** b * (lambda2 + 1.0) ** c * modulus * face_width)


def spur_contact_ratio(z1, z2, pressure_angle, addendum_coefficient=1.0):
    """Transverse contact ratio eps_alpha of a standard spur pair [-].

    eps = [sqrt(ra1^2 - rb1^2) + sqrt(ra2^2 - rb2^2) - a sin(alpha)] / (pi cos(alpha))
    per unit module (ra = z/2 + h*, rb = z cos(alpha)/2, a = (z1+z2)/2).
    Standard geometry (ISO 21771); zero profile shift.
    """
    ra1, ra2 = z1 / 2.0 + addendum_coefficient, z2 / 2.0 + addendum_coefficient
    rb1, rb2 = z1 * np.cos(pressure_angle) / 2.0, z2 * np.cos(pressure_angle) / 2.0
    a = (z1 + z2) / 2.0
    return (np.sqrt(ra1**2 - rb1**2) + np.sqrt(ra2**2 - rb2**2) - a * np.sin(pressure_angle)) / (
        np.pi * np.cos(pressure_angle)
    )


DEFORMATION_MODELS.update(
    {
        "iso6336": {
            "function": iso6336_deflection,
            "doc": "ISO 6336-1 single stiffness c', delta = F_t/(b c'); default",
            "keys": ("stiffness.iso_cm", "stiffness.iso_cr", "stiffness.iso_cb"),
        },
        "empirical": {
            "function": empirical_deflection,
            "doc": "the paper's delta = A1 F_N/((eps+1)^B (lambda2+1)^C E b)",
            "keys": ("stiffness.empirical_a1", "stiffness.empirical_b", "stiffness.empirical_c",
                     "stiffness.empirical_lambda2"),
        },
    }
)


def rack_contact_ratio(z, pressure_angle, addendum_coefficient=1.0):
    """Transverse contact ratio eps_alpha of a standard gear of ``z`` teeth against a rack [-].

    eps = [sqrt(ra^2 - rb^2) - r sin(alpha) + h* / sin(alpha)] / (pi cos(alpha)) per unit module
    (r = z/2, ra = r + h*, rb = r cos(alpha)): the gear's part of the path of contact plus the
    rack's, h* / sin(alpha) (ISO 21771 geometry, zero profile shift).  The limit of
    :func:`spur_contact_ratio` as the mating gear grows without bound.
    """
    r = z / 2.0
    ra, rb = r + addendum_coefficient, r * np.cos(pressure_angle)
    return (np.sqrt(ra**2 - rb**2) - r * np.sin(pressure_angle) + addendum_coefficient / np.sin(pressure_angle)) / (
        np.pi * np.cos(pressure_angle))
