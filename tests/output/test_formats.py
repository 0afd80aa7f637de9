"""Tests of the text formats shared by every command (:mod:`wormgear_cli.output.formats`)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from wormgear_cli.output.formats import csv_text, fmt_number, json_text

# --- the vectorised '%.12g' CSV formatter of the sweep ----------------------------------------


@settings(max_examples=300, deadline=None)
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=1, max_size=40))
def test_fast_formatter_equals_percent_g(values):
    from wormgear_cli.output.formats import format_g

    fields = format_g(np.array(values))
    got = [bytes(f[f != 0]).decode() for f in fields]
    assert got == ["" if v != v else f"{v:.12g}" for v in values]


def test_fast_formatter_on_hard_cases():
    from wormgear_cli.output.formats import csv_block

    values = [0.0, -0.0, 8.0, 202.5, 100.0, 1e-5, 0.0001, 99999999999.95, 999999999999.5, 1e12, 123456789012.5,
              2.5e-300, -7.0, 1 / 3]
    assert csv_block([np.array(values)]).decode().splitlines() == [f"{v:.12g}" for v in values]
    rng = np.random.default_rng(3)
    x = rng.random(5000) * 10.0 ** rng.integers(-8, 14, 5000)
    assert csv_block([x]).decode().splitlines() == [f"{v:.12g}" for v in x]



# --- Python-value CSV and JSON ---------------------------------------------------------------


def test_fmt_number_round_trips_and_leaves_undefined_empty():
    for x in (0.1, 1 / 3, 2.5e-300, -7.0, 1e22):
        assert float(fmt_number(x)) == x
    assert fmt_number(3) == "3" and fmt_number(True) == "1"
    assert fmt_number(None) == fmt_number(float("nan")) == fmt_number(float("inf")) == ""
    assert fmt_number(np.float64(0.5)) == "0.5" and fmt_number(np.int64(7)) == "7"


def test_csv_text_quotes_by_the_stdlib_rules():
    import csv
    import io

    text = csv_text(["a", "b,c"], [["x,y", 1.5], ['q"', None]])
    assert list(csv.reader(io.StringIO(text))) == [["a", "b,c"], ["x,y", "1.5"], ['q"', ""]]
    assert text.endswith("\n") and "\r" not in text


def test_json_text_is_strict_json_with_null_for_undefined():
    import json

    doc = {"b": float("nan"), "a": [np.float64(1.25), float("-inf")], "c": (1, 2)}
    text = json_text(doc)
    assert json.loads(text) == {"schema_version": 2, "b": None, "a": [1.25, None], "c": [1, 2]}
    assert list(json.loads(text)) == ["schema_version", "b", "a", "c"]  # the version first, then as built
    assert json.loads(json_text([1, 2])) == [1, 2]  # only a document (a dict) carries the version
