"""ISO 1328-1:2013 / ISO 1328-2:1997 tolerances from a grade (wormgear_cli.physics.iso1328).

Golden values: the standard's worked example (d = 100 mm, m = 2 mm, b = 20 mm, class 6:
f_pT 8.5, F_pT 27, F_alphaT 11, F_rT 24 um, exact after the standard's rounding) and
hand calculations written out in the comments (rounded per ISO 1328-1:2013 5.2.3).
"""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from wormgear_cli.physics import iso1328
from wormgear_cli.physics.iso1328 import GradeError, flank_tolerances, radial_composite, round_tolerance


def test_the_standards_worked_example():
    t = flank_tolerances(6, 2.0, 100.0, 20.0)
    assert (t.f_pT, t.F_pT, t.F_alphaT, t.F_rT) == (8.5, 27.0, 11.0, 24.0)


def test_second_check_value_m3_d120_class6():
    # hand: s = sqrt(2); f_pT = (0.12 + 1.2 + 5) s = 8.94 -> 9.0; F_pT = (0.24 + 6.025 + 2.1 + 12) s = 28.80 -> 29;
    # f_HaT = (1.2 + 0.12 + 4) s = 7.52, f_faT = (1.65 + 5) s = 9.40, F_aT = 12.04 -> 12;
    # the same three values as an independent open implementation's test of ISO 1328-1:2013
    t = flank_tolerances(6, 3.0, 120.0, 30.0)
    assert (t.f_pT, t.F_pT, t.F_alphaT) == (9.0, 29.0, 12.0)


def test_the_rotary_tables_class5_output_gear():
    # hand: F_pT = 0.72 + 0.55 sqrt(360) + 1.4 + 12 = 24.56 -> 25 um; f_pT = 0.36 + 0.8 + 5 = 6.16 -> 6.0 um
    t = flank_tolerances(5, 2.0, 360.0, 40.0, 180)
    assert (t.F_pT, t.f_pT) == (25.0, 6.0)


@pytest.mark.parametrize("raw, rounded", [(12.49, 12.0), (10.5, 11.0), (10.0, 10.0), (7.2, 7.0), (7.26, 7.5),
                                          (5.0, 5.0), (4.96, 5.0), (4.94, 4.9), (0.04, 0.0)])
def test_rounding_of_clause_5_2_3(raw, rounded):
    assert round_tolerance(raw) == rounded


@given(st.integers(1, 10), st.floats(0.5, 70), st.floats(5, 15000), st.floats(4, 1200))
def test_a_coarser_class_never_tightens_a_tolerance(a, m, d, b):
    lo, hi = flank_tolerances(a, m, d, b), flank_tolerances(a + 1, m, d, b)
    for name in ("f_pT", "F_pT", "F_alphaT", "F_rT", "F_betaT"):
        assert getattr(hi, name) >= getattr(lo, name)
    # one class is a factor sqrt(2) before rounding; rounding moves each by at most half a step (<= 0.5 um)
    assert hi.F_pT == pytest.approx(lo.F_pT * 2 ** 0.5, abs=0.5 + 0.5 * 2 ** 0.5)


@pytest.mark.parametrize("grade", [0, 12, -1])
def test_grade_outside_1_to_11_is_an_error(grade):
    with pytest.raises(GradeError, match=r"expected an integer in \[1, 11\]"):
        flank_tolerances(grade, 2.0, 100.0, 20.0)


@pytest.mark.parametrize("kwargs, message", [
    (dict(module=0.3), r"module 0.3 outside .* \[0.5, 70\] mm"),
    (dict(diameter=20000.0), r"diameter 20000 outside .* \[5, 15000\] mm"),
    (dict(face_width=2.0), r"face_width 2 outside .* \[4, 1200\] mm"),
    (dict(teeth=4), r"teeth 4 outside .* \[5, 1000\]"),
])
def test_outside_the_scope_of_part_1_is_an_error(kwargs, message):
    args = dict(module=2.0, diameter=100.0, face_width=20.0, teeth=50) | kwargs
    with pytest.raises(GradeError, match=message):
        flank_tolerances(6, **args)


def test_scope_is_data():
    assert {r.name for r in iso1328.PART1_SCOPE} == {"module", "diameter", "face_width", "teeth"}
    assert all(r.on_violation == "error" for r in iso1328.PART1_SCOPE)
    assert all(r.on_violation == "warning" for r in iso1328.PART2_SCOPE)


def test_radial_composite_with_range_means():
    # hand: m = 2 lies in (1.5, 2.5] -> sqrt(3.75) = 1.936; d = 100 in (50, 125] -> sqrt(6250) = 79.06;
    # F_i'' = (6.197 + 8.981 + 6.4) sqrt(2) = 30.52 -> 31; f_i'' = (5.732 + 0.089 + 0.8) sqrt(2) = 9.36 -> 9.5
    rc = radial_composite(6, 2.0, 100.0)
    assert (rc.F_i2T, rc.f_i2T) == (31.0, 9.5)
    assert rc.module_mean == pytest.approx(1.936, abs=1e-3) and rc.warnings == ()
    # hand: m = 3 in (2.5, 4] -> 3.162, d = 135 in (125, 280] -> 187.08: (10.12 + 13.81 + 6.4) = 30.3 -> 30
    assert radial_composite(5, 3.0, 135.0).F_i2T == 30.0


def test_radial_composite_extrapolated_warns_and_grades_are_4_to_12():
    rc = radial_composite(6, 2.0, 1500.0)
    assert rc.warnings == ("diameter 1500 outside ISO 1328-2:1997's scope [5, 1000] mm: the tolerance of its "
                           "nearest range is given (the formulas are not extrapolated)",)
    with pytest.raises(GradeError, match=r"\[4, 12\]"):
        radial_composite(3, 2.0, 100.0)


# --- mutation-testing round 2 (issue 13): every field, the boundaries, the messages -------------

def test_every_field_of_the_worked_example_by_hand():
    # hand, A = 6: s = sqrt(2) = 1.414214; m = 2, d = 100, b = 20 (sqrt(d) = 10, sqrt(b) = 4.472136)
    # f_pT  = (0.1 + 0.8 + 5) s = 8.344 -> 8.5;  F_pT = (0.2 + 5.5 + 1.4 + 12) s = 27.012 -> 27
    # f_HaT = (0.8 + 0.1 + 4) s = 6.930 -> 7.0;  f_faT = (1.1 + 5) s = 8.627 -> 8.5
    # F_aT  = hypot(6.930, 8.627) = 11.065 -> 11
    # f_HbT = (0.5 + 1.565248 + 4) s = 8.578 -> 8.5;  f_fbT = (0.7 + 2.012461 + 4) s = 9.493 -> 9.5
    # F_bT  = hypot(8.578, 9.493) = 12.794 -> 13;  F_rT = 0.9 * 27.012 = 24.31 -> 24
    t = flank_tolerances(6, 2.0, 100.0, 20.0)
    assert t == iso1328.FlankTolerances(6, 8.5, 27.0, 7.0, 8.5, 11.0, 8.5, 9.5, 13.0, 24.0)


def test_every_field_class5_large_diameter_by_hand():
    # hand, A = 5: s = 1; m = 2, d = 360, b = 40 (sqrt(d) = 18.973666, sqrt(b) = 6.324555)
    # f_pT  = 0.36 + 0.8 + 5 = 6.16 -> 6.0;  F_pT = 0.72 + 10.435516 + 1.4 + 12 = 24.556 -> 25
    # f_HaT = 0.8 + 0.36 + 4 = 5.16 -> 5.0 (0.5 steps from 5 um);  f_faT = 1.1 + 5 = 6.1 -> 6.0
    # F_aT  = hypot(5.16, 6.1) = 7.990 -> 8.0
    # f_HbT = 0.948683 + 2.213594 + 4 = 7.162 -> 7.0;  f_fbT = 1.328157 + 2.846050 + 4 = 8.174 -> 8.0
    # F_bT  = hypot(7.162, 8.174) = 10.868 -> 11;  F_rT = 0.9 * 24.556 = 22.10 -> 22
    t = flank_tolerances(5, 2.0, 360.0, 40.0, 180)
    assert t == iso1328.FlankTolerances(5, 6.0, 25.0, 5.0, 6.0, 8.0, 7.0, 8.0, 11.0, 22.0)


@pytest.mark.parametrize("raw, rounded", [(5.3, 5.5), (5.2, 5.0), (5.74, 5.5), (9.76, 10.0), (10.49, 10.0)])
def test_rounding_between_5_and_10_um_is_to_half_a_micrometre(raw, rounded):
    assert round_tolerance(raw) == rounded


def test_the_scope_bounds_are_inclusive():
    # clause 1: 0.5 <= m <= 70, 5 <= d <= 15000, 4 <= b <= 1200, 5 <= z <= 1000 -- the ends are inside
    flank_tolerances(6, 0.5, 5.0, 4.0, 5)
    flank_tolerances(6, 70.0, 15000.0, 1200.0, 1000)


@pytest.mark.parametrize("grade", [True, 6.0])
def test_a_grade_must_be_an_integer(grade):
    with pytest.raises(GradeError, match=r"ISO 1328-1:2013's range, expected an integer in \[1, 11\]"):
        flank_tolerances(grade, 2.0, 100.0, 20.0)


def test_messages_name_the_standard_word_for_word():
    with pytest.raises(GradeError) as e:
        flank_tolerances(6, 2.0, 100.0, 20.0, 4)
    assert str(e.value) == "teeth 4 outside ISO 1328-1:2013's scope [5, 1000] (its formulas are not extrapolated)"
    with pytest.raises(GradeError) as e:
        flank_tolerances(12, 2.0, 100.0, 20.0)
    assert str(e.value) == "grade 12 outside ISO 1328-1:2013's range, expected an integer in [1, 11]"
    with pytest.raises(GradeError) as e:
        radial_composite(13, 2.0, 100.0)
    assert str(e.value) == "grade 13 outside ISO 1328-2:1997's range, expected an integer in [4, 12]"


def test_radial_composite_range_upper_bounds_are_inclusive():
    # "above 1.5 up to and including 2.5": m = 2.5 -> sqrt(1.5 * 2.5) = 1.9365; d = 125 -> sqrt(50 * 125) = 79.057
    rc = radial_composite(6, 2.5, 125.0)
    assert rc.grade == 6
    assert rc.module_mean == pytest.approx(1.9365, abs=1e-4)
    assert rc.diameter_mean == pytest.approx(79.057, abs=1e-3)


NEAREST = "the tolerance of its nearest range is given (the formulas are not extrapolated)"


def test_radial_composite_beyond_the_last_range_uses_the_last_range():
    # d = 1500 > 1000: the last range (560, 1000] -> sqrt(560000) = 748.331; m = 12 > 10: (6, 10] -> sqrt(60) = 7.7460
    # F_i'' = (3.2 * 7.7460 + 1.01 * 27.3556 + 6.4) sqrt(2) = (24.787 + 27.629 + 6.4) sqrt(2) = 83.18 -> 83
    rc = radial_composite(6, 12.0, 1500.0)
    assert rc.diameter_mean == pytest.approx(748.331, abs=1e-3)
    assert rc.module_mean == pytest.approx(7.7460, abs=1e-4)
    assert rc.F_i2T == 83.0
    assert rc.warnings == (
        "module 12 outside ISO 1328-2:1997's scope [0.2, 10] mm: " + NEAREST,
        "diameter 1500 outside ISO 1328-2:1997's scope [5, 1000] mm: " + NEAREST)
