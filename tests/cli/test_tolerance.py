"""``wormgear tolerance`` and the ``min_yield`` requirement of ``check`` through the CLI."""

from __future__ import annotations

import csv
import io
import json

import pytest

from tests.support.paths import MCH50
from tests.support.tolerance import mch50_doc, write
from wormgear_cli.cli import app

PERCENTILE_KEYS = ["50", "90", "95", "99", "99.73", "max"]


def _run(runner, *args):
    return runner.invoke(app, ["tolerance", *map(str, args)])


def _tight(tmp_path, min_yield=None, te_limit=36.0):
    doc = mch50_doc()
    doc["requirements"]["max_transmission_error_arcsec"] = te_limit
    if min_yield is not None:
        doc["requirements"]["min_yield"] = min_yield
    return write(tmp_path, doc)


def test_json_contract(runner):
    r = _run(runner, MCH50, "-n", 2000, "--seed", 7, "--format", "json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["samples"] == 2000 and doc["seed"] == 7
    # the six metrics in its order, then the full budget's totals (more keys may be added)
    assert list(doc["metrics"]) == ["total_transmission_error", "total_backlash", "iso230_E", "iso230_B",
                                    "iso230_M", "iso230_A", "budget_linear", "budget_statistical", "budget_rss"]
    for v in doc["metrics"].values():
        assert list(v["percentiles"]) == PERCENTILE_KEYS
        p = [v["percentiles"][k] for k in PERCENTILE_KEYS]
        assert p == sorted(p)
        assert {"mean", "std", "corner", "rss"} <= set(v)
    assert set(doc["yield"]) == {"requirements.max_transmission_error_arcsec", "requirements.max_backlash_arcsec",
                                 "all"}
    for y in doc["yield"].values():
        assert y["low"] <= y["value"] <= y["high"]
    for idx in doc["sensitivity"].values():
        assert sum(idx.values()) == pytest.approx(1.0, abs=1e-9)  # indices + remainder
        assert idx["remainder"] >= 0


def test_metrics_paper_only(runner):
    doc = json.loads(_run(runner, MCH50, "-n", 500, "--metrics", "paper", "--format", "json").stdout)
    assert list(doc["metrics"]) == ["total_transmission_error", "total_backlash"]
    assert doc["plan"] is None


def test_same_seed_same_bytes_other_seed_other_bytes(runner):
    a = _run(runner, MCH50, "-n", 1000, "--format", "json").stdout
    b = _run(runner, MCH50, "-n", 1000, "--format", "json").stdout
    c = _run(runner, MCH50, "-n", 1000, "--format", "json", "--seed", 1).stdout
    assert a == b and a != c


def test_yield_equals_the_fraction_counted_from_the_csv(runner, tmp_path):
    drive = _tight(tmp_path)
    out = tmp_path / "s.csv"
    r = _run(runner, drive, "-n", 5000, "--metrics", "paper", "--format", "csv", "-o", out)
    assert r.exit_code == 0, r.output
    rows = list(csv.DictReader(io.StringIO(out.read_text())))
    assert [int(row["sample"]) for row in rows] == list(range(5000))
    passing = sum(float(row["total_transmission_error_arcsec"]) <= 36.0 for row in rows)
    doc = json.loads(_run(runner, drive, "-n", 5000, "--metrics", "paper", "--format", "json").stdout)
    y = doc["yield"]["requirements.max_transmission_error_arcsec"]
    assert 0 < passing < 5000  # the limit cuts through the distribution
    assert y["value"] == passing / 5000
    from scipy.stats import binomtest  # Clopper-Pearson oracle

    ci = binomtest(passing, 5000).proportion_ci(0.95, method="exact")
    assert (y["low"], y["high"]) == pytest.approx((ci.low, ci.high), rel=1e-12)


def test_csv_columns(runner):
    r = _run(runner, MCH50, "-n", 3, "--format", "csv", "--unit", "deg")
    header = r.stdout.splitlines()[0].split(",")
    assert header[0] == "sample"
    assert "assembly.wheel_eccentricity_mm" in header and "assembly.worm_pair_errors_mm[5]" in header
    assert "worm_pair.lead_error_phase_deg" in header
    assert header[-9:] == ["total_transmission_error_deg", "total_backlash_deg", "iso230_E_deg", "iso230_B_deg",
                           "iso230_M_deg", "iso230_A_deg", "budget_linear_deg", "budget_statistical_deg",
                           "budget_rss_deg"]
    assert len(r.stdout.splitlines()) == 4


def test_summarize_reads_the_samples_in_the_unit_they_were_written_in(runner, tmp_path):
    # samples written in deg, summarized with the default --unit arcsec: the same yields and, in
    # arcsec, the percentiles of the run made in arcsec (3600 arcsec per deg, to rounding)
    drive = _tight(tmp_path)
    in_deg = tmp_path / "deg.csv"
    assert _run(runner, drive, "-n", 3000, "--metrics", "paper", "--format", "csv", "--unit", "deg",
                "-o", in_deg).exit_code == 0
    summarized = json.loads(_run(runner, drive, "-n", 3000, "--metrics", "paper", "--summarize", in_deg,
                                 "--format", "json").stdout)
    direct = json.loads(_run(runner, drive, "-n", 3000, "--metrics", "paper", "--format", "json").stdout)
    assert summarized["yield"] == direct["yield"]
    te_s, te_d = (d["metrics"]["total_transmission_error"] for d in (summarized, direct))
    for q in ("50", "99"):
        assert te_s["percentiles"][q] == pytest.approx(te_d["percentiles"][q], rel=1e-9)
    assert te_s["mean"] == pytest.approx(te_d["mean"], rel=1e-9)
    assert 10.0 < te_d["percentiles"]["50"] < 100.0  # in arcsec, not deg


def test_summarize_still_reads_a_header_without_units_in_the_runs_unit(runner, tmp_path):
    drive = _tight(tmp_path)
    new = tmp_path / "new.csv"
    assert _run(runner, drive, "-n", 500, "--metrics", "paper", "--format", "csv", "-o", new).exit_code == 0
    old = tmp_path / "old.csv"
    lines = new.read_text().split("\n", 1)
    old.write_text(lines[0].replace("_arcsec", "") + "\n" + lines[1])
    a, b = (_run(runner, drive, "-n", 500, "--metrics", "paper", "--summarize", f, "--format", "json").stdout
            for f in (new, old))
    assert a == b


# 70 000 samples span two random-stream blocks (slow: run in CI)
@pytest.mark.parametrize("n,parts", [(1000, 3), pytest.param(70_000, 2, marks=pytest.mark.slow)])
def test_shards_concatenate_to_the_whole_run_and_summarize_reproduces_it(runner, tmp_path, n, parts):
    args = [MCH50, "-n", n, "--metrics", "paper" if n > 10_000 else "all", "--seed", 5]
    whole = tmp_path / "whole.csv"
    assert _run(runner, *args, "--format", "csv", "-o", whole).exit_code == 0
    text = []
    for k in range(1, parts + 1):
        part = tmp_path / f"part{k}.csv"
        r = _run(runner, *args, "--format", "csv", "--shard", f"{k}/{parts}", "-o", part)
        assert r.exit_code == 0, r.output
        lines = part.read_text().splitlines(keepends=True)
        text += lines if k == 1 else lines[1:]  # header once
    assert "".join(text) == whole.read_text()
    report = _run(runner, *args, "--format", "json").stdout
    summary = _run(runner, *args, "--format", "json", "--summarize", whole)
    assert summary.exit_code == 0, summary.output
    assert summary.stdout == report


def test_summarize_refuses_missing_or_repeated_parts(runner, tmp_path):
    whole = tmp_path / "whole.csv"
    _run(runner, MCH50, "-n", 100, "--metrics", "paper", "--format", "csv", "-o", whole)
    lines = whole.read_text().splitlines(keepends=True)
    bad = tmp_path / "bad.csv"
    bad.write_text("".join(lines[:50] + lines[51:]))
    r = _run(runner, MCH50, "-n", 100, "--metrics", "paper", "--summarize", bad)
    assert r.exit_code == 2
    assert r.stderr.strip() == (f"error: {bad}: line 51: sample 50, expected 49 (samples must be consecutive: a "
                                "shard missing, repeated or out of order?)")


@pytest.mark.parametrize("entry,message", [
    ({"assembly.wheel_eccentricty_mm": {"distribution": "uniform"}},
     'statistics."assembly.wheel_eccentricty_mm": unknown key, expected the TOML path of a toleranced key '
     '(did you mean "assembly.wheel_eccentricity_mm"?)'),
    ({"assembly.wheel_eccentricity_mm": {"distribution": "gauss"}},
     'statistics."assembly.wheel_eccentricity_mm".distribution: unknown distribution "gauss" '
     "(known: normal, rayleigh, uniform)"),
    ({"worm_pair.lead_error_mm": {"cpk": 0}},
     'statistics."worm_pair.lead_error_mm".cpk: expected a number > 0 (a process capability), got 0'),
    ({"worm_pair.lead_error_mm": {"cpk": -1.0}},
     'statistics."worm_pair.lead_error_mm".cpk: expected a number > 0 (a process capability), got -1.0'),
    ({"worm_pair.wheel.teeth": {"distribution": "uniform"}},
     'statistics."worm_pair.wheel.teeth": cannot be varied: the key has no tolerance (a nominal value such as '
     "teeth or module); toleranced keys: assembly.gear_eccentricity_mm, worm_pair.lead_error_mm, "
     "worm_pair.worm.profile_error_mm, ..."),
    ({"gear_pair.module_mm": {}},
     'statistics."gear_pair.module_mm": cannot be varied: the key has no tolerance (a nominal value such as '
     "teeth or module); toleranced keys: assembly.gear_eccentricity_mm, worm_pair.lead_error_mm, "
     "worm_pair.worm.profile_error_mm, ..."),
    ({"worm_pair.lead_error_mm": {"distribution": "rayleigh"}},
     'statistics."worm_pair.lead_error_mm".distribution: "rayleigh" does not fit a signed quantity '
     "(use normal or uniform)"),
])
def test_bad_statistics_table(runner, tmp_path, entry, message):
    doc = mch50_doc()
    doc["statistics"] = entry
    drive = write(tmp_path, doc)
    r = _run(runner, drive, "-n", 10)
    assert r.exit_code == 2
    assert r.stderr == f"error: {drive}: {message}\n"
    assert r.stdout == ""


@pytest.mark.parametrize("args,message", [
    (["-n", "0"], "error: --samples: expected an integer in [1, 10000000000], got 0\n"),
    (["--shard", "0/3"], 'error: --shard "0/3": expected K/N with 1 <= K <= N, e.g. 2/8, or auto in a job array\n'),
    (["--shard", "4/3"], 'error: --shard "4/3": expected K/N with 1 <= K <= N, e.g. 2/8, or auto in a job array\n'),
    (["--shard", "a/3"], 'error: --shard "a/3": expected K/N with whole numbers, e.g. 2/8, or auto in a job array\n'),
    (["-n", "2", "--shard", "1/3"], "error: --shard 1/3: expected 1 <= K <= N <= --samples (2)\n"),
    (["--target-yield", "1.5"], "error: --target-yield: expected a number in (0, 1), got 1.5\n"),
])
def test_bad_options(runner, args, message):
    r = _run(runner, MCH50, *args)
    assert r.exit_code == 2
    assert r.stderr == message


def test_allocation_ranks_the_key_that_buys_yield_first(runner, tmp_path):
    # TE limit 36": the gear eccentricity carries ~90 % of the TE variance, so tightening it gains most
    drive = _tight(tmp_path)
    doc = json.loads(_run(runner, drive, "-n", 20_000, "--metrics", "paper", "--target-yield", "0.99",
                          "--format", "json").stdout)
    steps = doc["allocation"]["steps"]
    assert steps[0]["key"] == "assembly.gear_eccentricity_mm"
    assert steps[0]["gain"] > 0 and steps[0]["yield"]["low"] >= 0.99
    # the least tightening that reaches the target, by bisection (issue 19; not a fixed 70 % step): the
    # kept fraction is a multiple of 2^-7, and a spec with that tolerance reaches 99 % while one with
    # 2^-7 of the tolerance more does not (each run by the command itself, the same samples and seed)
    kept = steps[0]["to_mm"] / 0.03
    assert kept * 128 == pytest.approx(round(kept * 128), abs=1e-9) and 0 < kept < 1
    assert steps[0]["step"] == f"{100 * kept:.0f} %"
    text = drive.read_text(encoding="utf-8")
    for fraction, reaches in ((kept, True), (kept + 1 / 128, False)):
        path = tmp_path / f"e{fraction:.4f}.toml"
        # the eccentricity defaults to the centre-distance error (0.03): written explicitly
        path.write_text(text.replace("gear_centre_distance_error_mm = 0.03\n", "gear_centre_distance_error_mm = 0.03\n"
                                     f"gear_eccentricity_mm = {0.03 * fraction!r}\n", 1))
        y = json.loads(_run(runner, path, "-n", 20_000, "--metrics", "paper", "--format", "json").stdout)["yield"]
        assert (y["all"]["low"] >= 0.99) is reaches
    reaching = [s for s in steps if s["yield"]["low"] >= 0.99]
    assert steps[:len(reaching)] == reaching
    kept_all = [s["to_mm"] / s["from_mm"] for s in reaching]
    assert kept_all == sorted(kept_all, reverse=True)
    gains = [s["gain"] for s in steps[len(reaching):]]
    assert gains == sorted(gains, reverse=True)


def test_check_min_yield_pass_fail_undecided(runner, tmp_path):
    from wormgear_cli.spec.loader import load_spec
    from wormgear_cli.tolerance.engine import check_yield

    est = check_yield(load_spec(_tight(tmp_path, 0.5))).estimate
    ok = runner.invoke(app, ["check", str(_tight(tmp_path, 0.5))])
    assert ok.exit_code == 0, ok.output
    assert "ok requirements.min_yield: target 50 %" in ok.stdout
    fail = runner.invoke(app, ["check", str(_tight(tmp_path, 0.999))])
    assert fail.exit_code == 1
    assert "FAIL requirements.min_yield: target 99.9 %" in fail.stdout
    mid = round((est.low + est.high) / 2, 6)
    undecided = runner.invoke(app, ["check", str(_tight(tmp_path, mid)), "--format", "json"])
    assert undecided.exit_code == 1
    y = json.loads(undecided.stdout)["files"][0]["yield"]
    assert y["verdict"] == "undecided" and y["low"] < mid < y["high"] and y["passed"] is False


def test_check_min_yield_without_limits_is_an_input_error(runner, tmp_path):
    doc = mch50_doc()
    doc["requirements"] = {"min_yield": 0.9}
    drive = write(tmp_path, doc)
    r = runner.invoke(app, ["check", str(drive)])
    assert r.exit_code == 2
    assert r.stderr == (f"error: {drive}: requirements.min_yield: needs a limit to count the yield against "
                        "(max_transmission_error_arcsec, max_backlash_arcsec, max_budget_linear_arcsec, "
                        "max_budget_statistical_arcsec, max_budget_rss_arcsec)\n")


def test_plot(runner, tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "t.png"
    r = _run(runner, MCH50, "-n", 500, "--plot", out, "--format", "json")
    assert r.exit_code == 0, r.output
    assert out.read_bytes()[:4] == b"\x89PNG"
    assert r.stderr == f"wrote {out}\n"  # every file written is announced, --plot too


def test_table_fits_80_columns(runner):
    r = runner.invoke(app, ["tolerance", str(MCH50), "-n", "500", "--target-yield", "0.99"], env={"COLUMNS": "80"})
    assert r.exit_code == 0, r.output
    assert max(len(line) for line in r.stdout.splitlines()) <= 80
    assert "worst case / RSS / Monte Carlo" in r.stdout


def test_one_sample(runner):
    r = _run(runner, MCH50, "-n", 1, "--format", "json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["samples"] == 1
    m = doc["metrics"]["total_transmission_error"]
    assert m["std"] is None and m["percentiles"]["50"] == m["percentiles"]["max"] == m["mean"]
    assert all(v is None for v in doc["sensitivity"].values())


def test_check_validates_statistics_without_min_yield(runner, tmp_path):
    doc = mch50_doc()
    doc["statistics"] = {"assembly.wheel_eccentricity_mm": {"distribution": "lognormal"}}
    drive = write(tmp_path, doc)
    r = runner.invoke(app, ["check", str(drive)])
    assert r.exit_code == 2
    assert r.stderr == (f'error: {drive}: statistics."assembly.wheel_eccentricity_mm".distribution: unknown '
                        'distribution "lognormal" (did you mean "normal"?)\n')


def test_csv_file_is_streamed_and_equals_stdout_over_several_blocks(runner, tmp_path, monkeypatch):
    # -o streams block by block through a staged file (no cap on the sample count): the file holds
    # exactly the bytes stdout gets, across block boundaries, and no staged file is left behind.
    # Blocks of 1000 samples (both runs alike) keep the test fast.
    from wormgear_cli.tolerance import engine, sampling

    monkeypatch.setattr(engine, "BLOCK", 1000)
    monkeypatch.setattr(sampling, "BLOCK", 1000)
    n = 2 * 1000 + 7
    out = tmp_path / "x.csv"
    to_file = _run(runner, MCH50, "-n", n, "--metrics", "budget", "--format", "csv", "-o", out)
    to_stdout = _run(runner, MCH50, "-n", n, "--metrics", "budget", "--format", "csv")
    assert to_file.exit_code == 0 and to_stdout.exit_code == 0
    assert to_file.stdout == "" and to_file.stderr.endswith(f"wrote {out}\n")
    text = out.read_text()
    assert text == to_stdout.stdout
    assert len(text.splitlines()) == n + 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.csv"]
