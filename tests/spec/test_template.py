"""Tests of the ``wormgear new`` template (:mod:`wormgear_cli.spec.template`)."""

from __future__ import annotations

import re
import tomllib

import pytest

from tests.support.paths import MCH50
from wormgear_cli.spec.loader import FIELDS, load_spec, loads_spec
from wormgear_cli.spec.template import template

#: a commented TOML line that holds a key or a table header: "# key = value" or "# [table]"
COMMENTED_TOML = re.compile(r"^# (?:[A-Za-z_][\w.]* = \S.*|\[[\w.]+\])$")


def _value(spec, f):
    record = spec
    for part in f.section.split("."):
        record = getattr(record, part)
    return getattr(record, f.attr)


def test_template_reproduces_the_shipped_mch50_drive():
    """The docs say `wormgear new` writes the MCH50 drive: every schema value (given or
    derived) equals configs/mch50.toml's; only the free-text description differs."""
    shipped = load_spec(MCH50)
    made = loads_spec(template(shipped.drive.name), "new.toml")
    compared = 0
    for f in FIELDS:
        if f.path == "drive.description":
            continue
        assert _value(made, f) == _value(shipped, f), f.path
        compared += 1
    assert compared == len(FIELDS) - 1
    assert made.effects == shipped.effects == {}


def test_every_commented_line_stays_valid_toml_when_uncommented():
    lines = template("t").splitlines()
    commented = [k for k, line in enumerate(lines) if COMMENTED_TOML.match(line)]
    # the derived keys, the optional requirements and the effect example
    assert len(commented) >= 3 + 4 + 3
    for k in commented:
        text = "\n".join(lines[:k] + [lines[k][2:]] + lines[k + 1:])
        tomllib.loads(text)  # raises on a syntax error


@pytest.mark.parametrize("key", ["transverse_pressure_angle_deg", "gear_eccentricity_mm", "contact_ratio"])
def test_uncommenting_a_derived_key_keeps_the_drive(key):
    """A derived key's comment holds the derived value (6 significant digits)."""
    text = template("t")
    line = next(ln for ln in text.splitlines() if ln.startswith(f"# {key} = "))
    base = loads_spec(text, "t.toml")
    again = loads_spec(text.replace(line, line[2:]), "t.toml")
    f = next(f for f in FIELDS if f.key == key)
    assert _value(again, f) == pytest.approx(_value(base, f), rel=1e-5)


def test_template_says_what_it_is():
    head = template("t").split("\n[")[0]
    assert "MCH50" in head and "configs/mch50.toml" in head
