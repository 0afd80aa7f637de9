"""The linear mixed model with nested random intercepts (run, pass) and white noise.

Closed-form GLS and REML from sufficient statistics (:class:`Cross`),
Wald F-tests with Satterthwaite / Fai-Cornelius denominator degrees of
freedom capped by the containment df (:func:`wald`), and the cell-means
F-test with lack of fit as error (:class:`CellTester`).  Distribution tails
and quantiles come from :mod:`scipy.special` (imported lazily).

Sources: Harville (1977) J. Am. Stat. Assoc. 72, 320-338 (REML); Searle,
Casella & McCulloch (1992) Variance Components; Satterthwaite (1946)
Biometrics Bull. 2, 110-114; Fai & Cornelius (1996) J. Stat. Comput.
Simul. 54, 363-378.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wormgear_cli.diagnosis.design import orthonormal
from wormgear_cli.diagnosis.runs import Cells, Groups, pass_sums


class Cross:
    """Sufficient statistics of a design X (N x k) and response y for GLS.

    With V = s^2 (I + g_p Zp Zp' + g_r Zr Zr') (Zp, Zr: pass and run
    indicators) the closed-form inverse gives, for every (g_p, g_r),

        A = X' V~^-1 X = X'X - sum_p w_p S_p S_p' - sum_r v_r U_r U_r'
        w_p = g_p / (1 + m_p g_p),  a_p = 1 / (1 + m_p g_p),
        U_r = sum_{p in r} a_p S_p,  t_r = sum_{p in r} a_p m_p,  v_r = g_r / (1 + g_r t_r)
        log det V~ = sum_p log(1 + m_p g_p) + sum_r log(1 + g_r t_r)

    (V~ = V / s^2, S_p the pass sums of X, m_p the pass sizes), and the same
    with y for X'V~^-1 y and y'V~^-1 y.  ``pass_count``/``run_count`` weight
    passes and runs (a cluster-bootstrap resample counts duplicates).
    """

    def __init__(self, xtx, xty, yty, s_x, s_y, groups: Groups, pass_count=None, run_count=None):
        self.xtx = xtx
        self.xty = xty
        self.yty = float(yty)
        self.s_x = s_x
        self.s_y = s_y
        self.groups = groups
        self.m = groups.pass_size
        self.pass_count = np.ones(groups.passes) if pass_count is None else pass_count
        self.run_count = np.ones(groups.runs) if run_count is None else run_count
        self.n = float(np.sum(self.pass_count * self.m))
        self.k = xtx.shape[0]

    @classmethod
    def build(cls, x: np.ndarray, y: np.ndarray, groups: Groups) -> Cross:
        return cls(x.T @ x, x.T @ y, float(y @ y), pass_sums(x, groups), pass_sums(y, groups), groups)

    def take(self, cols) -> Cross:
        cols = np.asarray(cols, dtype=int)
        return Cross(self.xtx[np.ix_(cols, cols)], self.xty[cols], self.yty, self.s_x[:, cols], self.s_y,
                     self.groups, self.pass_count, self.run_count)

    def weighted(self, gp, gr):
        """(A, b, c, logdet V~) for arrays of variance ratios gp, gr (shape (K,)); batched over K."""
        gp = np.atleast_1d(np.asarray(gp, dtype=float))
        gr = np.atleast_1d(np.asarray(gr, dtype=float))
        m, pc = self.m, self.pass_count
        sx, sy = self.s_x, self.s_y
        a, w = _pass_weights(gp, m, pc)
        wsx = w[:, :, None] * sx[None]  # (K, P, k)
        A = self.xtx[None] - np.matmul(wsx.transpose(0, 2, 1), sx)
        b = self.xty[None] - np.matmul(wsx.transpose(0, 2, 1), sy)
        c = self.yty - w @ (sy**2)
        ld = np.log1p(gp[:, None] * m[None, :]) @ pc
        if self.groups.nested and np.any(gr > 0):
            ind, t, v = _run_weights(a, m, gr, self.groups, self.run_count)
            u_x = np.matmul(ind[None] * a[:, None, :], sx)  # (K, R, k)
            u_y = (ind[None] * a[:, None, :]) @ sy  # (K, R)
            vux = v[:, :, None] * u_x
            A = A - np.matmul(vux.transpose(0, 2, 1), u_x)
            b = b - np.einsum("kri,kr->ki", vux, u_y)
            c = c - np.sum(v * u_y**2, axis=1)
            ld = ld + np.log1p(gr[:, None] * t) @ self.run_count
        return A, b, c, ld


def _pass_weights(gp, m, pass_count):
    """(a, w) (K, P) of :class:`Cross`: a_p = 1 / (1 + m_p g_p), w_p = g_p a_p (times the pass counts)."""
    a = 1.0 / (1.0 + gp[:, None] * m[None, :])
    return a, gp[:, None] * a * pass_count[None, :]


def _run_weights(a, m, gr, groups: Groups, run_count):
    """(run indicator (R, P), t (K, R), v (K, R)) of :class:`Cross`; a run duplicated in a resample is a
    new run holding its passes once each."""
    ind = groups.run_indicator
    t = (a * m[None, :]) @ ind.T
    return ind, t, gr[:, None] / (1.0 + gr[:, None] * t) * run_count[None, :]


def gls_quadratic(r: np.ndarray, groups: Groups, gp: float, gr: float) -> float:
    """r' V~^-1 r for a residual r (N,) at one (gp, gr): the ``c`` of :meth:`Cross.weighted`, by the same
    operations on the same arrays (the same number), without a design's sums (the cost the phase fits
    evaluate at every trial step)."""
    gp_, gr_ = np.array([gp], dtype=float), np.array([gr], dtype=float)
    m, sy = groups.pass_size, pass_sums(r, groups)
    a, w = _pass_weights(gp_, m, np.ones(groups.passes))
    c = float(r @ r) - w @ (sy**2)
    if groups.nested and np.any(gr_ > 0):
        ind, _, v = _run_weights(a, m, gr_, groups, np.ones(groups.runs))
        u_y = (ind[None] * a[:, None, :]) @ sy
        c = c - np.sum(v * u_y**2, axis=1)
    return float(c[0])


def _neg2_reml(cross: Cross, gp, gr):
    """-2 x REML log-likelihood profiled over s^2 (constants dropped), batched; also Q and beta."""
    A, b, c, ld = cross.weighted(gp, gr)
    k, n = cross.k, cross.n
    sign, logdet = np.linalg.slogdet(A)
    try:
        beta = np.linalg.solve(A, b[..., None])[..., 0]
    except np.linalg.LinAlgError:
        beta = np.einsum("kij,kj->ki", np.linalg.pinv(A), b)
    q = c - np.einsum("ki,ki->k", b, beta)
    q = np.maximum(q, 1e-300)
    val = (n - k) * np.log(q / (n - k)) + ld + logdet
    val = np.where(sign > 0, val, np.inf)
    return val, q, beta, A


@dataclass(frozen=True)
class VarFit:
    """A GLS/REML fit: variance ratios ``gp``, ``gr``; white variance ``sigma2``
    [arcsec^2]; ``beta`` (k,); ``cov`` (k, k) covariance of beta; ``dof`` = n - k."""

    gp: float
    gr: float
    sigma2: float
    beta: np.ndarray
    cov: np.ndarray
    dof: float
    neg2l: float

    @property
    def s_white(self) -> float:
        return math.sqrt(self.sigma2)

    @property
    def s_pass(self) -> float:
        return math.sqrt(self.sigma2 * self.gp)

    @property
    def s_run(self) -> float:
        return math.sqrt(self.sigma2 * self.gr)


def fit_at(cross: Cross, gp: float, gr: float) -> VarFit:
    val, q, beta, A = _neg2_reml(cross, [gp], [gr])
    dof = cross.n - cross.k
    sigma2 = float(q[0] / dof)
    cov = sigma2 * np.linalg.pinv(A[0])
    return VarFit(float(gp), float(gr), sigma2, beta[0], cov, dof, float(val[0]))


def reml(cross: Cross) -> VarFit:
    """Variance ratios by REML (grid, then a shrinking local grid in log scale; 0 allowed).

    With runs and passes the search is also run along each edge (g_r = 0, g_p = 0) and the
    best of the three is kept: the local steps of the two-ratio search cannot walk a ratio
    down to 0 when the coarse grid's best point holds a positive one, so a maximum on an edge
    would otherwise be missed."""
    g = cross.groups
    if not g.random or cross.n - cross.k < 2:
        return fit_at(cross, 0.0, 0.0)
    mbar = float(np.mean(g.pass_size))
    lo = math.log10(1e-3 / mbar)
    hi = 4.0
    axis = np.concatenate([[-np.inf], np.linspace(lo, hi, 15)])
    zero = np.array([-np.inf])

    def search(p_free: bool, r_free: bool):
        lp, lr = np.meshgrid(axis if p_free else zero, axis if r_free else zero, indexing="ij")
        lp, lr = lp.ravel(), lr.ravel()
        val = _neg2_reml(cross, 10.0**lp, 10.0**lr)[0]
        best = int(np.argmin(val))
        cp, cr, cv = lp[best], lr[best], val[best]
        step = (hi - lo) / 14.0
        for _ in range(6):
            step /= 2.0
            offs = np.array([-2, -1, 0, 1, 2]) * step

            def around(centre):
                if np.isinf(centre):
                    return np.concatenate([[-np.inf], lo + (np.arange(3)) * step])  # noqa: B023
                pts = centre + offs  # noqa: B023
                return np.where(pts < lo - 1e-12, -np.inf, pts)

            pa = around(cp) if p_free else zero
            ra = around(cr) if r_free else zero
            gp_, gr_ = np.meshgrid(pa, ra, indexing="ij")
            gp_, gr_ = gp_.ravel(), gr_.ravel()
            v = _neg2_reml(cross, 10.0**gp_, 10.0**gr_)[0]
            j = int(np.argmin(v))
            if v[j] < cv:
                cp, cr, cv = gp_[j], gr_[j], v[j]
        return cv, cp, cr

    found = [search(True, g.nested)]
    if g.nested:
        found += [search(True, False), search(False, True)]
    _, cp, cr = min(found, key=lambda f: f[0])
    return fit_at(cross, float(10.0**cp), float(10.0**cr))


@dataclass(frozen=True)
class Wald:
    """Wald F-test of a group of q coefficients: ``estimate`` (q,), ``cov`` (q, q),
    ``F``, ``df`` (denominator, Satterthwaite), ``p``; ``df_each`` per eigen-direction."""

    estimate: np.ndarray
    cov: np.ndarray
    F: float
    q: int
    df: float
    p: float


def _full_neg2_reml(cross: Cross, theta) -> tuple[float, np.ndarray | None]:
    """-2 l_R at natural variance parameters (s_white^2, s_pass^2, s_run^2); also cov(beta) (None where
    the parameters are outside the domain or the system is not positive definite)."""
    s2, sp, sr = theta
    if s2 <= 0 or sp < 0 or sr < 0:
        return math.inf, None
    A, b, c, ld = cross.weighted([sp / s2], [sr / s2])
    A, b, c, ld = A[0], b[0], float(c[0]), float(ld[0])
    sign, logdet = np.linalg.slogdet(A)
    if sign <= 0:
        return math.inf, None
    beta = np.linalg.solve(A, b)
    q = c - float(b @ beta)
    k, n = cross.k, cross.n
    val = n * math.log(s2) + ld + logdet - k * math.log(s2) + q / s2
    return val, s2 * np.linalg.inv(A)


def level_shares(cols: np.ndarray, groups: Groups) -> tuple[np.ndarray, np.ndarray]:
    """Per column: share of its sum of squares carried by its run means and by its pass means."""
    cols = cols.reshape(cols.shape[0], -1)
    tot = np.sum(cols * cols, axis=0)
    ps = pass_sums(cols, groups)
    pass_ss = np.sum(ps**2 / groups.pass_size[:, None], axis=0)
    ind = groups.run_indicator
    rs = ind @ ps
    rsize = ind @ groups.pass_size
    run_ss = np.sum(rs**2 / rsize[:, None], axis=0)
    safe = np.where(tot > 0, tot, 1.0)
    return np.where(tot > 0, run_ss / safe, 0.0), np.where(tot > 0, pass_ss / safe, 0.0)


def containment_df(groups: Groups, model_cols: np.ndarray, test_cols: np.ndarray) -> float:
    """Containment degrees of freedom of ``test_cols`` given ``model_cols``.

    A column varies mainly between runs (run means carry more than half its
    sum of squares), between passes, or within passes.  Its df are the
    number of units at that level minus the columns (model and tested) that
    live at that level or above: runs - k_run, passes - k_pass, or rows - k."""
    n = test_cols.shape[0]
    k = model_cols.shape[1] + test_cols.reshape(n, -1).shape[1]
    if not groups.random:
        return float(n - k)
    t_run, t_pass = level_shares(test_cols, groups)
    m_run, m_pass = level_shares(model_cols, groups) if model_cols.shape[1] else (np.zeros(0), np.zeros(0))
    q = t_run.shape[0]
    if np.max(t_run) > 0.5 and groups.nested:
        return float(groups.runs - np.count_nonzero(m_run > 0.5) - q)
    if np.max(t_pass) > 0.5:
        return float(groups.passes - np.count_nonzero(m_pass > 0.5) - q)
    return float(n - k)


def variance_info(cross: Cross, vf: VarFit):
    """(W, dC) for Satterthwaite: W = 2 H^-1 the asymptotic covariance of the free
    variance parameters (H: numerical Hessian of -2 l_R), dC the derivatives of
    cov(beta) with respect to each of them.  None when every variance component
    but the white one is at zero (or H is not positive definite)."""
    theta = np.array([vf.sigma2, vf.sigma2 * vf.gp, vf.sigma2 * vf.gr])
    free = [0] + [j for j in (1, 2) if theta[j] > 1e-12 * theta[0]]
    if len(free) == 1:
        return None
    nf = len(free)
    h = 1e-4 * theta[free]

    def f(delta):
        t = theta.copy()
        t[free] += delta
        return _full_neg2_reml(cross, t)

    f0 = f(np.zeros(nf))[0]
    H = np.empty((nf, nf))
    for i in range(nf):
        ei = np.zeros(nf)
        ei[i] = h[i]
        H[i, i] = (f(ei)[0] - 2 * f0 + f(-ei)[0]) / h[i] ** 2
        for j in range(i + 1, nf):
            ej = np.zeros(nf)
            ej[j] = h[j]
            H[i, j] = H[j, i] = (f(ei + ej)[0] - f(ei - ej)[0] - f(-ei + ej)[0] + f(-ei - ej)[0]) / (4 * h[i] * h[j])
    if not np.all(np.isfinite(H)):
        return None
    try:
        if not np.all(np.linalg.eigvalsh(H) > 0):
            return None
        W = 2.0 * np.linalg.inv(H)
    except np.linalg.LinAlgError:
        return None
    dC = []
    for i in range(nf):
        e = np.zeros(nf)
        e[i] = h[i]
        cp, cm = f(e)[1], f(-e)[1]
        if cp is None or cm is None:
            return None
        dC.append((cp - cm) / (2 * h[i]))
    return W, dC


def _df_of(vectors: np.ndarray, variances: np.ndarray, info) -> np.ndarray:
    """Satterthwaite df 2 c^2 / (g' W g) of contrasts ``vectors`` (rows, length k) with variances c."""
    W, dC = info
    g = np.stack([np.einsum("mi,ij,mj->m", vectors, d, vectors) for d in dC], axis=1)
    return 2.0 * variances**2 / np.maximum(np.einsum("mi,ij,mj->m", g, W, g), 1e-300)


def wald(cross: Cross, vf: VarFit, idx, containment: float | None = None, info="auto") -> Wald:
    """Wald test of coefficients ``idx`` with Satterthwaite degrees of freedom.

    F = b' (L C L')^-1 b / q.  df_m = 2 c_m^2 / (g_m' W g_m) for each
    eigen-direction m of L C L' (c_m its variance, g_m the gradient of c_m
    with respect to the variance parameters, W their asymptotic covariance);
    several directions combine as Fai & Cornelius, df = 2E / (E - q),
    E = sum df_m / (df_m - 2).  The df never exceed ``containment``, the
    df of the level the tested columns vary at (see :func:`containment_df`):
    when REML puts a variance component at zero (few runs) Satterthwaite
    alone would judge a between-run effect against the within-run noise."""
    idx = np.asarray(idx, dtype=int)
    q = idx.shape[0]
    est = vf.beta[idx]
    cov = vf.cov[np.ix_(idx, idx)]
    if isinstance(info, str):
        info = variance_info(cross, vf)
    if info is not None:
        lam, vec = np.linalg.eigh(cov)
        full = np.zeros((q, cross.k))
        full[:, idx] = vec.T
        dfs = _df_of(full, lam, info)
    else:
        dfs = np.full(q, vf.dof)
    cap = vf.dof if containment is None else min(vf.dof, float(containment))
    dfs = np.clip(dfs, 1.0, max(cap, 1.0))
    if q == 1:
        df = float(dfs[0])
    else:
        e_sum = float(np.sum(np.where(dfs > 2.0, dfs / np.maximum(dfs - 2.0, 1e-12), 0.0)))
        df = 2.0 * e_sum / (e_sum - q) if e_sum > q else float(np.min(dfs))
        df = float(np.clip(df, 1.0, max(cap, 1.0)))
    try:
        F = float(est @ np.linalg.solve(cov, est)) / q
    except np.linalg.LinAlgError:
        F = float(est @ np.linalg.pinv(cov) @ est) / q
    return Wald(est, cov, F, q, df, f_sf(F, q, df))


def contrast_df(vf: VarFit, vector: np.ndarray, info, fallback: float | None = None) -> float:
    """Satterthwaite df of the linear combination ``vector`` (length k) of all coefficients."""
    vec = np.asarray(vector, dtype=float)[None, :]
    if info is None:
        return float(fallback if fallback is not None else vf.dof)
    var = float(vec[0] @ vf.cov @ vec[0])
    return float(np.clip(_df_of(vec, np.array([var]), info)[0], 1.0, max(vf.dof, 1.0)))


class CellTester:
    """F-tests on the cell means (lack of fit as error) against one model.

    For a signature that depends only on the target and the direction, the
    runs replicate the noise but not the model's misfit at each target: a
    residual pattern the model lacks (repeated identically in every run)
    would otherwise count as many independent observations.  Regressing the
    cell means puts that lack of fit into the error term, with
    df = cells - columns.  The model's cell-mean columns are projected out
    once; each test then costs one small QR."""

    def __init__(self, cells: Cells, basis: np.ndarray, resid: np.ndarray):
        self.cells = cells
        mb = cells.means(basis) if basis.shape[1] else np.zeros((cells.cells, 0))
        self.q0 = orthonormal(mb)[0] / math.sqrt(cells.cells) if mb.shape[1] else mb
        self.k0 = self.q0.shape[1]
        self.e0 = self._project(cells.means(resid))
        self.r0 = float(self.e0 @ self.e0)

    def _project(self, a):
        return a - self.q0 @ (self.q0.T @ a) if self.k0 else a

    def test(self, cols=None, means=None) -> tuple[float, float, float]:
        """(F, df, p) of ``cols`` (rows) or their cell ``means``."""
        mc = means if means is not None else self.cells.means(cols.reshape(cols.shape[0], -1))
        mc = self._project(mc.reshape(mc.shape[0], -1))
        norms = np.sqrt(np.sum(mc * mc, axis=0))
        if not np.any(norms > 1e-12 * max(float(np.max(norms)), 1e-300)):
            return 0.0, 0.0, 1.0
        u, sv, _ = np.linalg.svd(mc / np.where(norms > 0, norms, 1.0), full_matrices=False)
        u = u[:, sv > 1e-6 * sv[0]]
        q_eff = u.shape[1]
        df = self.cells.cells - self.k0 - q_eff
        if df <= 0:
            return 0.0, float(max(df, 0)), 1.0
        red = float(np.sum((u.T @ self.e0) ** 2))
        r1 = max(self.r0 - red, 1e-300)
        F = red / q_eff / (r1 / df)
        return F, float(df), f_sf(F, q_eff, df)


def f_sf(f: float, d1: float, d2: float) -> float:
    """Upper tail P(F > f) of Fisher's F distribution with (d1, d2) degrees of freedom
    (:func:`scipy.special.fdtrc`); 1 for f <= 0, 0 for f = +inf."""
    if not math.isfinite(f):
        return 0.0 if f > 0 else 1.0
    if f <= 0.0:
        return 1.0
    # lazy: scipy.special is slow to import (a large part of a second); only this path needs it
    from scipy.special import fdtrc

    return float(fdtrc(d1, d2, f))


def t_ppf(p: float, df: float) -> float:
    """Quantile of Student's t with ``df`` (> 0, real) degrees of freedom (:func:`scipy.special.stdtrit`)."""
    # lazy: scipy.special is slow to import (a large part of a second); only this path needs it
    from scipy.special import stdtrit

    return float(stdtrit(df, p))
