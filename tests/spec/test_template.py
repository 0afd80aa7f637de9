"""Tests of the ``wormgear new`` templates (:mod:`wormgear_cli.spec.template`)."""

from __future__ import annotations

import re
import tomllib

import pytest

from tests.support.paths import MCH50
from wormgear_cli.spec.loader import load_spec, loads_spec
from wormgear_cli.spec.stages import STAGE_FIELDS, record_values
from wormgear_cli.spec.template import SUGGESTED, template

#: a commented TOML line that holds a key or a table header: "# key = value" or "# [table]"
COMMENTED_TOML = re.compile(r"^# (?:[A-Za-z_][\w.]* = \S.*|\[[\w.]+\])$")


def test_template_reproduces_the_shipped_mch50_drive():
    """The docs say `wormgear new` writes the MCH50 drive: every stage value (given or derived)
    equals configs/mch50.toml's, and so do the drive-level tables (the description aside)."""
    shipped = load_spec(MCH50)
    made = loads_spec(template(shipped.drive.name), "new.toml")
    assert [s.kind for s in made.stages] == ["worm", "spur"]
    for a, b in zip(shipped.stages, made.stages):
        assert record_values(a) == record_values(b)
    assert made.materials == shipped.materials and made.requirements == shipped.requirements
    assert made.stiffness == shipped.stiffness._replace(contact_ratio=None)  # derived per stage in the stage form
    assert made.effects == shipped.effects == {}


@pytest.mark.parametrize("stages", [s.split(",") for s in SUGGESTED] + [["belt", "spur", "worm"]])
def test_every_commented_line_stays_valid_when_uncommented(stages):
    text = template("t", stages)
    lines = text.splitlines()
    commented = [k for k, line in enumerate(lines) if COMMENTED_TOML.match(line)]
    assert len(commented) >= 10
    for k in commented:
        one = "\n".join(lines[:k] + [lines[k][2:]] + lines[k + 1:])
        tomllib.loads(one)  # raises on a syntax error
        if "effects" not in lines[k] and not any("effects" in ln for ln in lines[k - 3:k]):
            loads_spec(one, "t.toml")  # and the drive stays valid


@pytest.mark.parametrize("stages", [s.split(",") for s in SUGGESTED])
def test_every_key_of_each_kind_is_in_the_template(stages):
    text = template("t", stages)
    spec = loads_spec(text, "t.toml")
    assert [s.kind for s in spec.stages] == stages
    keys = {line.lstrip("# ").split(" = ")[0] for line in text.splitlines() if " = " in line}
    for kind in stages:
        for f in STAGE_FIELDS[kind]:
            assert f.path.rpartition(".")[2] in keys, f.path


@pytest.mark.parametrize("key, stage", [("transverse_pressure_angle_deg", 0), ("eccentricity_mm", 1)])
def test_uncommenting_a_derived_key_keeps_the_drive(key, stage):
    """A derived key's comment holds the derived value (6 significant digits)."""
    text = template("t")
    line = next(ln for ln in text.splitlines() if ln.startswith(f"# {key} = "))
    base = loads_spec(text, "t.toml")
    again = loads_spec(text.replace(line, line[2:].split("  #")[0]), "t.toml")
    assert record_values(again.stages[stage])[key] == pytest.approx(record_values(base.stages[stage])[key], rel=1e-5)


def test_template_says_what_it_is():
    head = template("t").split("\n[")[0]
    assert "MCH50" in head and "configs/mch50.toml" in head
    with pytest.raises(ValueError, match="chain"):
        template("t", ["chain"])
