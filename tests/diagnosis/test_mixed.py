"""The mixed model under diagnose: GLS/REML with run and pass effects, Wald tests, degrees of
freedom, the cell-means test and the F and t functions.  Checked against scipy, a dense inverse,
brute force and statsmodels' MixedLM."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import optimize, stats

from wormgear_cli import diagnosis as dg


@settings(max_examples=60, deadline=None)
@given(f=st.floats(0.0, 200.0), d1=st.integers(1, 6), d2=st.floats(1.0, 1e5))
def test_f_upper_tail_matches_scipy(f, d1, d2):
    assert dg.f_sf(f, d1, d2) == pytest.approx(stats.f.sf(f, d1, d2), rel=1e-8, abs=1e-14)


def test_f_upper_tail_at_the_ends():
    # P(F > 0) = 1, P(F > inf) = 0; F(1, d2) = t(d2)^2, so P(F > t_0.975^2) = 0.05 (two-sided t)
    assert dg.f_sf(0.0, 2, 10) == 1.0 and dg.f_sf(-1.0, 2, 10) == 1.0
    assert dg.f_sf(float("inf"), 2, 10) == 0.0
    assert dg.f_sf(dg.t_ppf(0.975, 12.0) ** 2, 1, 12.0) == pytest.approx(0.05, rel=1e-10)


@pytest.mark.parametrize("df", [1.0, 2.5, 4.0, 9.3, 30.0, 399.0, 401.0, 5000.0, 1e6])
def test_t_quantile_matches_scipy(df):
    assert dg.t_ppf(0.975, df) == pytest.approx(stats.t.ppf(0.975, df), rel=1e-7)


def _nested(seed=0, runs=6, per_pass=15, k=3):
    rng = np.random.default_rng(seed)
    run = np.repeat(np.arange(runs), 2 * per_pass)
    d = np.tile(np.repeat([1.0, -1.0], per_pass), runs)
    n = run.shape[0]
    x = np.column_stack([np.ones(n), d, rng.normal(size=(n, k - 2))])
    groups = dg.make_groups(d, run)
    y = x @ rng.normal(size=k) + rng.normal(0, 1.0, runs)[run] + rng.normal(0, 0.5, groups.passes)[
        groups.pass_id] + rng.normal(0, 0.4, n)
    return x, y, groups, run


def _dense_v(groups, run, gp, gr):
    zp = np.eye(groups.passes)[groups.pass_id]
    zr = np.eye(groups.runs)[run]
    return np.eye(run.shape[0]) + gp * zp @ zp.T + gr * zr @ zr.T


@settings(max_examples=15, deadline=None)
@given(gp=st.floats(0.0, 50.0), gr=st.floats(0.0, 50.0), seed=st.integers(0, 100))
def test_gls_from_sufficient_statistics_equals_the_dense_inverse(gp, gr, seed):
    x, y, groups, run = _nested(seed)
    vinv = np.linalg.inv(_dense_v(groups, run, gp, gr))
    A, b, c, ld = dg.Cross.build(x, y, groups).weighted([gp], [gr])
    assert np.allclose(A[0], x.T @ vinv @ x, rtol=1e-9, atol=1e-9)
    assert np.allclose(b[0], x.T @ vinv @ y, rtol=1e-9, atol=1e-9)
    assert c[0] == pytest.approx(y @ vinv @ y, rel=1e-9)
    assert ld[0] == pytest.approx(np.linalg.slogdet(_dense_v(groups, run, gp, gr))[1], rel=1e-9, abs=1e-9)


def test_reml_matches_a_brute_force_optimum():
    x, y, groups, run = _nested(3)
    zp = np.eye(groups.passes)[groups.pass_id]
    zr = np.eye(groups.runs)[run]

    zzp, zzr, eye = zp @ zp.T, zr @ zr.T, np.eye(y.shape[0])

    def neg2l(t):  # the REML criterion written densely (no structure used)
        s2, sp, sr = np.exp(t)
        v = s2 * eye + sp * zzp + sr * zzr
        vi = np.linalg.inv(v)
        a = x.T @ vi @ x
        beta = np.linalg.solve(a, x.T @ vi @ y)
        r = y - x @ beta
        return np.linalg.slogdet(v)[1] + np.linalg.slogdet(a)[1] + r @ vi @ r

    # a quasi-Newton search (two starts agree to 1e-6 relative; the tolerances below are far wider)
    best = optimize.minimize(neg2l, np.log([0.2, 0.3, 1.0]), method="L-BFGS-B", options={"ftol": 1e-13, "gtol": 1e-9})
    s2, sp, sr = np.sqrt(np.exp(best.x))
    vf = dg.reml(dg.Cross.build(x, y, groups))
    assert vf.s_white == pytest.approx(s2, rel=2e-3)
    assert vf.s_pass == pytest.approx(sp, rel=2e-2)
    assert vf.s_run == pytest.approx(sr, rel=2e-2)


def test_satterthwaite_df_follow_the_level_a_column_varies_at():
    # balanced one-level design: G groups of m rows; a group-level covariate has G - 2 df,
    # a covariate varying only within groups about N - G - 1
    rng = np.random.default_rng(7)
    g_count, m = 12, 20
    grp = np.repeat(np.arange(g_count), m)
    groups = dg.make_groups(np.ones(grp.shape[0]), grp)
    between = rng.normal(size=g_count)[grp]
    within = rng.normal(size=grp.shape[0])
    within -= (np.bincount(grp, within) / m)[grp]
    x = np.column_stack([np.ones(grp.shape[0]), between, within])
    y = 0.3 * between + rng.normal(0, 1.0, g_count)[grp] + rng.normal(0, 1.0, grp.shape[0])
    cross = dg.Cross.build(x, y, groups)
    vf = dg.reml(cross)
    assert vf.gp > 0
    assert dg.wald(cross, vf, [1]).df == pytest.approx(g_count - 2, abs=0.3)
    assert dg.wald(cross, vf, [2]).df == pytest.approx(grp.shape[0] - g_count - 1, rel=0.05)
    # containment df agree and cap
    assert dg.containment_df(groups, x[:, :1], x[:, 1:2]) == g_count - 2
    assert dg.containment_df(groups, x[:, :2], x[:, 2:3]) == grp.shape[0] - 3


def test_wald_p_values_are_uniform_under_the_null():
    # a between-run covariate with run-to-run noise: the Satterthwaite test keeps its level
    rejections = 0
    trials = 200
    rng = np.random.default_rng(11)
    runs, per = 6, 30
    run = np.repeat(np.arange(runs), per)
    groups = dg.make_groups(np.ones(run.shape[0]), run)
    cov = np.linspace(-1, 1, runs)[run]
    x = np.column_stack([np.ones(run.shape[0]), cov])
    for _ in range(trials):
        y = rng.normal(0, 1.0, runs)[run] + rng.normal(0, 1.0, run.shape[0])
        cross = dg.Cross.build(x, y, groups)
        rejections += dg.wald(cross, dg.reml(cross), [1], containment=dg.containment_df(groups, x[:, :1],
                                                                                        x[:, 1:])).p < 0.05
    # ordinary least squares would reject about 60 % here; the nominal 5 % allows 0..20 of 200
    assert rejections <= 20


def test_lack_of_fit_counts_as_error_in_the_cell_means_test():
    # a pattern repeated in every run at 12 targets, tested against an unrelated column
    rng = np.random.default_rng(2)
    targets = np.radians(np.sort(rng.uniform(0, 360, 12)))
    theta = np.tile(targets, 10)
    d = np.ones(theta.shape[0])
    cells = dg.make_cells(theta, d)
    pattern = 3.0 * np.sin(3 * theta)
    resid = pattern + rng.normal(0, 0.1, theta.shape[0])
    basis = np.ones((theta.shape[0], 1))
    other = np.column_stack([np.cos(40 * theta), np.sin(40 * theta)])
    F, df, p = dg.CellTester(cells, basis, resid).test(other)
    assert df == 12 - 1 - 2 and p > 0.01
    F3, _, p3 = dg.CellTester(cells, basis, resid).test(np.column_stack([np.cos(3 * theta), np.sin(3 * theta)]))
    assert p3 < 1e-6


@pytest.mark.parametrize("seed", [1, 2, 5])
def test_closed_form_reml_agrees_with_statsmodels_mixedlm(seed):
    """Nested random intercepts (passes within runs) on small data: the closed-form REML of
    :class:`~wormgear_cli.diagnosis.Cross` against statsmodels' MixedLM (REML, the run as group,
    the pass as a variance component).  Tolerances: fixed effects 1e-3 of their standard error
    (both are GLS at nearly the same variance ratios); variance components rel 3 % (our optimum is
    a shrinking log-grid of the variance ratios, statsmodels' a gradient method)."""
    pd = pytest.importorskip("pandas")
    smf = pytest.importorskip("statsmodels.formula.api")
    x, y, groups, run = _nested(seed, runs=8, per_pass=12)
    vf = dg.reml(dg.Cross.build(x, y, groups))
    df = pd.DataFrame({"y": y, "x1": x[:, 1], "x2": x[:, 2], "run": run, "pass_": groups.pass_id})
    model = smf.mixedlm("y ~ x1 + x2", df, groups="run", re_formula="1", vc_formula={"pass_": "0 + C(pass_)"})
    with np.errstate(all="ignore"):
        fit = model.fit(reml=True, method=["lbfgs", "powell"])
    se = np.sqrt(np.diag(vf.cov))
    assert np.all(np.abs(vf.beta - fit.fe_params.to_numpy()) <= 1e-3 * se + 1e-9)
    assert vf.sigma2 == pytest.approx(fit.scale, rel=0.03)
    assert vf.sigma2 * vf.gr == pytest.approx(float(fit.cov_re.iloc[0, 0]), rel=0.03)
    assert vf.sigma2 * vf.gp == pytest.approx(float(fit.vcomp[0]), rel=0.03)
