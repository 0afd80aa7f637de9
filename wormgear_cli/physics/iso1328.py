"""Accuracy grades of cylindrical involute gears: ISO 1328-1:2013 and ISO 1328-2:1997.

Pure functions from a grade and the gear's size to the standard's tolerances,
with the standard's rounding, and the standards' ranges of validity as data.

ISO 1328-1:2013 (flank tolerance classes A = 1..11), clause 5.2:

* step between classes (5.2.2): s = sqrt(2)^(A - 5)
* single pitch (eq. 5):        f_pT   = (0.001 d + 0.4 m + 5) s
* cumulative pitch (eq. 6):    F_pT   = (0.002 d + 0.55 sqrt(d) + 0.7 m + 12) s
* profile slope (eq. 7):       f_HaT  = (0.4 m + 0.001 d + 4) s
* profile form (eq. 8):        f_faT  = (0.55 m + 5) s
* total profile (eq. 9):       F_aT   = sqrt(f_HaT^2 + f_faT^2)  (from the unrounded parts)
* helix slope (eq. 10):        f_HbT  = (0.05 sqrt(d) + 0.35 sqrt(b) + 4) s
* helix form (eq. 11):         f_fbT  = (0.07 sqrt(d) + 0.45 sqrt(b) + 4) s
* total helix (eq. 12):        F_bT   = sqrt(f_HbT^2 + f_fbT^2)
* runout (informative annex of ISO 1328-1:2013): F_rT = 0.9 F_pT
* rounding (5.2.3): above 10 um to 1 um, 5..10 um to 0.5 um, below 5 um to 0.1 um.

Scope (clause 1): 5 <= z <= 1000, 5 <= d <= 15000 mm, 0.5 <= m_n <= 70 mm,
4 <= b <= 1200 mm, beta <= 45 deg; the formulas are not to be extrapolated
beyond it (values outside are agreed between purchaser and manufacturer), so a
gear outside it is an error here.

ISO 1328-2:1997 radial composite (grades 4..12), with m and d taken as the
geometric means of the standard's module and diameter ranges:

* total radial composite      F_i'' = (3.2 m + 1.01 sqrt(d) + 6.4) 2^(0.5 (Q - 5))
* tooth-to-tooth composite    f_i'' = (2.96 m + 0.01 sqrt(d) + 0.8) 2^(0.5 (Q - 5))

Scope: 0.2 <= m_n <= 10 mm, 5 <= d <= 1000 mm.  Outside it the formulas are not
extrapolated: the gear takes the nearest range's geometric mean (the end range:
0.2..0.5 or 6..10 mm, 5..20 or 560..1000 mm), i.e. the tolerance of the nearest
size the standard covers, and :func:`radial_composite` reports a warning saying so.

Check value (ISO 1328-1:2013 worked example, d = 100 mm, m = 2 mm, b = 20 mm,
A = 6): f_pT 8.5, F_pT 27, F_aT 11, F_rT 24 um.  Second check (hand calculation,
agreeing with an independent open implementation): d = 120 mm, m = 3 mm,
b = 30 mm, A = 6: f_pT 9.0, F_pT 29, F_aT 12 um.

Worm wheels and worms are outside ISO 1328 (cylindrical involute gears only).
The worm-gear grade system of DIN 3974-1/-2 is not publicly available and no
citable open source of its formulas was found, so worm-pair tolerances stay
explicit spec values (see docs/budget.md).
Units: lengths [mm] in, tolerances [um] out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: ISO 1328-1:2013 flank tolerance classes
PART1_GRADES = (1, 11)
#: ISO 1328-2:1997 radial composite grades
PART2_GRADES = (4, 12)


@dataclass(frozen=True)
class ValidityRange:
    """One parameter's range of validity of a standard (inclusive bounds).

    ``name``: parameter (``module``, ``diameter``, ``face_width``, ``teeth``);
    ``lo``/``hi`` in ``unit``; ``on_violation``: ``"error"`` where the standard
    does not apply outside the range, ``"warning"`` where the nearest range's
    value is used instead.
    """

    name: str
    lo: float
    hi: float
    unit: str
    on_violation: str

    def contains(self, value: float) -> bool:
        return self.lo <= value <= self.hi

    def describe(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        return f"[{self.lo:g}, {self.hi:g}]{unit}"


#: ISO 1328-1:2013 clause 1 (scope); the formulas are not extrapolated -> error
PART1_SCOPE = (
    ValidityRange("module", 0.5, 70.0, "mm", "error"),
    ValidityRange("diameter", 5.0, 15000.0, "mm", "error"),
    ValidityRange("face_width", 4.0, 1200.0, "mm", "error"),
    ValidityRange("teeth", 5.0, 1000.0, "", "error"),
)
#: ISO 1328-2:1997 scope; outside it the nearest range's value is used -> warning
PART2_SCOPE = (
    ValidityRange("module", 0.2, 10.0, "mm", "warning"),
    ValidityRange("diameter", 5.0, 1000.0, "mm", "warning"),
)
#: ISO 1328-2:1997 module ranges [mm] (bounds); the formulas use each range's geometric mean
PART2_MODULE_BOUNDS = (0.2, 0.5, 0.8, 1.0, 1.5, 2.5, 4.0, 6.0, 10.0)
#: ISO 1328-2:1997 reference-diameter ranges [mm] (bounds)
PART2_DIAMETER_BOUNDS = (5.0, 20.0, 50.0, 125.0, 280.0, 560.0, 1000.0)


class GradeError(ValueError):
    """A grade or a gear outside the standard's range (``key``-free: callers name the key)."""


@dataclass(frozen=True)
class FlankTolerances:
    """ISO 1328-1:2013 tolerances of one gear [um], rounded per 5.2.3.

    ``f_pT`` single pitch, ``F_pT`` cumulative pitch, ``f_HalphaT``/``f_falphaT``
    profile slope/form, ``F_alphaT`` total profile, ``f_HbetaT``/``f_fbetaT``/
    ``F_betaT`` helix, ``F_rT`` runout.
    """

    grade: int
    f_pT: float
    F_pT: float
    f_HalphaT: float
    f_falphaT: float
    F_alphaT: float
    f_HbetaT: float
    f_fbetaT: float
    F_betaT: float
    F_rT: float


@dataclass(frozen=True)
class RadialComposite:
    """ISO 1328-2:1997 radial composite tolerances [um] and the range means used.

    ``warnings``: one sentence per parameter outside the standard's scope
    (the nearest range's mean used instead of the gear's own value)."""

    grade: int
    F_i2T: float
    f_i2T: float
    module_mean: float
    diameter_mean: float
    warnings: tuple = ()


def round_tolerance(value_um: float) -> float:
    """The standard's rounding (ISO 1328-1:2013, 5.2.3) [um].

    Above 10 um to the nearest 1 um, from 5 to 10 um to the nearest 0.5 um,
    below 5 um to the nearest 0.1 um; halves round up (away from zero).

    Parameters
    ----------
    value_um : unrounded tolerance [um], >= 0
    """
    if value_um > 10.0:
        step = 1.0
    elif value_um >= 5.0:
        step = 0.5
    else:
        step = 0.1
    return round(math.floor(value_um / step + 0.5 + 1e-9) * step, 1)


def grade_step(grade: int) -> float:
    """s = sqrt(2)^(A - 5) [-]: the ratio between neighbouring classes (ISO 1328-1:2013, 5.2.2)."""
    return math.sqrt(2.0) ** (grade - 5)


def scope_problems(scope, **values) -> list[tuple[ValidityRange, float]]:
    """The ranges of ``scope`` that ``values`` (name -> value) violate, in scope order."""
    return [(r, values[r.name]) for r in scope if r.name in values and not r.contains(values[r.name])]


def _check_grade(grade, bounds, standard):
    if isinstance(grade, bool) or not isinstance(grade, int) or not bounds[0] <= grade <= bounds[1]:
        raise GradeError(f"grade {grade!r} outside {standard}'s range, expected an integer in "
                         f"[{bounds[0]}, {bounds[1]}]")


def flank_tolerances(grade: int, module: float, diameter: float, face_width: float,
                     teeth: int | None = None) -> FlankTolerances:
    """ISO 1328-1:2013 flank tolerances of one spur gear (eq. 5 to 12, rounding 5.2.3).

    Parameters
    ----------
    grade : flank tolerance class A [-], integer 1..11
    module : normal module m_n [mm], 0.5..70
    diameter : reference diameter d [mm], 5..15000
    face_width : face width b [mm], 4..1200
    teeth : number of teeth z [-], 5..1000 (checked when given)

    Returns
    -------
    FlankTolerances, every value [um] rounded as the standard prescribes; the
    total profile and helix tolerances are formed from the unrounded parts and
    F_rT = 0.9 F_pT from the unrounded F_pT.

    Raises
    ------
    GradeError
        grade outside 1..11, or a parameter outside the standard's scope
        (clause 1: the formulas are not to be extrapolated).
    """
    _check_grade(grade, PART1_GRADES, "ISO 1328-1:2013")
    values = {"module": module, "diameter": diameter, "face_width": face_width}
    if teeth is not None:
        values["teeth"] = teeth
    bad = scope_problems(PART1_SCOPE, **values)
    if bad:
        r, v = bad[0]
        raise GradeError(f"{r.name} {v:g} outside ISO 1328-1:2013's scope {r.describe()} "
                         "(its formulas are not extrapolated)")
    s = grade_step(grade)
    m, d, b = module, diameter, face_width
    f_pt = (0.001 * d + 0.4 * m + 5.0) * s
    f_p = (0.002 * d + 0.55 * math.sqrt(d) + 0.7 * m + 12.0) * s
    f_ha = (0.4 * m + 0.001 * d + 4.0) * s
    f_fa = (0.55 * m + 5.0) * s
    f_hb = (0.05 * math.sqrt(d) + 0.35 * math.sqrt(b) + 4.0) * s
    f_fb = (0.07 * math.sqrt(d) + 0.45 * math.sqrt(b) + 4.0) * s
    rt = round_tolerance
    return FlankTolerances(grade, rt(f_pt), rt(f_p), rt(f_ha), rt(f_fa), rt(math.hypot(f_ha, f_fa)),
                           rt(f_hb), rt(f_fb), rt(math.hypot(f_hb, f_fb)), rt(0.9 * f_p))


#: the coarsest accuracy used as a plausibility scale: one class beyond ISO 1328-1's coarsest (11),
#: the coarsest grade of ISO 1328-2 (12)
SCALE_GRADE = 12


def coarse_scale(module: float, diameter: float) -> dict[str, float]:
    """The size of a coarse gear's deviations [um]: ISO 1328-1:2013's formulas at class 12 (one
    step, sqrt(2), beyond its coarsest class), unrounded and without the scope check, and
    ISO 1328-2:1997's grade-12 F_i'' (the nearest range's mean outside its scope).  Not a
    tolerance anyone specifies: the scale a plausible deviation of a gear of this size stays
    well below (:mod:`wormgear_cli.spec.plausibility`).  Keys ``F_pT``, ``f_pT``, ``F_alphaT``,
    ``F_rT``, ``F_i2T``; ``module``, ``diameter`` [mm], > 0."""
    s = grade_step(SCALE_GRADE)
    m, d = module, diameter
    f_ha, f_fa = (0.4 * m + 0.001 * d + 4.0) * s, (0.55 * m + 5.0) * s
    f_p = (0.002 * d + 0.55 * math.sqrt(d) + 0.7 * m + 12.0) * s
    md, dd = _range_mean(m, PART2_MODULE_BOUNDS), _range_mean(d, PART2_DIAMETER_BOUNDS)
    return {"F_pT": f_p, "f_pT": (0.001 * d + 0.4 * m + 5.0) * s, "F_alphaT": math.hypot(f_ha, f_fa),
            "F_rT": 0.9 * f_p, "F_i2T": (3.2 * md + 1.01 * math.sqrt(dd) + 6.4) * 2.0 ** (0.5 * (SCALE_GRADE - 5))}


def _range_mean(value: float, bounds) -> float:
    """Geometric mean of the standard's range holding ``value`` (lower bound exclusive,
    as the standard's tables read "above .. up to and including"); the end range outside."""
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        if value <= hi:
            return math.sqrt(lo * hi)
    return math.sqrt(bounds[-2] * bounds[-1])


def radial_composite(grade: int, module: float, diameter: float) -> RadialComposite:
    """ISO 1328-2:1997 radial composite tolerances F_i'' and f_i'' of one gear [um].

    F_i'' = (3.2 m + 1.01 sqrt(d) + 6.4) 2^(0.5 (Q - 5)),
    f_i'' = (2.96 m + 0.01 sqrt(d) + 0.8) 2^(0.5 (Q - 5)),
    m and d the geometric means of the module and diameter ranges holding the
    gear (ISO 1328-2:1997, annex of formulas); rounded as ISO 1328-1 5.2.3.

    Parameters
    ----------
    grade : radial composite grade Q [-], integer 4..12
    module : normal module [mm], > 0 (scope 0.2..10: outside it the end range's mean, and a warning)
    diameter : reference diameter [mm], > 0 (scope 5..1000: outside it the end range's mean, and a warning)

    Raises
    ------
    GradeError
        grade outside 4..12.
    """
    _check_grade(grade, PART2_GRADES, "ISO 1328-2:1997")
    warnings = tuple(f"{r.name} {v:g} outside ISO 1328-2:1997's scope {r.describe()}: the tolerance of its "
                     "nearest range is given (the formulas are not extrapolated)"
                     for r, v in scope_problems(PART2_SCOPE, module=module, diameter=diameter))
    m = _range_mean(module, PART2_MODULE_BOUNDS)
    d = _range_mean(diameter, PART2_DIAMETER_BOUNDS)
    step = 2.0 ** (0.5 * (grade - 5))
    return RadialComposite(grade, round_tolerance((3.2 * m + 1.01 * math.sqrt(d) + 6.4) * step),
                           round_tolerance((2.96 * m + 0.01 * math.sqrt(d) + 0.8) * step), m, d, warnings)
