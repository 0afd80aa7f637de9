"""GLS, REML and the Wald/Satterthwaite machinery of the diagnosis, against independent paths:

* the restricted likelihood of the error contrasts K'y (K an orthonormal basis of the null space
  of X'), evaluated with ``scipy.stats.multivariate_normal`` and a dense covariance matrix;
* a design whose REML optimum is worked by hand (two residual contrasts, one between passes and
  one within a pass: 1 + m g_p = e1^2 / e2^2);
* duplicated runs written out row by row (the counts of a cluster-bootstrap resample);
* ordinary least squares (``numpy.linalg.lstsq``) where the noise is taken as white;
* the balanced one-level analysis of variance (between and within groups).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import linalg, stats

from wormgear_cli.diagnosis import Cross, make_groups, reml, wald
from wormgear_cli.diagnosis.mixed import _full_neg2_reml, fit_at, variance_info


def _nested(seed, runs=5, m=4, k_rand=1):
    rng = np.random.default_rng(seed)
    run = np.repeat(np.arange(runs), 2 * m)
    d = np.tile(np.repeat([1.0, -1.0], m), runs)
    n = run.shape[0]
    X = np.column_stack([np.ones(n), d, rng.normal(size=(n, k_rand))])
    groups = make_groups(d, run)
    y = (X @ rng.normal(size=X.shape[1]) + rng.normal(0, 1.0, runs)[run]
         + rng.normal(0, 0.7, groups.passes)[groups.pass_id] + rng.normal(0, 0.5, n))
    return X, y, groups, run


def _dense_v(groups, run, gp, gr):
    zp = np.eye(groups.passes)[groups.pass_id]
    zr = np.eye(int(run.max()) + 1)[run]
    return np.eye(run.shape[0]) + gp * zp @ zp.T + gr * zr @ zr.T


def _neg2_restricted(X, y, v):
    """-2 log-likelihood of the error contrasts K'y ~ N(0, K' V K) (scipy), plus log|X'X|: the
    restricted likelihood of Harville (1977) with only the constant (n - k) log(2 pi) left in."""
    K = linalg.null_space(X.T)
    ll = stats.multivariate_normal(np.zeros(K.shape[1]), K.T @ v @ K).logpdf(K.T @ y)
    return -2.0 * ll + np.linalg.slogdet(X.T @ X)[1]


# --- GLS sufficient statistics -------------------------------------------------------------------


def test_weighted_against_the_dense_inverse_batched():
    """A, b, c and log det V~ for three (g_p, g_r) at once, against the dense inverse; g_r = 0.5 and
    g_p = 0.3 (below 1) are included."""
    X, y, groups, run = _nested(2)
    gp, gr = np.array([0.3, 2.0, 0.0]), np.array([0.5, 0.0, 4.0])
    A, b, c, ld = Cross.build(X, y, groups).weighted(gp, gr)
    for i in range(3):
        v = _dense_v(groups, run, gp[i], gr[i])
        vi = np.linalg.inv(v)
        np.testing.assert_allclose(A[i], X.T @ vi @ X, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(b[i], X.T @ vi @ y, rtol=1e-9, atol=1e-9)
        assert c[i] == pytest.approx(y @ vi @ y, rel=1e-9)
        assert ld[i] == pytest.approx(np.linalg.slogdet(v)[1], rel=1e-9, abs=1e-9)


def test_counts_of_a_resample_equal_the_duplicated_runs_written_out():
    """A resample that draws run 0 three times, run 2 twice, run 4 never: Cross with pass and run
    counts equals the dense GLS of the data with those runs copied row by row (each copy a run
    of its own)."""
    X, y, groups, run = _nested(5)
    count = np.array([3, 1, 2, 1, 0])
    rows = np.concatenate([np.flatnonzero(run == r) for r in range(5) for _ in range(count[r])])
    new_run = np.concatenate([np.full(int(np.sum(run == r)), j) for j, r in
                              enumerate([r for r in range(5) for _ in range(count[r])])])
    Xe, ye = X[rows], y[rows]
    ge = make_groups(Xe[:, 1], new_run)
    cross = Cross(Xe.T @ Xe, Xe.T @ ye, float(ye @ ye), Cross.build(X, y, groups).s_x,
                  Cross.build(X, y, groups).s_y, groups, pass_count=count[groups.pass_run].astype(float),
                  run_count=count.astype(float))
    assert cross.n == ye.shape[0]
    A, b, c, ld = cross.weighted([0.7, 1.5], [2.0, 0.4])
    for i, (gp, gr) in enumerate([(0.7, 2.0), (1.5, 0.4)]):
        v = _dense_v(ge, new_run, gp, gr)
        vi = np.linalg.inv(v)
        np.testing.assert_allclose(A[i], Xe.T @ vi @ Xe, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(b[i], Xe.T @ vi @ ye, rtol=1e-9, atol=1e-9)
        assert c[i] == pytest.approx(ye @ vi @ ye, rel=1e-9)
        assert ld[i] == pytest.approx(np.linalg.slogdet(v)[1], rel=1e-9)


# --- the restricted likelihood ---------------------------------------------------------------------


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_full_restricted_likelihood_against_scipy(seed):
    """-2 l_R at natural parameters (s^2, s_p^2, s_r^2) = log|V| + log|X'V^-1X| + r'V^-1r, i.e. the
    scipy value of the contrasts' likelihood less (n - k) log 2 pi; cov(beta) = (X'V^-1X)^-1."""
    X, y, groups, run = _nested(seed)
    cross = Cross.build(X, y, groups)
    n, k = X.shape
    zp = np.eye(groups.passes)[groups.pass_id]
    zr = np.eye(5)[run]
    for theta in [(1.0, 0.5, 0.3), (0.4, 0.0, 1.2), (2.0, 3.0, 0.0), (1.0, 0.0, 0.0), (0.6, 0.0, 0.5)]:
        v = theta[0] * np.eye(n) + theta[1] * zp @ zp.T + theta[2] * zr @ zr.T
        val, cov = _full_neg2_reml(cross, theta)
        assert val == pytest.approx(_neg2_restricted(X, y, v) - (n - k) * math.log(2 * math.pi), rel=1e-9)
        np.testing.assert_allclose(cov, np.linalg.inv(X.T @ np.linalg.inv(v) @ X), rtol=1e-8)


def test_full_restricted_likelihood_outside_the_parameter_space():
    """s^2 <= 0 or a negative component: +inf and no covariance."""
    X, y, groups, _ = _nested(1)
    cross = Cross.build(X, y, groups)
    for theta in [(0.0, 1.0, 1.0), (-1.0, 0.0, 0.0), (1.0, -1e-3, 0.0), (1.0, 0.0, -1e-3), (1.0, -1.0, -1.0)]:
        assert _full_neg2_reml(cross, theta) == (math.inf, None)


@pytest.mark.parametrize("seed", [1, 4, 6])
def test_reml_criterion_and_white_variance_against_scipy(seed):
    """At the REML ratios: s^2 = (K'y)'(K'V~K)^-1 (K'y) / (n - k) (the profiled maximum), and the
    stored criterion -2 l_R(s^2) - (n - k) (1 + log 2 pi) (constants dropped)."""
    X, y, groups, run = _nested(seed)
    vf = reml(Cross.build(X, y, groups))
    n, k = X.shape
    vt = _dense_v(groups, run, vf.gp, vf.gr)
    K = linalg.null_space(X.T)
    e = K.T @ y
    s2 = float(e @ np.linalg.solve(K.T @ vt @ K, e)) / (n - k)
    assert vf.sigma2 == pytest.approx(s2, rel=1e-9)
    assert vf.dof == n - k
    want = _neg2_restricted(X, y, s2 * vt) - (n - k) * (1.0 + math.log(2 * math.pi))
    assert vf.neg2l == pytest.approx(want, rel=1e-9)


# --- REML on a design with a hand-worked optimum ----------------------------------------------------


def _two_contrasts(e1, e2=1.0):
    """Two passes of m = 3 rows (no run column), columns: intercept and three within-pass
    patterns; n - k = 2 residual contrasts: u1 between the passes (V~ u1 = (1 + 3 g_p) u1) and u2
    within a pass (V~ u2 = u2).  With y = X beta + e1 u1 + e2 u2 the REML criterion is
    log(s^2 (1 + 3 g_p)) + log s^2 + e1^2 / (s^2 (1 + 3 g_p)) + e2^2 / s^2, smallest at
    s^2 = e2^2 and 1 + 3 g_p = e1^2 / e2^2 (g_p = 0 when e1 <= e2)."""
    d = np.repeat([1.0, -1.0], 3)
    X = np.column_stack([np.ones(6), [1.0, -1, 0, 0, 0, 0], [0.0, 0, 0, 1, -1, 0], [1.0, 1, -2, 0, 0, 0]])
    u1 = np.array([1.0, 1, 1, -1, -1, -1]) / math.sqrt(6)
    u2 = np.array([0.0, 0, 0, 1, 1, -2]) / math.sqrt(6)
    y = X @ np.array([2.0, 0.3, -0.1, 0.2]) + e1 * u1 + e2 * u2
    return Cross.build(X, y, make_groups(d, None))


def test_reml_finds_the_hand_optimum_to_one_percent_over_the_whole_range():
    """g_p from just above the lowest ratio searched (1e-3 / mean pass size = 3.3e-4) to 1e4: the
    shrinking grid gets within 1 % (the docstring's precision); the run ratio stays 0 (no run
    structure)."""
    for gp in np.concatenate([[3.6e-4, 4e-4, 5e-4, 7e-4], np.geomspace(1e-3, 1e4, 29)]):
        vf = reml(_two_contrasts(math.sqrt(1.0 + 3.0 * gp)))
        assert vf.gp == pytest.approx(gp, rel=0.01), gp
        assert vf.gr == 0.0
        assert vf.sigma2 == pytest.approx(1.0, rel=0.01)


def test_reml_puts_the_pass_ratio_at_zero_when_passes_scatter_less_than_rows():
    """e1 = 0.5 < e2 = 1: g_p = 0 exactly and s^2 pooled over both contrasts, (0.25 + 1) / 2."""
    vf = reml(_two_contrasts(0.5))
    assert vf.gp == 0.0 and vf.gr == 0.0
    assert vf.sigma2 == pytest.approx(0.625, rel=1e-12)


@pytest.mark.parametrize("scale", [1e-4, 1e4])
def test_reml_and_satterthwaite_do_not_depend_on_the_unit_of_y(scale):
    """Scaling y (arcsec to another unit) scales s^2 by scale^2 and leaves the variance ratios and
    the degrees of freedom alone."""
    X, y, groups, _ = _nested(3)
    base, cross = reml(Cross.build(X, y, groups)), Cross.build(X, scale * y, groups)
    vf = reml(cross)
    assert vf.gp == pytest.approx(base.gp, rel=1e-9) and vf.gr == pytest.approx(base.gr, rel=1e-9)
    assert vf.sigma2 == pytest.approx(scale**2 * base.sigma2, rel=1e-9)
    for cols in ([1], [2], [1, 2]):
        assert wald(cross, vf, cols).df == pytest.approx(wald(Cross.build(X, y, groups), base, cols).df, rel=1e-4)


def test_noise_taken_as_white_gives_ordinary_least_squares():
    """Passes of two rows carry no run-to-run noise (not random): REML is skipped, the ratios are 0
    and the fit is ordinary least squares (lstsq), even with a strong pass-level scatter in y."""
    rng = np.random.default_rng(8)
    d = np.tile([1.0, 1.0, -1.0, -1.0], 10)
    groups = make_groups(d, None)
    assert not groups.random
    X = np.column_stack([np.ones(40), d, rng.normal(size=40)])
    y = X @ [1.0, 0.5, 0.2] + rng.normal(0, 3.0, groups.passes)[groups.pass_id] + rng.normal(0, 0.5, 40)
    vf = reml(Cross.build(X, y, groups))
    beta, rss, *_ = np.linalg.lstsq(X, y, rcond=None)
    assert vf.gp == 0.0 and vf.gr == 0.0
    np.testing.assert_allclose(vf.beta, beta, rtol=1e-9)
    assert vf.sigma2 == pytest.approx(float(rss[0]) / 37, rel=1e-9)
    np.testing.assert_allclose(vf.cov, float(rss[0]) / 37 * np.linalg.inv(X.T @ X), rtol=1e-9)


def _one_level(seed, groups_n=12, m=10, s_between=0.5, s_within=1.0):
    """Balanced one-level design without a run column: passes are blocks of m rows in alternating
    directions; a pass-level covariate z and a within-pass column w (zero mean in each pass)."""
    rng = np.random.default_rng(seed)
    g = np.repeat(np.arange(groups_n), m)
    d = np.where(g % 2 == 0, 1.0, -1.0)
    z = np.linspace(-1.0, 1.0, groups_n)[g]
    w = np.tile(np.linspace(-1.0, 1.0, m), groups_n)
    X = np.column_stack([np.ones(g.shape[0]), z, w])
    y = (0.5 + 0.3 * z + 0.2 * w + rng.normal(0, s_between, groups_n)[g] + rng.normal(0, s_within, g.shape[0]))
    return X, y, make_groups(d, None), g


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_one_level_reml_and_satterthwaite_by_the_analysis_of_variance(seed):
    """Between-pass regression on z: MS_b = m SS_res / (G - 2); within passes, deviations regressed
    on w: MS_w = SS / (N - G - 1).  REML: s^2 = MS_w, s_p^2 = (MS_b - MS_w) / m (here g_p < 1);
    Satterthwaite df of z = G - 2 = 10, of w = N - G - 1 = 107; no run ratio without runs."""
    X, y, groups, g = _one_level(seed)
    G, m, N = 12, 10, 120
    means = np.array([y[g == i].mean() for i in range(G)])
    zg = np.linspace(-1.0, 1.0, G)
    zc = zg - zg.mean()
    res_b = means - means.mean() - (zc @ means / (zc @ zc)) * zc
    ms_b = m * float(res_b @ res_b) / (G - 2)
    dev = y - means[g]
    w = X[:, 2]
    res_w = dev - (w @ dev / (w @ w)) * w
    ms_w = float(res_w @ res_w) / (N - G - 1)
    assert ms_b > ms_w
    cross = Cross.build(X, y, groups)
    vf = reml(cross)
    assert not groups.nested and vf.gr == 0.0
    assert vf.gp < 1.0
    assert vf.sigma2 == pytest.approx(ms_w, rel=0.01)
    assert vf.sigma2 * vf.gp == pytest.approx((ms_b - ms_w) / m, rel=0.02)
    assert wald(cross, vf, [1]).df == pytest.approx(G - 2, rel=0.03)
    assert wald(cross, vf, [2]).df == pytest.approx(N - G - 1, rel=0.03)


# --- a singular design -------------------------------------------------------------------------------


def _with_a_zero_column(seed=1):
    X, y, groups, run = _nested(seed)
    Xs = np.column_stack([X, np.zeros(X.shape[0])])
    return X, Xs, y, groups


def test_a_column_of_zeros_leaves_the_other_coefficients_alone():
    """A singular design (a column of zeros): the fit falls back to the pseudo-inverse, giving the
    other coefficients and their covariance of the design without that column, and 0 for it."""
    X, Xs, y, groups = _with_a_zero_column()
    for gp, gr in [(0.5, 2.0), (0.0, 0.0)]:
        full, part = fit_at(Cross.build(Xs, y, groups), gp, gr), fit_at(Cross.build(X, y, groups), gp, gr)
        np.testing.assert_allclose(full.beta[:3], part.beta, rtol=1e-9)
        assert full.beta[3] == 0.0
        # cov = s^2 (X'V~^-1X)^+, s^2 dividing by n - k with the zero column counted
        np.testing.assert_allclose(full.cov[:3, :3] / full.sigma2, part.cov / part.sigma2, rtol=1e-9)
        assert full.sigma2 * full.dof == pytest.approx(part.sigma2 * part.dof, rel=1e-9)
        assert np.all(full.cov[3] == 0.0)
    vf = reml(Cross.build(Xs, y, groups))
    assert vf.beta[3] == 0.0 and np.all(np.isfinite(vf.beta))
    np.testing.assert_allclose(vf.beta[:3], fit_at(Cross.build(X, y, groups), vf.gp, vf.gr).beta, rtol=1e-9)


def test_wald_on_a_singular_design():
    """No restricted likelihood on a singular design (-2 l_R = +inf, no variance information): the
    df are n - k; a test including the zero column uses the pseudo-inverse of its covariance,
    F = b^2 / var(b) / 2 for the pair (x, zero)."""
    X, Xs, y, groups = _with_a_zero_column()
    cross = Cross.build(Xs, y, groups)
    assert _full_neg2_reml(cross, (1.0, 0.5, 0.5)) == (math.inf, None)
    vf = fit_at(cross, 0.5, 2.0)
    assert variance_info(cross, vf) is None
    t = wald(cross, vf, [2, 3])
    assert vf.dof == X.shape[0] - 4
    assert t.df == pytest.approx(vf.dof, rel=1e-12)
    assert t.F == pytest.approx(vf.beta[2] ** 2 / vf.cov[2, 2] / 2, rel=1e-9)
    assert t.p == pytest.approx(stats.f.sf(t.F, 2, t.df), rel=1e-9)
