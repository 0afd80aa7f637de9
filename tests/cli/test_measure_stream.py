"""``measure --format json`` and ``--format csv`` write the per-target part a block of targets at a time
(a dense scan has a target a row): the bytes do not depend on the block size, and the streamed list
is the document's own per-target list (workflows.measure.report)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from wormgear_cli.cli import app
from wormgear_cli.workflows import measure as wf

DATA = Path(__file__).resolve().parent.parent / "data" / "field"


def _dense(tmp_path) -> Path:
    """A forward and a reverse scan at distinct angles, some cells one direction only (NaN figures)."""
    rng = np.random.default_rng(3)
    ang = np.concatenate([np.linspace(0, 350, 37), np.linspace(355, 5, 36)])
    d = np.repeat([1, -1], [37, 36])
    err = 2 * np.sin(np.radians(ang)) + 0.5 * d + rng.normal(0, 0.2, ang.size)
    path = tmp_path / "dense.csv"
    path.write_text("angle_deg,error_arcsec,direction\n" + "".join(f"{a:.4f},{e:.3f},{x}\n" for a, e, x in
                                                                    zip(ang, err, d)))
    return path


def _run(runner, monkeypatch, block, *args):
    monkeypatch.setattr(wf, "TARGET_BLOCK", block)
    res = runner.invoke(app, ["measure", *map(str, args)])
    assert res.exit_code == 0, res.stderr
    return res.stdout


@pytest.mark.parametrize("case", ["dense", "servo-quantised-backlash.csv", "one-position-backlash.csv"])
def test_json_and_csv_bytes_whatever_the_block(runner, monkeypatch, tmp_path, case):
    path = _dense(tmp_path) if case == "dense" else DATA / case
    for fmt in ("json", "csv"):
        whole = _run(runner, monkeypatch, 10**9, path, "-f", fmt, "--unit", "urad")
        for block in (1, 2, 5, 36):
            assert _run(runner, monkeypatch, block, path, "-f", fmt, "--unit", "urad") == whole, (fmt, block)
    out = tmp_path / "out.json"
    monkeypatch.setattr(wf, "TARGET_BLOCK", 3)
    assert runner.invoke(app, ["measure", str(path), "-f", "json", "--unit", "urad", "-o", str(out)]).exit_code == 0
    assert out.read_text() == _run(runner, monkeypatch, 10**9, path, "-f", "json", "--unit", "urad")


def test_streamed_list_is_the_documents(runner, monkeypatch, tmp_path):
    """The streamed per-target list, parsed, is ``report``'s (undefined values null), target by target;
    the rest of the document is the one without the list."""
    path = _dense(tmp_path)
    doc = json.loads(_run(runner, monkeypatch, 4, path, "-f", "json", "--unit", "urad"))
    result = wf.measure(path)
    want = wf.report(result, "urad")
    rows = [{k: None if isinstance(v, float) and math.isnan(v) else v for k, v in r.items()}
            for r in want["per_target"]]
    assert len(rows) == len(doc["per_target"]) > 60
    assert doc["per_target"] == rows
    assert any(r["R"] is None for r in rows)  # the one-direction cells: nulls inside the streamed blocks
    assert {k for k in want if k != "per_target"} < doc.keys()  # (and the schema version)
    assert list(doc)[-1] == "per_target"  # after the notes, as the document was always written
    assert doc["targets"] == want["targets"] == len(rows)


def test_no_targets_keeps_an_empty_list():
    """No block at all: the document's empty list, as written without streaming."""
    from wormgear_cli.cli.measure import json_chunks

    doc = {"a": 1, "per_target": [], "b": [1, 2]}
    empty = json.loads("".join(json_chunks(doc, iter([]))))
    assert {k: empty[k] for k in doc} == doc
    got = json.loads("".join(json_chunks(doc, [[], [{"x": 1.0}], [], [{"x": math.nan}]])))
    assert got == {**empty, "per_target": [{"x": 1.0}, {"x": None}]}
