"""Diagnosis: where a drive model and a measurement disagree, and which
catalogue effect the model lacks (the core of ``wormgear diagnose``).

Pure numpy; no I/O, no typer, no rich.  Angles are handled in arcsec inside
this module (the measured error and every model column are divided by
ARCSEC = pi/648000 once) so the statistics work on numbers of order one.

Model
-----
For row i (output angle theta_i [rad], direction d_i = +/-1, load [N m],
temperature [degC], time [s]) the measured error y_i [arcsec] is

    y_i = m(theta_i, d_i, ...; psi) + c + sum_j beta_j x_ij + u_run(i) + v_pass(i) + e_i

* m: the spec's model (:func:`wormgear_cli.simulation.simulate`) with the
  phases psi of its periodic sources fitted; their amplitudes stay as
  specified (a drawing knows sizes, not the angular position they were
  assembled at);
* c: ONE zero offset for the whole measurement (an offset per run would
  swallow a thermal drift);
* x_j, beta_j: the columns of catalogue effects added by the selection
  (linear in their physical parameter, or in its reciprocal for a
  stiffness, or a sin/cos pair for a periodic effect);
* noise: nested random intercepts, u ~ N(0, s_run^2) per run (both
  directions of a run share it) and v ~ N(0, s_pass^2) per pass (one run in
  one direction), plus white e ~ N(0, s_white^2).  Estimated by REML;
  fixed effects by generalised least squares (GLS).  Without a ``run``
  column a pass is a block of consecutive rows in one direction.

Everything that depends on the variance ratios g_p = s_pass^2/s_white^2,
g_r = s_run^2/s_white^2 is computed from sufficient statistics (X'X, X'y,
y'y and per-pass sums) with the closed-form inverse of the nested
covariance, so REML and GLS cost O(passes * k^2) per evaluation whatever
the number of rows.

Selection (forward, over groups of columns)
-------------------------------------------
1. Fit psi and c: deterministic starts, an exhaustive grid over the phases
   of each shaft's sources, Levenberg-Marquardt polish, then GLS with REML
   variance components on every row.
2. For every catalogue effect the spec lacks: check it is observable (the
   signal it needs varies, its order is not aliased by the target spacing,
   its columns are not absorbed by the offset or the effects already in),
   then a Wald F-test of its columns given the current model, variance
   components re-estimated by REML under the alternative, denominator
   degrees of freedom by Satterthwaite's approximation (Fai-Cornelius for
   two columns) capped by the containment df of the level the effect varies
   at, so effects that change only between runs are judged against
   run-to-run scatter.  A signature that depends only on angle and direction
   must also pass the same test on the per-target cell means (lack of fit
   as error: a misfit repeated in every run is not replication).  An effect
   on the order of spec sources with fitted phases is tested by refitting
   the phases with it (only content those fixed-size sources cannot reach
   counts).  p-values are multiplied by the number of candidates tested
   (Bonferroni).
3. Among the significant candidates the one with the largest Wald
   chi-square is accepted only if its parameter lies inside the catalogue's
   physical range, no other significant candidate has (nearly) the same
   signature (canonical correlation >= 0.99) and it is stable: best in at
   least 60 % of resamples of whole runs (cluster bootstrap, fixed seed).
   Otherwise the selection stops and says why.
4. Refit everything (phases, offset, accepted effects, variance
   components).  If the RMS residual does not shrink, the candidate is
   rejected and the selection stops (a significant GLS test whose fit makes
   the gap larger follows structure that is not its signature, the random
   effects absorbing what it gets wrong).  Otherwise repeat.

With fewer than MIN_RUNS runs no variance between runs or passes is
estimated (the noise is taken as white); candidates whose columns vary
mainly between passes, and thermal ones in a monotonic warm-up, are
"untestable", and the others are tested with their columns as nuisance.

A candidate that stops the selection narrowly (adjusted p < NEAR_FACTOR
alpha) or at the --max-effects limit is refitted: if it removes at least
NEAR_SHARE of the remaining mean-square gap it is reported as likely, and
each named effect's interval is widened to cover its interval in that
larger model.  An effect on the order of spec sources with fitted phases
gets the range of sizes that fit as well (profile of the GLS cost) instead
of an interval.

What is left is scanned for structure no catalogue effect explains:
harmonics at the drive's physical orders and low integer orders (common
and differential mode) and trends against temperature, load and time, and
a mean reversal change (each a Wald test, with the cell-means check for
orders; Bonferroni over the scan).  The RMS residual is compared with the
noise floor (point-to-point noise within passes plus the fitted scatter
between passes and runs): above EXCESS_FACTOR times it, it is reported.

Sources: REML and the nested-intercept GLS are textbook linear mixed model
results (Harville 1977; Searle, Casella & McCulloch 1992); the degrees of
freedom follow Satterthwaite (1946) and Fai & Cornelius (1996); the
continued fraction for the incomplete beta function is Lentz's method.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from wormgear_cli.errors import DataError, UsageError

ARCSEC = math.pi / 648000.0

#: canonical correlation above which two signatures cannot be told apart
INDISTINGUISHABLE = 0.99
#: ... and above which they are reported as nearly so
NEARLY = 0.95
#: fraction of a candidate's columns left after projecting out the model below which it is unobservable
MIN_TOLERANCE = 1e-6
#: share of resamples in which an accepted effect must come out best
MIN_STABILITY = 0.6
#: smallest temperature range [K] that lets thermal effects be seen
MIN_TEMPERATURE_RANGE = 0.1
#: fewest runs from which scatter between runs and passes can be estimated
MIN_RUNS = 3
#: |correlation| of temperature and time above which a warm-up is called monotonic
MONOTONIC = 0.95
#: a candidate not significant at alpha but below this multiple of it is reported as a likely effect ...
NEAR_FACTOR = 5.0
#: ... when adding it would remove at least this share of the remaining mean-square gap
NEAR_SHARE = 0.05
#: a residual RMS above this multiple of the noise floor is reported as unexplained
EXCESS_FACTOR = 2.0


# ============================================================================ distributions


def _beta_fraction(a: float, b: float, x: float) -> float:
    """Continued fraction of the incomplete beta function (Lentz's method)."""
    tiny = 1e-300
    f = 1.0
    c = 1.0
    d = 1.0 - (a + b) * x / (a + 1.0)
    d = 1.0 / (d if abs(d) > tiny else tiny)
    f = d
    for m in range(1, 100000):
        two_m = 2.0 * m
        # even step
        num = m * (b - m) * x / ((a + two_m - 1.0) * (a + two_m))
        d = 1.0 + num * d
        c = 1.0 + num / c
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = c if abs(c) > tiny else tiny
        f *= d * c
        # odd step
        num = -(a + m) * (a + b + m) * x / ((a + two_m) * (a + two_m + 1.0))
        d = 1.0 + num * d
        c = 1.0 + num / c
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = c if abs(c) > tiny else tiny
        step = d * c
        f *= step
        if abs(step - 1.0) < 1e-15:
            break
    return f


def betainc(a: float, b: float, x: float, y: float | None = None) -> float:
    """Regularised incomplete beta function I_x(a, b), a, b > 0, 0 <= x <= 1.

    ``y`` = 1 - x when the caller knows it more accurately than 1 - x rounds
    (x close to 1)."""
    if y is None:
        y = 1.0 - x
    if x <= 0.0:
        return 0.0
    if y <= 0.0:  # x is 1 (judged by y, which may be exact where x has rounded to 1)
        return 1.0
    log_front = (a * math.log(x) + b * math.log(y) + math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b))
    if x < (a + 1.0) / (a + b + 2.0):
        return math.exp(log_front) * _beta_fraction(a, b, x) / a
    return 1.0 - math.exp(log_front) * _beta_fraction(b, a, y) / b


def f_sf(f: float, d1: float, d2: float) -> float:
    """Upper tail P(F > f) of Fisher's F distribution with (d1, d2) degrees of freedom."""
    if not math.isfinite(f):
        return 0.0 if f > 0 else 1.0
    if f <= 0.0:
        return 1.0
    d2 = min(d2, 1e7)
    # x = d2 / (d2 + d1 f) and 1 - x = d1 f / (d2 + d1 f), both without cancellation
    return betainc(d2 / 2.0, d1 / 2.0, d2 / (d2 + d1 * f), d1 * f / (d2 + d1 * f))


def _norm_ppf(p: float) -> float:
    """Standard normal quantile by bisection on erfc (p in (0, 1))."""
    lo, hi = -40.0, 40.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if 0.5 * math.erfc(-mid / math.sqrt(2.0)) < p:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def t_ppf(p: float, df: float) -> float:
    """Quantile of Student's t with ``df`` (> 0, real) degrees of freedom, p in (0.5, 1)."""
    if df > 400.0:
        z = _norm_ppf(p)
        # Cornish-Fisher expansion of t around the normal quantile
        return z + (z**3 + z) / (4 * df) + (5 * z**5 + 16 * z**3 + 3 * z) / (96 * df**2)
    two_sided = 2.0 * (1.0 - p)
    lo, hi = 0.0, 1.0  # x = df / (df + t^2); P(|T| > t) = I_x(df/2, 1/2) grows with x
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if betainc(df / 2.0, 0.5, mid) < two_sided:
            lo = mid
        else:
            hi = mid
    x = 0.5 * (lo + hi)
    return math.sqrt(df * (1.0 - x) / x)


# ============================================================================ run structure


@dataclass(frozen=True)
class Groups:
    """The run structure of a measurement.

    ``pass_id`` (N,) pass of each row; a pass is one run in one direction.
    ``pass_size`` (P,), ``pass_run`` (P,) run index of each pass,
    ``pass_direction`` (P,).  ``runs``: number of runs R.  ``nested``: some
    run holds more than one pass (then run and pass variances are separate
    components).  ``random``: False when the rows carry no usable run
    structure (every row its own pass): noise is then taken as white.
    ``describe``: how the passes were found.
    """

    pass_id: np.ndarray
    pass_size: np.ndarray
    pass_run: np.ndarray
    pass_direction: np.ndarray
    runs: int
    nested: bool
    random: bool
    describe: str

    def __post_init__(self):
        order = np.argsort(self.pass_id, kind="stable")
        starts = np.searchsorted(self.pass_id[order], np.arange(self.pass_size.shape[0]))
        object.__setattr__(self, "order", order)
        object.__setattr__(self, "starts", starts)
        ind = np.zeros((self.runs, self.pass_size.shape[0]))
        ind[self.pass_run, np.arange(self.pass_size.shape[0])] = 1.0
        object.__setattr__(self, "run_indicator", ind)

    @property
    def passes(self) -> int:
        return int(self.pass_size.shape[0])


def make_groups(direction: np.ndarray, run: np.ndarray | None) -> Groups:
    """Passes and runs from the ``direction`` and (optional) ``run`` columns.

    With a run column: a pass is every row of one (run, direction) pair, a
    run every row of one run number.  Without: a pass is a block of
    consecutive rows in one direction and each pass is its own run."""
    direction = np.asarray(direction, dtype=float)
    n = direction.shape[0]
    if run is not None:
        run = np.asarray(run)
        keys = np.stack([run.astype(float), direction], axis=1)
        uniq, pass_id = np.unique(keys, axis=0, return_inverse=True)
        pass_id = pass_id.reshape(-1)
        run_vals, pass_run = np.unique(uniq[:, 0], return_inverse=True)
        pass_dir = uniq[:, 1]
        runs = int(run_vals.shape[0])
        describe = "run column: one pass per run and direction"
    else:
        change = np.ones(n, dtype=bool)
        change[1:] = direction[1:] != direction[:-1]
        pass_id = np.cumsum(change) - 1
        p = int(pass_id[-1]) + 1
        pass_run = np.arange(p)
        pass_dir = direction[change]
        runs = p
        describe = "no run column: a pass is a block of consecutive rows in one direction"
    size = np.bincount(pass_id, minlength=int(pass_id.max()) + 1).astype(float)
    nested = bool(np.bincount(pass_run).max() > 1) if runs > 0 else False
    random = bool(size.shape[0] >= 2 and np.mean(size) >= 3.0)
    if not random:
        describe += "; passes too short to carry run-to-run noise, noise taken as white"
    return Groups(pass_id.astype(int), size, np.asarray(pass_run, dtype=int), np.asarray(pass_dir, dtype=float),
                  runs, nested and random, random, describe)


# ============================================================================ GLS / REML from sufficient statistics


def _pass_sums(values: np.ndarray, groups: Groups) -> np.ndarray:
    """Per-pass column sums of a (N,) or (N, k) array."""
    if values.ndim == 1:
        return np.bincount(groups.pass_id, weights=values, minlength=groups.passes)
    if values.shape[1] == 0:
        return np.zeros((groups.passes, 0))
    return np.add.reduceat(values[groups.order], groups.starts, axis=0)


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
    def build(cls, x: np.ndarray, y: np.ndarray, groups: Groups) -> "Cross":
        return cls(x.T @ x, x.T @ y, float(y @ y), _pass_sums(x, groups), _pass_sums(y, groups), groups)

    def take(self, cols) -> "Cross":
        cols = np.asarray(cols, dtype=int)
        return Cross(self.xtx[np.ix_(cols, cols)], self.xty[cols], self.yty, self.s_x[:, cols], self.s_y,
                     self.groups, self.pass_count, self.run_count)

    def weighted(self, gp, gr):
        """(A, b, c, logdet V~) for arrays of variance ratios gp, gr (shape (K,)); batched over K."""
        gp = np.atleast_1d(np.asarray(gp, dtype=float))
        gr = np.atleast_1d(np.asarray(gr, dtype=float))
        m, pc = self.m, self.pass_count
        sx, sy = self.s_x, self.s_y
        a = 1.0 / (1.0 + gp[:, None] * m[None, :])  # (K, P)
        w = gp[:, None] * a * pc[None, :]
        wsx = w[:, :, None] * sx[None]  # (K, P, k)
        A = self.xtx[None] - np.matmul(wsx.transpose(0, 2, 1), sx)
        b = self.xty[None] - np.matmul(wsx.transpose(0, 2, 1), sy)
        c = self.yty - w @ (sy**2)
        ld = np.log1p(gp[:, None] * m[None, :]) @ pc
        if self.groups.nested and np.any(gr > 0):
            ind = self.groups.run_indicator
            # a run duplicated in a resample is a new run holding its passes once each
            t = (a * m[None, :]) @ ind.T  # (K, R)
            u_x = np.matmul(ind[None] * a[:, None, :], sx)  # (K, R, k)
            u_y = (ind[None] * a[:, None, :]) @ sy  # (K, R)
            v = gr[:, None] / (1.0 + gr[:, None] * t) * self.run_count[None, :]
            vux = v[:, :, None] * u_x
            A = A - np.matmul(vux.transpose(0, 2, 1), u_x)
            b = b - np.einsum("kri,kr->ki", vux, u_y)
            c = c - np.sum(v * u_y**2, axis=1)
            ld = ld + np.log1p(gr[:, None] * t) @ self.run_count
        return A, b, c, ld


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


def _fit_at(cross: Cross, gp: float, gr: float) -> VarFit:
    val, q, beta, A = _neg2_reml(cross, [gp], [gr])
    dof = cross.n - cross.k
    sigma2 = float(q[0] / dof)
    cov = sigma2 * np.linalg.pinv(A[0])
    return VarFit(float(gp), float(gr), sigma2, beta[0], cov, dof, float(val[0]))


def reml(cross: Cross) -> VarFit:
    """Variance ratios by REML (grid, then a shrinking local grid in log scale; 0 allowed)."""
    g = cross.groups
    if not g.random or cross.n - cross.k < 2:
        return _fit_at(cross, 0.0, 0.0)
    mbar = float(np.mean(g.pass_size))
    lo = math.log10(1e-3 / mbar)
    hi = 4.0
    axis = np.concatenate([[-np.inf], np.linspace(lo, hi, 15)])
    r_axis = axis if g.nested else np.array([-np.inf])
    lp, lr = np.meshgrid(axis, r_axis, indexing="ij")
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
                return np.concatenate([[-np.inf], lo + (np.arange(3)) * step])
            pts = centre + offs
            return np.where(pts < lo - 1e-12, -np.inf, pts)

        pa = around(cp)
        ra = around(cr) if g.nested else np.array([-np.inf])
        gp_, gr_ = np.meshgrid(pa, ra, indexing="ij")
        gp_, gr_ = gp_.ravel(), gr_.ravel()
        v = _neg2_reml(cross, 10.0**gp_, 10.0**gr_)[0]
        j = int(np.argmin(v))
        if v[j] < cv:
            cp, cr, cv = gp_[j], gr_[j], v[j]
    return _fit_at(cross, float(10.0**cp), float(10.0**cr))


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


def _full_neg2_reml(cross: Cross, theta) -> tuple[float, np.ndarray]:
    """-2 l_R at natural variance parameters (s_white^2, s_pass^2, s_run^2); also cov(beta)."""
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


def _level_shares(cols: np.ndarray, groups: Groups) -> tuple[np.ndarray, np.ndarray]:
    """Per column: share of its sum of squares carried by its run means and by its pass means."""
    cols = cols.reshape(cols.shape[0], -1)
    tot = np.sum(cols * cols, axis=0)
    ps = _pass_sums(cols, groups)
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
    t_run, t_pass = _level_shares(test_cols, groups)
    m_run, m_pass = _level_shares(model_cols, groups) if model_cols.shape[1] else (np.zeros(0), np.zeros(0))
    q = t_run.shape[0]
    if np.max(t_run) > 0.5 and groups.nested:
        return float(groups.runs - np.count_nonzero(m_run > 0.5) - q)
    if np.max(t_pass) > 0.5:
        return float(groups.passes - np.count_nonzero(m_pass > 0.5) - q)
    return float(n - k)


def _variance_info(cross: Cross, vf: VarFit):
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
        info = _variance_info(cross, vf)
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


@dataclass(frozen=True)
class Cells:
    """Cells = (target, direction) pairs: ``cell_id`` (N,), ``count`` (C,) rows per cell.
    ``replicated``: cells hold two or more rows on average (repeated runs)."""

    cell_id: np.ndarray
    count: np.ndarray

    @property
    def cells(self) -> int:
        return int(self.count.shape[0])

    @property
    def replicated(self) -> bool:
        return bool(np.mean(self.count) >= 2.0)

    def means(self, x: np.ndarray) -> np.ndarray:
        x2 = x.reshape(x.shape[0], -1)
        out = np.empty((self.cells, x2.shape[1]))
        for j in range(x2.shape[1]):
            out[:, j] = np.bincount(self.cell_id, weights=x2[:, j], minlength=self.cells) / self.count
        return out if x.ndim > 1 else out[:, 0]


def make_cells(theta: np.ndarray, direction: np.ndarray) -> Cells:
    """Cells of a measurement: rows at the same target (angles within 1e-6 deg) and direction."""
    from wormgear_cli.iso230 import group_targets

    tgt, _ = group_targets(theta)
    key = tgt.astype(np.int64) * 2 + (np.asarray(direction) < 0)
    _, cell = np.unique(key, return_inverse=True)
    cell = cell.reshape(-1)
    return Cells(cell, np.bincount(cell).astype(float))


def cell_level(cols: np.ndarray, cells: Cells) -> bool:
    """True when the columns depend on the cell only (no variation between the runs of a cell)."""
    cols = cols.reshape(cols.shape[0], -1)
    tot = float(np.sum(cols * cols))
    if tot <= 0:
        return False
    m = cells.means(cols)
    within = tot - float(np.sum(cells.count[:, None] * m * m))
    return within <= 1e-9 * tot


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
        self.q0 = _orthonormal(mb)[0] / math.sqrt(cells.cells) if mb.shape[1] else mb
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


# ============================================================================ the spec's model, split by phase


@dataclass(frozen=True)
class PhaseSource:
    """A periodic term of the spec whose phase is fitted.

    ``name``: source name (as :func:`simulation.periodic_sources`) or
    ``effect:NAME``; ``key``: TOML path of its phase key; ``order``
    [cycles/output rev]; ``amplitude`` [arcsec] (first harmonic, as
    specified); ``phase`` [rad] as specified; ``contrib(signals, psi)`` ->
    its whole contribution [arcsec] (common part and lost-motion part)."""

    name: str
    key: str
    order: float
    amplitude: float
    phase: float
    contrib: Callable


def _source_contrib(src):
    def contrib(sig, psi):
        out = src.curve(sig.theta, psi)
        if src.lost_motion is not None:
            out = out - sig.direction * src.lost_motion(sig.theta, psi) / 2.0
        return out / ARCSEC
    return contrib


def _effect_contrib(eff, params, g):
    def contrib(sig, psi):
        return eff.function(sig, g, **{**params, eff.phase: psi}) / ARCSEC
    return contrib


def phase_sources(spec, geometry, signals) -> tuple[list[PhaseSource], list[PhaseSource]]:
    """(fittable, all) periodic terms of the spec.

    All of :func:`simulation.periodic_sources` plus the spec's periodic
    ``[effects.*]`` (those with a phase key).  A term is fittable when its
    contribution at these samples changes with its phase (a source of zero
    size, or one whose lost motion does not depend on the phase, is not)."""
    from wormgear_cli.models.effects import EFFECTS
    from wormgear_cli.simulation import periodic_sources

    out = []
    for src in periodic_sources(spec):
        out.append(PhaseSource(src.name, src.phase_path, float(src.order), float(src.amplitude) / ARCSEC,
                               float(src.phase), _source_contrib(src)))
    for name, params in spec.effects.items():
        eff = EFFECTS[name]
        if eff.phase is None or eff.order is None:
            continue
        amp = float(np.max(np.abs(eff.function(_unit_circle(), geometry, **params)))) / ARCSEC
        key = next(p.key for p in eff.params if p.name == eff.phase)
        out.append(PhaseSource(f"effect:{name}", f"effects.{name}.{key}", float(eff.order(geometry)), amp,
                               float(params[eff.phase]),
                               _effect_contrib(eff, dict(params), geometry)))
    probe = _probe_signals(signals)
    fittable = []
    for s in out:
        a = s.contrib(probe, 0.3)
        b = s.contrib(probe, 1.9)
        if np.max(np.abs(a - b)) > 1e-9:
            fittable.append(s)
    return fittable, out


def _unit_circle(n: int = 720):
    from wormgear_cli.models.effects import Signals

    return Signals.make(np.linspace(0.0, 2.0 * np.pi, n, endpoint=False))


def _probe_signals(signals, n: int = 2000):
    from wormgear_cli.models.effects import Signals

    step = max(1, signals.theta.shape[0] // n)
    sl = slice(None, None, step)
    theta = np.concatenate([signals.theta[sl], np.linspace(0.0, 2.0 * np.pi, 360, endpoint=False)])
    direction = np.concatenate([signals.direction[sl], np.where(np.arange(360) % 2 == 0, 1.0, -1.0)])
    pad = lambda v, fill: np.concatenate([np.asarray(v)[sl], np.full(360, fill)])  # noqa: E731
    return Signals(theta, direction, pad(signals.load, 0.0), pad(signals.temperature, 20.0), pad(signals.time, 0.0))


def _subset(sig, idx):
    from wormgear_cli.models.effects import Signals

    return Signals(sig.theta[idx], sig.direction[idx], sig.load[idx], sig.temperature[idx], sig.time[idx])


# ============================================================================ candidate effects


@dataclass(frozen=True)
class Candidate:
    """A catalogue effect as design columns.

    ``kind``: "linear" (error = p * column), "reciprocal" (error = column / p,
    a stiffness) or "periodic" (error = A [cos(psi) col_sin + sin(psi) col_cos],
    A the amplitude parameter, psi the phase).  ``columns`` (N, q)
    [arcsec per internal unit]; ``fixed``: the other parameters (internal
    units, e.g. the reference temperature at its catalogue default)."""

    name: str
    kind: str
    columns: np.ndarray
    order: float | None
    needs: str | None
    fixed: dict

    @property
    def q(self) -> int:
        return self.columns.shape[1]


def candidate(name: str, signals, geometry) -> Candidate | None:
    """Design columns of catalogue effect ``name`` from its registry signature.

    The signature is evaluated with its amplitude parameter at 1 (and 2,
    to tell linear from reciprocal), the phase at 0 and 90 deg, every other
    parameter at its catalogue default.  Returns None for a signature that
    is none of the three forms (it cannot be fitted linearly)."""
    from wormgear_cli.models.effects import EFFECTS

    eff = EFFECTS[name]
    base = {}
    for p in eff.params:
        base[p.name] = (p.default if p.default is not None else 0.0) * p.scale
    amp = eff.amplitude
    fixed = {k: v for k, v in base.items() if k not in (amp, eff.phase)}

    def ev(a, ph=None, sig=signals):
        kw = {**base, amp: a}
        if eff.phase is not None:
            kw[eff.phase] = ph if ph is not None else 0.0
        return np.asarray(eff.function(sig, geometry, **kw), dtype=float) * np.ones(sig.theta.shape) / ARCSEC

    order = float(eff.order(geometry)) if eff.order is not None else None
    probe = _probe_signals(signals)
    if eff.phase is not None:
        c_sin = ev(1.0, 0.0, probe)
        c_cos = ev(1.0, math.pi / 2, probe)
        test = ev(2.0, 1.0, probe)
        if not np.allclose(test, 2.0 * (math.cos(1.0) * c_sin + math.sin(1.0) * c_cos),
                           atol=1e-9 * max(1.0, float(np.max(np.abs(test))))):
            return None
        cols = np.column_stack([ev(1.0, 0.0), ev(1.0, math.pi / 2)])
        return Candidate(name, "periodic", cols, order, eff.needs, fixed)
    one, two = ev(1.0, sig=probe), ev(2.0, sig=probe)
    scale = max(1e-300, float(np.max(np.abs(one))))
    if np.allclose(two, 2.0 * one, atol=1e-9 * scale):
        kind = "linear"
    elif np.allclose(two, 0.5 * one, atol=1e-9 * scale):
        kind = "reciprocal"
    else:
        return None
    return Candidate(name, kind, ev(1.0)[:, None], order, eff.needs, fixed)


def candidate_params(cand: Candidate, beta: np.ndarray) -> dict:
    """Internal parameters of an effect from its fitted column coefficients."""
    from wormgear_cli.models.effects import EFFECTS

    eff = EFFECTS[cand.name]
    out = dict(cand.fixed)
    if cand.kind == "periodic":
        out[eff.amplitude] = float(math.hypot(beta[0], beta[1]))
        out[eff.phase] = float(math.atan2(beta[1], beta[0]))
    elif cand.kind == "reciprocal":
        out[eff.amplitude] = float(1.0 / beta[0]) if beta[0] != 0 else math.inf
    else:
        out[eff.amplitude] = float(beta[0])
    return out


# ============================================================================ fitting the model (phases, offset, effects)


@dataclass
class ModelFit:
    """The fitted model at the measured rows.

    ``psi`` [rad] fitted phase of each fittable source; ``beta`` linear
    coefficients (offset [arcsec] first, then effect columns); ``fitted``,
    ``residual`` [arcsec]; ``jac`` (N, m) d fitted / d psi [arcsec/rad];
    ``lin`` (N, l) the linear columns; ``var``: the REML fit of the
    linearised model; ``cost``: residual' V~^-1 residual."""

    psi: np.ndarray
    beta: np.ndarray
    fitted: np.ndarray
    residual: np.ndarray
    jac: np.ndarray
    lin: np.ndarray
    var: VarFit
    cost: float

    @property
    def offset(self) -> float:
        return float(self.beta[0])


def _src_total(sources, sig, psi):
    out = np.zeros(sig.theta.shape)
    for s, p in zip(sources, psi):
        out = out + s.contrib(sig, p)
    return out


def _jacobian(sources, sig, psi, h: float = 1e-5, parts=None):
    """d contribution / d phase [arcsec/rad] per source: central differences, or forward
    differences from the contributions ``parts`` already computed at ``psi``."""
    cols = np.empty((sig.theta.shape[0], len(sources)))
    for j, (s, p) in enumerate(zip(sources, psi)):
        if parts is None:
            cols[:, j] = (s.contrib(sig, p + h) - s.contrib(sig, p - h)) / (2 * h)
        else:
            cols[:, j] = (s.contrib(sig, p + h) - parts[j]) / h
    return cols


def _gls_cost(r, groups, gp, gr):
    cr = Cross(np.zeros((1, 1)), np.zeros(1), float(r @ r), np.zeros((groups.passes, 1)), _pass_sums(r, groups),
               groups)
    return float(cr.weighted([gp], [gr])[2][0])


def _lm(y, sig, groups, base, sources, psi, lin, gp, gr, fit_phases=True, iters=40):
    """Levenberg-Marquardt on the phases and the linear coefficients in the GLS metric."""
    m = len(sources) if fit_phases else 0
    psi = np.array(psi, dtype=float)
    parts = [s.contrib(sig, p) for s, p in zip(sources, psi)]
    src = np.sum(parts, axis=0) if parts else np.zeros(y.shape[0])
    # start with the linear coefficients solved exactly
    r0 = y - base - src
    cr = Cross.build(lin, r0, groups)
    A, b, _, _ = cr.weighted([gp], [gr])
    beta = np.linalg.lstsq(A[0], b[0], rcond=None)[0]
    resid = r0 - lin @ beta
    cost = _gls_cost(resid, groups, gp, gr)
    mu = 1e-3
    for _ in range(iters):
        jac = _jacobian(sources, sig, psi, h=1e-6, parts=parts) if m else np.zeros((y.shape[0], 0))
        design = np.hstack([jac, lin])
        cr = Cross.build(design, resid, groups)
        A, b, _, _ = cr.weighted([gp], [gr])
        A, b = A[0], b[0]
        diag = np.diag(A).copy()
        diag = np.where(diag > 0, diag, 1.0)
        improved = False
        for _ in range(12):
            try:
                step = np.linalg.solve(A + mu * np.diag(diag) + 1e-12 * np.max(diag) * np.eye(len(b)), b)
            except np.linalg.LinAlgError:
                mu *= 10.0
                continue
            psi_new = psi + step[:m]
            beta_new = beta + step[m:]
            parts_new = [s.contrib(sig, p) for s, p in zip(sources, psi_new)] if m else parts
            src_new = np.sum(parts_new, axis=0) if m else src
            resid_new = y - base - src_new - lin @ beta_new
            cost_new = _gls_cost(resid_new, groups, gp, gr)
            if cost_new <= cost:
                rel = (cost - cost_new) / max(cost, 1e-300)
                psi, beta, src, resid, cost, parts = psi_new, beta_new, src_new, resid_new, cost_new, parts_new
                mu = max(mu / 5.0, 1e-12)
                improved = True
                break
            mu *= 8.0
        if not improved or rel < 1e-10:
            break
    return psi, beta, resid, cost


def _harmonic_starts(y, sig, base, sources, spec_psi):
    """Deterministic starting phases: as specified; aligned with the measured
    harmonic at each order; and rotated variants for shafts carrying several sources."""
    from wormgear_cli.harmonics import fit_orders

    starts = [np.array(spec_psi, dtype=float)]
    if not sources:
        return starts
    orders = sorted({s.order for s in sources})
    with np.errstate(invalid="ignore", divide="ignore"):
        fit = fit_orders(sig.theta, y - base, orders)
    measured = {o: fit.phase[i] for i, o in enumerate(orders)}
    circle = _unit_circle(1440)
    intrinsic = []
    for s in sources:
        both = 0.5 * (s.contrib(circle, 0.0)
                      + s.contrib(type(circle)(circle.theta, -circle.direction, circle.load, circle.temperature,
                                                circle.time), 0.0))
        with np.errstate(invalid="ignore", divide="ignore"):
            f0 = fit_orders(circle.theta, both, [s.order])
        intrinsic.append(float(f0.phase[0]) if f0.amplitude[0] > 1e-12 else 0.0)
    rank = {}
    for s in sources:
        rank[s.name] = sum(1 for t in sources if t.order == s.order and sources.index(t) < sources.index(s))
    for spread in (0.0, math.pi):
        starts.append(np.array([measured[s.order] - intrinsic[j] + spread * min(rank[s.name], 1)
                                for j, s in enumerate(sources)]))
    return starts


def _group_scan(y, sig, base, sources, psi, lin, grid: int = 24, sweeps: int = 4, keep: int = 4):
    """Candidate phase vectors found shaft by shaft on a grid (white-noise metric, linear
    columns projected out).

    For the sources sharing an order (at most three at a time; larger groups one
    by one), every combination of ``grid`` phases is scored with the others held:
    the cost of (i_1..i_m) is |r - sum_k c_k(i_k)|^2 after the projection,
    expanded with the Gram matrix of the projected columns, so all grid^m
    combinations cost one small matrix product.  Sweeps repeat until nothing
    moves.  Grid points are only a coarse look at the landscape (a large source
    misplaced by half a step costs more than a wrong basin), so besides the best
    vector the ``keep`` lowest local minima of each shaft's grid are returned,
    for the caller to polish and compare."""
    from wormgear_cli.models.effects import Signals

    psi = np.array(psi, dtype=float)
    if not sources:
        return [psi]
    q, _ = np.linalg.qr(lin)
    sig2 = Signals(sig.theta[:, None], sig.direction[:, None], sig.load[:, None], sig.temperature[:, None],
                   sig.time[:, None])
    phases = np.linspace(0.0, 2.0 * np.pi, grid, endpoint=False)
    by_order: dict = {}
    for k, s in enumerate(sources):
        by_order.setdefault(s.order, []).append(k)
    blocks = []
    for members in by_order.values():
        blocks += [members] if len(members) <= 3 else [[k] for k in members]
    contrib = [s.contrib(sig, p) for s, p in zip(sources, psi)]
    total = np.sum(contrib, axis=0)

    def project(a):
        return a - q @ (q.T @ a)

    def grid_cost(members):
        m = len(members)
        rest = y - base - (total - sum(contrib[k] for k in members))
        cols = [np.broadcast_to(sources[k].contrib(sig2, phases[None, :]), (y.shape[0], grid)) for k in members]
        z = project(np.hstack([*cols, rest[:, None]]))
        gram = z.T @ z
        cost = np.full((grid,) * m, gram[-1, -1])
        for a in range(m):
            shape = [grid if i == a else 1 for i in range(m)]
            cost = cost - 2.0 * gram[a * grid:(a + 1) * grid, -1].reshape(shape)
            for b in range(m):
                blk = gram[a * grid:(a + 1) * grid, b * grid:(b + 1) * grid]
                if a == b:
                    cost = cost + np.diag(blk).reshape(shape)
                else:
                    # G_ab[i_a, i_b] laid out on axes a and b (rows on the lower axis)
                    pair = blk if a < b else blk.T
                    cost = cost + pair.reshape([grid if i in (a, b) else 1 for i in range(m)])
        now = project(rest - sum(contrib[k] for k in members))
        return cost, float(now @ now)

    def move(members, idx):
        nonlocal total
        for a, k in enumerate(members):
            psi[k] = phases[idx[a]]
            new = sources[k].contrib(sig, psi[k])
            total = total - contrib[k] + new
            contrib[k] = new

    for _ in range(sweeps):
        changed = False
        for members in blocks:
            cost, now = grid_cost(members)
            best = np.unravel_index(int(np.argmin(cost)), cost.shape)
            if float(cost[best]) < now * (1.0 - 1e-9):
                move(members, best)
                changed = True
        if not changed:
            break
    out = [psi.copy()]
    for members in blocks:
        cost, _ = grid_cost(members)
        # local minima of the periodic grid (no neighbour lower)
        is_min = np.ones(cost.shape, dtype=bool)
        for axis in range(cost.ndim):
            for shift in (-1, 1):
                is_min &= cost <= np.roll(cost, shift, axis=axis)
        flat = np.flatnonzero(is_min.ravel())
        for j in flat[np.argsort(cost.ravel()[flat])][1:keep]:
            alt = psi.copy()
            for a, k in enumerate(members):
                alt[k] = phases[np.unravel_index(int(j), cost.shape)[a]]
            out.append(alt)
    return out


def fit_model(y, sig, groups, base, sources, spec_psi, lin, fit_phases=True, extra_starts=(),
              variance: VarFit | None = None) -> ModelFit:
    """Fit the phases (if ``fit_phases``) and the linear coefficients of ``lin`` by
    GLS with REML variance components (alternating, at most three rounds).

    The phases start from several deterministic points (:func:`_harmonic_starts`
    plus ``extra_starts``), each refined on a subsample of at most 3000 rows with
    white-noise weights; the best is then refined on every row.  With
    ``variance`` the variance ratios are held at that fit's (no REML)."""
    m = len(sources) if fit_phases else 0
    n = y.shape[0]
    psi = np.array(spec_psi, dtype=float)
    if m:
        step = max(1, n // 2000)
        idx = np.arange(0, n, step)
        sub_sig = _subset(sig, idx)
        one = Groups(np.zeros(idx.shape[0], dtype=int), np.array([float(idx.shape[0])]), np.zeros(1, int),
                     np.ones(1), 1, False, False, "subsample")
        best = None
        starts = [*_harmonic_starts(y[idx], sub_sig, base[idx], sources, spec_psi), *extra_starts]
        inits = [*starts[:1], *extra_starts]
        for start in starts:
            inits += _group_scan(y[idx], sub_sig, base[idx], sources, start, lin[idx], keep=3)
        seen = set()
        for init in inits:
            key = tuple(np.round(np.mod(init, 2 * np.pi), 3))
            if key in seen:
                continue
            seen.add(key)
            p, _, _, c = _lm(y[idx], sub_sig, one, base[idx], sources, init, lin[idx], 0.0, 0.0, True, 25)
            if best is None or c < best[1] - 1e-9 * abs(c):
                best = (p, c)
        psi = best[0]
    if variance is not None:
        psi, beta, resid, cost = _lm(y, sig, groups, base, sources, psi, lin, variance.gp, variance.gr, m > 0)
        jac = _jacobian(sources, sig, psi) if m else np.zeros((n, 0))
        return ModelFit(psi, beta, y - resid, resid, jac, lin, variance, cost)
    gp = gr = 0.0
    var = None
    for _ in range(3):
        psi, beta, resid, cost = _lm(y, sig, groups, base, sources, psi, lin, gp, gr, m > 0)
        jac = _jacobian(sources, sig, psi) if m else np.zeros((n, 0))
        cr = Cross.build(_orthonormal(np.hstack([lin, jac]))[0], resid, groups)
        var = reml(cr)
        done = abs(var.gp - gp) <= 0.05 * max(gp, 1e-9) and abs(var.gr - gr) <= 0.05 * max(gr, 1e-9)
        gp, gr = var.gp, var.gr
        if done:
            break
    else:
        psi, beta, resid, cost = _lm(y, sig, groups, base, sources, psi, lin, gp, gr, m > 0)
        jac = _jacobian(sources, sig, psi) if m else np.zeros((n, 0))
    return ModelFit(psi, beta, y - resid, resid, jac, lin, var, cost)


def _orthonormal(x: np.ndarray, rtol: float = 1e-7):
    """An orthonormal basis (scaled to unit RMS) of the column space of ``x`` and its rank."""
    if x.shape[1] == 0:
        return x, 0
    norms = np.sqrt(np.sum(x * x, axis=0))
    ok = norms > 0
    xs = x[:, ok] / norms[ok]
    u, sv, _ = np.linalg.svd(xs, full_matrices=False)
    keep = sv > rtol * sv[0] if sv.size else np.zeros(0, bool)
    basis = u[:, keep] * math.sqrt(x.shape[0])
    return basis, int(np.count_nonzero(keep))


# ============================================================================ scoring candidates


@dataclass
class Score:
    """One candidate at one selection step.

    ``status``: "tested", "unobservable" (cannot be seen in these data),
    ``reason``: why not; ``remedy``: what measurement would show it;
    ``wald``/``var``: the test and the REML fit of its model; ``p_adj``:
    Bonferroni-adjusted p; ``tolerance``: share of its columns left after
    projecting out the current model (1 = unaffected, 0 = absorbed);
    ``absorbed_by``: model parts that explain its signature;
    column scaling (coefficient = scaled estimate / scale)."""

    name: str
    status: str
    reason: str = ""
    remedy: str = ""
    wald: Wald | None = None
    var: VarFit | None = None
    p_adj: float = math.nan
    tolerance: float = math.nan
    absorbed_by: list = field(default_factory=list)
    containment: float | None = None
    cell_test: bool = False
    same_order: list = field(default_factory=list)
    reach: float = 0.0
    scale: np.ndarray | None = None
    beta: np.ndarray | None = None
    params: dict | None = None
    aliases: list = field(default_factory=list)


@dataclass(frozen=True)
class DataInfo:
    """What varies in the measurement (decides which effects can be seen)."""

    directions: tuple
    temperature_range: float
    temperature_present: bool
    load_range: float
    load_present: bool
    time_range: float
    temperature_time_corr: float
    passes_per_direction: float


def data_info(meas, groups: Groups) -> DataInfo:
    d = tuple(sorted({int(x) for x in np.unique(meas.direction)}, reverse=True))
    t_rng = float(np.ptp(meas.temperature))
    tt = math.nan
    if t_rng > 0 and np.ptp(meas.time) > 0:
        tt = float(np.corrcoef(meas.temperature, meas.time)[0, 1])
    return DataInfo(d, t_rng, "temperature_C" in meas.present, float(np.ptp(meas.load)), "load_Nm" in meas.present,
                    float(np.ptp(meas.time)), tt, groups.passes / max(len(d), 1))


def needs_problem(name: str, needs: str | None, info: DataInfo) -> str | None:
    """Why the data cannot show an effect that needs a varying signal (None: they can)."""
    if needs == "temperature":
        if not info.temperature_present:
            return ("no temperature_C column: record the drive temperature (a sensor on the housing) during a "
                    "warm-up, ideally heating and cooling")
        if info.temperature_range < MIN_TEMPERATURE_RANGE:
            return (f"the temperature varies by only {info.temperature_range:.3g} K: measure through a warm-up "
                    "(several kelvin), ideally heating and cooling")
    if needs == "load":
        if not info.load_present:
            return "no load_Nm column: measure at two or more output torques (load steps)"
        if info.load_range <= 0:
            return "the load does not vary: measure at two or more output torques (load steps)"
    if needs in ("direction", "temperature") and name in ("bearing_clearance", "thermal_backlash"):
        if len(info.directions) < 2:
            return "only one direction measured: lost motion shows only between forward and reverse runs"
    if needs == "direction" and len(info.directions) < 2:
        return "only one direction measured: measure forward and reverse runs"
    return None


REPLICATION_REMEDY = "measure at least 3 runs in each direction"


def replication_problem(cand: "Candidate", basis, groups: Groups, info: DataInfo) -> tuple[str, str] | None:
    """Why, with fewer than MIN_RUNS runs, a candidate cannot be tested (None: it can), and the remedy.

    Its test needs replication between runs when its columns (after the
    model) vary mainly between passes or runs: with one or two runs, scatter
    between passes cannot be estimated and would be taken for the effect.  A
    thermal effect in a monotonic warm-up within so few runs is tied to time
    and angle as well (a drift over time or an angle pattern fits as well)."""
    runs = groups.runs
    plural = "s" if runs != 1 else ""
    res = _residualise(basis, cand.columns)
    if float(np.sum(res * res)) > 1e-12 * float(np.sum(cand.columns**2)):
        run_s, pass_s = _level_shares(res, groups)
        if max(float(np.max(run_s)), float(np.max(pass_s))) > 0.5:
            return (f"it changes mainly between passes, and with {runs} run{plural} the scatter between passes "
                    "cannot be estimated: it would be taken for the effect", REPLICATION_REMEDY)
    corr = info.temperature_time_corr
    if cand.needs == "temperature" and not math.isnan(corr) and abs(corr) > MONOTONIC:
        return (f"with {runs} run{plural}, a monotonic warm-up ties temperature to time and angle (correlation "
                f"{corr:.2f}): a drift over time or an angle pattern fits as well",
                REPLICATION_REMEDY + ", ideally heating and cooling")
    return None


def _residualise(basis, cols):
    """cols minus their least-squares projection on an orthonormal (unit-RMS) basis."""
    if basis.shape[1] == 0:
        return cols
    n = basis.shape[0]
    return cols - basis @ (basis.T @ cols) / n


def _tolerance(basis, cols):
    """Smallest share of a unit direction in span(cols) that survives projection on the basis."""
    norms = np.sqrt(np.sum(cols * cols, axis=0))
    if np.any(norms == 0):
        return 0.0
    cn = cols / norms
    res = _residualise(basis, cn)
    g0 = cn.T @ cn
    g1 = res.T @ res
    # generalised eigenproblem g1 v = lam g0 v: the worst direction inside the column space
    lam0, v0 = np.linalg.eigh(g0)
    if lam0[0] <= 1e-12 * lam0[-1]:
        return 0.0
    w = v0 / np.sqrt(lam0)
    return float(max(np.linalg.eigvalsh(w.T @ g1 @ w)[0], 0.0))


def _canonical(a, b):
    """Largest canonical correlation between the column spaces of a and b."""
    qa = np.linalg.qr(a)[0]
    qb = np.linalg.qr(b)[0]
    return float(np.linalg.svd(qa.T @ qb, compute_uv=False)[0])


def _r2(block, cols):
    """Share of the columns' sum of squares explained by the block (least squares)."""
    if block.shape[1] == 0:
        return 0.0
    coef, *_ = np.linalg.lstsq(block, cols, rcond=None)
    fit = block @ coef
    tot = float(np.sum(cols * cols))
    return float(np.sum(fit * fit) / tot) if tot > 0 else 0.0


def _blocks(lin_names, sources, jac, lin):
    """Named parts of the current model, for saying what absorbs a candidate."""
    out = [(name, lin[:, sl]) for name, sl in lin_names]
    orders = {}
    for j, s in enumerate(sources):
        orders.setdefault(s.order, []).append(j)
    for order, idx in orders.items():
        names = ", ".join(sources[j].name for j in idx)
        out.append((f"the fitted phase{'s' if len(idx) > 1 else ''} of the spec's order-{order:g} "
                    f"source{'s' if len(idx) > 1 else ''} ({names})", jac[:, idx]))
    return out


class Step:
    """Scores of every candidate against the current model (one selection step)."""

    def __init__(self, state: ModelFit, cands: dict, groups: Groups, info: DataInfo, lin_names, sources,
                 alias_notes: dict, alpha: float, cells: Cells, nonlinear: Callable | None = None,
                 few_runs: bool = False):
        self.state = state
        self.groups = groups
        nuis = np.hstack([state.lin, state.jac])
        basis0, _ = _orthonormal(nuis)
        blocks = _blocks(lin_names, sources, state.jac, state.lin)
        self.scores: dict[str, Score] = {}
        self.better_null = None
        # with fewer than MIN_RUNS runs, effects that need replication between runs cannot be tested; they may
        # still be there, so every other candidate is tested with their signatures as nuisance columns
        untestable_cols = []
        if few_runs:
            for name, cand in cands.items():
                if cand is None or needs_problem(name, cand.needs, info) is not None:
                    continue
                if alias_notes.get(name) and any(a[0] == 0.0 for a in alias_notes[name]):
                    continue
                problem = replication_problem(cand, basis0, groups, info)
                if problem is not None:
                    self.scores[name] = Score(name, "untestable", problem[0], problem[1],
                                              aliases=alias_notes.get(name, []))
                    untestable_cols.append(cand.columns)
                    blocks.append((f"{name}'s signature (untestable with {groups.runs} run"
                                   f"{'s' if groups.runs != 1 else ''})", cand.columns))
        self.basis = _orthonormal(np.hstack([nuis, *untestable_cols]))[0] if untestable_cols else basis0
        kb = self.basis.shape[1]
        tested_cols = []
        slices = {}
        nonlinear_names: list[str] = []
        for name, cand in cands.items():
            if name in self.scores:
                continue
            if cand is None:
                self.scores[name] = Score(name, "unobservable", "its signature is not linear in its parameters")
                continue
            why = needs_problem(name, cand.needs, info)
            sc = Score(name, "tested", aliases=alias_notes.get(name, []))
            if why is None and alias_notes.get(name) and any(a[0] == 0.0 for a in alias_notes[name]):
                why = f"order {cand.order:g} falls on a constant at these targets (aliased by the target spacing)"
                sc.remedy = ("use irregular target spacing or a dense scan with more than "
                             f"{2 * cand.order:g} points per revolution")
            same = [s for s in sources if cand.order is not None and abs(s.order - cand.order) < 1e-9
                    and s.amplitude > 1e-9]
            if why is None and same and nonlinear is not None:
                # the spec's sources on this order have fixed sizes and free phases: a linearised test would
                # call any content at this order absorbed; refit the phases with the candidate instead
                sc.same_order = [s.name for s in same]
                sc.reach = float(sum(s.amplitude for s in same))
                F, df, p, beta, better = nonlinear(cand)
                if better is not None:
                    self.better_null = better
                sc.wald = Wald(beta, np.full((cand.q, cand.q), np.nan), F, cand.q, df, p)
                sc.beta = beta
                sc.params = candidate_params(cand, beta)
                nonlinear_names.append(name)
                self.scores[name] = sc
                continue
            if why is None:
                sc.tolerance = _tolerance(self.basis, cand.columns)
                if sc.tolerance < MIN_TOLERANCE:
                    sc.absorbed_by = [label for label, blk in blocks if _r2(blk, cand.columns) > 0.5] or \
                        [label for label, _ in blocks]
                    why = "absorbed by " + " and ".join(sc.absorbed_by)
                    if any("fitted phase" in a for a in sc.absorbed_by):
                        sc.remedy = ("the spec's sources on this shaft take up any content at this order by "
                                     "changing their phases: measure their runout and phase directly (dial "
                                     "indicator), enter the phases in the spec and rerun with --keep-phases")
            if why is not None:
                sc.status = "unobservable"
                if ": " in why and not sc.remedy:
                    why, sc.remedy = why.split(": ", 1)
                sc.reason = why
                self.scores[name] = sc
                continue
            rms = np.sqrt(np.mean(cand.columns**2, axis=0))
            sc.scale = 1.0 / np.where(rms > 0, rms, 1.0)
            sc.containment = containment_df(groups, self.basis, _residualise(self.basis, cand.columns))
            start = kb + sum(c.shape[1] for c in tested_cols)
            slices[name] = slice(start, start + cand.q)
            tested_cols.append(cand.columns * sc.scale)
            self.scores[name] = sc
        self.slices = slices
        self.design = np.hstack([self.basis, *tested_cols]) if tested_cols else self.basis
        self.cross = Cross.build(self.design, state.residual, groups)
        cell_tester = None
        for name, sl in slices.items():
            sc = self.scores[name]
            idx = np.r_[np.arange(kb), np.arange(sl.start, sl.stop)]
            sub = self.cross.take(idx)
            vf = reml(sub)
            w = wald(sub, vf, np.arange(kb, kb + cands[name].q), containment=sc.containment)
            if cells.replicated and cell_level(cands[name].columns, cells):
                # both the mixed-model test and the lack-of-fit-aware cell-means test must agree
                if cell_tester is None:
                    cell_tester = CellTester(cells, self.basis, state.residual)
                _, df_c, p_c = cell_tester.test(cands[name].columns)
                if p_c > w.p:
                    w = Wald(w.estimate, w.cov, w.F, w.q, min(w.df, df_c), p_c)
                    sc.cell_test = True
            sc.wald, sc.var = w, vf
            sc.beta = w.estimate * sc.scale
            sc.params = candidate_params(cands[name], sc.beta)
        tested = [n for n in slices] + nonlinear_names
        self.nonlinear = set(nonlinear_names)
        for n in tested:
            self.scores[n].p_adj = min(1.0, self.scores[n].wald.p * len(tested))
        # forward selection takes the significant candidate that improves the fit most (Wald chi^2 = F q,
        # the drop in GLS residual in units of the noise); insignificant ones follow by p
        def rank(n):
            sc = self.scores[n]
            return (0, -sc.wald.F * sc.wald.q) if sc.p_adj < alpha else (1, sc.wald.p)

        self.tested = sorted(tested, key=rank)
        # how alike the signatures of the tested candidates are, once the model is projected out
        self.similar: dict[tuple, float] = {}
        res = {n: _residualise(self.basis, cands[n].columns) for n in tested}
        for i, a in enumerate(tested):
            for b in tested[i + 1:]:
                self.similar[(a, b)] = self.similar[(b, a)] = _canonical(res[a], res[b])

    def stability(self, resamples: int, alpha: float, seed: int = 0) -> dict[str, float]:
        """Share of cluster-bootstrap resamples (whole runs) in which each tested candidate scores best."""
        g = self.groups
        names = [n for n in self.tested if n in self.slices]
        if g.runs < 3 or not names or resamples <= 0:
            return {}
        z = np.hstack([self.design, self.state.residual[:, None]])
        k = z.shape[1]
        order = np.argsort(g.pass_id, kind="stable")
        bounds = np.searchsorted(g.pass_id[order], np.arange(g.passes + 1))
        grams = np.empty((g.passes, k, k))
        for p in range(g.passes):
            blk = z[order[bounds[p]:bounds[p + 1]]]
            grams[p] = blk.T @ blk
        sums = np.vstack([_pass_sums(z[:, j], g) for j in range(k)]).T
        rng = np.random.default_rng(seed)
        counts = rng.multinomial(g.runs, np.full(g.runs, 1.0 / g.runs), size=resamples).astype(float)
        kb = self.basis.shape[1]
        pvals = np.full((resamples, len(names)), 1.0)
        chi2 = np.zeros((resamples, len(names)))
        for j, name in enumerate(names):
            sc = self.scores[name]
            sl = self.slices[name]
            idx = np.r_[np.arange(kb), np.arange(sl.start, sl.stop)]
            q = sl.stop - sl.start
            for b in range(resamples):
                rc = counts[b]
                pc = rc[g.pass_run]
                gram = np.einsum("p,pij->ij", pc, grams)
                cr = Cross(gram[np.ix_(idx, idx)], gram[idx, k - 1], gram[k - 1, k - 1], sums[:, idx],
                           sums[:, k - 1], g, pc, rc)
                if cr.n - cr.k < 2:
                    continue
                A, bb, c, _ = cr.weighted([sc.var.gp], [sc.var.gr])
                try:
                    beta = np.linalg.solve(A[0], bb[0])
                    inv = np.linalg.inv(A[0])
                except np.linalg.LinAlgError:
                    continue
                s2 = max(float(c[0] - bb[0] @ beta), 1e-300) / (cr.n - cr.k)
                est = beta[kb:]
                cov = s2 * inv[kb:, kb:]
                try:
                    F = float(est @ np.linalg.solve(cov, est)) / q
                except np.linalg.LinAlgError:
                    continue
                chi2[b, j] = F * q
                pvals[b, j] = f_sf(F, q, sc.wald.df)
        # best in a resample: the largest chi^2 among the candidates significant there (else the smallest p)
        sig_ = pvals * len(names) < alpha
        score = np.where(sig_, chi2, -pvals)
        best = np.argmax(np.where(np.any(sig_, axis=1, keepdims=True), np.where(sig_, chi2, -np.inf), score), axis=1)
        return {name: float(np.mean(best == j)) for j, name in enumerate(names)}


def physical_problem(name: str, params: dict) -> str | None:
    """A fitted parameter outside the catalogue's physical range (None: inside)."""
    from wormgear_cli.models.effects import EFFECTS, params_to_keys

    eff = EFFECTS[name]
    keys = params_to_keys(name, params)
    p = eff.param(next(pp.key for pp in eff.params if pp.name == eff.amplitude))
    v = keys[p.key]
    if not math.isfinite(v) or v < p.lo or v > p.hi:
        return f"{p.key} = {v:.4g} {p.unit}, outside its physical range [{p.lo:g}, {p.hi:g}] {p.unit}"
    return None


#: what a significant but unphysical fit of an effect says about the spec
UNPHYSICAL_HINT = {
    "bearing_clearance": "the table shows less lost motion than the spec predicts: the spec's backlash terms "
                         "(thickness deviations, clearances) are larger than the table's",
    "torsional_compliance": "the table winds up less under load than the spec's tooth stiffness predicts",
}


# ============================================================================ the diagnosis


@dataclass
class Found:
    """A named effect: internal ``params``; ``intervals`` catalogue key -> (lo, hi)
    at 95 %; ``p``/``df`` of its test in the final model; ``share``: fraction of the
    gap (mean square residual after step 1) it removed when added; ``stability``:
    share of run resamples in which it scored best (None: not assessed,
    ``stability_note`` says why); ``notes``: caveats (same-order sources,
    correlated candidates); ``separable``: False when its size trades against
    the fitted phases of spec sources on its order (``intervals`` then holds
    the range of sizes that fit as well, the phase none); ``fixed_keys``:
    catalogue keys held at their defaults (reference temperatures)."""

    name: str
    kind: str
    params: dict
    intervals: dict
    p: float
    p_adj: float
    df: float
    share: float
    stability: float | None
    step: int
    notes: list = field(default_factory=list)
    indistinguishable_from: list = field(default_factory=list)
    signature_rms: float = 0.0
    stability_note: str = ""
    separable: bool = True
    fixed_keys: list = field(default_factory=list)


@dataclass
class Diagnosis:
    """Everything ``wormgear diagnose`` reports (angles in arcsec)."""

    spec: object
    meas: object
    groups: Groups
    info: DataInfo
    sources: list
    fit_phases: bool
    alpha: float
    as_specified: np.ndarray
    simulated_spec: np.ndarray
    before: ModelFit
    after: ModelFit
    found: list
    candidates: dict
    steps: list
    stop: dict
    unexplained: list
    augmented: dict
    augmented_fitted: np.ndarray
    thermal_prediction: float | None
    few_runs: bool = False
    noise_floor: float = math.nan
    likely: dict | None = None


def _alias_notes(theta, cands: dict, sources, geometry) -> dict:
    """Per periodic candidate: the orders it cannot be told from at these angles, as (order, label)."""
    from wormgear_cli.harmonics import alias_groups, folded_orders, physical_orders

    labels = {o: lab for o, lab in physical_orders(geometry, 3)}
    for s in sources:
        labels.setdefault(s.order, s.name)
    orders = sorted({*labels, *(c.order for c in cands.values() if c is not None and c.order is not None)})
    groups = alias_groups(theta, orders)
    folded = set(folded_orders(theta, orders))
    out = {}
    for name, c in cands.items():
        if c is None or c.order is None:
            continue
        notes = []
        for grp in groups:
            if c.order in grp:
                notes += [(o, "a constant" if o == 0 else labels.get(o, f"order {o:g}")) for o in grp if o != c.order]
        if c.order in folded and not any(o == 0.0 for o, _ in notes):
            notes.append((c.order, "its own mirror (only one phase component is sampled)"))
        out[name] = notes
    return out


def diagnose(spec, meas, alpha: float = 0.01, fit_phases: bool = True, max_effects: int = 4,
             resamples: int = 50, progress: Callable | None = None) -> Diagnosis:
    """Fit the spec to a measurement, name the missing catalogue effects, refit.

    Parameters
    ----------
    spec : a loaded drive (:class:`wormgear_cli.spec.Spec`)
    meas : a :class:`wormgear_cli.measurement.Measurement` with measured errors
    alpha : family-wise significance level per selection step (0 < alpha < 0.5)
    fit_phases : False holds the spec's phases (when they are known), fitting
        only the zero offset and effects
    max_effects : most effects to name (>= 0)
    resamples : cluster-bootstrap resamples of whole runs for the stability check
    progress : optional callable(str) told about each stage

    See the module docstring for the model and the selection rules.  Raises
    UsageError for bad options and DataError for data it cannot use.
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        return _diagnose(spec, meas, alpha, fit_phases, max_effects, resamples, progress)


def _diagnose(spec, meas, alpha, fit_phases, max_effects, resamples, progress) -> Diagnosis:
    from wormgear_cli.analysis import geometry as drive_geometry
    from wormgear_cli.models.effects import EFFECTS
    from wormgear_cli.simulation import simulate

    if not (0.0 < alpha < 0.5):
        raise UsageError(f"--alpha: expected a number in (0, 0.5), got {alpha:g}")
    if max_effects < 0:
        raise UsageError(f"--max-effects: expected an integer >= 0, got {max_effects}")
    if np.any(np.isnan(meas.error)):
        raise DataError(f"{meas.source}: no error_arcsec column; diagnose needs measured errors")
    say = progress or (lambda text: None)
    sig = meas.signals()
    y = meas.error / ARCSEC
    n = y.shape[0]
    g = drive_geometry(spec)
    groups = make_groups(meas.direction, meas.run if "run" in meas.present else None)
    few_runs = groups.runs < MIN_RUNS
    if few_runs:
        # one or two runs: scatter between runs and passes cannot be estimated (a variance from one run is
        # meaningless); the noise is taken as white and effects that need replication are not tested
        plural = "s" if groups.runs != 1 else ""
        groups = Groups(groups.pass_id, groups.pass_size, groups.pass_run, groups.pass_direction, groups.runs,
                        False, False, groups.describe.split(";")[0] + f"; {groups.runs} run{plural}, fewer than "
                        f"{MIN_RUNS}: scatter between runs and passes cannot be estimated, noise taken as white")
    info = data_info(meas, groups)
    fittable, _ = phase_sources(spec, g, sig)
    sources = fittable if fit_phases else []
    cells = make_cells(sig.theta, sig.direction)
    simulated_spec = simulate(spec, sig) / ARCSEC
    base = simulated_spec - (_src_total(sources, sig, [s.phase for s in sources]) if sources else 0.0)
    spec_psi = [s.phase for s in sources]
    if n < len(sources) + 4:
        raise DataError(f"{meas.source}: {n} rows are too few to fit {len(sources)} phase"
                        f"{'s' if len(sources) != 1 else ''} and a zero offset with noise to spare; need at least "
                        f"{len(sources) + 4} rows (more targets or runs)")
    say("fitting phases and offset")
    lin = np.ones((n, 1))
    lin_names = [("the zero offset", slice(0, 1))]
    state = fit_model(y, sig, groups, base, sources, spec_psi, lin, fit_phases)
    before = state
    rss_before = float(before.residual @ before.residual)
    cands = {name: candidate(name, sig, g) for name in EFFECTS if name not in spec.effects}
    alias_notes = _alias_notes(sig.theta, cands, sources, g)
    accepted: list = []
    steps = []
    final_scores: dict[str, Score] = {}
    stop: dict = {}
    remaining = dict(cands)
    redo = 0
    while True:
        say(f"scoring {len(remaining)} candidate effects (step {len(steps) + 1})")
        current, current_lin = state, lin

        def nonlinear(cand, current=current, current_lin=current_lin):
            return _nonlinear_test(y, sig, groups, base, sources, spec_psi, current, current_lin, cand, cells)

        step = Step(state, remaining, groups, info, lin_names, sources, alias_notes, alpha, cells,
                    nonlinear if fit_phases else None, few_runs=few_runs)
        if step.better_null is not None and redo < 3:
            # a same-order refit showed the phase fit sat in a local minimum: refit from there, score again
            redo += 1
            state = fit_model(y, sig, groups, base, sources, spec_psi, lin, fit_phases,
                              extra_starts=[step.better_null])
            if not accepted:
                before = state
                rss_before = float(before.residual @ before.residual)
            continue
        for name, sc in step.scores.items():
            final_scores[name] = sc
        record = {"step": len(steps) + 1, "tested": len(step.tested),
                  "scores": [{"name": nm, "F": step.scores[nm].wald.F, "df": step.scores[nm].wald.df,
                              "p": step.scores[nm].wald.p, "p_adjusted": step.scores[nm].p_adj}
                             for nm in step.tested]}
        steps.append(record)
        if not step.tested:
            stop = {"reason": "nothing left to test"} if accepted else {"reason": "no candidate is observable"}
            break
        best = step.tested[0]
        sc = step.scores[best]
        if sc.p_adj >= alpha:
            stop = {"reason": "no further candidate is significant", "best": best, "p_adjusted": sc.p_adj}
            break
        if len(accepted) >= max_effects:
            stop = {"reason": f"--max-effects {max_effects} reached", "best": best}
            break
        twins = [o for o in step.tested if o != best and step.similar.get((best, o), 0) >= INDISTINGUISHABLE
                 and step.scores[o].p_adj < alpha]
        if twins:
            stop = {"reason": "ambiguous", "candidates": [best, *twins],
                    "correlation": max(step.similar[(best, o)] for o in twins)}
            break
        problem = physical_problem(best, sc.params)
        if problem:
            stop = {"reason": "unphysical", "candidate": best, "detail": problem,
                    "hint": UNPHYSICAL_HINT.get(best, "")}
            break
        stab, stab_note = {}, ""
        if best in step.nonlinear:
            stab_note = ("not assessed: its test refits the phases of the spec's sources on its order, which "
                         "resampling does not repeat")
        elif resamples <= 0:
            stab_note = "not assessed (--resamples 0)"
        elif groups.runs < MIN_RUNS:
            stab_note = (f"not assessed: {groups.runs} run{'s' if groups.runs != 1 else ''}; resampling whole "
                         f"runs needs at least {MIN_RUNS}")
        else:
            say(f"checking {best} on {resamples} resamples of whole runs")
            stab = step.stability(resamples, alpha)
        frac = stab.get(best) if stab else None
        if frac is not None and frac < MIN_STABILITY:
            rivals = sorted(((v, k) for k, v in stab.items() if k != best and v > 0), reverse=True)
            stop = {"reason": "unstable", "candidate": best, "stability": frac,
                    "rivals": [{"name": k, "share": v} for v, k in rivals]}
            break
        near = [(o, step.similar[(best, o)]) for o in step.tested if o != best
                and step.similar.get((best, o), 0.0) >= NEARLY]
        cand = remaining[best]
        start = lin.shape[1]
        new_lin = np.hstack([lin, cand.columns])
        prev_rss = float(state.residual @ state.residual)
        say(f"refitting with {best}")
        new_state = fit_model(y, sig, groups, base, sources, spec_psi, new_lin, fit_phases,
                              extra_starts=[state.psi])
        new_rss = float(new_state.residual @ new_state.residual)
        if not new_rss < prev_rss * (1.0 - 1e-9):
            # significant in the GLS metric, yet the gap grows once everything is refitted: the estimate follows
            # structure that is not its signature (typically the random effects absorb what it gets wrong)
            stop = {"reason": "worsens", "candidate": best, "p_adjusted": sc.p_adj,
                    "rms_before_arcsec": math.sqrt(prev_rss / n), "rms_with_arcsec": math.sqrt(new_rss / n)}
            record["rejected"] = best
            break
        record["accepted"] = best
        remaining.pop(best)
        lin = new_lin
        lin_names.append((best, slice(start, start + cand.q)))
        state = new_state
        accepted.append((best, cand, sc, frac, len(steps), (prev_rss - new_rss) / rss_before if rss_before else 0.0,
                         near, stab_note))
    after = state
    found = _final_inference(after, accepted, lin_names, groups, fittable, fit_phases)
    for f in found:
        final_scores[f.name] = Score(f.name, "named")
    for f in found:
        if not f.separable:
            say(f"profiling the size of {f.name} against the phases of its shaft's sources")
            cand = next(a[1] for a in accepted if a[0] == f.name)
            sl = next(sl_ for nm, sl_ in lin_names if nm == f.name)
            _same_order_range(f, y, sig, groups, base, sources, after, lin, sl, cand, g)
    likely = None
    if stop.get("reason") in ("no further candidate is significant", f"--max-effects {max_effects} reached") \
            and stop.get("best") in remaining and stop["best"] in step.slices:
        best = stop["best"]
        sc = step.scores[best]
        if sc.p_adj < min(NEAR_FACTOR * alpha, 0.5) or stop["reason"].startswith("--max-effects"):
            say(f"checking whether {best} is a likely further effect")
            likely = _likely_effect(y, sig, groups, base, sources, spec_psi, after, lin, lin_names, accepted, found,
                                    best, remaining[best], sc, fittable, fit_phases, len(steps))
            if likely is not None:
                final_scores[best].status = "likely"
    say("scanning the residual for structure")
    unexplained = _scan(after, sig, groups, g, alpha, info, sources, cells)
    floor = _noise_floor_rms(after, groups, sig.time if "time_s" in meas.present else None)
    unexplained = _annotate(unexplained, final_scores, groups, few_runs, likely, after, floor, g)
    augmented, aug_fitted = _augment(spec, sig, after, sources, found, fit_phases, y)
    thermal = None
    try:
        from wormgear_cli.models.thermal import predicted_centre_distance_um_per_K

        thermal = float(predicted_centre_distance_um_per_K(spec))
    except (ImportError, AttributeError):
        thermal = None
    return Diagnosis(spec, meas, groups, info, sources, fit_phases, alpha, y - simulated_spec, simulated_spec,
                     before, after, found, final_scores, steps, stop, unexplained, augmented, aug_fitted, thermal,
                     few_runs, floor, likely)


def _nonlinear_test(y, sig, groups, base, sources, spec_psi, state: ModelFit, lin, cand: Candidate, cells: Cells):
    """(F, df, p, coefficients) of a candidate that shares its order with sources whose phases are fitted.

    Refits the phases with the candidate's columns added and compares the GLS
    residual (at the current variance ratios): F = (cost0 - cost1) / q /
    (cost1 / (n - k1)), k1 the phases plus linear columns.  With repeated
    runs the same comparison on the cell means (lack of fit as error) must
    agree; the larger p is kept."""
    gp, gr = state.var.gp, state.var.gr
    lin1 = np.hstack([lin, cand.columns])
    # the candidate's columns are linear: from the null optimum (candidate at zero) the refit moves continuously
    psi1, beta1, resid1, cost1 = _lm(y, sig, groups, base, sources, state.psi, lin1, gp, gr, True)
    n = y.shape[0]
    q = cand.q
    k1 = lin1.shape[1] + len(sources)
    cost0 = _gls_cost(state.residual, groups, gp, gr)
    # the refit may have found phases the null fit missed: the null must get the same chance
    psi0, _, resid0, c0 = _lm(y, sig, groups, base, sources, psi1, lin, gp, gr, True)
    better = None
    if c0 < cost0 * (1.0 - 1e-6):
        better = psi0
        cost0 = c0
        state_resid = resid0
    else:
        state_resid = state.residual
    dof = max(n - k1, 1)
    F = max(cost0 - cost1, 0.0) / q / max(cost1 / dof, 1e-300)
    p = f_sf(F, q, dof)
    df = float(dof)
    if cells.replicated and cells.cells - k1 > 0:
        m0, m1 = cells.means(state_resid), cells.means(resid1)
        r0, r1 = float(m0 @ m0), float(m1 @ m1)
        dfc = cells.cells - k1
        Fc = max(r0 - r1, 0.0) / q / max(r1 / dfc, 1e-300)
        pc = f_sf(Fc, q, dfc)
        if pc > p:
            F, p, df = Fc, pc, float(dfc)
    return F, df, p, beta1[lin.shape[1]:], better


def _final_inference(state: ModelFit, accepted, lin_names, groups, sources, fit_phases=True) -> list[Found]:
    """Each named effect tested and bounded in the final model (every other term as nuisance)."""
    from wormgear_cli.models.effects import EFFECTS, params_to_keys

    if not accepted:
        return []
    lin = state.lin
    nuis, _ = _orthonormal(np.hstack([lin[:, :1], state.jac]))
    kb = nuis.shape[1]
    eff_cols = lin[:, 1:]
    rms = np.sqrt(np.mean(eff_cols**2, axis=0))
    scale = 1.0 / np.where(rms > 0, rms, 1.0)
    y_lin = state.residual + eff_cols @ state.beta[1:]
    cross = Cross.build(np.hstack([nuis, eff_cols * scale]), y_lin, groups)
    vf = reml(cross)
    vinfo = _variance_info(cross, vf)
    out = []
    design = np.hstack([nuis, eff_cols * scale])
    for (name, cand, sc, frac, step_no, share, near, stab_note), (_, sl) in zip(accepted, lin_names[1:]):
        idx = np.arange(kb + sl.start - 1, kb + sl.stop - 1)
        rest = np.delete(design, idx, axis=1)
        cont = containment_df(groups, rest, _residualise(_orthonormal(rest)[0], design[:, idx]))
        w = wald(cross, vf, idx, containment=cont, info=vinfo)
        sc_ = scale[sl.start - 1:sl.stop - 1]
        beta = state.beta[sl]
        cov = w.cov * np.outer(sc_, sc_)
        params = candidate_params(cand, beta)
        eff = EFFECTS[name]
        amp_key = next(p.key for p in eff.params if p.name == eff.amplitude)
        amp_p = eff.param(amp_key)
        intervals = {}
        if cand.kind == "periodic":
            amp = math.hypot(beta[0], beta[1])
            u = np.array([beta[0], beta[1]]) / amp if amp > 0 else np.array([1.0, 0.0])
            perp = np.array([-u[1], u[0]])
            se_amp = math.sqrt(max(float(u @ cov @ u), 0.0))
            se_ph = math.sqrt(max(float(perp @ cov @ perp), 0.0)) / amp if amp > 0 else math.inf
            full = np.zeros(cross.k)
            full[idx] = u / sc_
            df_a = contrast_df(vf, full, vinfo, w.df)
            tq = t_ppf(0.975, df_a)
            lo, hi = max(amp - tq * se_amp, 0.0), amp + tq * se_amp
            intervals[amp_key] = (lo / amp_p.scale, hi / amp_p.scale)
            ph = params[eff.phase]
            ph_key = next(p.key for p in eff.params if p.name == eff.phase)
            ph_scale = eff.param(ph_key).scale
            intervals[ph_key] = ((ph - tq * se_ph) / ph_scale, (ph + tq * se_ph) / ph_scale)
        else:
            se = math.sqrt(max(float(cov[0, 0]), 0.0))
            tq = t_ppf(0.975, w.df)
            lo, hi = beta[0] - tq * se, beta[0] + tq * se
            if cand.kind == "reciprocal":
                lo, hi = (1.0 / hi if hi > 0 else math.inf), (1.0 / lo if lo > 0 else math.inf)
                if lo > hi:
                    lo, hi = hi, lo
            intervals[amp_key] = (lo / amp_p.scale, hi / amp_p.scale)
        same_fitted = fit_phases and cand.order is not None and any(
            abs(s.order - cand.order) < 1e-9 and s.amplitude > 1e-9 for s in sources)
        if same_fitted:
            # traded against the fitted phases of the sources on this order: no meaningful interval
            intervals = {}
            w = Wald(w.estimate, w.cov, sc.wald.F, sc.wald.q, sc.wald.df, sc.wald.p)
        f = Found(name, cand.kind, params, intervals, w.p, min(1.0, w.p * len(accepted)), w.df, share, frac,
                  step_no, stability_note=stab_note, separable=not same_fitted,
                  fixed_keys=[p.key for p in eff.params if p.name in cand.fixed])
        f.signature_rms = float(np.sqrt(np.mean((lin[:, sl] @ beta) ** 2)))
        if cand.order is not None:
            same = [s.name for s in sources if abs(s.order - cand.order) < 1e-9 and s.amplitude > 1e-9]
            if same and fit_phases:
                # the note with the range of sizes that fit as well is added by _same_order_range
                f.indistinguishable_from += same
            elif same:
                f.notes.append(f"shares order {cand.order:g} with the spec's {', '.join(same)}, held at their "
                               f"specified phases: naming it relies on those phases being right; a larger "
                               + " or ".join(same) + " at another phase would fit as well")
                f.indistinguishable_from += same
        for other, corr in near:
            f.notes.append(f"its signature correlates {corr:.3f} with {other}'s once the rest of the model is "
                           f"accounted for: {other} was tested and fits worse")
            if corr >= INDISTINGUISHABLE:
                f.indistinguishable_from.append(other)
        out.append(f)
    return out


def _same_order_range(f: Found, y, sig, groups, base, sources, state: ModelFit, lin, sl, cand: Candidate,
                      geometry, steps: int = 5) -> None:
    """Sizes of an effect on the order of spec sources with fitted phases that fit as well as the best.

    The effect becomes one more periodic source of fixed size a with a free
    phase; for each a the phases of the spec's sources on that order and the
    effect's are refitted (the other sources held at their fitted phases, the
    variance ratios at the final fit's) and the GLS cost c(a) is recorded.
    Sizes with c(a) <= c_min (1 + t^2 / dof) (t: 97.5 % quantile of Student's t;
    the profile-likelihood 95 % region) fit as well: the lower end by bisection
    between 0 and the fitted size, the upper end by bisection beyond it.  Sets
    ``f.intervals`` to that range of the amplitude key (the phase has none) and
    adds a note."""
    from wormgear_cli.models.effects import EFFECTS

    eff = EFFECTS[cand.name]
    same = [j for j, src in enumerate(sources) if abs(src.order - cand.order) < 1e-9]
    other = [j for j in range(len(sources)) if j not in same]
    n = y.shape[0]
    base2 = base + sum((sources[j].contrib(sig, state.psi[j]) for j in other), np.zeros(n))
    lin2 = np.delete(lin, np.arange(sl.start, sl.stop), axis=1)
    dof = max(n - lin.shape[1] - len(sources), 1)
    a_fit, ph_fit = float(f.params[eff.amplitude]), float(f.params[eff.phase])
    unit = math.sqrt(float(np.mean(np.sum(cand.columns**2, axis=1))))  # arcsec per internal unit of size
    reach = float(sum(sources[j].amplitude for j in same))
    span = max(reach / unit if unit > 0 else 0.0, a_fit, 1e-12)
    same_src = [sources[j] for j in same]
    costs: dict[float, float] = {}

    def cost(a: float) -> float:
        if a not in costs:
            if a <= 0.0:
                start = np.asarray(state.psi)[same]
                srcs = same_src
            else:
                start = np.r_[np.asarray(state.psi)[same], ph_fit]
                srcs = [*same_src, PhaseSource(f"effect:{cand.name}", "", float(cand.order), a * unit, ph_fit,
                                               _effect_contrib(eff, {**cand.fixed, eff.amplitude: a}, geometry))]
            fm = fit_model(y, sig, groups, base2, srcs, start, lin2, True, extra_starts=[start], variance=state.var)
            costs[a] = float(fm.cost)
        return costs[a]

    factor = 1.0 + t_ppf(0.975, dof) ** 2 / dof

    def fits(a: float) -> bool:
        c = cost(a)
        return c <= min(costs.values()) * factor

    def edge(inside: float, outside: float) -> float:
        """Bisect towards the boundary between a size that fits and one that does not;
        returns the last size found to fit."""
        for _ in range(steps):
            m = 0.5 * (inside + outside)
            if fits(m):
                inside = m
            else:
                outside = m
        return inside

    cost(a_fit)
    lo = 0.0 if fits(0.0) else edge(a_fit, 0.0)
    a, b = a_fit, a_fit + span
    open_ended = False
    for _ in range(3):
        if not fits(b):
            break
        a, b = b, b + span
    else:
        open_ended = True
    hi = b if open_ended else edge(a, b)
    amp_key = next(p.key for p in eff.params if p.name == eff.amplitude)
    amp_p = eff.param(amp_key)
    f.intervals = {amp_key: (lo / amp_p.scale, hi / amp_p.scale)}
    names = [sources[j].name for j in same]
    f.notes.append(
        f"shares order {cand.order:g} with the spec's {', '.join(names)}, whose phases are fitted: its size trades "
        f"against their phases, so any {amp_key} from {lo / amp_p.scale:.3g} to {hi / amp_p.scale:.3g} {amp_p.unit}"
        f"{' or more' if open_ended else ''} fits as well (95 % profile of the fit) and its phase is not determined; "
        f"a larger {' or '.join(names)} would fit as well. To separate them, measure the runout and phase of "
        "those parts directly (dial indicator), enter the phases in the spec and rerun with --keep-phases")


def _likely_effect(y, sig, groups, base, sources, spec_psi, state: ModelFit, lin, lin_names, accepted, found,
                   name: str, cand: Candidate, sc: Score, fittable, fit_phases, step_no) -> dict | None:
    """A candidate that missed the significance level narrowly (or the --max-effects limit): refit with it.

    When it would remove at least NEAR_SHARE of the remaining mean-square gap
    it is reported as a likely further effect, and every named effect's
    interval is widened to cover its interval in that larger model too (the
    named effect's estimate may be biased by what is left out).  Returns the
    report entry, or None."""
    n = y.shape[0]
    rss = float(state.residual @ state.residual)
    alt_lin = np.hstack([lin, cand.columns])
    alt = fit_model(y, sig, groups, base, sources, spec_psi, alt_lin, fit_phases, extra_starts=[state.psi])
    rss_alt = float(alt.residual @ alt.residual)
    gain = (rss - rss_alt) / rss if rss > 0 else 0.0
    if not gain >= NEAR_SHARE:
        return None
    alt_names = [*lin_names, (name, slice(lin.shape[1], lin.shape[1] + cand.q))]
    alt_found = _final_inference(alt, [*accepted, (name, cand, sc, None, step_no, gain, [], "")], alt_names, groups,
                                 fittable, fit_phases)
    by = {f.name: f for f in alt_found}
    extra = by[name]
    if physical_problem(name, extra.params):
        return None
    for f in found:
        other = by.get(f.name)
        if other is None or not f.separable:
            continue
        for key, (lo, hi) in list(f.intervals.items()):
            if key in other.intervals:
                lo2, hi2 = other.intervals[key]
                f.intervals[key] = (min(lo, lo2), max(hi, hi2))
        est = augmented_params(other)
        values = ", ".join(f"{k} = {est[k]:.4g} [{lo:.4g}, {hi:.4g}]" for k, (lo, hi) in other.intervals.items())
        f.notes.append(f"with {name} also in the model (a likely further effect, see unexplained) it would be "
                       f"{values}; its interval covers both models")
    return {"name": name, "p_adjusted": sc.p_adj, "gain": gain, "rms_now": math.sqrt(rss / n),
            "rms_with": math.sqrt(rss_alt / n), "parameters": augmented_params(extra),
            "interval_95": {k: [float(lo), float(hi)] for k, (lo, hi) in extra.intervals.items()}}


def short_term_noise(resid: np.ndarray, groups: Groups, time: np.ndarray | None = None) -> float:
    """Point-to-point noise [arcsec]: robust standard deviation (1.4826 x median absolute value) of the
    differences of consecutive rows within a pass (in time order), over sqrt(2).  Offsets per pass or
    run cancel; structure that changes slowly along a pass adds little.  NaN without such pairs."""
    t = np.arange(resid.shape[0], dtype=float) if time is None else np.asarray(time, dtype=float)
    order = np.lexsort((np.arange(resid.shape[0]), t, groups.pass_id))
    pid = groups.pass_id[order]
    diff = np.diff(resid[order])[pid[1:] == pid[:-1]]
    if diff.shape[0] < 3:
        return math.nan
    return float(1.4826 * np.median(np.abs(diff)) / math.sqrt(2.0))


def _noise_floor_rms(state: ModelFit, groups: Groups, time=None) -> float:
    """The noise the data establish [arcsec]: point-to-point noise within passes, plus the fitted scatter
    between passes and runs where it can be estimated (at least MIN_RUNS runs)."""
    short = short_term_noise(state.residual, groups, time)
    if not math.isfinite(short):
        short = state.var.s_white
    between = state.var.sigma2 * (state.var.gp + state.var.gr) if groups.runs >= MIN_RUNS else 0.0
    return math.sqrt(short**2 + between)


#: the catalogue effect whose signature a pattern of the residual scan is
def _signature_of(item: dict, geometry) -> str | None:
    from wormgear_cli.models.effects import EFFECTS

    if item["kind"] == "reversal":
        return "bearing_clearance"
    if item["kind"] == "trend":
        return {("temperature_C", "differential"): "thermal_backlash", ("temperature_C", "common"): "thermal_drift",
                ("load_Nm", "common"): "torsional_compliance"}.get((item["signal"], item["mode"]))
    if item["kind"] == "order" and item["mode"] == "common":
        for name, eff in EFFECTS.items():
            if eff.order is not None and abs(float(eff.order(geometry)) - item["order"]) < 1e-9:
                return name
    return None


def _pattern(name: str, geometry) -> tuple[str, str]:
    """(mode, words) of a catalogue effect's signature."""
    from wormgear_cli.models.effects import EFFECTS

    eff = EFFECTS[name]
    if name == "thermal_backlash":
        return "differential", "a differential-mode trend with temperature (the reversal changing as it warms)"
    if name == "bearing_clearance":
        return "differential", "a change of the mean reversal"
    if name == "thermal_drift":
        return "common", "a common-mode trend with temperature"
    if name == "torsional_compliance":
        return "common", "a common-mode trend with load"
    if eff.order is not None:
        return "common", f"order {float(eff.order(geometry)):g} content in common mode"
    return "common", eff.doc


def _annotate(items: list, scores: dict, groups: Groups, few_runs: bool, likely: dict | None, state: ModelFit,
              floor: float, geometry) -> list:
    """Add to the scan's items what the run structure and the candidates say about them: a pattern that is
    the signature of a candidate these data cannot test, the caveat of few runs, a likely further effect,
    and a residual far above the noise floor."""
    runs = groups.runs
    for item in items:
        name = _signature_of(item, geometry)
        if name == "bearing_clearance" and item.get("mean_reversal_change_arcsec", 0.0) < 0.0:
            name = None  # less lost motion than modelled is not a clearance
        sc = scores.get(name) if name else None
        if item["kind"] == "reversal" and scores.get("thermal_backlash") is not None and \
                scores["thermal_backlash"].status == "untestable" and (sc is None or sc.status != "untestable"):
            name, sc = "thermal_backlash", scores["thermal_backlash"]  # a warm-up changes the reversal between passes
        if sc is not None and sc.status == "untestable":
            item["untestable_candidate"] = name
            item["explanation"] += (f"; it is {name}'s signature, which {runs} run{'s' if runs != 1 else ''} "
                                    f"cannot test: {sc.remedy}")
        elif few_runs and item["kind"] in ("trend", "reversal"):
            item["explanation"] += (f"; with {runs} run{'s' if runs != 1 else ''} it cannot be told from scatter "
                                    f"between passes: {REPLICATION_REMEDY}")
    out = list(items)
    if likely is not None:
        mode, words = _pattern(likely["name"], geometry)
        item = {"kind": "likely_effect", "mode": mode, "p_adjusted": likely["p_adjusted"], "name": likely["name"],
                "parameters": likely["parameters"], "interval_95": likely["interval_95"],
                "rms_arcsec": likely["rms_now"], "rms_with_arcsec": likely["rms_with"]}
        item["explanation"] = (f"{words}: {likely['name']} would explain it (adjusted p = "
                               f"{likely['p_adjusted']:.2g}, short of the level) and would bring the RMS gap from "
                               f"{likely['rms_now']:.3g} to "
                               f"{likely['rms_with']:.3g} arcsec: a likely further effect; more runs would settle it")
        out.insert(0, item)
    rms = float(np.sqrt(np.mean(state.residual**2)))
    if math.isfinite(floor) and floor > 0 and rms > EXCESS_FACTOR * floor:
        words = ("point-to-point noise within passes" if few_runs or groups.runs < MIN_RUNS
                 else "point-to-point noise within passes and the scatter between passes and runs")
        out.append({"kind": "excess", "mode": "all", "p_adjusted": None, "rms_arcsec": rms,
                    "noise_floor_arcsec": floor,
                    "explanation": f"the residual ({rms:.3g} arcsec RMS) is {rms / floor:.1f} times the noise floor "
                                   f"({floor:.3g} arcsec, {words}): the model still misses something"
                                   + ("" if items or likely else "; no single order or trend stands out")})
    return out


# ============================================================================ what no catalogue effect explains


def _scan(state: ModelFit, sig, groups, geometry, alpha, info: DataInfo, sources, cells: Cells) -> list[dict]:
    """Significant structure left in the residual: harmonics at physical and low
    orders (common and differential mode), trends against temperature, load and
    time, and a mean reversal; Bonferroni over every test made."""
    from wormgear_cli.harmonics import physical_orders
    from wormgear_cli.iso230 import group_targets

    from wormgear_cli.models.effects import EFFECTS

    catalogue_orders = [float(e.order(geometry)) for e in EFFECTS.values() if e.order is not None]
    r = state.residual
    basis, _ = _orthonormal(np.hstack([state.lin, state.jac]))
    part = (basis.T @ basis, basis.T @ r, _pass_sums(basis, groups) if basis.shape[1] else np.zeros((groups.passes, 0)))
    theta, d = sig.theta, sig.direction
    both = len(info.directions) == 2
    labels = dict(physical_orders(geometry, 3))
    n_targets = int(group_targets(theta)[1].shape[0])
    top = min(30, n_targets // 2)
    orders = sorted({*map(float, range(1, top + 1)), *labels})
    keep, _ = resolvable_orders(theta, orders)
    tests = []
    for o in keep:
        c = np.column_stack([np.cos(o * theta), np.sin(o * theta)])
        tests.append(("order", o, "common", c))
        if both:
            tests.append(("order", o, "differential", c * d[:, None]))
    signals = [("temperature_C", sig.temperature, info.temperature_range >= MIN_TEMPERATURE_RANGE, "K"),
               ("load_Nm", sig.load, info.load_range > 0, "N m"),
               ("time_s", sig.time, info.time_range > 0, "s")]
    for name, values, varies, unit in signals:
        if not varies:
            continue
        col = (values - np.mean(values))[:, None]
        tests.append(("trend", name, "common", col))
        if both:
            tests.append(("trend", name, "differential", col * d[:, None]))
    if both:
        tests.append(("reversal", None, "differential", d[:, None].astype(float)))
    m = len(tests)
    out = []
    kb = basis.shape[1]
    btb, btr, sb = part
    sr = _pass_sums(r, groups)
    results = []
    chunk: list = []
    partial_dirs: dict = {}

    def flush():
        # residualise a block of test columns on the model at once, then test each set
        if not chunk:
            return
        big = np.hstack([c[3] for c in chunk])
        res = _residualise(basis, big)
        gram = res.T @ res
        rr = res.T @ r
        ps = _pass_sums(res, groups)
        norms = np.sum(big * big, axis=0)
        j = 0
        for kind, what, mode, cols in chunk:
            q = cols.shape[1]
            sl = slice(j, j + q)
            j += q
            g = gram[sl, sl]
            lam, vec = np.linalg.eigh(g)
            keep = lam > 1e-6 * float(np.mean(norms[sl]))
            if not np.any(keep):
                continue
            rot = np.eye(1) if q == 1 else vec[:, keep]
            k2 = rot.shape[1]
            xtx = np.zeros((kb + k2, kb + k2))
            xtx[:kb, :kb] = btb
            xtx[kb:, kb:] = rot.T @ g @ rot
            cross = Cross(xtx, np.concatenate([btr, rot.T @ rr[sl]]), float(r @ r), np.hstack([sb, ps[:, sl] @ rot]),
                          sr, groups)
            if kind == "order" and k2 < q:
                v = (res[:, sl] @ rot)[:, 0]
                partial_dirs[(what, mode)] = v / max(float(np.linalg.norm(v)), 1e-300)
            results.append((kind, what, mode, cross, kb + np.arange(k2), rot if k2 == q else None,
                            res[:, sl] @ rot if kind != "order"
                            else None, cells.means(cols) if kind == "order" and cells.replicated else None))
        chunk.clear()

    for test in tests:
        chunk.append(test)
        if sum(c[3].shape[1] for c in chunk) >= 48:
            flush()
    flush()
    n = r.shape[0]
    cell_tester = CellTester(cells, basis, r) if cells.replicated else None
    for kind, what, mode, cross, idx, full_rot, tcols, ocols in results:
        if kind == "order":
            vf = _fit_at(cross, state.var.gp, state.var.gr)
            w = wald(cross, vf, idx, info=None)
            if cells.replicated:
                _, df_c, p_c = cell_tester.test(means=ocols)
                if p_c > w.p:
                    w = Wald(w.estimate, w.cov, w.F, w.q, min(w.df, df_c), p_c)
        else:
            vf = reml(cross)
            w = wald(cross, vf, idx, containment=containment_df(groups, basis, tcols))
        p_adj = min(1.0, w.p * m)
        if p_adj >= alpha:
            continue
        if tcols is not None:
            # as for the candidates: a trend whose GLS slope makes the residual larger is an artefact of the
            # variance components absorbing what it gets wrong, not structure of the residual
            moved = r - tcols @ w.estimate
            if not float(moved @ moved) < float(r @ r):
                continue
        item = {"kind": kind, "mode": mode, "p_adjusted": p_adj}
        if kind == "order":
            if full_rot is not None:
                # no direction absorbed: by Frisch-Waugh-Lovell these are the joint-fit cos/sin coefficients
                amp = float(np.hypot(*(full_rot @ w.estimate)))
            else:
                g_t = cross.xtx[np.ix_(idx, idx)]
                amp = float(math.sqrt(max(2.0 * float(w.estimate @ g_t @ w.estimate) / n, 0.0)))
            item.update(order=what, amplitude_arcsec=amp)
            if idx.shape[0] < 2:
                item["partial"] = "only the part the fitted phases cannot take up is tested"
            if what in labels:
                item["label"] = labels[what]
                same = [s.name for s in sources if abs(s.order - what) < 1e-9]
                if same:
                    item["explanation"] = (f"order {what:g} ({labels[what]}) in {mode} mode that the spec's "
                                           f"{', '.join(same)} cannot produce with their specified sizes and "
                                           "fitted phases")
                elif any(abs(what - o) < 1e-9 for o in catalogue_orders):
                    item["explanation"] = (f"order {what:g} ({labels[what]}) in {mode} mode, which the catalogue "
                                           "effect at this order does not explain (a different mode, or not "
                                           "significant on its own)")
                else:
                    item["explanation"] = (f"order {what:g} ({labels[what]}) in {mode} mode: the catalogue has no "
                                           "effect at this order")
            else:
                item["label"] = "not an order of any shaft or mesh of this drive"
                item["explanation"] = (f"a {mode}-mode harmonic at order {what:g}, which belongs to no shaft or "
                                       "mesh of this drive: no catalogue effect has this signature")
        elif kind == "trend":
            unit = {"temperature_C": "K", "load_Nm": "N m", "time_s": "s"}[what]
            item.update(signal=what, slope_arcsec_per_unit=float(w.estimate[0]), unit=unit)
            item["explanation"] = f"a {mode}-mode trend of the residual with {what} ({w.estimate[0]:.4g} arcsec/{unit})"
            if what == "time_s" and not info.temperature_present:
                item["explanation"] += "; record temperature_C to tell a thermal effect from a plain drift"
        else:
            item.update(mean_reversal_change_arcsec=float(-2.0 * w.estimate[0]))
            item["explanation"] = (f"the mean reversal differs from the spec's by {-2.0 * w.estimate[0]:.3g} "
                                   "arcsec" + (" (more lost motion than modelled)" if w.estimate[0] < 0 else
                                               " (less lost motion than modelled: the spec's backlash is too large)"))
        out.append(item)
    # where the fitted phases leave one direction at an order, its "common" and "differential" tests
    # may test the same mixed direction: report it once
    merged = []
    for item in out:
        if item["kind"] == "order" and item["mode"] == "differential":
            a, b = partial_dirs.get((item["order"], "common")), partial_dirs.get((item["order"], "differential"))
            twin = next((it for it in out if it["kind"] == "order" and it["order"] == item["order"]
                         and it["mode"] == "common"), None)
            if a is not None and b is not None and twin is not None and abs(float(a @ b)) > 0.99:
                twin["mode"] = "mixed"
                twin["explanation"] = twin["explanation"].replace("in common mode", "in a mix of common and "
                                                                  "differential mode (not separable here)")
                continue
        merged.append(item)
    merged.sort(key=lambda it: it["p_adjusted"])
    return merged


# ============================================================================ the augmented spec


def _wrap_deg(x: float) -> float:
    v = (math.degrees(x) + 180.0) % 360.0 - 180.0
    return 180.0 if v == -180.0 else v


def _sig6(x: float) -> float:
    return float(f"{x:.6g}")


def _set_path(doc: dict, dotted: str, value) -> None:
    parts = dotted.split(".")
    node = doc
    for part in parts[:-1]:
        node = node.setdefault(part, {})
    node[parts[-1]] = value


def augmented_params(found: Found) -> dict:
    """A named effect's parameters keyed as in the catalogue (rounded as written)."""
    from wormgear_cli.models.effects import EFFECTS, params_to_keys

    eff = EFFECTS[found.name]
    keys = params_to_keys(found.name, found.params)
    out = {}
    for p in eff.params:
        v = keys[p.key]
        if p.name == eff.phase:
            v = _wrap_deg(v * p.scale)
            v = round(v, 4)
        else:
            v = _sig6(v)
        out[p.key] = v
    return out


def _augment(spec, sig, after: ModelFit, sources, found, fit_phases, y):
    """The spec as a TOML dict with fitted phases and the named effects, and its
    simulation (plus the fitted zero offset) at the measured rows [arcsec]."""
    from wormgear_cli.simulation import simulate
    from wormgear_cli.spec import raw_copy, spec_from_dict

    raw = raw_copy(spec)
    if fit_phases:
        for s, psi in zip(sources, after.psi):
            _set_path(raw, s.key, round(_wrap_deg(float(psi)), 4))
    for f in found:
        raw.setdefault("effects", {})[f.name] = augmented_params(f)
    aug = spec_from_dict(raw, str(spec.source), spec.drive.name)
    return raw, simulate(aug, sig) / ARCSEC + after.offset


def augmented_toml(diag: Diagnosis, data_name: str = "") -> str:
    """The augmented spec as TOML text, with a comment header saying what changed."""
    import tomli_w

    lines = [f"# {diag.spec.drive.name}: written by wormgear diagnose from {diag.spec.source}"
             + (f" and {data_name}" if data_name else "")]
    if diag.fit_phases and diag.sources:
        lines.append("# fitted phases: " + ", ".join(s.key for s in diag.sources))
    if diag.found:
        lines.append("# effects added: " + ", ".join(f.name for f in diag.found))
        for f in diag.found:
            if not f.separable and f.intervals:
                key, (lo, hi) = next(iter(f.intervals.items()))
                lines.append(f"# {f.name}: its size is not separable from the fitted phases of "
                             f"{', '.join(f.indistinguishable_from)} ({key} from {lo:.3g} to {hi:.3g} fits as well)")
    else:
        lines.append("# no effect added (no missing effect found)")
    lines.append(f"# the fitted zero offset ({diag.after.offset:.4f} arcsec) is not part of a drive spec")
    return "\n".join(lines) + "\n\n" + tomli_w.dumps(diag.augmented)


# ============================================================================ views of the residual


def _target_pairs(meas):
    """(key of each row's target/run cell, common and differential per cell with both directions)."""
    from wormgear_cli.iso230 import group_targets

    tgt, _ = group_targets(meas.angle)
    run = meas.run if "run" in meas.present else np.zeros(len(meas), dtype=int)
    return tgt, run


def gap_summary(meas, resid: np.ndarray) -> dict:
    """RMS and max |residual| [arcsec] of all rows, and of the common mode (mean of
    the directions) and differential mode (half forward - reverse) per target and run."""
    tgt, run = _target_pairs(meas)
    out = {"rms_arcsec": float(np.sqrt(np.mean(resid**2))), "max_arcsec": float(np.max(np.abs(resid)))}
    _, run_idx = np.unique(run, return_inverse=True)
    pair = tgt.astype(np.int64) * (int(run_idx.max()) + 1) + run_idx.reshape(-1)
    uniq, inv = np.unique(pair, return_inverse=True)
    inv = inv.reshape(-1)
    sums = {}
    for dv in (1, -1):
        sel = meas.direction == dv
        cnt = np.bincount(inv[sel], minlength=uniq.shape[0])
        tot = np.bincount(inv[sel], weights=resid[sel], minlength=uniq.shape[0])
        sums[dv] = (tot, cnt)
    ok = (sums[1][1] > 0) & (sums[-1][1] > 0)
    if np.any(ok):
        fwd = sums[1][0][ok] / sums[1][1][ok]
        rev = sums[-1][0][ok] / sums[-1][1][ok]
        common, diff = 0.5 * (fwd + rev), 0.5 * (fwd - rev)
        out.update(common_rms_arcsec=float(np.sqrt(np.mean(common**2))),
                   common_max_arcsec=float(np.max(np.abs(common))),
                   differential_rms_arcsec=float(np.sqrt(np.mean(diff**2))),
                   differential_max_arcsec=float(np.max(np.abs(diff))), pairs=int(common.shape[0]))
    else:
        out.update(common_rms_arcsec=None, common_max_arcsec=None, differential_rms_arcsec=None,
                   differential_max_arcsec=None, pairs=0)
    return out


def resolvable_orders(theta, orders) -> tuple[list, dict]:
    """(orders these angles can resolve, {order: what it is aliased with}) among ``orders``.

    An order aliased onto a constant, or folded onto its own mirror, is not
    resolvable; of orders aliased with each other only the lowest is kept."""
    from wormgear_cli.harmonics import alias_groups, folded_orders

    orders = [float(o) for o in orders]
    aliased = {}
    for grp in alias_groups(theta, orders):
        members = [o for o in grp if o != 0.0]
        if 0.0 in grp:
            for o in members:
                aliased[o] = "a constant"
        else:
            for o in members[1:]:
                aliased[o] = f"order {members[0]:g}"
    for o in folded_orders(theta, orders):
        aliased.setdefault(o, "its own mirror (one phase component)")
    return [o for o in orders if o not in aliased], aliased


def jointly_resolvable(theta, orders, priority=None, tol: float = 0.05) -> tuple[list, dict]:
    """Like :func:`resolvable_orders`, then greedily (in ``priority`` order) keep
    only orders whose cos/sin columns stay independent of the intercept and the
    orders kept before them at the distinct sampled angles (smallest singular
    value of the column-normalised design >= ``tol``), while the columns use at
    most half the distinct angles."""
    keep, aliased = resolvable_orders(theta, orders)
    angles = np.unique(np.round(np.asarray(theta, dtype=float), 9))
    cols = [np.ones_like(angles) / math.sqrt(angles.shape[0])]
    chosen = []
    for o in (priority or keep):
        if o not in keep:
            continue
        trial = [np.cos(o * angles), np.sin(o * angles)]
        trial = [c / max(np.linalg.norm(c), 1e-300) for c in trial]
        design = np.column_stack(cols + trial)
        sv = np.linalg.svd(design, compute_uv=False)
        # keep at least half the distinct angles as residual degrees of freedom
        if 2 * design.shape[1] <= design.shape[0] and sv[-1] >= tol:
            cols += trial
            chosen.append(o)
        else:
            aliased[o] = "other orders at these targets (too few targets to resolve them all)"
    return [o for o in keep if o in chosen], aliased


def order_table(meas, resid, geometry) -> list[dict]:
    """Amplitude of the residual at each physical order (common and differential
    mode, joint least squares at the exact orders the targets resolve; standard
    errors assume white noise).  Orders the targets cannot resolve are listed
    with what they are aliased with."""
    from wormgear_cli.harmonics import fit_modes, physical_orders

    phys = physical_orders(geometry, 3)
    bases = (1.0, float(geometry.gear_ratio), float(geometry.output_teeth), float(geometry.worm_order))

    def harmonic(o):
        return min((h for h in (1, 2, 3) for b in bases if abs(o - h * b) < 1e-9 * max(o, 1.0)), default=4)

    priority = sorted((o for o, _ in phys), key=lambda o: (harmonic(o), o))
    keep, aliased = jointly_resolvable(meas.angle, [o for o, _ in phys], priority)
    fit = None
    if keep:
        with np.errstate(invalid="ignore", divide="ignore"):
            fit = fit_modes(meas.angle, resid, meas.direction, keep)
    out = []
    if fit is not None:
        row = {"order": 0.0, "label": "constant (common: offset; differential: half the mean reversal change)",
               "identifiable": True, "common_arcsec": float(fit.common.offset)}
        if np.isfinite(fit.differential.offset):
            row["differential_arcsec"] = float(fit.differential.offset)
        out.append(row)
    for o, label in phys:
        row = {"order": o, "label": label}
        if o in aliased or fit is None:
            row.update(identifiable=False, aliased_with=aliased.get(o, "a constant"))
            out.append(row)
            continue
        i = keep.index(o)
        ident = bool(fit.common.identifiable[i])
        row.update(identifiable=ident, common_arcsec=float(fit.common.amplitude[i]),
                   common_stderr_arcsec=float(fit.common.amplitude_stderr[i]))
        if np.isfinite(fit.differential.amplitude[i]):
            row["differential_arcsec"] = float(fit.differential.amplitude[i])
            row["differential_stderr_arcsec"] = float(fit.differential.amplitude_stderr[i])
        out.append(row)
    return out


def versus(meas, resid, info: DataInfo, bins: int = 5) -> dict:
    """The residual against temperature, load and time (each that varies):
    least-squares slopes of the common and differential mode and binned means per direction."""
    out = {}
    both = len(info.directions) == 2
    for name, values in (("temperature_C", meas.temperature), ("load_Nm", meas.load), ("time_s", meas.time)):
        if np.ptp(values) <= 0:
            continue
        x = values - np.mean(values)
        cols = [np.ones_like(x), x] + ([meas.direction, meas.direction * x] if both else [])
        coef, *_ = np.linalg.lstsq(np.column_stack(cols), resid, rcond=None)
        entry = {"range": [float(np.min(values)), float(np.max(values))], "slope_common": float(coef[1])}
        if both:
            entry["slope_differential"] = float(coef[3])
        edges = np.quantile(values, np.linspace(0, 1, bins + 1))
        idx = np.clip(np.searchsorted(edges, values, side="right") - 1, 0, bins - 1)
        rows = []
        for b in range(bins):
            sel = idx == b
            if not np.any(sel):
                continue
            row = {"from": float(edges[b]), "to": float(edges[b + 1]), "rows": int(np.count_nonzero(sel))}
            for dname, dv in (("forward", 1), ("reverse", -1)):
                s2 = sel & (meas.direction == dv)
                row[f"mean_{dname}_arcsec"] = float(np.mean(resid[s2])) if np.any(s2) else None
            rows.append(row)
        entry["bins"] = rows
        out[name] = entry
    return out


def noise_floor(meas, resid, var: VarFit, groups: Groups) -> dict:
    """Scatter over repeated runs [arcsec]: pooled standard deviation of the residual
    per target and direction, and the fitted white, pass and run components."""
    from wormgear_cli.iso230 import iso230_figures

    t = iso230_figures(meas.angle, resid * ARCSEC, meas.direction).targets
    num = 0.0
    den = 0.0
    for s, nn in ((t.s_up, t.n_up), (t.s_down, t.n_down)):
        ok = np.isfinite(s) & (nn >= 2)
        num += float(np.sum((nn[ok] - 1) * (s[ok] / ARCSEC) ** 2))
        den += float(np.sum(nn[ok] - 1))
    between = groups.runs >= MIN_RUNS  # scatter between passes and runs is estimated only from enough runs
    return {"repeat_std_arcsec": math.sqrt(num / den) if den > 0 else None, "white_arcsec": var.s_white,
            "pass_arcsec": var.s_pass if between else None, "run_arcsec": var.s_run if between else None,
            "total_arcsec": math.sqrt(var.sigma2 * (1.0 + var.gp + var.gr)), "passes": groups.passes,
            "runs": groups.runs, "structure": groups.describe}


def iso_figures(meas, error_arcsec) -> dict:
    """ISO 230-2 axis figures A, B, E, M, R [arcsec] of an error array at the measured rows."""
    from wormgear_cli.iso230 import iso230_figures

    f = iso230_figures(meas.angle, np.asarray(error_arcsec) * ARCSEC, meas.direction)
    out = {}
    for key in ("A", "B", "E", "M", "R"):
        v = getattr(f, key)
        out[key] = float(v / ARCSEC) if math.isfinite(v) else None
    return out


# ============================================================================ the report


def _status(diag: Diagnosis) -> list[dict]:
    from wormgear_cli.models.effects import EFFECTS

    stop = diag.stop
    out = []
    named = {f.name for f in diag.found}
    for name in EFFECTS:
        entry = {"name": name}
        if name in diag.spec.effects:
            entry.update(status="in_spec", reason="already in the spec (its parameters are kept as specified)")
            out.append(entry)
            continue
        sc = diag.candidates.get(name)
        if name in named:
            entry["status"] = "named"
            f = next(f for f in diag.found if f.name == name)
            if not f.separable:
                entry["reason"] = ("indistinguishable from a larger " + " or ".join(f.indistinguishable_from)
                                   + ": its size trades against their fitted phases")
                entry["remedy"] = ("measure the runout and phase of those parts directly (dial indicator), enter "
                                   "the phases in the spec and rerun with --keep-phases")
        elif sc is None:
            entry.update(status="unobservable", reason="not scored")
        elif sc.status in ("unobservable", "untestable"):
            entry.update(status=sc.status, reason=sc.reason)
            if sc.remedy:
                entry["remedy"] = sc.remedy
        else:
            entry["status"] = "not_significant"
            if sc.same_order and sc.p_adj >= diag.alpha:
                entry.update(status="unobservable",
                             reason=f"absorbed by the fitted phases of the spec's order-"
                                    f"{_effect_order(name, diag):g} sources ({', '.join(sc.same_order)}): adding it "
                                    f"does not improve the fit (together they produce up to {sc.reach:.3g} arcsec "
                                    "at this order; only content they cannot reach would show)",
                             remedy="measure the runout and phase of those parts directly (dial indicator), "
                                    "enter the phases in the spec and rerun with --keep-phases")
            if stop.get("reason") == "ambiguous" and name in stop.get("candidates", []):
                others = [c for c in stop["candidates"] if c != name]
                entry.update(status="indistinguishable",
                             reason=f"fits as well as {', '.join(others)} (signatures correlate "
                                    f"{stop['correlation']:.3f})", remedy=_separate_hint([name, *others]))
            elif stop.get("reason") == "unphysical" and stop.get("candidate") == name:
                entry.update(status="unphysical", reason=stop["detail"])
                if stop["hint"]:
                    entry["remedy"] = stop["hint"]
            elif stop.get("reason") == "unstable" and stop.get("candidate") == name:
                entry.update(status="unstable",
                             reason=f"best in only {100 * stop['stability']:.0f} % of resamples of whole runs")
            elif stop.get("reason") == "worsens" and stop.get("candidate") == name:
                entry.update(status="rejected",
                             reason=f"significant, but fitting it makes the RMS gap larger "
                                    f"({stop['rms_before_arcsec']:.3g} -> {stop['rms_with_arcsec']:.3g} arcsec): its "
                                    "estimate follows structure that is not its signature (see unexplained)")
            elif diag.likely is not None and diag.likely["name"] == name:
                entry.update(status="likely",
                             reason=f"short of the level, but it would remove {100 * diag.likely['gain']:.0f} % of "
                                    "the remaining mean-square gap: a likely further effect (see unexplained)",
                             remedy="measure more runs (or a wider temperature or load range) to settle it")
            if sc.wald is not None:
                entry.update(p_value=sc.wald.p, p_adjusted=sc.p_adj, F=sc.wald.F, df=sc.wald.df)
                if sc.params is not None and not sc.same_order:
                    entry["estimate"] = _keys(name, sc.params)
            if sc.aliases:
                entry["aliased_with"] = [{"order": o, "label": lab} for o, lab in sc.aliases]
        out.append(entry)
    return out


def _effect_order(name: str, diag: "Diagnosis") -> float:
    from wormgear_cli.analysis import geometry as drive_geometry
    from wormgear_cli.models.effects import EFFECTS

    return float(EFFECTS[name].order(drive_geometry(diag.spec)))


def _keys(name, params) -> dict:
    from wormgear_cli.models.effects import params_to_keys

    return {k: float(v) for k, v in params_to_keys(name, params).items()}


def _separate_hint(names) -> str:
    s = set(names)
    if s >= {"thermal_backlash", "thermal_drift"}:
        return "measure both directions during the warm-up"
    if "thermal_drift" in s or "thermal_backlash" in s:
        return "vary temperature independently of the other signals (heat and cool, or hold it during load steps)"
    if "torsional_compliance" in s:
        return "apply load steps at constant temperature and in both signs"
    return "measure with irregular target spacing or a dense scan, in both directions"


def _verdict(diag: Diagnosis) -> str:
    found = [f for f in diag.found if f.separable]
    mixed = [f for f in diag.found if not f.separable]
    parts = []
    if found:
        parts.append(f"missing effect{'s' if len(found) > 1 else ''} found: " + ", ".join(f.name for f in found))
    for f in mixed:
        key, (lo, hi) = next(iter(f.intervals.items())) if f.intervals else ("size", (math.nan, math.nan))
        order = _effect_order(f.name, diag)
        parts.append(f"missing content at order {order:g} that the spec's sources cannot produce: {f.name} "
                     f"({key} anywhere from {lo:.3g} to {hi:.3g}) or a larger "
                     + " or ".join(f.indistinguishable_from)
                     + " (indistinguishable here: measure their runouts directly, enter the phases and rerun with "
                     "--keep-phases)")
    untestable = [n for n, sc in diag.candidates.items() if sc.status == "untestable"]
    if not diag.found:
        text = "no missing effect found"
        if untestable:
            text += " that these data can test"
        elif diag.unexplained:
            text += " in the catalogue"
        stop = diag.stop
        if stop.get("reason") == "ambiguous":
            text += (f" that the data can single out: {' or '.join(stop['candidates'])} fit equally well")
        elif stop.get("reason") == "unphysical":
            text += f" ({stop['candidate']} would fit only with {stop['detail']})"
        elif stop.get("reason") == "unstable":
            text += f" ({stop['candidate']} is significant but not stable under resampling of runs)"
        elif stop.get("reason") == "worsens":
            text += (f" ({stop['candidate']} tests significant, but fitting it makes the RMS gap larger: "
                     f"{stop['rms_before_arcsec']:.3g} -> {stop['rms_with_arcsec']:.3g} arcsec)")
        parts.append(text)
    elif diag.stop.get("reason") == "worsens":
        parts.append(f"{diag.stop['candidate']} was rejected: fitting it makes the RMS gap larger")
    if untestable:
        runs = diag.groups.runs
        parts.append(f"untestable with {runs} run{'s' if runs != 1 else ''}: {', '.join(untestable)} "
                     f"({REPLICATION_REMEDY})")
    if diag.likely is not None:
        parts.append(f"likely {'further ' if diag.found else ''}effect: {diag.likely['name']} (adjusted p = "
                     f"{diag.likely['p_adjusted']:.2g}, short of the level; see unexplained)")
    others = [u for u in diag.unexplained if u["kind"] != "likely_effect"]
    if others:
        text = "the residual keeps structure no catalogue effect explains"
        excess = next((u for u in others if u["kind"] == "excess"), None)
        if excess is not None:
            text += (f" ({excess['rms_arcsec']:.3g} arcsec RMS against a noise floor of "
                     f"{excess['noise_floor_arcsec']:.3g})")
        parts.append(text + " (see unexplained)")
    return "; ".join(parts)


def _direction_warning(meas, groups: Groups) -> str | None:
    """A note when the file has no direction column yet a pass visits a target more than once."""
    from wormgear_cli.iso230 import group_targets

    if "direction" in meas.present:
        return None
    tgt, _ = group_targets(meas.angle)
    key = groups.pass_id.astype(np.int64) * (int(np.max(tgt)) + 1) + tgt.astype(np.int64)
    if np.unique(key).shape[0] == key.shape[0]:
        return None
    return ("no direction column: every row is taken as forward, yet one "
            + ("run" if "run" in meas.present else "block of rows") + " visits the same target more than once: if "
            "some visits were made in reverse, add a direction column (+1 forward, -1 reverse)"
            + ("" if "run" in meas.present else "; if they are repeated runs, add a run column"))


def report(diag: Diagnosis) -> dict:
    """The JSON document of ``wormgear diagnose`` (angles in arcsec, effect parameters keyed as in the catalogue)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        return _report(diag)


def _report(diag: Diagnosis) -> dict:
    from wormgear_cli.analysis import geometry as drive_geometry

    g = drive_geometry(diag.spec)
    meas = diag.meas
    y = meas.error / ARCSEC
    resid_after = y - diag.augmented_fitted
    found = []
    for f in diag.found:
        item = {"name": f.name, "parameters": augmented_params(f),
                "interval_95": {k: [float(lo), float(hi)] for k, (lo, hi) in f.intervals.items()},
                "p_value": f.p, "df": f.df, "gap_share_pct": 100.0 * f.share,
                "stability": f.stability, "stability_note": f.stability_note,
                "signature_rms_arcsec": f.signature_rms, "step": f.step, "separable": f.separable,
                "fixed_parameters": list(f.fixed_keys),
                "notes": list(f.notes), "indistinguishable_from": list(f.indistinguishable_from)}
        if f.name == "thermal_backlash" and diag.thermal_prediction is not None and \
                "centre_distance_um_per_K" in f.intervals:
            lo, hi = f.intervals["centre_distance_um_per_K"]
            pred = diag.thermal_prediction
            fitted = item["parameters"]["centre_distance_um_per_K"]
            item["prediction"] = {"centre_distance_um_per_K": pred, "inside_interval": bool(lo <= pred <= hi),
                                  "fitted_over_predicted": fitted / pred if pred else None,
                                  "basis": "housing, worm and wheel warming alike, expansion from the spec's "
                                           "[materials]"}
        found.append(item)
    phases = []
    for s, psi in zip(diag.sources, diag.after.psi):
        same = [t.name for t in diag.sources if abs(t.order - s.order) < 1e-9 and t is not s]
        phases.append({"source": s.name, "key": s.key, "order": s.order, "amplitude_arcsec": s.amplitude,
                       "specified_deg": _wrap_deg(s.phase), "fitted_deg": round(_wrap_deg(float(psi)), 4),
                       "shares_order_with": same})
    info = diag.info
    doc = {
        "drive": diag.spec.drive.name,
        "data": str(meas.source),
        "rows": len(meas),
        "verdict": _verdict(diag),
        "effects_found": found,
        "gap_as_specified": gap_summary(meas, diag.as_specified),
        "gap_before": gap_summary(meas, diag.before.residual),
        "gap_after": gap_summary(meas, resid_after),
        "unexplained": diag.unexplained,
        "candidates": _status(diag),
        "fit": {
            "phases_fitted": bool(diag.fit_phases),
            "zero_offset_before_arcsec": diag.before.offset,
            "zero_offset_after_arcsec": diag.after.offset,
            "phases": phases,
            "note": ("sources on one shaft share an order: only their combined vector is determined, the "
                     "individual phases are one of several equivalent solutions") if any(p["shares_order_with"]
                                                                                       for p in phases) else "",
        },
        "noise": {"before": noise_floor(meas, diag.before.residual, diag.before.var, diag.groups),
                  "after": noise_floor(meas, resid_after, diag.after.var, diag.groups),
                  "floor_arcsec": diag.noise_floor if math.isfinite(diag.noise_floor) else None},
        "orders": {"before": order_table(meas, diag.before.residual, g), "after": order_table(meas, resid_after, g)},
        "residual_vs": {"before": versus(meas, diag.before.residual, info), "after": versus(meas, resid_after, info)},
        "iso230": {"measured": iso_figures(meas, y), "simulated_before": iso_figures(meas, diag.before.fitted),
                   "simulated_after": iso_figures(meas, diag.augmented_fitted)},
        "signals": {"directions": list(info.directions),
                    "temperature_C": [float(np.min(meas.temperature)), float(np.max(meas.temperature))]
                    if info.temperature_present else None,
                    "load_Nm": [float(np.min(meas.load)), float(np.max(meas.load))] if info.load_present else None,
                    "time_s": [float(np.min(meas.time)), float(np.max(meas.time))] if "time_s" in meas.present
                    else None,
                    "temperature_time_correlation": None if math.isnan(info.temperature_time_corr)
                    else info.temperature_time_corr},
        "selection": {"alpha": diag.alpha, "steps": diag.steps, "stop": diag.stop,
                      "method": "forward selection; Wald F-test with REML run/pass random intercepts and "
                                "Satterthwaite df, Bonferroni over the candidates of each step; stability by "
                                "cluster bootstrap of whole runs; a candidate whose refit does not shrink the "
                                "RMS gap is rejected; fewer than 3 runs: white noise, effects needing "
                                "replication untestable"},
    }
    data_warning = _direction_warning(meas, diag.groups)
    if data_warning:
        doc["signals"]["data_warning"] = data_warning
    if info.temperature_present and not math.isnan(info.temperature_time_corr) and \
            abs(info.temperature_time_corr) > 0.95:
        doc["signals"]["warning"] = (f"temperature and time correlate {info.temperature_time_corr:.2f}: a "
                                     "common-mode thermal_drift cannot be told apart from a plain drift over "
                                     "time; heating and cooling separates them")
    return doc
