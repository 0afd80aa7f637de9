"""Drive-spec loading: validation messages, defaults, unit conversion, round trips."""

from __future__ import annotations

import math
import tomllib
from dataclasses import FrozenInstanceError

import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.support.paths import MCH50
from wormgear_cli.errors import SpecError
from wormgear_cli.spec.loader import FIELDS, load_spec, loads_spec, raw_copy, spec_from_dict, with_values
from wormgear_cli.spec.template import template


def minimal() -> dict:
    """The smallest valid drive: only the required keys."""
    return {
        "gear_pair": {"module_mm": 2.5, "pressure_angle_deg": 20.0, "output_gear": {"teeth": 144},
                      "pinion": {"teeth": 18}},
        "worm_pair": {"module_mm": 2.5, "normal_pressure_angle_deg": 20.0, "lead_angle_deg": 3.178,
                      "worm": {"starts": 1}, "wheel": {"teeth": 30}},
    }


def problems_of(data: dict | str, source="d.toml") -> list[str]:
    with pytest.raises(SpecError) as info:
        if isinstance(data, str):
            loads_spec(data, source)
        else:
            spec_from_dict(data, source)
    return info.value.problems


def test_minimal_drive_loads_with_documented_defaults():
    spec = spec_from_dict(minimal(), "d.toml", default_name="d")
    assert spec.drive.name == "d"
    # face width defaults to 10 x module (documented in FIELDS)
    assert spec.gear_pair.face_width == pytest.approx(25.0)
    # Delta e defaults to the spur centre-distance error (0 here)
    assert spec.assembly.gear_eccentricity == 0.0
    # alpha_2 = atan(tan 20 / cos 3.178) from DIN 3975, computed here by hand in degrees
    assert math.degrees(spec.worm_pair.transverse_pressure_angle) == pytest.approx(20.0284, abs=1e-3)  # tan20/cos3.178 = 0.36453
    assert spec.stiffness.model == "iso6336"
    assert spec.worm_pair.lead_error == 0.0


def test_units_are_converted_once_at_load_time(mch50_spec):
    s = mch50_spec
    assert s.gear_pair.pressure_angle == pytest.approx(math.pi / 9)  # 20 deg in rad
    assert s.worm_pair.lead_error == pytest.approx(0.030)  # mm stays mm
    assert s.materials.gear_elastic_modulus == pytest.approx(206_000.0)  # GPa -> N/mm^2
    assert s.materials.wheel_expansion == pytest.approx(18.5e-6)  # ppm/K -> 1/K
    assert s.requirements.max_backlash == pytest.approx(252.0 * math.pi / 648000)  # arcsec -> rad


def test_mch50_has_table1_values(mch50_spec):
    """Table 1 of the paper, as given."""
    s = mch50_spec
    assert (s.gear_pair.output_gear.teeth, s.gear_pair.pinion.teeth) == (144, 18)
    assert (s.worm_pair.wheel.teeth, s.worm_pair.worm.starts) == (30, 1)
    assert s.assembly.gear_centre_distance_error == 0.030
    assert s.assembly.worm_centre_distance_error == 0.035
    assert s.worm_pair.lead_error == 0.030
    assert s.worm_pair.wheel.radial_composite_error == 0.036
    assert (s.worm_pair.worm.profile_error, s.worm_pair.wheel.profile_error) == (0.036, 0.011)
    assert (s.worm_pair.worm.thickness_deviation, s.worm_pair.wheel.thickness_deviation) == (0.045, 0.090)
    assert (s.loads.gear_normal_force, s.loads.worm_normal_force) == (666.0, 85.0)


def test_spec_is_immutable(mch50_spec):
    with pytest.raises(FrozenInstanceError):
        mch50_spec.gear_pair.module = 3.0  # type: ignore[misc]
    with pytest.raises(TypeError):
        mch50_spec.raw["gear_pair"]["module_mm"] = 3.0


@pytest.mark.parametrize(
    "change, expected",
    [
        (("gear_pair", "modul_mm", 2.5), "d.toml: gear_pair.modul_mm: unknown key (did you mean gear_pair.module_mm?)"),
        (("", "foo", 1), "d.toml: foo: unknown key (a drive file holds the tables [assembly], [drive], [effects], "
                         "[gear_pair], [loads], [materials], [requirements], [statistics], [stiffness], [test_plan], [worm_pair])"),
        (("gear_pair.output_gear", "teeth", 18.5),
         "d.toml: gear_pair.output_gear.teeth: expected an integer in [1, 10000], got 18.5 (not a whole number)"),
        (("gear_pair.output_gear", "teeth", 0), "d.toml: gear_pair.output_gear.teeth: expected an integer in [1, 10000], got 0"),
        (("gear_pair.pinion", "teeth", -3), "d.toml: gear_pair.pinion.teeth: expected an integer in [1, 10000], got -3"),
        (("gear_pair", "pressure_angle_deg", 95.0),
         "d.toml: gear_pair.pressure_angle_deg: expected a number in [1, 45) [deg], got 95.0"),
        (("worm_pair", "lead_angle_deg", 0),
         "d.toml: worm_pair.lead_angle_deg: expected a number in [0.1, 45) [deg], got 0"),
        (("worm_pair", "lead_error_mm", -0.01), "d.toml: worm_pair.lead_error_mm: expected a number in [0, 10] [mm], got -0.01"),
        (("gear_pair", "module_mm", "2.5"), 'd.toml: gear_pair.module_mm: expected a number in [0.05, 100] [mm], got "2.5"'),
        (("gear_pair", "module_mm", True), "d.toml: gear_pair.module_mm: expected a number in [0.05, 100] [mm], got a boolean"),
        (("gear_pair", "module_mm", float("nan")), "d.toml: gear_pair.module_mm: expected a number in [0.05, 100] [mm], got nan"),
        (("gear_pair", "module_mm", float("inf")), "d.toml: gear_pair.module_mm: expected a number in [0.05, 100] [mm], got inf"),
        (("stiffness", "model", "iso6663"),
         'd.toml: stiffness.model: expected one of "iso6336", "empirical", got "iso6663" (did you mean "iso6336"?)'),
        (("assembly", "worm_pair_errors_mm", [0.01, 0.02]),
         "d.toml: assembly.worm_pair_errors_mm: expected an array of 6 numbers in [0, 10] [mm], got 2 values"),
        ((None, "gearpair", {}), "d.toml: gearpair: unknown table (did you mean gear_pair?)"),
        (("gear_pair", "module_mm", 10**400),
         "d.toml: gear_pair.module_mm: expected a number in [0.05, 100] [mm], got an integer of 401 digits"),
        (("gear_pair.output_gear", "teeth", 10**6),
         "d.toml: gear_pair.output_gear.teeth: expected an integer in [1, 10000], got 1000000"),
        (("worm_pair", "lead_error_mm", 1e155), "d.toml: worm_pair.lead_error_mm: expected a number in [0, 10] [mm], got 1e+155"),
        (("stiffness", "model", "ISO6336"),
         'd.toml: stiffness.model: expected one of "iso6336", "empirical", got "ISO6336" (did you mean "iso6336"?)'),
        (("assembly", "gear_eccentricity_mm", {"a": 1}), "d.toml: assembly.gear_eccentricity_mm: expected a value, got a table"),
        (("drive", "name", "MCH50\nrev B"),
         'd.toml: drive.name: expected a single-line name without control characters, got "MCH50\\nrev B"'),
        (("assembly", "worm_phase_deg", 10.0),
         "d.toml: assembly.worm_phase_deg: unknown key (did you mean assembly.worm_eccentricity_phase_deg?)"),
        # a key that differs in case only is the one meant (difflib alone would offer max_iso230_M_arcsec)
        (("requirements", "max_iso230_a_arcsec", 20.0),
         "d.toml: requirements.max_iso230_a_arcsec: unknown key (did you mean requirements.max_iso230_A_arcsec?)"),
        (("effects", "thermal_backlsh", {"centre_distance_um_per_K": 1.0}),
         "d.toml: effects.thermal_backlsh: unknown effect (did you mean effects.thermal_backlash?)"),
        (("effects", "thermal_backlash", {"reference_temperature_C": 20.0}),
         "d.toml: effects.thermal_backlash.centre_distance_um_per_K: missing required key, expected a number "
         "in [-20, 20] [um/K]"),
    ],
)
def test_each_problem_has_its_exact_message(change, expected):
    data = minimal()
    section, key, value = change
    node = data
    if section:
        for part in section.split("."):
            node = node.setdefault(part, {})
    node[key] = value
    assert problems_of(data) == [expected]


def test_missing_required_key_and_section():
    data = minimal()
    del data["gear_pair"]["module_mm"]
    del data["worm_pair"]["wheel"]
    assert problems_of(data) == [
        "d.toml: worm_pair.wheel: missing section [worm_pair.wheel]",
        "d.toml: gear_pair.module_mm: missing required key, expected a number in [0.05, 100] [mm]",
    ]


def test_all_problems_are_reported_at_once():
    data = minimal()
    data["gear_pair"]["module_mm"] = -1
    data["gear_pair"]["pinion"]["teeth"] = 2.5
    data["loads"] = {"gear_force_N": 3}
    assert len(problems_of(data)) == 3


def test_syntax_error_names_line_and_column():
    assert problems_of("[gear_pair]\nmodule_mm = 2.5\nmodule_mm = 3\n") == [
        "d.toml:3:14: TOML syntax error: Cannot overwrite a value"
    ]
    assert problems_of("a = [1,\n") == ["d.toml:1:8: TOML syntax error: Invalid value (at end of file)"]


def test_bad_files(tmp_path):
    with pytest.raises(SpecError, match=r"nope.toml: file not found$"):
        load_spec(tmp_path / "nope.toml")
    with pytest.raises(SpecError, match=r": is a directory, expected a TOML drive file$"):
        load_spec(tmp_path)
    empty = tmp_path / "empty.toml"
    empty.write_text("  \n")
    with pytest.raises(SpecError, match=r"empty.toml: file is empty"):
        load_spec(empty)
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\x7fELF\x00\x01")
    with pytest.raises(SpecError, match=r"bin.toml: binary file, expected a TOML drive file$"):
        load_spec(binary)
    latin = tmp_path / "latin.toml"
    latin.write_bytes(b"name = '\xe9'\n")
    with pytest.raises(SpecError, match=r"latin.toml: not UTF-8 text"):
        load_spec(latin)


def test_template_is_complete_and_valid():
    from wormgear_cli.spec.loader import DRIVE_FIELDS
    from wormgear_cli.spec.stages import STAGE_FIELDS

    text = template("t")
    spec = loads_spec(text, "t.toml")
    assert spec.drive.name == "t"
    keys = {line.lstrip("# ").split(" = ")[0] for line in text.splitlines() if " = " in line}
    for f in DRIVE_FIELDS:  # every drive-level key and every key of each stage appears, commented or set
        assert f.key in keys, f.path
    for kind in ("worm", "spur"):
        for f in STAGE_FIELDS[kind]:
            assert f.path.rpartition(".")[2] in keys, f.path


def test_toml_round_trip_through_tomli_w(mch50_spec):
    """raw -> tomli_w -> tomllib -> spec gives the same values."""
    again = loads_spec(tomli_w.dumps(raw_copy(mch50_spec)), str(MCH50))
    assert again == mch50_spec


def test_with_values_revalidates(mch50_spec):
    s = with_values(mch50_spec, {"worm_pair.lead_error_mm": 0.05})
    assert s.worm_pair.lead_error == 0.05
    assert mch50_spec.worm_pair.lead_error == 0.030  # the original is untouched
    with pytest.raises(SpecError, match=r"worm_pair.lead_error_mm: expected a number in \[0, 10\]"):
        with_values(mch50_spec, {"worm_pair.lead_error_mm": -1.0})


# --- property: any TOML document either loads or raises SpecError (never anything else) ---------------

_paths = [f.path for f in FIELDS] + ["gear_pair.bogus", "effects.thermal_drift.arcsec_per_K", "x.y"]
_values = st.one_of(
    st.integers(-5, 500), st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=5), st.booleans(),
    st.lists(st.floats(-1, 1), max_size=7), st.just({}),
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.dictionaries(st.sampled_from(_paths), _values, max_size=8), st.booleans())
def test_any_document_loads_or_raises_spec_error(changes, start_valid):
    data = minimal() if start_valid else {}
    for path, value in changes.items():
        node = data
        parts = path.split(".")
        ok = True
        for part in parts[:-1]:
            nxt = node.setdefault(part, {})
            if not isinstance(nxt, dict):
                ok = False
                break
            node = nxt
        if ok:
            node[parts[-1]] = value
    try:
        text = tomli_w.dumps(data)
    except Exception:  # tomli_w cannot write some values (e.g. nested empties in arrays); not our concern
        return
    try:
        spec = loads_spec(text, "h.toml")
    except SpecError as exc:
        assert exc.problems and all(p.startswith("h.toml") for p in exc.problems)
        assert all("\n" not in p for p in exc.problems)
    else:
        assert spec.gear_pair.module > 0
        tomllib.loads(text)


@settings(max_examples=100, deadline=None)
@given(st.text(max_size=60))
def test_arbitrary_text_loads_or_raises_spec_error(text):
    try:
        loads_spec(text, "h.toml")
    except SpecError as exc:
        assert all(p.startswith("h.toml") for p in exc.problems)


def test_a_file_of_neither_form_is_told_how_a_drive_is_written():
    """Only [drive] (or another table of neither form): one line pointing to [[stage]] and the
    template, not the legacy form's missing tables."""
    assert problems_of({"drive": {"name": "x"}}) == [
        'd.toml: stage: no stages: a drive is a list of [[stage]] tables from the motor to the output, each '
        'with kind = "worm", "spur" or "belt"; start from a template: wormgear new FILE --stages worm']
