"""The readers parse a file a block of lines at a time (measurement/readers/source.py, text.DelimitedBody):
whatever the block size, the measurement (every column, note, warning, the rows read back) or the
message is the one the whole text read at once gives.

Block sizes are drawn by hypothesis, so block boundaries fall anywhere: inside a quoted cell (and the
line break a quoted cell runs over), between the \\r and \\n of a CRLF line end (the file is read in
raw chunks of that many bytes), inside a multi-byte character, in a preamble, on a comment or blank
line, before an export's EOF tag.  The one-shot reading is ``parse_measurement`` of the text with one
block; the block reading is ``read_measurement`` of the file (its own raw reads and line cuts)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.support.examples import examples
from wormgear_cli.errors import WormgearError
from wormgear_cli.measurement.reader import ReadOptions
from wormgear_cli.measurement.readers import parse_measurement, read_measurement

DATA = Path(__file__).resolve().parent.parent / "data"
WHOLE = 1 << 40  # one block: the whole text


def _iso_rows(targets=(0.0, 90.0, 180.0, 270.0, 355.5), runs=3):
    """(angle, error, direction, run) of a small ISO 230-2 test, errors made up by a fixed rule."""
    out = []
    for run in range(runs):
        for d in (1, -1):
            for k, t in enumerate(targets if d > 0 else targets[::-1]):
                out.append((t, round(1.5 * np.sin(np.radians(t)) + 0.7 * d + 0.1 * run - 0.03 * k, 3), d, run))
    return out


def _table(fmt, header="angle_deg,error_arcsec,direction,run", rows=None):
    return header + "\n" + "".join(fmt(*r) + "\n" for r in (rows or _iso_rows()))


PLAIN = _table(lambda a, e, d, r: f"{a:g},{e:g},{d},{r}")
CASES = {
    "plain": (PLAIN, {}),
    "crlf-bom": ("\ufeff" + PLAIN.replace("\n", "\r\n"), {}),
    "lone-cr": (PLAIN.replace("\n", "\r"), {}),
    "no-final-line-end": (PLAIN.rstrip("\n"), {}),
    "quoted-cells": (_table(lambda a, e, d, r: f'"{a:g}","{e:g}",{"CW" if d > 0 else "CCW"},"{r}"'), {}),
    "direction-words": (_table(lambda a, e, d, r: f"{a:g},{e:g},{'forward' if d > 0 else 'reverse'},{r}"), {}),
    "semicolon-decimal-comma-arcmin": (
        _table(lambda a, e, d, r: f"{a:g};{e / 60:.6f};{d};{r}".replace(".", ","),
               header="Position (°);Écart (arcmin);Sens;Série").replace("\n", "\r\n"),
        {"column_map": (("angle_deg", "Position (°)"), ("error_arcsec", "Écart (arcmin)"), ("direction", "Sens"),
                        ("run", "Série"))}),
    "tab-utf8": (_table(lambda a, e, d, r: f"{a:g}\t{e:g}\t{d}\t{r}", header="angle_deg\terror_arcsec\tdirection\trun"),
                 {}),
    "preamble-comments-blank-rows": (
        "# axis C, test of 2024-05-01\nMachine: VMC 850\nOperator; J. Doe\n# comment in the preamble\n"
        + PLAIN.split("\n", 1)[0] + "\n"
        + "".join(line + "\n" + ("# a comment\n" if k % 7 == 3 else "") + ("\n" if k % 9 == 4 else "")
                  + (",,,\n" if k % 11 == 5 else "")
                  for k, line in enumerate(PLAIN.split("\n")[1:-1])), {}),
    "actual-target": (_table(lambda a, e, d, r: f"{a:g},{a + e / 3600:.9f},{d},{r}",
                             header="target_deg,actual_deg,direction,run"), {}),
    "quoted-thousands-comment-column": (
        _table(lambda a, e, d, r: f'{a:g},{e:g},{d},{r},"note, with comma {r}"',
               header="angle_deg,error_arcsec,direction,run,comment"), {}),
    # files the readers refuse: the same message whatever the blocks
    "line-break-in-quoted-cell": (PLAIN + '10,"1\n2",1,3\n' + "20,1,1,3\n", {}),
    # a stray quote in an unquoted cell, then a quoted cell left open: an even count of quotes on the line
    "stray-quote-then-open-quote": (PLAIN + '10,1x"y,1,"3\n4"\n20,1,1,3\n', {}),
    "bad-cell-late": (PLAIN + "10,1.2.3,1,3\n", {}),
    "digit-separator-after-bad": (PLAIN + "10,abc,1,3\n20,1_0,1,3\n", {}),
    "cell-count-off": (PLAIN + "10,1,1\n", {}),
    "bad-direction": (PLAIN + "10,1,sideways,3\n", {}),
    "non-ascii-number": (PLAIN + "10,１,1,3\n", {}),
}
FIELD = {p.name: p for p in sorted((DATA / "field").glob("*.csv"))}


def _same(one, other) -> None:
    """Two measurements equal in every field (arrays element by element, NaN equal to NaN) and rows."""
    for f in dataclasses.fields(one):
        if f.name.startswith("_"):
            continue
        a, b = getattr(one, f.name), getattr(other, f.name)
        if isinstance(a, np.ndarray):
            np.testing.assert_array_equal(a, b, err_msg=f.name)
        else:
            assert a == b, f.name
    assert list(one.rows) == list(other.rows)


def _outcome(read):
    try:
        return read(), None
    except WormgearError as exc:
        return None, (type(exc).__name__, str(exc))


#: the whole text's reading by (path, text, options): the same for every block size drawn against it
_WHOLE: dict = {}


def _compare(path: Path, text: str, options: dict, block: int) -> None:
    key = (str(path), text, repr(sorted(options.items())))
    if key not in _WHOLE:
        _WHOLE[key] = _outcome(lambda: parse_measurement(text, str(path), options=ReadOptions(
            block_chars=WHOLE, **options)))
    whole, whole_error = _WHOLE[key]
    blocks, blocks_error = _outcome(lambda: read_measurement(path, options=ReadOptions(block_chars=block, **options)))
    assert blocks_error == whole_error
    if whole is not None:
        _same(whole, blocks)
        assert len(whole) > 2


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    folder = tmp_path_factory.mktemp("blocks")
    out = {}
    for name, (text, options) in CASES.items():
        path = folder / f"{name}.csv"
        path.write_bytes(text.encode("utf-8"))
        # the text as a reader sees it: BOM dropped, every line end \n
        seen = text.lstrip("\ufeff").replace("\r\n", "\n").replace("\r", "\n")
        out[name] = (path, seen, options)
    return out


@pytest.mark.parametrize("name", list(CASES))
@settings(max_examples=examples(40), deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_blocks_read_as_the_whole_text(written, name, data):
    path, text, options = written[name]
    block = data.draw(st.integers(1, 48) | st.integers(1, len(text.encode()) + 8), label="block bytes")
    _compare(path, text, options, block)


def test_every_block_size_of_a_quoted_line_break_and_crlf(written):
    """Exhaustively, each block size: a boundary at every byte of the file, the open quote and the
    CRLF pairs included."""
    for name in ("line-break-in-quoted-cell", "stray-quote-then-open-quote", "crlf-bom", "quoted-cells"):
        path, text, options = written[name]
        for block in range(1, 90):
            _compare(path, text, options, block)


@pytest.mark.parametrize("name", list(FIELD))
@settings(max_examples=6, deadline=None)
@given(data=st.data())
def test_field_files_in_blocks(name, data):
    """The field recordings (CSV exports, a TwinCAT Scope export with its EOF tag and CRLF line ends)."""
    path = FIELD[name]
    text = path.read_bytes().decode("utf-8").lstrip("\ufeff").replace("\r\n", "\n").replace("\r", "\n")
    block = data.draw(st.integers(64, 4096) | st.integers(64, len(text) + 8), label="block bytes")
    _compare(path, text, {}, block)


def test_the_cases_say_what_they_should(written):
    """The refused cases are refused with the message that names the line (the comparison above is not
    between two equal failures of another kind)."""
    expect = {"line-break-in-quoted-cell": "quoted cell", "stray-quote-then-open-quote": "quoted cell",
              "bad-cell-late": "expected a number, got '1.2.3'",
              "digit-separator-after-bad": "got '1_0'", "cell-count-off": "expected 4 cells as in the header, got 3",
              "bad-direction": "'sideways'", "non-ascii-number": "expected a number"}
    for name, part in expect.items():
        path, text, options = written[name]
        with pytest.raises(WormgearError) as err:
            read_measurement(path, options=ReadOptions(block_chars=7, **options))
        assert part in str(err.value), name
        # the last line, or the line the quoted cell opens on (two before the last); a digit separator is
        # named before another bad cell of its column, wherever they are
        line = text.count("\n") - (2 if "quote" in name else 0)
        assert f"{path}:{line}:" in str(err.value), name
