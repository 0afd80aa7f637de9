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

Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

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


def _as_1d(name: str, value, n: int | None = None) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional")
    if n is not None and arr.shape[0] != n:
        raise ValueError(f"{name} has {arr.shape[0]} entries, expected {n}")
    return arr


def _solve(x: np.ndarray, y: np.ndarray, weights: np.ndarray | None, rcond: float, n_fixed: int) -> _Solve:
    """Weighted least squares with a relative singular-value cutoff.

    Well-conditioned designs are solved by the normal equations (fast on
    100 000 rows); anything else by QR and an SVD of R, cutting singular
    values below ``rcond`` times the largest (minimum-norm solution).

    The first ``n_fixed`` columns (intercept, cos/sin: all of magnitude <= 1)
    are used as they are, so a column that vanishes on the samples (sin at a
    Nyquist-like order, ~1e-13) stays negligible and is cut off; later
    (user) columns are scaled to unit RMS so the cutoff does not depend on
    their units.  A column is *identifiable* when the null space of the
    design has no weight on it (its coefficient is unique).
    """
    n, p = x.shape
    if weights is None:
        sw = None
        xw, yw = x, y
        wsum = float(n)
    else:
        if np.any(weights < 0) or not np.all(np.isfinite(weights)):
            raise ValueError("weights must be finite and non-negative")
        sw = np.sqrt(weights)
        xw = x * sw[:, None]
        yw = y * sw
        wsum = float(np.sum(weights))
    norms = np.sqrt(np.einsum("ij,ij->j", xw, xw))
    rms_norm = math.sqrt(max(wsum, 1e-300))
    safe = np.where(norms > 0, norms / rms_norm, 1.0)
    safe[:n_fixed] = 1.0
    xs = xw / safe if np.any(safe != 1.0) else xw
    coef_s = cov_s = None
    identifiable = np.ones(p, dtype=bool)
    rank = p
    if n >= p and p > 0:
        # fast path: normal equations, used only when the design is well
        # conditioned (cond(X) < 1e4, so cond(X^T X) < 1e8 and the solution
        # loses at most ~1e-8 relative accuracy)
        gram = xs.T @ xs
        lam, vec = np.linalg.eigh(gram)
        if lam[0] > 1e-8 * lam[-1] > 0:
            cov_s = (vec / lam) @ vec.T
            coef_s = cov_s @ (xs.T @ yw)
    if coef_s is None:
        # robust path: QR of [X y] (or X padded to square), then SVD of R
        if n < p:
            xs = np.vstack([xs, np.zeros((p - n, p))])
            yq = np.concatenate([yw, np.zeros(p - n)])
        else:
            yq = yw
        r_aug = np.linalg.qr(np.column_stack([xs, yq]), mode="r")
        r, qty = r_aug[:p, :p], r_aug[:p, p]
        u, sv, vt = np.linalg.svd(r)
        smax = sv[0] if sv.size else 0.0
        keep = (sv > rcond * smax) & (sv > 0) if smax > 0 else np.zeros_like(sv, dtype=bool)
        rank = int(np.count_nonzero(keep))
        inv = np.zeros_like(sv)
        inv[keep] = 1.0 / sv[keep]
        coef_s = vt.T @ (inv * (u.T @ qty))
        cov_s = (vt.T * inv**2) @ vt
        # null-space weight of each column: a coefficient is unique only if it has none
        null = vt[~keep]
        null_weight = np.sum(null**2, axis=0) if null.size else np.zeros(p)
        identifiable = null_weight < 1e-6
    coef = coef_s / safe
    cov = cov_s / np.outer(safe, safe)
    residual = y - x @ coef
    wres = residual if sw is None else residual * sw
    rss = float(wres @ wres)
    dof = n - rank
    sigma = math.sqrt(rss / dof) if dof > 0 else math.nan
    rms = math.sqrt(rss / wsum) if wsum > 0 else math.nan
    return _Solve(coef, cov, residual, rank, identifiable, sigma, rms)


def harmonic_columns(theta: np.ndarray, orders: np.ndarray) -> np.ndarray:
    """Design columns [cos(k1 t), sin(k1 t), cos(k2 t), sin(k2 t), ...] (n x 2m)."""
    arg = np.multiply.outer(theta, orders)
    cols = np.empty((theta.shape[0], 2 * orders.shape[0]))
    cols[:, 0::2] = np.cos(arg)
    cols[:, 1::2] = np.sin(arg)
    return cols


def _order_values(a, b, cov_ab, ident, sigma):
    """Amplitude, phase and their standard errors from (a, b) and their covariance."""
    amp = np.hypot(a, b)
    phase = np.arctan2(a, b)
    va, vb, cab = cov_ab[:, 0, 0], cov_ab[:, 1, 1], cov_ab[:, 0, 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        # grad A = (a, b) / A ; grad phi = (b, -a) / A^2
        var_amp = np.where(amp > 0, (a * a * va + b * b * vb + 2 * a * b * cab) / amp**2, 0.5 * (va + vb))
        var_phase = np.where(amp > 0, (b * b * va + a * a * vb - 2 * a * b * cab) / amp**4, np.inf)
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


def fit_modes(theta, y, direction, orders: Sequence[float], weights=None, rcond: float = RCOND) -> ModeFit:
    """Joint least squares of the common and differential modes on all rows.

    Model: y_i = c + sum_k [a_k cos + b_k sin](k theta_i)
    + d_i (c' + sum_k [a'_k cos + b'_k sin](k theta_i)), d_i = +1 forward,
    -1 reverse.  With the same targets in both directions and the same
    number of runs this equals fitting the mean of the directions (common
    mode) and half their difference (differential mode) separately; it also
    works when the directions are sampled at different angles (dense
    scans).  If only one direction is present the differential columns are
    left out and the differential fit is all NaN.
    Units as in :func:`fit_orders`.
    """
    theta = _as_1d("theta", theta)
    n = theta.shape[0]
    y = _as_1d("y", y, n)
    d = _as_1d("direction", direction, n)
    ords = np.atleast_1d(np.asarray(orders, dtype=float))
    m = ords.shape[0]
    w = None if weights is None else _as_1d("weights", weights, n)
    base = np.hstack([np.ones((n, 1)), harmonic_columns(theta, ords)])
    both = bool(np.any(d > 0) and np.any(d < 0))
    x = np.hstack([base, base * d[:, None]]) if both else base
    sol = _solve(x, y, w, rcond, x.shape[1])
    p = 1 + 2 * m
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
        coef = sol.coef[start:start + p]
        cov = sol.cov[start:start + p, start:start + p]
        ident_cols = sol.identifiable[start:start + p]
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
    """(C_minus, C_plus, C_zero) of :func:`order_correlations` and :func:`offset_correlations`."""
    theta = _as_1d("theta", theta)
    ords = np.atleast_1d(np.asarray(orders, dtype=float))
    ut, w = _sampling(theta, weights)
    e = np.exp(1j * np.multiply.outer(ut, ords))
    ew = e * w[:, None]
    c_minus = np.abs(e.conj().T @ ew)
    c_plus = np.abs(e.T @ ew)
    c_zero = np.abs(w @ e)
    return c_minus, c_plus, c_zero


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


def physical_orders(geometry, harmonics: int = 3, worm_starts: int = 1,
                    rel_tol: float = 1e-9) -> list[tuple[float, str]]:
    """Orders [cycles per output revolution] that belong to the drive's shafts and meshes.

    Base orders: 1 "output gear (table)" (once per output revolution);
    i_c = z1/z2 "intermediate shaft (pinion and wheel)"; z1 "spur mesh"
    (tooth-mesh order of the output gear and pinion); n_w = i_c z3 / z_worm
    "worm shaft" and, when the worm has ``worm_starts`` > 1 starts, the worm
    mesh order z_worm n_w = i_c z3 "worm mesh" (for a single-start worm the
    two coincide and the label is "worm shaft and worm mesh").  Each base
    order k also contributes h k for h = 2..``harmonics`` ("2nd harmonic of
    ...").  ``geometry``: :class:`~wormgear_cli.models.effects.DriveGeometry`
    (fields gear_ratio, worm_order, output_teeth).  Orders equal within
    ``rel_tol`` are merged and their labels joined with " / " in the order
    above.  Returns (order, label) sorted by order.
    """
    return [(k, " / ".join(labels)) for k, labels, _ in sorted(_physical(geometry, harmonics, worm_starts,
                                                                             rel_tol), key=lambda t: t[0])]


def _physical(geometry, harmonics: int, worm_starts: int, rel_tol: float) -> list[tuple[float, list[str], int]]:
    """(order, labels, lowest harmonic number) of the drive's orders, merged, unsorted."""
    if harmonics < 1:
        raise ValueError("harmonics must be at least 1")
    i_c = float(geometry.gear_ratio)
    n_w = float(geometry.worm_order)
    z1 = float(geometry.output_teeth)
    bases = [(1.0, "output gear (table)"), (i_c, "intermediate shaft (pinion and wheel)"), (z1, "spur mesh")]
    if worm_starts == 1:
        bases.append((n_w, "worm shaft and worm mesh"))
    else:
        bases.append((n_w, "worm shaft"))
        bases.append((n_w * worm_starts, "worm mesh"))
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


def physical_priority(geometry, harmonics: int = 3, worm_starts: int = 1, rel_tol: float = 1e-9) -> list[float]:
    """The orders of :func:`physical_orders` ranked for fitting when not all
    can be resolved: every shaft/mesh fundamental first (by order), then the
    2nd harmonics, and so on."""
    items = _physical(geometry, harmonics, worm_starts, rel_tol)
    return [k for k, _, _ in sorted(items, key=lambda t: (t[2], t[0]))]


# --- a measurement's orders, aliasing included ---------------------------------------------------------------


@dataclass(frozen=True)
class OrderReport:
    """One requested order after :func:`analyse_orders`.

    ``order`` [cycles/rev]; ``label`` (shaft or mesh, or None); ``status``:
    "fitted"; "aliased" (not fitted: the samples cannot tell it from the
    offset or from another requested order, which then carries its
    content); "folded" (its cos and sin are collinear on the samples: one
    phase component only, not fitted); "unresolved" (not fitted: the
    targets cannot resolve this many orders together, orders earlier in the
    priority list were kept); ``fitted`` = status is "fitted";
    ``aliased_with``: the other requested orders (0.0 = the offset) the
    samples cannot tell it from; ``common`` / ``differential``: (amplitude,
    amplitude_stderr, phase [rad]) of the mean of the directions and of
    half the reversal, NaN where not fitted.
    """

    order: float
    label: str | None
    status: str
    aliased_with: tuple[float, ...]
    common: tuple[float, float, float]
    differential: tuple[float, float, float]

    @property
    def fitted(self) -> bool:
        return self.status == "fitted"


@dataclass(frozen=True)
class OrdersAnalysis:
    """Result of :func:`analyse_orders`: ``items`` per distinct requested
    order (in request order), the joint fit's ``residual_rms`` and
    ``sigma``, ``common_offset`` and ``differential_offset`` (half the mean
    reversal; NaN with one direction), ``alias_tol``, ``both_directions``,
    ``distinct_angles`` (number of distinct sampled angles)."""

    items: tuple[OrderReport, ...]
    residual_rms: float
    sigma: float
    common_offset: float
    differential_offset: float
    alias_tol: float
    both_directions: bool
    distinct_angles: int


def resolvable_orders(theta, candidates: Sequence[float], min_eigenvalue: float = RESOLVE_MIN_EIG) -> list[float]:
    """The candidates that can be fitted together, taken greedily in the given order.

    Starting from the offset alone, each candidate order is kept when the
    design [1, cos(k theta), sin(k theta), ...] of the kept orders plus this
    one stays well conditioned: the smallest eigenvalue of the column
    correlation matrix (unit-diagonal Gram matrix) is at least
    ``min_eigenvalue`` (1e-6: the standard errors are inflated by at most
    ~1000x).  With N distinct targets at most (N - 1) / 2 orders fit; the
    rest are left out (not resolvable by these targets), the first ones
    in ``candidates`` having priority."""
    theta = _as_1d("theta", theta)
    ords = np.atleast_1d(np.asarray(candidates, dtype=float))
    if ords.size == 0:
        return []
    x = np.hstack([np.ones((theta.shape[0], 1)), harmonic_columns(theta, ords)])
    gram = x.T @ x
    diag = np.sqrt(np.diag(gram))
    keep_cols = [0]
    kept = []
    for i, k in enumerate(ords):
        cols = [1 + 2 * i, 2 + 2 * i]
        if np.any(diag[cols] <= 1e-9 * diag[0]):
            continue  # a column vanishing on the samples (folded order)
        trial = keep_cols + cols
        sub = gram[np.ix_(trial, trial)] / np.outer(diag[trial], diag[trial])
        if np.linalg.eigvalsh(sub)[0] >= min_eigenvalue:
            keep_cols = trial
            kept.append(float(k))
    return kept


def analyse_orders(theta, y, direction, orders: Sequence[float], labels: Sequence[str | None] | None = None,
                   priority: Sequence[float] | None = None, tol: float = ALIAS_TOL) -> OrdersAnalysis:
    """Amplitudes at exact orders of a measurement, aliasing and resolution handled.

    ``theta`` [rad], ``y`` errors [any unit], ``direction`` +1/-1 per row;
    ``orders`` [cycles/rev] (repeats dropped, first kept), optional
    ``labels``; ``priority``: the orders in the order they should be kept
    when not all can be fitted (default: ``orders`` as given).

    1. Alias groups on the sampled angles (:func:`alias_groups`): an order
       grouped with the offset is not fitted; in any other group only the
       member first in ``priority`` is fitted and carries the group.
    2. Folded orders (:func:`folded_orders`) are not fitted.
    3. The rest are kept greedily in priority order while the design stays
       well conditioned (:func:`resolvable_orders`).
    4. One joint least-squares fit on all rows (:func:`fit_modes`): common
       mode + direction x differential mode at the kept orders.
    """
    theta = _as_1d("theta", theta)
    d = _as_1d("direction", direction, theta.shape[0])
    ords: list[float] = []
    labs: list[str | None] = []
    for i, k in enumerate(np.atleast_1d(np.asarray(orders, dtype=float))):
        if float(k) not in ords:
            ords.append(float(k))
            labs.append(None if labels is None else labels[i])
    rank = {k: len(ords) for k in ords}
    for i, k in enumerate([] if priority is None else [float(v) for v in priority]):
        if k in rank and rank[k] == len(ords):
            rank[k] = i
    by_priority = sorted(ords, key=lambda k: (rank[k], ords.index(k)))
    if ords:
        arr = np.asarray(ords)
        cm, cp, cz = _correlations(theta, arr, None)
        groups = _groups(arr, cm, cp, cz, tol)
        folded = set(_folded(arr, cp, tol))
    else:
        groups, folded = [], set()
    group_of: dict[float, tuple[float, ...]] = {}
    for g in groups:
        for k in g:
            group_of[k] = g
    status: dict[float, str] = {}
    candidates = []
    for k in by_priority:
        g = group_of.get(k)
        if g is not None and (0.0 in g or k != min((v for v in g if v in rank), key=lambda v: (rank[v], ords.index(v)))):
            status[k] = "aliased"
        elif k in folded:
            status[k] = "folded"
        else:
            candidates.append(k)
    kept = set(resolvable_orders(theta, candidates))
    for k in candidates:
        status[k] = "fitted" if k in kept else "unresolved"
    fitted = [k for k in ords if status[k] == "fitted"]
    fit = fit_modes(theta, y, d, fitted)
    pos = {k: i for i, k in enumerate(fitted)}
    nan3 = (math.nan, math.nan, math.nan)

    def triple(f, i):
        if not f.identifiable[i] or not np.isfinite(f.amplitude[i]):
            return nan3
        return (float(f.amplitude[i]), float(f.amplitude_stderr[i]), float(f.phase[i]))

    items = []
    for k, lab in zip(ords, labs):
        others = [v for v in group_of.get(k, (k,)) if v != k]
        if k in pos:
            i = pos[k]
            items.append(OrderReport(k, lab, "fitted", tuple(others), triple(fit.common, i),
                                     triple(fit.differential, i)))
        else:
            items.append(OrderReport(k, lab, status[k], tuple(others), nan3, nan3))
    both = bool(np.any(d > 0) and np.any(d < 0))
    return OrdersAnalysis(tuple(items), fit.rms, fit.sigma, fit.common.offset,
                          fit.differential.offset if both else math.nan, tol, both, int(np.unique(theta).size))
