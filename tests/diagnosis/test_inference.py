"""The named effects in the final model: 95 % intervals (coverage), the range of sizes of a same-order
effect, the stability note, the likely further effect."""

from __future__ import annotations

import io
import re

import numpy as np
import pytest

from tests.support.diagnosis_data import HIDDEN, TB, WARM_SLOW, Plan, diagnose_doc, make_csv, make_measurement
from tests.support.paths import CONFIGS
from wormgear_cli.cli import app
from wormgear_cli.diagnosis import diagnose, report


@pytest.mark.slow  # 30-45 s: 30 and 40 seeded replicates
def test_the_95_percent_interval_covers_the_truth_at_its_nominal_rate(mch50_spec):

    _, plan, params, _ = HIDDEN["thermal_backlash"]
    inside, estimates, half = [], [], []
    for seed in range(30):
        meas, _ = make_measurement(mch50_spec, plan, hidden={"thermal_backlash": params}, seed=500 + seed)
        found = diagnose(mch50_spec, meas, resamples=0).found
        assert [f.name for f in found] == ["thermal_backlash"]
        lo, hi = found[0].intervals["centre_distance_um_per_K"]
        inside.append(lo <= -0.8 <= hi)
        estimates.append(found[0].params["coefficient"] * 1e3)
        half.append((hi - lo) / 2)
    assert sum(inside) >= 26, sum(inside)  # P(<= 25 of 30 | 95 %) ~ 1.6 %
    # and not by being needlessly wide: the half-width is about 1.96 times the scatter of the estimates
    assert np.mean(half) < 3.0 * np.std(estimates)


def test_same_order_excess_beyond_the_spec_sources_is_named_with_its_rivals(mch50_spec):
    # 40 um (49 arcsec) is more than the order-8 sources can produce together (about 42 arcsec)
    meas, _ = make_measurement(mch50_spec, Plan(), hidden={"intermediate_shaft_runout":
                                                           {"eccentricity_um": 40.0, "phase_deg": 30.0}}, seed=9)
    doc = report(diagnose(mch50_spec, meas, resamples=30))
    found = {e["name"]: e for e in doc["effects_found"]}
    assert "intermediate_shaft_runout" in found
    rivals = found["intermediate_shaft_runout"]["indistinguishable_from"]
    assert {"gear_eccentricity", "wheel_radial_composite", "wheel_eccentricity"} <= set(rivals)


@pytest.fixture(scope="module")
def same_order():
    from wormgear_cli.spec.loader import load_spec

    spec = load_spec(CONFIGS / "mch50.toml")
    text, _ = make_csv(spec, Plan(), seed=1, hidden={"intermediate_shaft_runout":
                                                     {"eccentricity_um": 6.0, "phase_deg": 30.0}})
    return diagnose_doc(spec, text)


def test_a_same_order_effect_gets_the_range_of_sizes_that_fit_not_a_confident_value(same_order):
    doc = same_order
    found = {e["name"]: e for e in doc["effects_found"]}["intermediate_shaft_runout"]
    assert found["separable"] is False
    lo, hi = found["interval_95"]["eccentricity_um"]
    assert lo <= 6.0 <= hi and hi > 2 * lo  # the truth is inside a range that admits very different sizes
    assert "phase_deg" not in found["interval_95"] and found["fixed_parameters"] == []
    assert {"gear_eccentricity", "wheel_eccentricity"} <= set(found["indistinguishable_from"])
    assert "indistinguishable" in doc["verdict"] and "--keep-phases" in doc["verdict"]


def test_the_table_says_fixed_only_for_parameters_held_fixed(same_order):
    from rich.console import Console

    from wormgear_cli.cli.common import _rich_table
    from wormgear_cli.cli.diagnose import _tables
    from wormgear_cli.output.tables import Table

    console = Console(record=True, width=200, file=io.StringIO())
    for part in _tables(same_order, "arcsec"):
        console.print(_rich_table(part) if isinstance(part, Table) else part)
    text = console.export_text()
    row = re.compile(r"│\s+(eccentricity_um|phase_deg)\s+│[^│]*│([^│]*)│")
    rows = {m.group(1): m.group(2) for m in row.finditer(text)}
    assert set(rows) == {"eccentricity_um", "phase_deg"}
    assert "fixed" not in rows["eccentricity_um"] and "not determined" in rows["phase_deg"]
    flat = " ".join(text.split())
    assert "refits the phases" in flat and "fewer than 3 runs" not in flat


def test_stability_note_gives_the_real_reason(runner, mch50_path):
    result = runner.invoke(app, ["diagnose", str(mch50_path), str(CONFIGS / "mch50-warm.csv"), "--resamples", "0"])
    assert result.exit_code == 0, result.stderr
    flat = " ".join(result.stdout.split())
    assert "stability not assessed (--resamples 0)" in flat
    assert "fewer than 3 runs" not in flat
    # and the demo's reference temperature is still shown as held fixed
    assert re.search(r"reference_temperature_C\s+│\s+20\s+│\s+fixed", result.stdout)


def test_with_two_effects_the_named_interval_covers_the_truth_or_the_second_is_reported(mch50_spec):
    hidden = {**TB, "bearing_clearance": {"clearance_arcsec": 5.0}}
    for seed in (3, 7):
        text, _ = make_csv(mch50_spec, Plan(runs=5, warmup=WARM_SLOW), hidden=hidden, seed=seed)
        doc = diagnose_doc(mch50_spec, text)
        found = {e["name"]: e for e in doc["effects_found"]}
        lo, hi = found["bearing_clearance"]["interval_95"]["clearance_arcsec"]
        assert lo <= 5.0 <= hi, (seed, lo, hi)
        if "thermal_backlash" not in found:
            likely = [u for u in doc["unexplained"] if u["kind"] == "likely_effect"]
            assert likely and likely[0]["name"] == "thermal_backlash" and likely[0]["mode"] == "differential"
            assert likely[0]["rms_with_arcsec"] < likely[0]["rms_arcsec"]
            assert "likely" in doc["verdict"] and "thermal_backlash" in doc["verdict"]


def test_the_same_order_range_is_the_profile_region_derived_by_hand(mch50_spec):
    """The range of sizes of a same-order effect against a derivation written here (issue 26).

    White noise, an offset, one spec source of fixed size A = 2 arcsec and free phase on order 8, and the
    effect on order 8 (intermediate shaft runout, a pure first harmonic of ``u`` arcsec per um): together
    they make an order-8 phasor of any size m between |A - a u| and A + a u.  With the targets evenly
    spaced over a turn, sin 8t and cos 8t are orthogonal to each other and to the offset with the same
    squared norm Q, so the least cost at size m is RSS + Q (R - m)^2 (R, RSS: the plain least-squares fit
    of offset + sin + cos, here statsmodels OLS).  The 95 % profile region {c <= c_min (1 + F / dof)},
    F = F(0.95; 1, dof) = t(0.975, dof)^2 (scipy.stats.f, not the package's t), dof = n - 4 (offset, the
    effect's two columns, the source's phase) is then |R - m| <= delta = sqrt(F RSS / (dof Q)) (the t
    interval of the size), and the effect's sizes are [(R - A - delta) / u, (R + A + delta) / u]."""
    import math

    import statsmodels.regression.linear_model as sm  # OLS (not all of statsmodels.api)
    from scipy import stats

    from wormgear_cli import diagnosis as dg
    from wormgear_cli.analysis.accuracy import geometry
    from wormgear_cli.diagnosis.inference import Found, same_order_range
    from wormgear_cli.diagnosis.phases import PhaseSource, effect_contrib
    from wormgear_cli.physics.effects import EFFECTS, Signals

    g = geometry(mch50_spec)
    n, a_src = 96, 2.0
    theta = np.arange(n) * 2.0 * np.pi / n
    d = np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    sig = Signals.make(theta, d)
    name = "intermediate_shaft_runout"
    cand = dg.candidate(name, sig, g)
    assert cand is not None and cand.order == 8.0
    s, c = np.sin(8.0 * theta), np.cos(8.0 * theta)
    eff = EFFECTS[name]
    one_um = effect_contrib(eff, {**cand.fixed, eff.amplitude: 1e-3}, g)(sig, 0.0)  # 1 um (internal mm)
    harmonic = np.linalg.lstsq(np.column_stack([np.ones(n), s, c]), one_um, rcond=None)[0]
    u = math.hypot(harmonic[1], harmonic[2])  # arcsec per um
    y = 3.0 + 12.0 * np.sin(8.0 * theta + 0.7) + np.random.default_rng(5).normal(0.0, 15.0, n)

    source = PhaseSource("spec_source", "", 8.0, a_src, 0.0, lambda sg, psi: a_src * np.sin(8.0 * sg.theta + psi))
    ctx = dg.FitContext(y, sig, dg.make_groups(d, np.arange(n)), np.zeros(n), (source,), (0.0,))
    lin = np.column_stack([np.ones(n), cand.columns])
    state = dg.fit_model(ctx, lin)
    found = Found(name, cand.kind, dg.candidate_params(cand, state.beta[1:3]), {}, 0.0, 0.0, 0.0, 0.0, None, 1)
    same_order_range(found, ctx, state, lin, slice(1, 3), cand, g, steps=14)  # bisected to 2^-14 of the span
    lo, hi = found.intervals["eccentricity_um"]

    ols = sm.OLS(y, np.column_stack([np.ones(n), s, c])).fit()
    r = math.hypot(ols.params[1], ols.params[2])
    q = float(np.sum((s - s.mean()) ** 2))
    assert float(c @ s) == pytest.approx(0.0, abs=1e-9) and float(c @ c) == pytest.approx(q, rel=1e-12)
    dof = n - 4
    delta = math.sqrt(stats.f.ppf(0.95, 1, dof) * ols.ssr / (dof * q))
    assert r - a_src - delta > 0.0  # (so the lower end is not 0)
    assert lo == pytest.approx((r - a_src - delta) / u, rel=1e-3)
    assert hi == pytest.approx((r + a_src + delta) / u, rel=1e-3)
