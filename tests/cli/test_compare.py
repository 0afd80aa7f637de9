"""wormgear compare: each drive's figures are analyze's and tolerance's, side by side, and the
differences are to the first drive."""

from __future__ import annotations

import csv
import io
import json

import pytest

from tests.support.paths import CONFIGS, MCH50, ROOT
from wormgear_cli.cli import app

RT = CONFIGS / "rotary-table-precision.toml"
RADAR = CONFIGS / "radar-pedestal-2start.toml"


def _json(runner, *args) -> dict:
    r = runner.invoke(app, [str(a) for a in args])
    assert r.exit_code == 0, r.stderr
    return json.loads(r.stdout)


@pytest.fixture(scope="module")
def three():
    from typer.testing import CliRunner

    runner = CliRunner()
    return runner, _json(runner, "compare", MCH50, RT, RADAR, "-f", "json")


def test_the_totals_and_budget_lines_are_analyzes(three):
    runner, doc = three
    assert [d["file"] for d in doc["drives"]] == [str(MCH50), str(RT), str(RADAR)]
    for k, path in enumerate((MCH50, RT, RADAR)):
        a = _json(runner, "analyze", path, "-f", "json")
        assert doc["drives"][k]["drive"] == a["drive"]
        t = doc["totals"]
        assert t["total_transmission_error"]["values"][k] == a["total"]["transmission_error"]
        assert t["total_backlash"]["values"][k] == a["total"]["backlash"]
        for key, name in (("budget_linear", "linear"), ("budget_statistical", "statistical"), ("budget_peak", "peak")):
            assert t[key]["values"][k] == a["total_with_budget"][f"transmission_error_amplitude_{name}"]
        for line in a["budget"]:
            assert doc["budget"][line["source"]]["values"][k] == line["amplitude"]


def test_differences_are_to_the_first_drive(three):
    runner, doc = three
    first = _json(runner, "analyze", MCH50, "-f", "json")["total"]["transmission_error"]
    q = doc["totals"]["total_transmission_error"]
    assert q["differences"][0] == 0.0
    for v, d in zip(q["values"], q["differences"]):
        assert d == pytest.approx(v - first, abs=1e-12)


def test_the_table_shows_every_drive_and_the_difference_columns(runner, monkeypatch):
    monkeypatch.chdir(ROOT)
    args = ["compare", "configs/mch50.toml", "configs/rotary-table-precision.toml", "configs/radar-pedestal-2start.toml"]
    r = runner.invoke(app, args, env={"COLUMNS": "80"})
    assert r.exit_code == 0
    out = r.stdout
    assert out.startswith("A = configs/mch50.toml (MCH50 rotary table)\n"
                          "B = configs/rotary-table-precision.toml (precision rotary table)\n")
    head = next(ln for ln in out.splitlines() if ln.split()[:1] == ["quantity"])
    assert head.split() == ["quantity", "A", "B", "C", "B", "-", "A", "C", "-", "A"]
    row = next(ln for ln in out.splitlines() if ln.strip().startswith("total TE (paper)"))
    assert row.split()[3:] == ["53.56", "9.29", "9.93", "-44.27", "-43.63"]  # analyze's (the test above)
    assert max(len(ln) for ln in out.splitlines()) <= 80


def test_the_yield_is_tolerances_with_the_same_samples_and_seed(runner):
    doc = _json(runner, "compare", MCH50, RT, "--samples", "3e3", "--seed", "4", "-f", "json")
    y = doc["yield"]
    assert (y["samples"], y["seed"]) == (3000, 4)
    for k, (path, metrics) in enumerate(((MCH50, "paper"), (RT, "paper+budget"))):
        t = _json(runner, "tolerance", path, "--samples", "3000", "--seed", "4", "--metrics", metrics, "-f", "json")
        for key, tol in t["yield"].items():
            row = y["requirements"][key]
            assert (row["values"][k], row["low"][k], row["high"][k]) == (tol["value"], tol["low"], tol["high"])
    # MCH50 has no budget limits: no yield there, and no difference
    row = y["requirements"]["requirements.max_budget_statistical_arcsec"]
    assert row["values"][0] is None and row["differences"] == [None, None]


def test_no_yield_without_samples_and_a_unit_converts(runner):
    arcsec = _json(runner, "compare", MCH50, RT, "-f", "json")
    deg = _json(runner, "compare", MCH50, RT, "-f", "json", "--unit", "deg")
    assert arcsec["yield"] is None
    for key, q in arcsec["totals"].items():
        assert deg["totals"][key]["values"] == pytest.approx([v / 3600 for v in q["values"]], rel=1e-12)


def test_csv_is_long_one_row_per_quantity_and_drive(runner, tmp_path):
    out = tmp_path / "c.csv"
    r = runner.invoke(app, ["compare", str(MCH50), str(RT), "--samples", "1000", "-o", str(out)])
    assert r.exit_code == 0 and r.stderr == f"wrote {out}\n"
    rows = list(csv.DictReader(io.StringIO(out.read_text())))
    doc = _json(runner, "compare", MCH50, RT, "--samples", "1000", "-f", "json")
    n_quantities = len(doc["totals"]) + len(doc["budget"]) + len(doc["yield"]["requirements"])
    assert len(rows) == 2 * n_quantities
    te = [r for r in rows if r["quantity"] == "total_transmission_error"]
    assert [float(r["value"]) for r in te] == doc["totals"]["total_transmission_error"]["values"]
    assert {r["unit"] for r in rows if r["section"] == "yield"} == {"fraction"}


@pytest.mark.parametrize("args", [[str(MCH50)], []])
def test_one_drive_is_not_a_comparison(runner, args):
    r = runner.invoke(app, ["compare", *args])
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr.startswith("error: ")


def test_the_same_input_gives_the_same_bytes(runner):
    args = ["compare", str(MCH50), str(RT), "--samples", "500"]
    assert runner.invoke(app, args).stdout_bytes == runner.invoke(app, args).stdout_bytes


def test_the_api_gives_the_clis_document(runner):
    import wormgear_cli as wg

    c = wg.compare([MCH50, RT], samples=500, seed=2)
    doc = _json(runner, "compare", MCH50, RT, "--samples", "500", "--seed", "2", "-f", "json", "--unit", "arcmin")
    assert c.to_dict("arcmin") == doc
    assert c.totals["total_backlash"][1].arcmin == pytest.approx(doc["totals"]["total_backlash"]["values"][1])
    assert c.yields == doc["yield"]["requirements"]
