"""Counts are read as engineers type them: 1e6, 1_000_000, 2.5e3; a fraction is refused with one line."""

from __future__ import annotations

import pytest

from tests.support.commands import click_group
from tests.support.paths import MCH50
from wormgear_cli.cli import app
from wormgear_cli.cli.common import count_type, parse_count


@pytest.mark.parametrize("text,value", [("100000", 100_000), ("100_000", 100_000), ("1e5", 100_000),
                                        ("1E5", 100_000), ("2.5e3", 2500), ("1e6", 10**6), (" 42 ", 42),
                                        ("-3", -3), ("1e0", 1), ("1_000_000", 10**6), ("7.0", 7)])
def test_a_count_is_read_in_engineering_notation(text, value):
    assert parse_count(text) == value and isinstance(parse_count(text), int)


@pytest.mark.parametrize("text", ["1.5", "1e-3", "2.5e0", "nan", "inf", "1e400", "abc", "", "1,000", "0x10"])
def test_a_fraction_or_a_non_number_is_refused(text):
    with pytest.raises(ValueError, match="expected a whole number"):
        parse_count(text)


def test_a_range_still_holds_and_says_so():
    t = count_type(1, 10)
    assert t.convert("1e1", None, None) == 10
    with pytest.raises(Exception, match="not in the range 1<=x<=10"):
        t.convert("1e2", None, None)


#: every integer option that counts something, by command (option -> a value written as 2e1)
COUNT_OPTIONS = {
    "tolerance": ["--samples", "--targets", "--points", "--jobs"],
    "simulate": ["--points", "--jobs"],
    "synth": ["--targets", "--points", "--runs", "--cycles"],
    "measure": ["--harmonics"],
    "diagnose": ["--max-effects", "--resamples", "--jobs"],
    "sweep": ["--min-pinion-teeth", "--jobs"],
    "merge": ["--jobs"],
    "compensate": ["--harmonics", "--points", "--steps-per-worm"],
    "grade": ["--teeth"],
    "compare": ["--samples"],
}
#: integer options that are not counts (identifiers and classes), read as plain integers
NOT_COUNTS = {("tolerance", "--seed"), ("synth", "--seed"), ("compare", "--seed"), ("grade", "--grade"),
              ("compensate", "--type"),
              ("sweep", "--stage")}  # a stage's position (1 = the first), checked against the drive


def test_every_integer_option_is_a_count_or_named_as_not_one():
    commands = click_group(app).commands
    for name, cmd in commands.items():
        for p in cmd.params:
            opt = next((o for o in getattr(p, "opts", []) if o.startswith("--")), None)
            if opt is None or type(p.type).__name__ not in ("IntParamType", "IntRange", "Count", "CountRange"):
                continue
            is_count = type(p.type).__name__ in ("Count", "CountRange")
            assert is_count == (opt in COUNT_OPTIONS.get(name, [])), f"{name} {opt}"
            assert is_count or (name, opt) in NOT_COUNTS, f"{name} {opt}: a count? add it to COUNT_OPTIONS"


def test_samples_in_engineering_notation_run(runner):
    r = runner.invoke(app, ["tolerance", str(MCH50), "--samples", "2e3", "--metrics", "paper", "-f", "json"])
    assert r.exit_code == 0, r.stderr
    assert '"samples": 2000' in r.stdout
    r2 = runner.invoke(app, ["tolerance", str(MCH50), "--samples", "2_000", "--metrics", "paper", "-f", "json"])
    assert r2.stdout == r.stdout


@pytest.mark.parametrize("value", ["1.5", "1e-3"])
def test_a_fractional_count_is_one_clear_line(runner, value):
    r = runner.invoke(app, ["tolerance", str(MCH50), "--samples", value])
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr == (f"error: Invalid value for '--samples' / '-n': expected a whole number (e.g. 100000, "
                        f"100_000 or 1e5), got {value}; see 'wormgear tolerance --help'\n")


def test_synth_runs_in_engineering_notation(runner):
    r = runner.invoke(app, ["synth", str(MCH50), "--runs", "2e0", "--targets", "4e0"])
    assert r.exit_code == 0, r.stderr
    assert "4 targets" in r.stdout and "2 runs" in r.stdout
