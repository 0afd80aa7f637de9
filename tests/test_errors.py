"""The one quoting of names (errors.py): what reaches a terminal, a message, a TOML comment or a
CSV text cell (issue 23, items 9 and 10; the commands' side is tests/files/test_names.py)."""

from __future__ import annotations

import tomllib

import pytest
from hypothesis import given
from hypothesis import strategies as st

from wormgear_cli.errors import csv_cell, escape, quote, toml_key


@pytest.mark.parametrize("cell", ["=1+1", "+1+1", "-1+1", "@SUM(A1)", "\t=1", "\r=1"])
def test_formula_prefixes_are_neutralised(cell):
    out = csv_cell(cell)
    assert out.startswith("'") and out.isprintable()


@pytest.mark.parametrize("number", ["-3.5", "+1e3", "-0", "-inf", ".5e-3"])
def test_numbers_in_text_cells_stay_numbers(number):
    assert csv_cell(number) == number


@given(st.text())
def test_a_quoted_name_is_one_printable_line_and_a_toml_string(name):
    q = quote(name)
    assert q.isprintable()
    if q != name:  # quoted: a TOML basic string holding exactly the name
        assert tomllib.loads(f"k = {q}")["k"] == name
    assert tomllib.loads(f"{toml_key(name)} = 1") == {name: 1}


@given(st.text())
def test_escape_keeps_printable_text_and_writes_out_the_rest(text):
    out = escape(text)
    assert out.isprintable()
    if text.isprintable():
        assert out == text


def test_ordinary_names_are_left_alone():
    assert quote("configs/mch50.toml") == "configs/mch50.toml"
    assert quote("MCH50 rotary table") == "MCH50 rotary table"
    assert quote(" padded") == '" padded"'


@pytest.mark.parametrize(("name", "shown"), [
    ("a\x1b]0;T\x07", '"a\\u001B]0;T\\u0007"'),  # an OSC title: ESC and BEL written out
    ('say "hi"\n', '"say \\"hi\\"\\n"'),  # quotes and the line break escaped inside the quotes
    ("tab\there\\", '"tab\\there\\\\"'),
    ("\u202eevil", '"\\u202Eevil"'),  # a bidirectional override
    ("tag\U000e0041", '"tag\\U000E0041"'),  # beyond the BMP: eight hex digits
    ("last\uffff", '"last\\uFFFF"'),  # the BMP's last code point: still four
    ("\b\f\r", '"\\b\\f\\r"'),
])
def test_names_with_control_characters_are_quoted_with_toml_escapes(name, shown):
    assert quote(name) == shown
    assert tomllib.loads(f"k = {shown}")["k"] == name


def test_escape_writes_out_controls_but_keeps_quotes_and_the_asked_line_ends():
    assert escape('a "b" \\ \x1b[31m') == 'a "b" \\ \\u001B[31m'
    assert escape("one\ntwo\x07", keep="\n") == "one\ntwo\\u0007"
    assert escape("one\ntwo") == "one\\ntwo"


def test_toml_keys_are_bare_only_when_toml_allows():
    assert toml_key("output_gear-runout2") == "output_gear-runout2"
    assert toml_key("a b") == '"a b"' and toml_key("a.b") == '"a.b"' and toml_key("") == '""'
    assert toml_key('x"\n') == '"x\\"\\n"'


# --- the core speaks the API's words, the command line its flags (issue 17) ----------------------------------


def test_a_usage_error_names_the_parameter_and_the_cli_shows_its_flag():
    import pickle

    from wormgear_cli.errors import UsageError

    err = UsageError(["max_effects: expected an integer >= 0, got -1", "second line"], parameter="max_effects")
    assert err.in_flags({"max_effects": "--max-effects"}) == ["--max-effects: expected an integer >= 0, got -1",
                                                             "second line"]
    assert err.in_flags({}) == err.problems  # a command without that flag: the API's word stays
    assert UsageError("alpha is bad").in_flags({"alpha": "--alpha"}) == ["alpha is bad"]  # no parameter named
    back = pickle.loads(pickle.dumps(err))  # raised in a --jobs worker, reported by the parent
    assert (back.problems, back.parameter) == (err.problems, err.parameter)


def test_the_api_says_alpha_where_the_command_line_says_dash_dash_alpha(runner):
    from wormgear_cli import api
    from wormgear_cli.cli import app
    from wormgear_cli.errors import UsageError

    with pytest.raises(UsageError, match=r"^alpha: expected a number in \(0, 0.5\), got 0.7$"):
        api.diagnose("configs/mch50.toml", "configs/mch50-warm.csv", alpha=0.7)
    res = runner.invoke(app, ["diagnose", "configs/mch50.toml", "configs/mch50-warm.csv", "--alpha", "0.7"])
    assert res.exit_code == 2
    assert "error: --alpha: expected a number in (0, 0.5), got 0.7" in res.output
