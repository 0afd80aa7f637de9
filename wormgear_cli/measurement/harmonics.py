"""Harmonic content at exact orders: least squares, aliasing, shaft labels.

An *order* k is a number of cycles per output revolution (it need not be a
whole number).  A component of order k at output angle theta [rad] is
written

    y(theta) ~ A sin(k theta + phi) = a cos(k theta) + b sin(k theta),
    a = A sin(phi),  b = A cos(phi),  A = hypot(a, b),  phi = atan2(a, b).

Coefficients are estimated by (weighted) linear least squares on the
sampled columns themselves, never by FFT bins, so the targets may be
unevenly spaced and the orders non-integer.  Whether two orders can be told
apart is decided from the samples too (:func:`alias_groups`): with 24
evenly spaced targets over one revolution order 240 is indistinguishable
from a constant and order 300 from order 12.

The measurement-level steps live in their own modules and are re-exported
here: :mod:`wormgear_cli.measurement.coverage` (span covered, trend, unwrapping) and
:mod:`wormgear_cli.measurement.orders` (:func:`analyse_orders`).  The one test
of which orders can be fitted together is :func:`select_orders` /
:func:`resolvable_orders` here.

Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np

from wormgear_cli.measurement.coverage import as_1d as _as_1d

#: default relative singular-value cutoff of the least-squares solve
RCOND = 1e-9
#: smallest eigenvalue of the column correlation matrix for an order to count as resolvable
RESOLVE_MIN_EIG = 1e-6
#: default alias tolerance: two orders are aliased when the correlation of
#: their sampled complex exponentials is at least 1 - ALIAS_TOL
ALIAS_TOL = 1e-3


@dataclass(frozen=True)
class OrderFit:
    """Result of :func:`fit_orders`.

    Per-order arrays (same length and order as the requested ``orders``):
    ``amplitude`` A [unit of y], ``phase`` phi [rad] in (-pi, pi] with
    y ~ A sin(k theta + phi), ``cos`` a and ``sin`` b coefficients
    (y ~ a cos + b sin), ``amplitude_stderr`` and ``phase_stderr``
    (first-order propagation of the coefficient covariance; NaN where the
    order is not identifiable or no degrees of freedom are left),
    ``identifiable`` (False where the sampled columns of the order are
    collinear with other columns: the values shown are then the minimum-norm
    split and mean nothing on their own).

    ``offset``: the intercept [unit of y]; ``extra``: coefficients of the
    ``design_extra`` columns; ``residual``: y - fit per sample; ``rms``:
    weighted root-mean-square residual; ``sigma``: residual standard error
    (weighted, divided by n - rank); ``rank`` and ``columns``: rank and
    number of columns of the design matrix; ``rank_deficient``: rank <
    columns; ``offset_identifiable``: False when an order aliases onto a
    constant so the intercept is not unique either.
    """

    orders: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray
    cos: np.ndarray
    sin: np.ndarray
    amplitude_stderr: np.ndarray
    phase_stderr: np.ndarray
    identifiable: np.ndarray
    offset: float
    extra: np.ndarray
    residual: np.ndarray
    rms: float
    sigma: float
    rank: int
    columns: int
    rank_deficient: bool
    offset_identifiable: bool = True

    def evaluate(self, theta) -> np.ndarray:
        """The fitted harmonic part plus the offset at angles ``theta`` [rad]
        (without the ``design_extra`` terms)."""
        theta = np.asarray(theta, dtype=float)
        out = np.full(theta.shape, self.offset, dtype=float)
        for k, a, b in zip(self.orders, self.cos, self.sin):
            out = out + a * np.cos(k * theta) + b * np.sin(k * theta)
        return out


@dataclass(frozen=True)
class _Solve:
    coef: np.ndarray
    cov: np.ndarray  # unscaled (X^T W X)^+ in original column units
    residual: np.ndarray
    rank: int
    identifiable: np.ndarray  # per column
    sigma: float
    rms: float


#: rows per block when a design is built and reduced in blocks (bounds the memory of long measurements)
BLOCK_ROWS = 65536


def _solve(x: np.ndarray, y: np.ndarray, weights: np.ndarray | None, rcond: float, n_fixed: int) -> _Solve:
    """Weighted least squares of ``y`` on the columns of ``x`` (see :func:`_solve_blocks`)."""
    return _solve_blocks(lambda a, b: x[a:b], x.shape[0], x.shape[1], y, weights, rcond, n_fixed)


def _solve_blocks(block, n: int, p: int, y: np.ndarray, weights: np.ndarray | None, rcond: float,
                  n_fixed: int) -> _Solve:
    """Weighted least squares with a relative singular-value cutoff, the design built in row blocks.

    ``block(a, b)`` returns rows a..b-1 of the (n x p) design; it is called
    in blocks of :data:`BLOCK_ROWS` rows, so the whole design is never held
    (a single block when n <= BLOCK_ROWS).  Well-conditioned designs are
    solved by the normal equations accumulated over the blocks; anything
    else by a QR of [X y] reduced block by block (R of the stacked previous
    R and the next block) and an SVD of R, cutting singular values below
    ``rcond`` times the largest (minimum-norm solution).

    The first ``n_fixed`` columns (intercept, cos/sin: all of magnitude <= 1)
    are used as they are, so a column that vanishes on the samples (sin at a
    Nyquist-like order, ~1e-13) stays negligible and is cut off; later
    (user) columns are scaled to unit RMS so the cutoff does not depend on
    their units.  A column is *identifiable* when the null space of the
    design has no weight on it (its coefficient is unique).
    """
    return _solve_blocks_each(block, n, p, [y], weights, rcond, n_fixed)[0]


class _WeightedDesign:
    """The (n x p) design of :func:`_solve_blocks_each`, weighted and column-scaled, served in row blocks.

    Rows are multiplied by sqrt(weights); columns after the first ``n_fixed``
    are divided by ``safe`` (their RMS over the weighted samples) so the
    singular-value cutoff does not depend on their units.  A design of at
    most :data:`BLOCK_ROWS` rows is built once and kept."""

    def __init__(self, block, n: int, p: int, weights: np.ndarray | None, n_fixed: int) -> None:
        if weights is not None and (np.any(weights < 0) or not np.all(np.isfinite(weights))):
            raise ValueError("weights must be finite and non-negative")
        self.block, self.n, self.p = block, n, p
        self.sw = None if weights is None else np.sqrt(weights)
        self.wsum = float(n) if weights is None else float(np.sum(weights))
        self.starts = list(range(0, n, BLOCK_ROWS)) or [0]
        self.single = n <= BLOCK_ROWS
        self.xw_all = self.xblock(0, n) if self.single else None
        self.safe = self._column_scales(n_fixed)
        self.scaled = bool(np.any(self.safe != 1.0))

    def _column_scales(self, n_fixed: int) -> np.ndarray:
        """Per-column divisor: the RMS of each user column over the weighted samples (1 where unused)."""
        n, p = self.n, self.p
        if n_fixed >= p:
            sq = np.ones(p)  # no column is scaled: the norms are not needed
        elif self.xw_all is not None:
            sq = np.einsum("ij,ij->j", self.xw_all, self.xw_all)
        else:
            sq = np.zeros(p)
            for a in self.starts:
                xb = self.xblock(a, min(a + BLOCK_ROWS, n))
                sq += np.einsum("ij,ij->j", xb, xb)
        norms = np.sqrt(sq)
        rms_norm = math.sqrt(max(self.wsum, 1e-300))
        safe = np.where(norms > 0, norms / rms_norm, 1.0)
        safe[:n_fixed] = 1.0
        return safe

    def ranges(self):
        """The (a, b) row ranges of the blocks."""
        return [(a, min(a + BLOCK_ROWS, self.n)) for a in self.starts]

    def xblock(self, a: int, b: int) -> np.ndarray:
        """Rows a..b-1 of the weighted (unscaled) design."""
        xb = self.block(a, b)
        return xb if self.sw is None else xb * self.sw[a:b, None]

    def yblock(self, y: np.ndarray, a: int, b: int) -> np.ndarray:
        """Samples a..b-1 of ``y``, weighted."""
        return y[a:b] if self.sw is None else y[a:b] * self.sw[a:b]

    def sxblock(self, a: int, b: int) -> np.ndarray:
        """Rows a..b-1 of the weighted, column-scaled design."""
        xb = self.xw_all if self.xw_all is not None else self.xblock(a, b)
        return xb / self.safe if self.scaled else xb

    def syblock(self, y: np.ndarray, a: int, b: int) -> np.ndarray:
        """Samples a..b-1 of ``y``, weighted (all of them for a single-block design)."""
        return self.yblock(y, 0, self.n) if self.single else self.yblock(y, a, b)


def _solve_normal(d: _WeightedDesign, ys) -> tuple[np.ndarray, list[np.ndarray]] | None:
    """Fast path of :func:`_solve_blocks_each`: the normal equations, accumulated over the blocks.

    Used only when the design is well conditioned (cond(X) < 1e4, so
    cond(X^T X) < 1e8 and the solution loses at most ~1e-8 relative
    accuracy).  Returns the scaled (X^T W X)^-1 and the scaled coefficients
    of each right-hand side, or None when the design is not well conditioned
    (or not overdetermined)."""
    n, p = d.n, d.p
    if not (n >= p and p > 0):
        return None
    gram = np.zeros((p, p))
    rhs = [np.zeros(p) for _ in ys]
    for a, b in d.ranges():
        xs = d.sxblock(a, b)
        gram += xs.T @ xs
        for i, y in enumerate(ys):
            rhs[i] += xs.T @ d.syblock(y, a, b)
    lam, vec = np.linalg.eigh(gram)
    if not lam[0] > 1e-8 * lam[-1] > 0:
        return None
    cov = (vec / lam) @ vec.T
    return cov, [cov @ r for r in rhs]


def _solve_robust(d: _WeightedDesign, y: np.ndarray, rcond: float) -> tuple[np.ndarray, np.ndarray, int, np.ndarray]:
    """Robust path of :func:`_solve_blocks_each` for one right-hand side ``y``.

    QR of [X y] (X padded to square when n < p), reduced block by block,
    then an SVD of R cut at ``rcond`` times the largest singular value
    (minimum-norm solution).  Returns the scaled coefficients, the scaled
    unscaled-covariance (X^T W X)^+, the rank and the per-column
    identifiability (no weight in the null space)."""
    n, p = d.n, d.p
    r_aug: np.ndarray | None = None
    for a, b in d.ranges():
        aug = np.column_stack([d.sxblock(a, b), d.syblock(y, a, b)])
        if n < p:
            aug = np.vstack([aug, np.zeros((p - n, p + 1))])
        stacked = aug if r_aug is None else np.vstack([r_aug, aug])
        r_aug = cast(np.ndarray, np.linalg.qr(stacked, mode="r"))  # mode "r": R alone, not a QRResult
    assert r_aug is not None  # there is always at least one block
    if r_aug.shape[0] < p + 1:
        r_aug = np.vstack([r_aug, np.zeros((p + 1 - r_aug.shape[0], p + 1))])
    r, qty = r_aug[:p, :p], r_aug[:p, p]
    u, sv, vt = np.linalg.svd(r)
    smax = sv[0] if sv.size else 0.0
    keep = (sv > rcond * smax) & (sv > 0) if smax > 0 else np.zeros_like(sv, dtype=bool)
    inv = np.zeros_like(sv)
    inv[keep] = 1.0 / sv[keep]
    coef = vt.T @ (inv * (u.T @ qty))
    cov = (vt.T * inv**2) @ vt
    # null-space weight of each column: a coefficient is unique only if it has none
    null = vt[~keep]
    null_weight = np.sum(null**2, axis=0) if null.size else np.zeros(p)
    return coef, cov, int(np.count_nonzero(keep)), null_weight < 1e-6


def _residuals(d: _WeightedDesign, ys, coef: list[np.ndarray]) -> list[np.ndarray]:
    """y - X coef for each right-hand side (unweighted, original column units), one pass over the blocks."""
    residual = [np.empty(d.n) for _ in ys]
    for a, b in d.ranges():
        xb = d.block(a, b)
        for i, y in enumerate(ys):
            residual[i][a:b] = y[a:b] - xb @ coef[i]
    return residual


def _solve_blocks_each(block, n: int, p: int, ys, weights: np.ndarray | None, rcond: float,
                       n_fixed: int) -> list[_Solve]:
    """:func:`_solve_blocks` of each right-hand side in ``ys`` (each (n,)) on one design.

    The same numbers as one call per right-hand side, but each block of the
    design is built once per pass over the rows for all of them (column
    norms, normal equations, residuals); only the robust path (an
    ill-conditioned design) reduces [X y] for each y on its own."""
    d = _WeightedDesign(block, n, p, weights, n_fixed)
    r_count = len(ys)
    identifiable = [np.ones(p, dtype=bool) for _ in range(r_count)]
    rank = [p] * r_count
    normal = _solve_normal(d, ys)
    if normal is not None:
        cov_s = [normal[0]] * r_count
        coef_s = normal[1]
    else:
        cov_s, coef_s = [], []
        for i, y in enumerate(ys):
            c, cv, rank[i], identifiable[i] = _solve_robust(d, y, rcond)
            coef_s.append(c)
            cov_s.append(cv)
    coef = [c / d.safe for c in coef_s]
    residual = _residuals(d, ys, coef)
    out = []
    for i in range(r_count):
        wres = residual[i] if d.sw is None else residual[i] * d.sw
        rss = float(wres @ wres)
        dof = n - rank[i]
        sigma = math.sqrt(rss / dof) if dof > 0 else math.nan
        rms = math.sqrt(rss / d.wsum) if d.wsum > 0 else math.nan
        out.append(_Solve(coef[i], cov_s[i] / np.outer(d.safe, d.safe), residual[i], rank[i], identifiable[i], sigma,
                          rms))
    return out


def harmonic_columns(theta: np.ndarray, orders: np.ndarray) -> np.ndarray:
    """Design columns [cos(k1 t), sin(k1 t), cos(k2 t), sin(k2 t), ...] (n x 2m)."""
    arg = np.multiply.outer(theta, orders)
    cols = np.empty((theta.shape[0], 2 * orders.shape[0]))
    cols[:, 0::2] = np.cos(arg)
    cols[:, 1::2] = np.sin(arg)
    return cols


def _harmonic_table(theta: np.ndarray, orders: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(index (n,) of each row's angle, :func:`harmonic_columns` at the distinct angles (U x 2m)) when
    the rows repeat their angles (repeated runs: U <= n / 2, bitwise equal values) and the table is
    no larger than one block of rows; else None.  The table's rows are the rows' columns, bit for
    bit (the same elementwise operations on the same values)."""
    n = theta.shape[0]
    if n < 2 or orders.shape[0] == 0:
        return None
    t = np.ascontiguousarray(theta, dtype=float)
    _, first, inverse = np.unique(t.view(np.int64), return_index=True, return_inverse=True)
    if first.shape[0] > min(n // 2, BLOCK_ROWS):
        return None
    # np.intp: np.take converts any other index type on every call
    return np.ascontiguousarray(inverse.reshape(-1), dtype=np.intp), harmonic_columns(t[first], orders)


def _order_values(a, b, cov_ab, ident, sigma):
    """Amplitude, phase and their standard errors from (a, b) and their covariance."""
    amp = np.hypot(a, b)
    phase = np.arctan2(a, b)
    va, vb, cab = cov_ab[:, 0, 0], cov_ab[:, 1, 1], cov_ab[:, 0, 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        # grad A = (a, b) / A ; grad phi = (b, -a) / A^2
        var_amp = np.where(amp > 0, (a * a * va + b * b * vb + 2 * a * b * cab) / amp**2, 0.5 * (va + vb))
        var_phase = np.where(amp > 0, (b * b * va + a * a * vb - 2 * a * b * cab) / amp**4, np.inf)
    with np.errstate(invalid="ignore"):  # 0 x inf (exact fit, zero amplitude): the phase is undefined
        amp_se = sigma * np.sqrt(np.maximum(var_amp, 0.0))
        phase_se = sigma * np.sqrt(np.maximum(var_phase, 0.0))
    amp_se = np.where(ident, amp_se, np.nan)
    phase_se = np.where(ident, phase_se, np.nan)
    return amp, phase, amp_se, phase_se


def fit_orders(theta, y, orders: Sequence[float], weights=None, design_extra=None, rcond: float = RCOND) -> OrderFit:
    """Weighted least squares of y on 1, cos(k theta), sin(k theta) for each order k.

    Model: y_i = c + sum_k [a_k cos(k theta_i) + b_k sin(k theta_i)]
    + sum_j e_j X_ij, minimising sum_i w_i r_i^2.

    Parameters: ``theta`` output angles [rad] (any spacing); ``y`` values
    [any unit]; ``orders`` cycles per output revolution [-] (exact, may be
    non-integer, repeated or zero); ``weights`` w_i >= 0 [1/unit^2] or None
    (all 1); ``design_extra`` optional extra columns (n x m, or n) fitted
    alongside (e.g. a direction term); ``rcond`` relative singular-value
    cutoff.  Collinear columns (aliased orders, repeated orders, order 0)
    never raise: the minimum-norm solution is returned, ``rank_deficient``
    is set and the affected orders are marked not ``identifiable``.
    Standard errors assume independent samples with equal variance (scaled
    by the weights).
    """
    theta = _as_1d("theta", theta)
    n = theta.shape[0]
    y = _as_1d("y", y, n)
    ords = np.atleast_1d(np.asarray(orders, dtype=float))
    if ords.ndim != 1:
        raise ValueError("orders must be a sequence of numbers")
    w = None if weights is None else _as_1d("weights", weights, n)
    if design_extra is None:
        extra = np.zeros((n, 0))
    else:
        extra = np.asarray(design_extra, dtype=float)
        if extra.ndim == 1:
            extra = extra[:, None]
        if extra.ndim != 2 or extra.shape[0] != n:
            raise ValueError(f"design_extra must have {n} rows")
    m = ords.shape[0]
    x = np.hstack([np.ones((n, 1)), harmonic_columns(theta, ords), extra])
    sol = _solve(x, y, w, rcond, 1 + 2 * m)
    a = sol.coef[1:1 + 2 * m:2]
    b = sol.coef[2:2 + 2 * m:2]
    ia = 1 + 2 * np.arange(m)
    cov_ab = np.empty((m, 2, 2))
    cov_ab[:, 0, 0] = sol.cov[ia, ia]
    cov_ab[:, 1, 1] = sol.cov[ia + 1, ia + 1]
    cov_ab[:, 0, 1] = cov_ab[:, 1, 0] = sol.cov[ia, ia + 1]
    ident_cols = sol.identifiable
    ident = ident_cols[ia] & ident_cols[ia + 1]
    amp, phase, amp_se, phase_se = _order_values(a, b, cov_ab, ident, sol.sigma)
    return OrderFit(
        orders=ords,
        amplitude=amp,
        phase=phase,
        cos=a,
        sin=b,
        amplitude_stderr=amp_se,
        phase_stderr=phase_se,
        identifiable=ident,
        offset=float(sol.coef[0]),
        extra=sol.coef[1 + 2 * m:],
        residual=sol.residual,
        rms=sol.rms,
        sigma=sol.sigma,
        rank=sol.rank,
        columns=x.shape[1],
        rank_deficient=sol.rank < x.shape[1],
        offset_identifiable=bool(sol.identifiable[0]),
    )


@dataclass(frozen=True)
class ModeFit:
    """Result of :func:`fit_modes`: y = common(theta) + d * differential(theta).

    ``common``: the direction-independent part (mean of the directions);
    ``differential``: half the forward - reverse difference, i.e. half the
    ISO 230-2 reversal B(theta) / 2 (negative with lost motion).  Both are
    :class:`OrderFit` on the same orders; ``differential.offset`` is half
    the mean reversal.  ``residual``, ``rms``, ``sigma``, ``rank``,
    ``columns``, ``rank_deficient`` describe the joint fit.
    """

    common: OrderFit
    differential: OrderFit
    residual: np.ndarray
    rms: float
    sigma: float
    rank: int
    columns: int
    rank_deficient: bool


def fit_modes(theta, y, direction, orders: Sequence[float], weights=None, rcond: float = RCOND,
              trend=None) -> ModeFit:
    """Joint least squares of the common and differential modes on all rows.

    Model: y_i = c + sum_k [a_k cos + b_k sin](k theta_i)
    + d_i (c' + sum_k [a'_k cos + b'_k sin](k theta_i)), d_i = +1 forward,
    -1 reverse.  With the same targets in both directions and the same
    number of runs this equals fitting the mean of the directions (common
    mode) and half their difference (differential mode) separately; it also
    works when the directions are sampled at different angles (dense
    scans).  If only one direction is present the differential columns are
    left out and the differential fit is all NaN.
    ``trend``: optional extra columns (n x t, e.g. :func:`trend_columns`)
    added to both modes (a slow drift over a partial span); their
    coefficients are not reported.  The design is built and reduced in
    blocks of rows (:func:`_solve_blocks`), so memory stays proportional to
    the number of rows, not rows x columns.
    Units as in :func:`fit_orders`.
    """
    return fit_modes_each(theta, [y], direction, orders, weights, rcond, trend)[0]


def fit_modes_each(theta, ys, direction, orders: Sequence[float], weights=None, rcond: float = RCOND,
                   trend=None) -> list[ModeFit]:
    """:func:`fit_modes` of each of several responses ``ys`` (a sequence of (n,) arrays, same
    unit) at the same angles, directions, orders and weights.

    The same numbers as ``[fit_modes(theta, y, direction, orders, ...) for y in ys]``, but
    each block of the design is built once for all responses (its cos/sin
    columns are most of the cost), so e.g. the residual before and after a
    refit are tabulated for little more than one."""
    theta = _as_1d("theta", theta)
    n = theta.shape[0]
    ys = [_as_1d("y", y, n) for y in ys]
    d = _as_1d("direction", direction, n)
    ords = np.atleast_1d(np.asarray(orders, dtype=float))
    m = ords.shape[0]
    w = None if weights is None else _as_1d("weights", weights, n)
    tr = np.zeros((n, 0)) if trend is None else np.asarray(trend, dtype=float).reshape(n, -1)
    both = bool(np.any(d > 0) and np.any(d < 0))

    p_mode = 1 + 2 * m + tr.shape[1]
    ncols = 2 * p_mode if both else p_mode

    table = _harmonic_table(theta, ords)

    def block(a, b):
        # [1, cos/sin per order, trend] and, with both directions, the same times the direction
        out = np.empty((b - a, ncols))
        out[:, 0] = 1.0
        if table is None:
            out[:, 1:1 + 2 * m] = harmonic_columns(theta[a:b], ords)
        else:
            out[:, 1:1 + 2 * m] = np.take(table[1], table[0][a:b], axis=0)
        out[:, 1 + 2 * m:p_mode] = tr[a:b]
        if both:
            np.multiply(out[:, :p_mode], d[a:b, None], out=out[:, p_mode:])
        return out

    return [_mode_fit(sol, ords, p_mode, both, ncols) for sol in _solve_blocks_each(block, n, ncols, ys, w, rcond,
                                                                                    ncols)]


def _mode_fit(sol: _Solve, ords: np.ndarray, p: int, both: bool, ncols: int) -> ModeFit:
    """The :class:`ModeFit` of one solve of :func:`fit_modes_each`'s design (``p`` columns per mode)."""
    m = ords.shape[0]
    x = np.empty((0, ncols))  # only its shape is used below
    fits = []
    for start in (0, p):
        if start == p and not both:
            nan = np.full(m, np.nan)
            fits.append(OrderFit(
                orders=ords, amplitude=nan, phase=nan, cos=nan, sin=nan, amplitude_stderr=nan, phase_stderr=nan,
                identifiable=np.zeros(m, dtype=bool), offset=math.nan, extra=np.zeros(0), residual=sol.residual,
                rms=sol.rms, sigma=sol.sigma, rank=sol.rank, columns=x.shape[1],
                rank_deficient=sol.rank < x.shape[1]))
            continue
        coef = sol.coef[start:start + 1 + 2 * m]
        cov = sol.cov[start:start + 1 + 2 * m, start:start + 1 + 2 * m]
        ident_cols = sol.identifiable[start:start + 1 + 2 * m]
        a, b = coef[1::2], coef[2::2]
        ia = 1 + 2 * np.arange(m)
        cov_ab = np.empty((m, 2, 2))
        cov_ab[:, 0, 0] = cov[ia, ia]
        cov_ab[:, 1, 1] = cov[ia + 1, ia + 1]
        cov_ab[:, 0, 1] = cov_ab[:, 1, 0] = cov[ia, ia + 1]
        ident = ident_cols[ia] & ident_cols[ia + 1]
        amp, phase, amp_se, phase_se = _order_values(a, b, cov_ab, ident, sol.sigma)
        offset = float(coef[0])
        fits.append(OrderFit(
            orders=ords, amplitude=amp, phase=phase, cos=a, sin=b, amplitude_stderr=amp_se,
            phase_stderr=phase_se, identifiable=ident, offset=offset, extra=np.zeros(0),
            residual=sol.residual, rms=sol.rms, sigma=sol.sigma, rank=sol.rank, columns=x.shape[1],
            rank_deficient=sol.rank < x.shape[1], offset_identifiable=bool(ident_cols[0])))
    return ModeFit(fits[0], fits[1], sol.residual, sol.rms, sol.sigma, sol.rank, x.shape[1],
                   sol.rank < x.shape[1])


# --- aliasing -----------------------------------------------------------------------------------------------


def _sampling(theta: np.ndarray, weights) -> tuple[np.ndarray, np.ndarray]:
    """Distinct sampled angles and their normalised weights (row counts, or
    summed ``weights``): means over rows become weighted means over angles."""
    ut, inverse, counts = np.unique(theta, return_inverse=True, return_counts=True)
    if weights is None:
        w = counts.astype(float)
    else:
        w = np.bincount(inverse.ravel(), weights=np.asarray(weights, dtype=float), minlength=ut.shape[0])
    total = w.sum()
    return ut, (w / total if total > 0 else w)


def _correlations(theta, orders, weights) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(C_minus, C_plus, C_zero) of :func:`order_correlations` and :func:`offset_correlations`,
    accumulated over blocks of the distinct angles."""
    theta = _as_1d("theta", theta)
    ords = np.atleast_1d(np.asarray(orders, dtype=float))
    ut, w = _sampling(theta, weights)
    m = ords.shape[0]
    s_minus = np.zeros((m, m), dtype=complex)
    s_plus = np.zeros((m, m), dtype=complex)
    s_zero = np.zeros(m, dtype=complex)
    for a in range(0, max(ut.shape[0], 1), BLOCK_ROWS):
        b = min(a + BLOCK_ROWS, ut.shape[0])
        e = np.exp(1j * np.multiply.outer(ut[a:b], ords))
        ew = e * w[a:b, None]
        s_minus += e.conj().T @ ew
        s_plus += e.T @ ew
        s_zero += w[a:b] @ e
    return np.abs(s_minus), np.abs(s_plus), np.abs(s_zero)


def order_correlations(theta, orders: Sequence[float], weights=None) -> tuple[np.ndarray, np.ndarray]:
    """Correlations of the sampled exponentials of every pair of orders.

    Returns (C_minus, C_plus), m x m arrays with
    C_minus[i, j] = |mean(exp(i (k_i - k_j) theta))| and
    C_plus[i, j] = |mean(exp(i (k_i + k_j) theta))| (means over the rows,
    weighted when ``weights`` are given).  C_minus near 1: k_i and k_j look
    the same on the samples; C_plus near 1: k_i looks like -k_j (same
    cos/sin span, mirrored phase); C_plus[i, i] near 1: cos and sin of k_i
    are collinear (k_i sits on a Nyquist-like fold and only one phase
    component is seen).
    """
    c_minus, c_plus, _ = _correlations(theta, orders, weights)
    return c_minus, c_plus


def offset_correlations(theta, orders: Sequence[float], weights=None) -> np.ndarray:
    """|mean(exp(i k theta))| per order: near 1 means the order is
    indistinguishable from a constant offset on these samples."""
    return _correlations(theta, orders, weights)[2]


def _groups(ords: np.ndarray, c_minus, c_plus, c_zero, tol) -> list[tuple[float, ...]]:
    m = ords.shape[0]
    to_zero = c_zero >= 1.0 - tol
    linked = (c_minus >= 1.0 - tol) | (c_plus >= 1.0 - tol)
    np.fill_diagonal(linked, False)
    # union-find over m orders plus a node for the offset (index m)
    parent = list(range(m + 1))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    def union(i, j):
        ri, rj = find(i), find(j)
        if ri != rj:
            parent[max(ri, rj)] = min(ri, rj)

    for i, j in zip(*np.nonzero(np.triu(linked, 1))):
        union(int(i), int(j))
    for i in np.flatnonzero(to_zero | (ords == 0)):
        union(int(i), m)
    groups: dict[int, list[float]] = {}
    for i in range(m):
        groups.setdefault(find(i), []).append(float(ords[i]))
    root0 = find(m)
    out = []
    for root, members in groups.items():
        if root == root0 and 0.0 not in members:
            members = [0.0, *members]
        if len(members) >= 2:
            out.append(tuple(sorted(members)))
    return sorted(out)


def alias_groups(theta, orders: Sequence[float], tol: float = ALIAS_TOL, weights=None) -> list[tuple[float, ...]]:
    """Groups of orders that the sampling angles cannot tell apart.

    Two orders k1, k2 are aliased when their sampled columns span (nearly)
    the same space: |mean(exp(i (k1 - k2) theta))| >= 1 - tol or
    |mean(exp(i (k1 + k2) theta))| >= 1 - tol over the samples ``theta``
    [rad].  An order aliased onto a constant (|mean(exp(i k theta))| >=
    1 - tol) is grouped with 0.0 (the offset); 0.0 then appears in the group
    even if it was not among ``orders``.  Repeated orders always group
    together (parts on one shaft).  Grouping is transitive.  Returns only
    groups of two or more entries, each sorted, the list sorted by its
    first entries; orders keep their multiplicity.  Being decided on the
    samples, irregular spacing is handled: jittered targets break the
    exact aliases of evenly spaced ones.
    """
    ords = np.atleast_1d(np.asarray(orders, dtype=float))
    if ords.shape[0] == 0:
        return []
    return _groups(ords, *_correlations(theta, ords, weights), tol)


def aliasing(theta, orders: Sequence[float], tol: float = ALIAS_TOL,
             weights=None) -> tuple[list[tuple[float, ...]], list[float]]:
    """(:func:`alias_groups`, :func:`folded_orders`) of the same samples and orders, from one
    pass over the sampled angles (each alone makes the same pass)."""
    ords = np.atleast_1d(np.asarray(orders, dtype=float))
    if ords.shape[0] == 0:
        return [], []
    c_minus, c_plus, c_zero = _correlations(theta, ords, weights)
    return _groups(ords, c_minus, c_plus, c_zero, tol), _folded(ords, c_plus, tol)


def folded_orders(theta, orders: Sequence[float], tol: float = ALIAS_TOL, weights=None) -> list[float]:
    """Orders whose own cos and sin columns are (nearly) collinear on the
    samples (|mean(exp(2 i k theta))| >= 1 - tol), e.g. order 12 with 24
    evenly spaced targets: only one phase component is observed, so the
    amplitude is not identifiable.  Order 0 and orders aliased onto it are
    included."""
    ords = np.atleast_1d(np.asarray(orders, dtype=float))
    if ords.shape[0] == 0:
        return []
    return _folded(ords, _correlations(theta, ords, weights)[1], tol)


def _folded(ords: np.ndarray, c_plus: np.ndarray, tol: float) -> list[float]:
    return [float(k) for k, c in zip(ords, np.diag(c_plus)) if c >= 1.0 - tol]


# --- physical orders ----------------------------------------------------------------------------------------


_NTH = {1: "", 2: "2nd harmonic of ", 3: "3rd harmonic of "}


def _harmonic_label(h: int, name: str) -> str:
    if h == 1:
        return name
    prefix = _NTH.get(h, f"{h}th harmonic of ")
    return prefix + name


def physical_orders(geometry, harmonics: int = 3, worm_starts: int | None = None,
                    rel_tol: float = 1e-9) -> list[tuple[float, str]]:
    """Orders [cycles per output revolution] that belong to the drive's shafts and meshes.

    Base orders: 1 "output gear (table)" (once per output revolution);
    i_c = z1/z2 "intermediate shaft (pinion and wheel)"; z1 "spur mesh"
    (tooth-mesh order of the output gear and pinion); n_w = i_c z3 / z_worm
    "worm shaft" and, when the worm has ``worm_starts`` > 1 starts, the worm
    mesh order z_worm n_w = i_c z3 "worm mesh" (for a single-start worm the
    two coincide and the label is "worm shaft and worm mesh").  Each base
    order k also contributes h k for h = 2..``harmonics`` ("2nd harmonic of
    ...").  ``geometry``: :class:`~wormgear_cli.physics.effects.DriveGeometry`
    (fields gear_ratio, worm_order, output_teeth).  Orders equal within
    ``rel_tol`` are merged and their labels joined with " / " in the order
    above.  Returns (order, label) sorted by order.
    """
    return [(k, " / ".join(labels)) for k, labels, _ in sorted(_physical(geometry, harmonics, worm_starts,
                                                                             rel_tol), key=lambda t: t[0])]


def _physical(geometry, harmonics: int, worm_starts: int | None, rel_tol: float) -> list[tuple[float, list[str], int]]:
    """(order, labels, lowest harmonic number) of the drive's orders, merged, unsorted."""
    if harmonics < 1:
        raise ValueError("harmonics must be at least 1")
    if worm_starts is None:
        worm_starts = int(getattr(geometry, "worm_starts", 1))
    i_c = float(geometry.gear_ratio)
    n_w = float(geometry.worm_order)
    z1 = float(geometry.output_teeth)
    bases = [(1.0, "output gear (table)"), (i_c, "intermediate shaft (pinion and wheel)"), (z1, "spur mesh")]
    if worm_starts == 1:
        bases.append((n_w, "worm shaft and worm mesh"))
    else:
        bases.append((n_w, "worm shaft"))
        bases.append((n_w * worm_starts, "worm mesh"))
    if getattr(geometry, "labels", ()):  # any other train: its shafts and meshes (drive.train.orders)
        bases = [(float(k), name) for k, name in geometry.labels]
    merged: list[tuple[float, list[str], int]] = []
    for h in range(1, harmonics + 1):
        for k, name in bases:
            order, label = h * k, _harmonic_label(h, name)
            for item in merged:
                if abs(item[0] - order) <= rel_tol * max(abs(order), 1.0):
                    if label not in item[1]:
                        item[1].append(label)
                    break
            else:
                merged.append((order, [label], h))
    return merged


def physical_priority(geometry, harmonics: int = 3, worm_starts: int | None = None,
                      rel_tol: float = 1e-9) -> list[float]:
    """The orders of :func:`physical_orders` ranked for fitting when not all
    can be resolved: every shaft/mesh fundamental first (by order), then the
    2nd harmonics, and so on."""
    items = _physical(geometry, harmonics, worm_starts, rel_tol)
    return [k for k, _, _ in sorted(items, key=lambda t: (t[2], t[0]))]


# --- which orders can be fitted together ----------------------------------------------------------------------


@dataclass(frozen=True)
class Resolution:
    """Result of :func:`select_orders`.

    ``kept``: the candidate orders fitted together (in candidate order);
    ``determinacy``: order -> smallest eigenvalue of the order's (cos, sin)
    block of the column correlation matrix after the other kept columns are
    projected out (1: independent of the others; 1 / determinacy is the
    largest variance inflation of its coefficients), taken when the order
    was kept or dropped; ``reason``: dropped order -> sentence.
    """

    kept: tuple[float, ...]
    determinacy: dict
    reason: dict


def _weighted_gram(theta: np.ndarray, ords: np.ndarray, extra: np.ndarray | None) -> np.ndarray:
    """Gram matrix of [1, extra, cos/sin per order] over the rows, accumulated in blocks."""
    n = theta.shape[0]
    ncol = 1 + (0 if extra is None else extra.shape[1]) + 2 * ords.shape[0]
    gram = np.zeros((ncol, ncol))
    for a in range(0, n, BLOCK_ROWS):
        b = min(a + BLOCK_ROWS, n)
        parts = [np.ones((b - a, 1))]
        if extra is not None:
            parts.append(extra[a:b])
        parts.append(harmonic_columns(theta[a:b], ords))
        xb = np.hstack(parts)
        gram += xb.T @ xb
    return gram


def select_orders(theta, candidates: Sequence[float], min_eigenvalue: float = RESOLVE_MIN_EIG,
                  extra=None, gram=None, distinct: int | None = None) -> Resolution:
    """The candidate orders that can be fitted together, chosen by how well each is determined.

    Backward elimination on the column correlation matrix G (unit-diagonal
    Gram matrix) of [1, ``extra`` columns, cos(k theta), sin(k theta) per
    candidate]: the determinacy of an order is the smallest eigenvalue of
    its 2 x 2 block of the Schur complement of the other columns, i.e.
    1 / lambda_max((G^-1)_kk) (variance inflation factors of the pair).
    While some order's determinacy is below ``min_eigenvalue`` (1e-6: the
    standard errors inflated by more than 1000x), the worst-determined one
    is dropped.  The list order of ``candidates`` only breaks ties between
    orders that cannot be told apart at all (determinacy below 1e-8, e.g.
    more columns than distinct angles): the later one is dropped.  A column
    that vanishes on the samples (a folded order) is dropped first.

    Parameters
    ----------
    theta : array_like [rad], shape (n,)
    candidates : sequence of float [cycles/rev]
    min_eigenvalue : float [-]
    extra : array_like, shape (n, t), optional
        Columns always kept (e.g. a trend, :func:`trend_columns`).
    gram : ndarray, optional
        The Gram matrix of [1, extra, cos/sin per candidate] when already
        accumulated (then ``theta`` and ``extra`` only give the counts).
    distinct : int, optional
        Number of distinct angles (default: counted from ``theta``).
    """
    theta = _as_1d("theta", theta)
    ords = np.atleast_1d(np.asarray(candidates, dtype=float))
    if ords.size == 0:
        return Resolution((), {}, {})
    if gram is None:
        ex = None if extra is None else np.asarray(extra, dtype=float).reshape(theta.shape[0], -1)
        gram = _weighted_gram(theta, ords, ex)
    n_fixed = gram.shape[0] - 2 * ords.size
    has_extra = n_fixed > 1
    diag = np.sqrt(np.maximum(np.diag(gram), 0.0))
    if distinct is None:
        distinct = int(np.unique(theta).size)
    alive = list(range(ords.size))
    det: dict = {}
    reason: dict = {}
    for i in list(alive):
        cols = [n_fixed + 2 * i, n_fixed + 2 * i + 1]
        if np.any(diag[cols] <= 1e-9 * diag[0]):
            alive.remove(i)
            det[float(ords[i])] = 0.0
            reason[float(ords[i])] = "only one phase component is seen on these angles"
    fixed = list(range(n_fixed))
    while alive:
        cols = fixed + [c for i in alive for c in (n_fixed + 2 * i, n_fixed + 2 * i + 1)]
        sub = gram[np.ix_(cols, cols)] / np.outer(diag[cols], diag[cols])
        inv = np.linalg.pinv(sub + 1e-10 * np.eye(len(cols)), hermitian=True)
        d_list = []
        for j in range(len(alive)):
            blk = inv[n_fixed + 2 * j:n_fixed + 2 * j + 2, n_fixed + 2 * j:n_fixed + 2 * j + 2]
            d_list.append(1.0 / max(float(np.linalg.eigvalsh(blk)[-1]), 1.0))
        d = np.asarray(d_list)
        for j, i in enumerate(alive):
            det[float(ords[i])] = float(d[j])
        if d.min() >= min_eigenvalue:
            break
        undetermined = np.flatnonzero(d < 1e-8)
        j = int(undetermined[-1]) if undetermined.size else int(np.argmin(d))
        k = float(ords[alive[j]])
        if len(cols) > distinct:
            reason[k] = (f"too few distinct angles ({distinct}) for {len(cols)} coefficients "
                         f"(offset{', trend' if has_extra else ''} and 2 per order)")
        else:
            reason[k] = (f"not determined apart from the other orders on these angles (variance inflation "
                         f"{1.0 / max(d[j], 1e-300):.3g})")
        alive.pop(j)
    kept = tuple(float(ords[i]) for i in sorted(alive))
    return Resolution(kept, det, reason)


def resolvable_orders(theta, candidates: Sequence[float], min_eigenvalue: float = RESOLVE_MIN_EIG,
                      extra=None) -> list[float]:
    """The candidates that can be fitted together (:func:`select_orders`), in candidate order.

    The single test of resolvability in the code base: an order is kept
    when its determinacy (smallest eigenvalue of its Schur-complement block
    of the column correlation matrix) is at least ``min_eigenvalue``; when
    not all can be kept, the worst-determined is dropped first and the list
    order only breaks exact ties."""
    return list(select_orders(theta, candidates, min_eigenvalue, extra).kept)
