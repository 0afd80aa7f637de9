"""The strongest orders of a measurement: a scan over every order the data can resolve.

:func:`dominant_orders` is the one strongest-order report of the code base, used by ``measure``
(its ``dominant`` section), by ``diagnose`` (orders of the residual beyond its fixed list) and meant
for the telescope-log and compensation-table work.  It is a pure function of arrays.

Method (a periodogram at exact orders, then exact least squares at the peaks):

1. The slow part and what is held are projected out first: the offset, a direction offset (both
   directions), the slow part over a partial arc
   (:func:`~wormgear_cli.measurement.drift.slow_model`: a trend over the arc, or a drift in time
   when the arc is traversed repeatedly) and the ``held`` orders.
2. Every order the data can resolve is scanned: from one cycle over the covered arc (order 1 on a
   full turn) up to the Nyquist limit of the spacing (pi / median spacing of the distinct angles),
   on a grid of whole orders over a full turn, or of 1 / ``oversample`` of the resolution
   (360 deg / span) over a partial arc.  The power at an order is the sum of squares its (cos, sin)
   pair explains once the model is projected out (the generalised Lomb-Scargle periodogram,
   Zechmeister & Kuerster 2009, A&A 496, 577), computed exactly at every grid order when rows x
   orders is small, else screened by an FFT of the residual binned along the arc.
3. The noise level at each order follows the periodogram's medians in logarithmic bins, joined
   piecewise linearly in log-log (a smooth background, so that a drift's red spectrum is not taken
   for peaks; the test of a peak against a fitted red-noise continuum of Vaughan 2010, MNRAS 402,
   307); under noise alone power / level is exponentially distributed, so p = exp(-power / level),
   Bonferroni over the independent orders scanned.
4. Peaks are taken one at a time, strongest first, each refined to the exact order of largest
   power (partial arcs) and projected out before the next (prewhitening), while significant, up
   to ``max_peaks``.  Over a partial arc the peaks' orders are then refined together, each with the
   others held and its own harmonics fitted with it (:func:`_improve`).  The peaks are then fitted
   jointly by least squares with the model of step 1;
   standard errors from blocks of consecutive rows where the residual is serially correlated
   (:func:`~wormgear_cli.measurement.serial.serial_blocks`).
5. Each peak's *group*: the interval of orders that cannot be told apart from it (canonical
   correlation of their columns at least
   :data:`~wormgear_cli.measurement.separation.SEPARATION_CORR`): on a 39 deg arc, order 225
   cannot be told from 224 or 226.

Pure numpy, no I/O.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from wormgear_cli.measurement.arrays import unique as lean_unique
from wormgear_cli.measurement.coverage import Coverage, coverage, unwrap_passes
from wormgear_cli.measurement.coverage import as_1d as _as_1d
from wormgear_cli.measurement.drift import MIN_PERIOD_SHARE, SlowPart, drift_size, slow_model
from wormgear_cli.measurement.separation import SEPARATION_CORR
from wormgear_cli.measurement.serial import SerialBlocks, block_covariance, serial_blocks

#: orders from which :func:`cos_sin` computes an evenly spaced grid by the angle-addition formulas
SPLIT_ORDERS = 64
#: how far [units in the last place of the largest order] the orders the addition formulas stand for may lie
#: from the grid's (else cos and sin are taken directly)
SPLIT_ULPS = 8.0
#: highest order ever scanned [cycles/rev] (a thousandth of a degree of angle error is a sizeable phase error beyond)
MAX_SCAN_ORDER = 100_000.0
#: rows x grid orders up to which the power is computed exactly at every grid order over a partial arc (beyond:
#: FFT screening); over a full turn, where the binned FFT is close, up to FULL_TURN_BUDGET
DIRECT_BUDGET = 8.0e6
FULL_TURN_BUDGET = 1.0e6
#: share of an order's columns that must survive projection on the model for it to be scanned
MIN_SCAN_SHARE = 0.05
#: fewest grid orders for a background that follows the spectrum (fewer: one level, the median)
MIN_BACKGROUND_POINTS = 40
#: most logarithmic bins of the background
BACKGROUND_BINS = 16
#: rows used to find a peak's group on a long measurement (an even subsample)
GROUP_ROWS = 20_000
#: correlation above which a labelled order beyond the scanned range is named as (partly) aliased onto a peak
ALIAS_CORR = 0.5
#: largest FFT length of the screening
MAX_FFT = 1 << 22
#: rows up to which an orthonormal basis of the model is kept (beyond: normal equations in blocks of rows)
BASIS_ROWS = 100_000
#: rows per block when the model is handled in blocks
BLOCK = 65_536
#: harmonics of a peak fitted with it when the peaks' orders are refined together (partial arcs)
REFINE_HARMONICS = 3
#: rounds of that refinement (each peak in turn, the others held)
REFINE_ROUNDS = 2


@dataclass(frozen=True)
class ScanOptions:
    """Options of :func:`dominant_orders`.

    ``max_peaks``: most orders reported (the strongest first);
    ``alpha``: family-wise level of the peak test (Bonferroni over the
    independent orders scanned); ``min_order`` / ``max_order`` [cycles/rev]:
    the scanned range (default: one cycle over the arc, order 1 on a full
    turn, up to the Nyquist limit of the spacing, at most
    :data:`MAX_SCAN_ORDER`); ``oversample``: grid orders per resolution
    element over a partial arc; ``held``: orders already fitted (projected
    out, never reported); ``labels``: (order, label) pairs that name a peak
    whose group holds the order (a drive's shafts and meshes);
    ``seconds_per_turn``: time of one turn [s] for the periods (default:
    from ``time`` when the rows move at a steady rate); ``separation``: the
    canonical correlation of a peak's group; ``drift_per_run``: each run
    (``passes``) has an offset and a drift in time of its own (the sessions of
    a guide log; :func:`~wormgear_cli.measurement.drift.slow_model`), and
    orders slower than one cycle over the longest run are not scanned;
    ``label_window`` [cycles/rev]: a labelled order at most this far from a
    peak names it even outside the peak's group (runs whose relative phase is
    known less well than their placement on the angle says: a guide log's
    sessions placed by their logged hour angle)."""

    max_peaks: int = 5
    alpha: float = 0.01
    min_order: float | None = None
    max_order: float | None = None
    oversample: int = 5
    held: tuple = ()
    labels: tuple = ()
    seconds_per_turn: float | None = None
    separation: float = SEPARATION_CORR
    drift_per_run: bool = False
    label_window: float = 0.0


@dataclass(frozen=True)
class DominantOrder:
    """One of the strongest orders (:func:`dominant_orders`).

    ``order`` [cycles/rev] (exact: the order of largest power, refined off
    the grid over a partial arc); ``amplitude`` (zero-to-peak) and
    ``amplitude_stderr`` [unit of y], ``phase`` [rad] with y ~ A sin(k theta
    + phase), from the joint fit; ``power_ratio``: its power over the
    background level at its order; ``p_adjusted``: exp(-power_ratio) times
    the independent orders scanned (capped at 1); ``significant``:
    p_adjusted < alpha; ``group`` (lo, hi) [cycles/rev]: the orders that
    cannot be told apart from it; ``period_s``: seconds per cycle (None
    without a time base); ``label``: the label of an order in its group;
    ``differential`` / ``differential_stderr``: the amplitude of half the
    reversal at the order (both directions measured; else NaN).  With both
    directions each order is scanned as its common and differential pair
    together.  ``aliases``: ((order, correlation, label), ...) of the labelled
    orders beyond the scanned range whose columns correlate with this
    order's by at least :data:`ALIAS_CORR` on these samples (on sparse
    targets a drive order above the Nyquist limit shows partly here); the
    ``label`` then names the strongest of them when no labelled order is in
    the group."""

    order: float
    amplitude: float
    amplitude_stderr: float
    phase: float
    power_ratio: float
    p_adjusted: float
    significant: bool
    group: tuple[float, float]
    period_s: float | None = None
    label: str | None = None
    differential: float = math.nan
    differential_stderr: float = math.nan
    aliases: tuple = ()

    @property
    def size(self) -> float:
        """hypot(amplitude, differential): what orders the peaks (the differential counts where measured)."""
        return math.hypot(self.amplitude, self.differential) if math.isfinite(self.differential) else self.amplitude


@dataclass(frozen=True)
class Dominant:
    """Result of :func:`dominant_orders`.

    ``peaks``: the significant orders, strongest (largest amplitude, the
    differential counted with both directions) first,
    at most ``max_peaks``; when none is significant, the strongest scanned
    order alone (``significant`` False); ``scanned`` (lo, hi) [cycles/rev];
    ``resolution`` [cycles/rev]: the spacing of independent orders
    (360 deg / span; 1 on a full turn); ``nyquist`` [cycles/rev]: pi over
    the median spacing of the distinct angles; ``independent``: independent
    orders scanned (the Bonferroni count); ``method``: how the powers were
    computed; ``slow``: the trend or drift projected out, with its size;
    ``residual_rms``: RMS of the residual after the model and the
    significant peaks [unit of y]; ``serial``: how the standard errors treat
    serially correlated rows; ``seconds_per_turn`` (None without a time
    base); ``coverage``; ``note``: why nothing was scanned (else empty)."""

    peaks: tuple[DominantOrder, ...]
    scanned: tuple[float, float]
    resolution: float
    nyquist: float
    independent: int
    method: str
    slow: SlowPart
    residual_rms: float
    serial: SerialBlocks
    seconds_per_turn: float | None
    coverage: Coverage
    note: str = ""

    @property
    def strongest(self) -> DominantOrder | None:
        return self.peaks[0] if self.peaks else None

    @property
    def significant(self) -> tuple[DominantOrder, ...]:
        return tuple(p for p in self.peaks if p.significant)


@dataclass
class _Scan:
    """The data of one scan: angles, residual, the model's orthonormal basis and the grid."""

    theta: np.ndarray
    y: np.ndarray
    base: np.ndarray  # (n, q) model columns (offset, direction offset, slow part, held orders)
    grid: np.ndarray
    span: float
    full_turn: bool
    d: np.ndarray | None = None  # directions when both occur (then each order has a differential pair too)
    q: np.ndarray | None = field(default=None)  # orthonormal basis of base and the accepted peaks
    peaks: list = field(default_factory=list)
    q_peaks: int = 0  # peaks already in q
    normal: tuple | None = None  # (peaks, X'X, X'y) of the last normal equations
    sw: np.ndarray | None = None  # sqrt of the rows per unit when the rows are reduced to (angle, direction) units
    rows: tuple | None = None  # (y per row, unit of each row) when reduced
    bins: tuple | None = None  # (cells, cell of each unit) of the FFT screening

    @property
    def total(self) -> float:
        """Rows behind the scan (units weighted by their rows)."""
        return float(self.theta.shape[0]) if self.sw is None else float(self.sw @ self.sw)

    def trig(self, k: float, a: int = 0, b: int | None = None) -> np.ndarray:
        """cos, sin [, d cos, d sin] of order ``k`` at units a..b-1, weighted when reduced."""
        th = self.theta[a:b]
        return self.weighted(np.column_stack([np.cos(k * th), np.sin(k * th)]), a, b)

    def weighted(self, c: np.ndarray, a: int = 0, b: int | None = None) -> np.ndarray:
        """(cos, sin) columns ``c`` (rows a..b-1, (m, 2)) as the scan's columns: [, d cos, d sin] with both
        directions, weighted when reduced."""
        if self.d is not None:
            c = np.hstack([c, c * self.d[a:b, None]])
        return c if self.sw is None else c * self.sw[a:b, None]

    def order_columns(self, k: float) -> np.ndarray:
        """(n, 2) or, with both directions, (n, 4): cos, sin [, d cos, d sin] of order ``k``."""
        return self.trig(k)

    def design(self, a: int, b: int) -> np.ndarray:
        """Rows a..b-1 of the model's columns: [base, each accepted peak's columns]."""
        return np.hstack([self.base[a:b]] + [self.trig(k, a, b) for k in self.peaks])

    def blocks(self):
        n = self.theta.shape[0]
        return [(a, min(a + BLOCK, n)) for a in range(0, n, BLOCK)] or [(0, 0)]

    def refresh(self) -> np.ndarray:
        """The residual of y on the model and the accepted peaks.  Up to :data:`BASIS_ROWS` rows an
        orthonormal basis is kept (the base's once, each new peak's columns orthogonalised against it and
        appended) for the exact powers; beyond, the normal equations are accumulated in blocks of rows."""
        if self.theta.shape[0] > BASIS_ROWS:
            gram, rhs = self.normal_equations()
            coef = _solve_gram(gram, rhs)
            resid = np.empty_like(self.y)
            for a, b in self.blocks():
                resid[a:b] = self.y[a:b] - self.design(a, b) @ coef
            return resid
        if self.q is None:
            self.q = _orthonormal(self.base)
        for k in self.peaks[self.q_peaks:]:
            c = self.order_columns(k)
            for _ in range(2):  # twice is enough (Gram-Schmidt with reorthogonalisation)
                c = c - self.q @ (self.q.T @ c)
            self.q = np.hstack([self.q, _orthonormal(c)])
        self.q_peaks = len(self.peaks)
        return self.y - self.q @ (self.q.T @ self.y)

    def normal_equations(self) -> tuple[np.ndarray, np.ndarray]:
        """(X'X, X'y) of the model and the accepted peaks, accumulated in blocks of rows (kept per peak set)."""
        key = tuple(self.peaks)
        if self.normal is not None and self.normal[0] == key:
            return self.normal[1], self.normal[2]
        gram, rhs = None, None
        for a, b in self.blocks():
            x = self.design(a, b)
            g, r = x.T @ x, x.T @ self.y[a:b]
            gram, rhs = (g, r) if gram is None else (gram + g, rhs + r)
        assert gram is not None and rhs is not None  # (blocks() gives at least one block)
        self.normal = (key, gram, rhs)
        return gram, rhs


def _solve_gram(gram: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """The least-squares coefficients from the normal equations (scaled, pseudo-inverse for safety)."""
    return _gram_inverse(gram) @ rhs


def _gram_inverse(gram: np.ndarray) -> np.ndarray:
    scale = np.sqrt(np.maximum(np.diag(gram), 1e-300))
    return np.linalg.pinv(gram / np.outer(scale, scale), rcond=1e-12, hermitian=True) / np.outer(scale, scale)


def _orthonormal(x: np.ndarray) -> np.ndarray:
    """An orthonormal basis of the columns of ``x`` (n x k, k small) from the eigenvectors of its Gram
    matrix (directions below 1e-10 of the largest left out): n k^2 work, no n x n factor."""
    gram = x.T @ x
    lam, vec = np.linalg.eigh(gram)
    keep = lam > 1e-10 * max(float(lam[-1]), 1e-300)
    return x @ (vec[:, keep] / np.sqrt(lam[keep]))


def dominant_orders(theta, y, direction=None, time=None, passes=None, options: ScanOptions | None = None) -> Dominant:
    """The strongest orders of ``y`` over angles ``theta``, with their groups, periods and significance.

    Parameters
    ----------
    theta : array_like [rad], shape (n,)
        Output angles (any spacing, wrapped or not).
    y : array_like [any unit], shape (n,)
        Errors (or a residual).
    direction : array_like, shape (n,), optional
        +1 / -1 per row (a direction offset is held when both occur).
    time : array_like [s], shape (n,), optional
        Time of each row: the drift in time over a repeatedly traversed arc,
        the time order of the rows, and the periods in seconds.
    passes : array_like of int, shape (n,), optional
        Run or pass of each row (unwrapping, traversals, blocks).
    options : ScanOptions, optional

    Returns
    -------
    Dominant
        See the module docstring for the method.  Fewer than 8 rows or 3
        distinct angles, or an empty range, give no peaks and a ``note``.
    """
    opt = options or ScanOptions()
    theta = _as_1d("theta", theta)
    n = theta.shape[0]
    y = _as_1d("y", y, n)
    d = np.ones(n) if direction is None else _as_1d("direction", direction, n)
    t = None if time is None else _as_1d("time", time, n)
    th = unwrap_passes(theta, passes)
    cov = coverage(theta, orders=[1.0, *[float(k) for k in opt.held]])
    slow = slow_model(theta, cov, passes, d, t, per_run=opt.drift_per_run)
    slow_at = _slow_at(d, slow.columns)
    lo, hi, resolution, nyquist = _range(th, cov, slow, opt)
    spt = opt.seconds_per_turn if opt.seconds_per_turn else _seconds_per_turn(th, t, passes)
    empty = n < 8 or cov.distinct < 3 or not hi >= lo
    grid = _grid(lo, hi, resolution, cov.full_turn, opt.oversample) if not empty else np.zeros(0)
    both = bool(np.any(d > 0) and np.any(d < 0))
    scan = _make_scan(th, y, d if both else None, functools.partial(_base_matrix, th, d, slow.columns, opt.held),
                      grid, cov, slow.kind != "time")
    del th  # the scan holds what it needs (the distinct angles when it works on units)
    resid = scan.refresh()
    independent = max(1, int(round((hi - lo) / resolution)) + 1) if grid.size else 0
    found, method = _peaks(scan, resid, independent, opt) if grid.size else ([], "")
    found = _improve(scan, found, hi, resolution)
    fit = _joint_fit(scan, [f[0] for f in found], passes, t)
    slow_size = drift_size(slow.columns, fit["coef"][slow_at]) if slow.degree else 0.0
    peaks = []
    for i, (k, ratio, p_adj) in enumerate(found):
        group = _group(scan, k, opt.separation, resolution)
        aliases = _aliases(scan, k, [(o, lab) for o, lab in opt.labels if float(o) > hi])
        label = _label((min(group[0], k - opt.label_window), max(group[1], k + opt.label_window)), k, opt.labels)
        if label is None and aliases:
            o, c, lab = aliases[0]
            label = f"partly aliased with order {o:g} ({lab}; correlation {c:.2f} on these angles)"
        peaks.append(DominantOrder(k, fit["amp"][i], fit["se"][i], fit["phase"][i], ratio, p_adj, p_adj < opt.alpha,
                                   group, spt / k if spt else None, label, fit["diff"][i], fit["diff_se"][i],
                                   aliases))
    significant = sorted((p for p in peaks if p.significant), key=lambda p: -p.size)[:opt.max_peaks]
    shown = tuple(significant) if significant else tuple(peaks[:1])
    note = "" if grid.size else _empty_note(n, cov, lo, hi)
    return Dominant(shown, (lo, hi), resolution, nyquist, independent, method, slow.part(slow_size),
                    fit["rms"], fit["serial"], spt, cov, note)


def _make_scan(th, y, d, base_of, grid, cov: Coverage, reducible: bool) -> _Scan:
    """The scan over the rows, or, when the model is a function of angle and direction (no drift in time)
    and rows repeat their (angle, direction) at least four times on average, over those units: the unit
    means weighted by sqrt(rows) give the rows' least squares exactly, for a fraction of the work.
    ``base_of()``: the model's columns at every row (made once the units are known, and dropped after)."""
    n = th.shape[0]
    if reducible and cov.distinct * 4 <= n:  # (distinct angles on the circle: no more than in th)
        key = lean_unique(th)[1]  # the row's distinct angle, made the (angle, direction) key in place
        key *= 2
        if d is not None:
            key += d > 0
        uk, first, unit = lean_unique(key, return_index=True)
        del key
        if uk.shape[0] * 4 <= n:
            counts = np.bincount(unit).astype(float)
            sw = np.sqrt(counts)
            mean = np.bincount(unit, weights=y) / counts
            return _Scan(th[first], mean * sw, base_of()[first] * sw[:, None], grid, cov.span, cov.full_turn,
                         None if d is None else d[first], sw=sw, rows=(y, unit))
    return _Scan(th, y, base_of(), grid, cov.span, cov.full_turn, d)


def _slow_at(d, slow_cols) -> slice:
    """Where the slow part sits among the base columns (:func:`_base_columns`)."""
    first = 2 if np.any(d > 0) and np.any(d < 0) else 1
    return slice(first, first + slow_cols.shape[1])


def _base_matrix(theta, d, slow_cols, held) -> np.ndarray:
    return _base_columns(theta, d, slow_cols, held)[0]


def _base_columns(theta, d, slow_cols, held) -> tuple[np.ndarray, slice]:
    """([1, direction (both directions), slow part, cos/sin of the held orders], where the slow part sits)."""
    cols = [np.ones((theta.shape[0], 1))]
    if np.any(d > 0) and np.any(d < 0):
        cols.append(d[:, None])
    first = len(cols)
    cols.append(slow_cols)
    for k in held:
        cols.append(np.column_stack([np.cos(float(k) * theta), np.sin(float(k) * theta)]))
    return np.hstack(cols), slice(first, first + slow_cols.shape[1])


def _range(theta, cov: Coverage, slow, opt: ScanOptions) -> tuple[float, float, float, float]:
    """(lowest, highest order scanned, resolution, Nyquist limit) [cycles/rev] (``slow``: the
    :class:`~wormgear_cli.measurement.drift.SlowModel`)."""
    two_pi = 2.0 * math.pi
    resolution = 1.0 if cov.full_turn or cov.span <= 0 else two_pi / cov.span
    distinct = np.unique(np.mod(theta, two_pi))
    if distinct.size >= 2:
        gaps = np.diff(distinct)
        if not cov.full_turn:
            gaps = gaps[gaps < cov.largest_gap * (1.0 - 1e-12)] if gaps.size > 1 else gaps
        spacing = float(np.median(gaps)) if gaps.size else two_pi
    else:
        spacing = two_pi
    nyquist = math.pi / spacing if spacing > 0 else 0.0
    if cov.full_turn:
        lo = 1.0
    else:
        lo = resolution * (MIN_PERIOD_SHARE if slow.kind == "time" else 1.0)
    if slow.run_span > 0:  # an offset and a drift per run: one cycle over the longest run at least
        lo = max(lo, 2.0 * math.pi / slow.run_span)
    hi = min(nyquist, MAX_SCAN_ORDER)
    if opt.min_order is not None:
        lo = max(lo, float(opt.min_order))
    if opt.max_order is not None:
        hi = min(hi, float(opt.max_order))
    if cov.full_turn:
        lo, hi = float(math.ceil(lo - 1e-9)), float(math.floor(hi + 1e-9))
    return lo, hi, resolution, nyquist


def _grid(lo: float, hi: float, resolution: float, full_turn: bool, oversample: int) -> np.ndarray:
    if full_turn:
        return np.arange(lo, hi + 0.5)
    step = resolution / max(1, int(oversample))
    return lo + step * np.arange(int(math.floor((hi - lo) / step)) + 1)


def _seconds_per_turn(theta, time, passes) -> float | None:
    """Seconds per turn from the rows' steady motion: the median over passes of |d theta / d t| (least
    squares), used only when angle and time move together in every pass (|correlation| > 0.99)."""
    if time is None or theta.shape[0] < 3:
        return None
    pid = np.zeros(theta.shape[0], dtype=np.int64) if passes is None else np.asarray(passes).reshape(-1)
    rates = []
    for p in np.unique(pid):
        sel = pid == p
        tt, aa = time[sel], theta[sel]
        if tt.shape[0] < 3 or np.ptp(tt) <= 0 or np.ptp(aa) <= 0:
            continue
        c = float(np.corrcoef(tt, aa)[0, 1])
        if not abs(c) > 0.99:
            return None
        rates.append(abs(float(np.polyfit(tt, aa, 1)[0])))
    if not rates:
        return None
    rate = float(np.median(rates))
    return 2.0 * math.pi / rate if rate > 0 else None


def _empty_note(n: int, cov: Coverage, lo: float, hi: float) -> str:
    if n < 8 or cov.distinct < 3:
        return f"too few rows or distinct angles ({n} rows, {cov.distinct} angles) to scan for orders"
    return (f"no order to scan: one cycle over the arc needs order {lo:.4g}, while the spacing of the angles "
            f"resolves up to order {hi:.4g}")


def cos_sin(theta: np.ndarray, orders: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of ``orders[j] * theta[i]``, shape (n, m) each.

    On an evenly spaced grid of at least :data:`SPLIT_ORDERS` orders (the scan's), by the angle-addition
    formulas from the cos and sin of about 2 sqrt(m) columns: order ``k[a M + b]`` is taken as
    ``k[a M] + (k[b] - k[0])``, which rounds to within :data:`SPLIT_ULPS` units in the last place of the
    largest order of the grid (else the direct form is used), and each value is one product sum of
    exact cos and sin (an error of a few units in the last place, as the direct form's rounding of
    the product ``k theta``), for a quarter of the work of m cos and sin per row.

    Parameters
    ----------
    theta : ndarray [rad], shape (n,)
    orders : ndarray [cycles/rev], shape (m,)

    Returns
    -------
    (ndarray, ndarray)
        cos and sin, shape (n, m) each (rows contiguous; a view of a slightly wider array on the grid).
    """
    n, m = theta.shape[0], orders.shape[0]
    if m >= SPLIT_ORDERS:
        width = int(math.ceil(math.sqrt(m)))
        blocks = -(-m // width)
        base = orders[::width]
        offset = orders[:width] - orders[0]
        taken = (base[:, None] + offset[None, :]).reshape(-1)[:m]
        if np.all(np.abs(taken - orders) <= SPLIT_ULPS * np.finfo(float).eps * float(np.max(np.abs(orders)))):
            a, b = np.multiply.outer(theta, base), np.multiply.outer(theta, offset)
            ca, sa, cb, sb = np.cos(a)[:, :, None], np.sin(a)[:, :, None], np.cos(b)[:, None, :], np.sin(b)[:, None, :]
            cos, sin, work = (np.empty((n, blocks, width)) for _ in range(3))
            np.multiply(ca, cb, out=cos)
            cos -= np.multiply(sa, sb, out=work)
            np.multiply(sa, cb, out=sin)
            sin += np.multiply(ca, sb, out=work)
            return cos.reshape(n, -1)[:, :m], sin.reshape(n, -1)[:, :m]
    arg = np.multiply.outer(theta, orders)
    return np.cos(arg), np.sin(arg)


def _powers(scan: _Scan, resid: np.ndarray, orders: np.ndarray) -> np.ndarray:
    """Sum of squares of ``resid`` explained by each order's (cos, sin) pair (and its differential pair with
    both directions) with the model projected out, exactly, in chunks (NaN where the model takes up all
    but MIN_SCAN_SHARE of the columns)."""
    if scan.q is None:
        return _powers_blocks(scan, resid, orders)
    n = scan.theta.shape[0]
    width = 2 if scan.d is None else 4
    out = np.full(orders.shape[0], np.nan)
    chunk = max(1, int(2_000_000 // max(n * width // 2, 1)))
    q = scan.q
    for a in range(0, orders.shape[0], chunk):
        ks = orders[a:a + chunk]
        cols = list(cos_sin(scan.theta, ks))
        if scan.d is not None:
            cols += [cols[0] * scan.d[:, None], cols[1] * scan.d[:, None]]
        if scan.sw is not None:
            cols = [c * scan.sw[:, None] for c in cols]
        proj = [q.T @ c for c in cols]
        gram = np.empty((ks.shape[0], width, width))
        for i in range(width):
            for j in range(i, width):
                gram[:, i, j] = gram[:, j, i] = (np.einsum("ij,ij->j", cols[i], cols[j])
                                                 - np.einsum("ij,ij->j", proj[i], proj[j]))
        rhs = np.stack([resid @ c for c in cols], axis=1)
        total = np.einsum("kii->k", gram)
        keep = total > MIN_SCAN_SHARE * scan.total * width / 2
        lam = np.linalg.eigvalsh(gram)
        keep &= lam[:, 0] > 1e-9 * np.maximum(lam[:, -1], 1e-300)
        safe = np.where(keep[:, None, None], gram, np.eye(width))
        coef = np.linalg.solve(safe, rhs[:, :, None])[:, :, 0]
        out[a:a + chunk] = np.where(keep, np.einsum("ki,ki->k", coef, rhs), np.nan)
    return out


def _powers_blocks(scan: _Scan, resid: np.ndarray, orders: np.ndarray) -> np.ndarray:
    """:func:`_powers` at a few orders on a long measurement: the orders' columns against the model by
    normal equations accumulated in blocks of rows (no n x k basis)."""
    gram_model, _ = scan.normal_equations()
    g_inv = _gram_inverse(gram_model)
    width = 2 if scan.d is None else 4
    out = np.full(orders.shape[0], np.nan)
    for i, k in enumerate(orders):
        cc = np.zeros((width, width))
        cx = np.zeros((width, gram_model.shape[0]))
        cr = np.zeros(width)
        for a, b in scan.blocks():
            c = scan.trig(k, a, b)
            cc += c.T @ c
            cx += c.T @ scan.design(a, b)
            cr += c.T @ resid[a:b]
        m = cc - cx @ g_inv @ cx.T
        lam = np.linalg.eigvalsh(m)
        if np.trace(m) > MIN_SCAN_SHARE * scan.total * width / 2 and lam[0] > 1e-9 * max(lam[-1], 1e-300):
            out[i] = float(cr @ np.linalg.solve(m, cr))
    return out


def _fft_powers(scan: _Scan, resid: np.ndarray) -> np.ndarray:
    """Screening powers at the grid orders from an FFT of the residual binned along the arc
    (2 |sum r e^(-i k theta)|^2 / n, each row moved to its bin's centre)."""
    two_pi = 2.0 * math.pi
    grid = scan.grid
    hi = float(grid[-1])
    start = float(np.min(scan.theta))
    extent = two_pi if scan.full_turn else max(float(np.ptp(scan.theta)), 1e-12)
    cells = 1 << max(4, int(math.ceil(math.log2(max(4.0 * hi * extent / math.pi, 16.0)))))
    cells = min(cells, MAX_FFT)
    width = extent / cells
    if scan.bins is None or scan.bins[0] != cells:
        if scan.full_turn:
            idx = np.mod((np.mod(scan.theta, two_pi) / width).astype(np.int64), cells)
        else:
            idx = np.clip(((scan.theta - start) / width).astype(np.int64), 0, cells - 1)
        scan.bins = (cells, idx)
    idx = scan.bins[1]
    step = float(grid[1] - grid[0]) if grid.shape[0] > 1 else 1.0
    length = cells
    while two_pi / (length * width) > step * (1.0 + 1e-9) and length < MAX_FFT:
        length *= 2
    freq = two_pi * np.arange(length // 2 + 1) / (length * width)  # cycles per revolution of each bin
    pos = np.clip(np.searchsorted(freq, grid), 1, freq.shape[0] - 1)
    nearest = np.where(np.abs(freq[pos - 1] - grid) < np.abs(freq[pos] - grid), pos - 1, pos)
    out = np.zeros(grid.shape[0])
    n = scan.total
    if scan.sw is not None:
        resid = resid * scan.sw  # the rows' residuals summed per unit
    for weights in ([resid] if scan.d is None else [resid, resid * scan.d]):
        spec = np.fft.rfft(np.bincount(idx, weights=weights, minlength=cells), n=length)
        # the phase reference of the bins (their centres, from ``start``) does not change |F|
        out += 2.0 * np.abs(spec[nearest]) ** 2 / n
    return out


def _background(orders: np.ndarray, power: np.ndarray) -> np.ndarray:
    """The noise level (mean power) at each order: the medians / ln 2 of the powers in logarithmic bins
    (at most :data:`BACKGROUND_BINS`, each of at least 20 orders), joined piecewise linearly in
    log-log (a red spectrum bending into white noise fits); one median / ln 2 with few orders."""
    ok = np.isfinite(power) & (power > 0)
    level = np.full(orders.shape[0], np.nan)
    if not np.any(ok):
        return level
    count = int(np.count_nonzero(ok))
    bins = min(BACKGROUND_BINS, count // 20)
    if count < MIN_BACKGROUND_POINTS or bins < 2 or orders[ok].max() <= orders[ok].min() * 1.2:
        level[:] = float(np.median(power[ok])) / math.log(2.0)
        return level
    lk, lp = np.log(orders[ok]), power[ok]
    # bins of equal counts in log order (equal widths would leave the top decade with most of the orders)
    edges = np.quantile(lk, np.linspace(0.0, 1.0, bins + 1))
    which = np.clip(np.searchsorted(edges, lk, side="right") - 1, 0, bins - 1)
    xs = np.array([float(np.median(lk[which == b])) for b in range(bins)])
    ys = np.array([math.log(float(np.median(lp[which == b])) / math.log(2.0)) for b in range(bins)])
    x = np.log(orders)
    inner = np.interp(x, xs, ys)
    # beyond the first and last bin centres: their segments extended
    lo_slope = (ys[1] - ys[0]) / (xs[1] - xs[0]) if xs[1] > xs[0] else 0.0
    hi_slope = (ys[-1] - ys[-2]) / (xs[-1] - xs[-2]) if xs[-1] > xs[-2] else 0.0
    left = ys[0] + lo_slope * (x - xs[0])
    right = ys[-1] + hi_slope * (x - xs[-1])
    return np.exp(np.where(x < xs[0], left, np.where(x > xs[-1], right, inner)))


def _peaks(scan: _Scan, resid: np.ndarray, independent: int, opt: ScanOptions) -> tuple[list, str]:
    """[(order, power ratio, adjusted p)] taken one at a time (prewhitening) while significant; the
    strongest alone when none is; and the method's description."""
    direct = scan.theta.shape[0] * scan.grid.shape[0] <= (FULL_TURN_BUDGET if scan.full_turn else DIRECT_BUDGET)
    method = ("exact least-squares power at every order" if direct else
              "FFT of the residual binned along the arc, exact least squares at the peaks")
    found: list = []
    for _ in range(max(1, opt.max_peaks)):
        power = _powers(scan, resid, scan.grid) if direct else _fft_powers(scan, resid)
        level = _background(scan.grid, power)
        ratio = power / level
        ratio = np.where(np.isfinite(ratio), ratio, -np.inf)
        for k_old in scan.peaks:  # never the same peak again
            ratio[np.abs(scan.grid - k_old) < _half_width(scan)] = -np.inf
        if not np.any(np.isfinite(ratio)):
            break
        i = int(np.argmax(ratio))
        k = float(scan.grid[i]) if scan.full_turn else _refine(scan, resid, float(scan.grid[i]),
                                                                 bounds=_apart(float(scan.grid[i]), scan.peaks,
                                                                               _half_width(scan)))
        exact = _powers(scan, resid, np.array([k]))[0]
        r = float(exact / level[i]) if math.isfinite(exact) else float(ratio[i])
        p_adj = min(1.0, independent * math.exp(-r))
        if found and p_adj >= opt.alpha:
            break
        found.append((k, r, p_adj))
        if p_adj >= opt.alpha:
            break
        scan.peaks.append(k)
        resid = scan.refresh()
    return found, method


def _half_width(scan: _Scan) -> float:
    """Half the width of a peak in the grid [cycles/rev] (the resolution: one independent order)."""
    return 0.5 if scan.full_turn else math.pi / scan.span


def _refine(scan: _Scan, resid: np.ndarray, k: float, power=None, bounds=(-math.inf, math.inf)) -> float:
    """The order of largest exact power within one grid step of ``k`` and inside ``bounds`` (golden-section
    search); ``power`` (orders -> powers) defaults to :func:`_powers`."""
    step = float(scan.grid[1] - scan.grid[0]) if scan.grid.shape[0] > 1 else 0.0
    a, b = max(k - step, bounds[0]), min(k + step, bounds[1])
    if step <= 0 or not a < b:
        return k
    if power is None:
        def power(orders):
            return _powers(scan, resid, orders)
    g = (math.sqrt(5.0) - 1.0) / 2.0
    x1, x2 = b - g * (b - a), a + g * (b - a)
    f1, f2 = power(np.array([x1, x2]))
    for _ in range(20):
        if not (f1 < f2):
            b, x2, f2 = x2, x1, f1
            x1 = b - g * (b - a)
            f1 = power(np.array([x1]))[0]
        else:
            a, x1, f1 = x1, x2, f2
            x2 = a + g * (b - a)
            f2 = power(np.array([x2]))[0]
    best = 0.5 * (a + b)
    return best if math.isfinite(power(np.array([best]))[0]) else k


def _improve(scan: _Scan, found: list, hi: float, resolution: float) -> list:
    """The peaks' orders refined together over a partial arc (on a full turn they are whole orders).

    Each peak found one at a time was refined with only the stronger ones held; here each is refined
    again, in turn, with every other peak held and its own harmonics (up to :data:`REFINE_HARMONICS`
    times its order, below ``hi`` and more than a ``resolution`` from another peak) fitted with it: the
    fundamental of an error that is not a pure sine is located by its whole series (the multi-harmonic
    periodogram, Schwarzenberg-Czerny 1996, ApJ 460, L107), and a strong neighbour no longer pulls it
    (the final step of prewhitening: every frequency improved with the others in the model).
    :data:`REFINE_ROUNDS` rounds; on more than :data:`BASIS_ROWS` rows (units), on an even subsample of
    them.  ``found`` [(order, power ratio, adjusted p)] keeps its ratios and p-values (from the scan)."""
    if scan.full_turn or not found or scan.grid.shape[0] < 2:
        return found
    n = scan.theta.shape[0]
    pick = None if n <= BASIS_ROWS else np.linspace(0, n - 1, BASIS_ROWS).astype(np.int64)

    def rows(x):
        return x if x is None or pick is None else x[pick]

    sub = _Scan(rows(scan.theta), rows(scan.y), rows(scan.base), scan.grid, scan.span, scan.full_turn, rows(scan.d),
                sw=rows(scan.sw))
    ks = [float(f[0]) for f in found]
    half = _half_width(scan)
    for _ in range(REFINE_ROUNDS):
        for j, k in enumerate(ks):
            others = ks[:j] + ks[j + 1:]
            sub.peaks, sub.q, sub.q_peaks = others, None, 0
            resid = sub.refresh()
            series = [h for h in range(1, REFINE_HARMONICS + 1)
                      if h == 1 or (h * k <= hi and all(abs(h * k - o) > resolution for o in others))]
            # never closer than half a resolution to another peak (two columns that close trade amplitude)
            ks[j] = _refine(sub, resid, k, lambda orders, resid=resid, series=series:
                            _series_powers(sub, resid, orders, series), _apart(k, others, half))
    return [(k, r, p) for k, (_, r, p) in zip(ks, found)]


def _apart(k: float, others, half: float) -> tuple[float, float]:
    """The interval around ``k`` that keeps at least ``half`` [cycles/rev] from every order of ``others``
    (two peaks closer than half a resolution trade amplitude instead of being told apart)."""
    return (max([o + half for o in others if o < k], default=-math.inf),
            min([o - half for o in others if o > k], default=math.inf))


def _series_powers(scan: _Scan, resid: np.ndarray, orders: np.ndarray, series: list) -> np.ndarray:
    """Sum of squares of ``resid`` explained by the columns of h x k for h in ``series``, for each k of
    ``orders``, the model's basis ``scan.q`` projected out (NaN where the columns are degenerate)."""
    q = scan.q
    assert q is not None  # (the series are refined on a scan that keeps its basis)
    out = np.full(orders.shape[0], np.nan)
    for i, k in enumerate(orders):
        c = _harmonic_columns(scan, float(k), series)
        proj = q.T @ c
        gram = c.T @ c - proj.T @ proj
        rhs = c.T @ resid
        lam = np.linalg.eigvalsh(gram)
        if np.trace(gram) > MIN_SCAN_SHARE * scan.total * gram.shape[0] / 2 and lam[0] > 1e-9 * max(lam[-1], 1e-300):
            out[i] = float(rhs @ np.linalg.solve(gram, rhs))
    return out


def _harmonic_columns(scan: _Scan, k: float, series: list) -> np.ndarray:
    """The columns of :meth:`_Scan.trig` at orders h x ``k`` for h in ``series`` side by side, (n, 2 or 4
    per harmonic): one cos and sin of order ``k``, the harmonics from it by the angle-addition formulas
    (each a product sum: a few units in the last place from cos and sin taken directly)."""
    th = scan.theta
    c1, s1 = np.cos(k * th), np.sin(k * th)
    c, s, h = c1, s1, 1
    pairs = []
    for want in series:
        while h < want:
            c, s, h = c * c1 - s * s1, s * c1 + c * s1, h + 1
        pairs.append(scan.weighted(np.column_stack([c, s])))
    return np.hstack(pairs)


def _joint_fit(scan: _Scan, orders: list, passes, time) -> dict:
    """Least squares of y on the model columns and the peaks' (cos, sin): amplitudes, phases, standard
    errors (block-robust when the residual is serially correlated), the residual RMS."""
    keep_peaks = scan.peaks
    scan.peaks = list(orders)
    gram, rhs = scan.normal_equations()
    gram_inv = _gram_inverse(gram)
    coef = gram_inv @ rhs
    p = gram.shape[0]
    fitted = np.empty(scan.theta.shape[0])
    for a, b in scan.blocks():
        fitted[a:b] = scan.design(a, b) @ coef
    if scan.sw is None:
        resid, unit = scan.y - fitted, None
    else:
        assert scan.rows is not None  # (rows reduced to units: sw and rows are set together)
        y_rows, unit = scan.rows
        resid = y_rows - (fitted / scan.sw)[unit]
    n = resid.shape[0]
    serial = serial_blocks(resid, passes, time) if n > p + 2 else SerialBlocks("independent rows", math.nan, 1, n)
    if serial.independent:
        dof = n - p
        cov = gram_inv * (float(resid @ resid) / dof if dof > 0 else math.nan)
    else:
        cov = block_covariance(gram_inv, _scores(scan, serial, serial.whiten(resid), unit, p), n) * serial.recolour
    scan.peaks = keep_peaks
    q0, width = scan.base.shape[1], 2 if scan.d is None else 4
    out: dict = {"coef": coef, "serial": serial, "rms": float(math.sqrt(np.mean(resid**2))) if n else math.nan,
                 "amp": [], "se": [], "phase": [], "diff": [], "diff_se": []}
    for i in range(len(orders)):
        j = q0 + width * i
        amp, se, phase = _amplitude(coef[j:j + 2], cov[j:j + 2, j:j + 2])
        out["amp"].append(amp)
        out["se"].append(se)
        out["phase"].append(phase)
        diff, diff_se, _ = (_amplitude(coef[j + 2:j + 4], cov[j + 2:j + 4, j + 2:j + 4]) if width == 4
                            else (math.nan, math.nan, math.nan))
        out["diff"].append(diff)
        out["diff_se"].append(diff_se)
    return out


def _scores(scan: _Scan, serial: SerialBlocks, v: np.ndarray, unit, p: int) -> np.ndarray:
    """Per block, the sum over its rows of x_t v_t (x_t the row's model and peak columns)."""
    assert serial.block_id is not None  # (called for serial blocks only)
    scores = np.zeros((serial.blocks, p))
    for a, b in scan.blocks():
        x = scan.design(a, b)
        if scan.sw is not None:
            x = x / scan.sw[a:b, None]  # the unit's columns, unweighted
        if unit is None:
            for j in range(p):
                scores[:, j] += np.bincount(serial.block_id[a:b], weights=x[:, j] * v[a:b], minlength=serial.blocks)
        else:
            rows = (unit >= a) & (unit < b)
            for j in range(p):
                scores[:, j] += np.bincount(serial.block_id[rows], weights=x[unit[rows] - a, j] * v[rows],
                                            minlength=serial.blocks)
    return scores


def _amplitude(ab: np.ndarray, cov: np.ndarray) -> tuple[float, float, float]:
    """(amplitude, its standard error by the delta method, phase) of a (cos, sin) coefficient pair."""
    a, b = float(ab[0]), float(ab[1])
    amplitude = math.hypot(a, b)
    g = np.array([a, b]) / amplitude if amplitude > 0 else np.array([math.sqrt(0.5), math.sqrt(0.5)])
    return amplitude, math.sqrt(max(float(g @ cov @ g), 0.0)), math.atan2(a, b)


def _group(scan: _Scan, k: float, threshold: float, resolution: float) -> tuple[float, float]:
    """(lo, hi): the orders near ``k`` whose columns correlate with k's by at least ``threshold``
    (canonical correlation with the model projected out), found on a grid of 1/20 of the resolution
    (on a full turn whole orders are told apart: (k, k))."""
    if scan.full_turn:
        return (k, k)
    theta = scan.theta
    base = scan.base
    sel = None
    if theta.shape[0] > GROUP_ROWS:
        sel = np.linspace(0, theta.shape[0] - 1, GROUP_ROWS).astype(np.int64)
        theta, base = theta[sel], base[sel]
    q = np.linalg.qr(base)[0]

    sw = None if scan.sw is None else (scan.sw if theta.shape[0] == scan.theta.shape[0] else scan.sw[sel])

    def basis(order):
        c = np.column_stack([np.cos(order * theta), np.sin(order * theta)])
        if sw is not None:
            c = c * sw[:, None]
        c = c - q @ (q.T @ c)
        return np.linalg.qr(c)[0]

    own = basis(k)
    step = resolution / 20.0
    bounds = []
    for sign in (-1.0, 1.0):
        edge = k
        for j in range(1, 41):
            other = k + sign * j * step
            if other <= 0:
                break
            if float(np.linalg.svd(own.T @ basis(other), compute_uv=False)[0]) < threshold:
                break
            edge = other
        bounds.append(edge)
    return (bounds[0], bounds[1])


def _aliases(scan: _Scan, k: float, labelled: list) -> tuple:
    """((order, correlation, label), ...) of ``labelled`` orders whose (cos, sin) columns correlate with order
    ``k``'s by at least ALIAS_CORR on the sampled angles (offset projected out), strongest first."""
    if not labelled:
        return ()
    theta = scan.theta
    if theta.shape[0] > GROUP_ROWS:
        theta = theta[np.linspace(0, theta.shape[0] - 1, GROUP_ROWS).astype(np.int64)]

    def basis(order):
        c = np.column_stack([np.cos(order * theta), np.sin(order * theta)])
        c = c - c.mean(axis=0)
        return _orthonormal(c)

    own = basis(k)
    out = []
    for o, lab in labelled:
        other = basis(float(o))
        if own.shape[1] and other.shape[1]:
            corr = float(np.linalg.svd(own.T @ other, compute_uv=False)[0])
            if corr >= ALIAS_CORR:
                out.append((float(o), corr, lab))
    return tuple(sorted(out, key=lambda t: -t[1]))


def _label(group: tuple[float, float], k: float, labels) -> str | None:
    """The label of the labelled order nearest ``k`` inside its group (within 1e-6 relative on a full turn)."""
    lo, hi = group
    inside = [(abs(o - k), lab) for o, lab in labels
              if lo - 1e-6 * max(abs(o), 1.0) <= float(o) <= hi + 1e-6 * max(abs(o), 1.0)]
    return min(inside)[1] if inside else None
