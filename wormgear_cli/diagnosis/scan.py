"""What no catalogue effect explains: significant harmonics, trends and a reversal change
left in the residual, annotated with what the run structure and the candidates say."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from wormgear_cli.diagnosis.candidates import REPLICATION_REMEDY, catalogue_orders, unaliased_orders
from wormgear_cli.diagnosis.design import orthonormal, tolerance
from wormgear_cli.diagnosis.mixed import CellTester, Cross, Wald, containment_df, fit_at, reml, wald
from wormgear_cli.diagnosis.phases import ModelFit, distinct_pairs
from wormgear_cli.diagnosis.runs import Cells, DataInfo, Groups, pass_sums
from wormgear_cli.diagnosis.scoring import ScoreStatus
from wormgear_cli.diagnosis.thresholds import (
    EXCESS_FACTOR,
    MIN_HELD_TOLERANCE,
    MIN_RUNS,
    MIN_SCAN_SHARE,
    MIN_TEMPERATURE_RANGE,
)
from wormgear_cli.measurement.coverage import coverage
from wormgear_cli.measurement.dominant import ScanOptions, dominant_orders
from wormgear_cli.measurement.drift import slow_model
from wormgear_cli.measurement.harmonics import physical_orders
from wormgear_cli.measurement.iso230 import group_targets
from wormgear_cli.measurement.separation import SEPARATION_CORR, canonical_correlations
from wormgear_cli.physics.effects import EFFECTS, train_effects
from wormgear_cli.physics.signals import SIGNALS, SLOPE_UNITS

if TYPE_CHECKING:
    from wormgear_cli.measurement.coverage import Coverage
    from wormgear_cli.measurement.drift import SlowModel
    from wormgear_cli.physics.effects import Signals
    from wormgear_cli.physics.geometry import DriveGeometry


def _signature_of(item: dict, geometry) -> str | None:
    """The catalogue effect whose signature a pattern of the residual scan is (its record's ``pattern``,
    ``needs`` and ``mode``), None if none."""
    if item["kind"] == "reversal":
        return next((name for name, eff in EFFECTS.items() if eff.pattern == "reversal"), None)
    if item["kind"] == "trend":
        return next((name for name, eff in EFFECTS.items() if eff.pattern == "trend" and eff.needs is not None
                     and SIGNALS[eff.needs].column == item["signal"] and eff.mode == item["mode"]), None)
    if item["kind"] == "order" and item["mode"] == "common":
        for name in train_effects(geometry):
            eff = EFFECTS[name]
            if eff.order is not None and abs(float(eff.order(geometry)) - item["order"]) < 1e-9:
                return name
    return None


def _pattern(name: str, geometry) -> tuple[str, str]:
    """(mode, words) of a catalogue effect's signature (from its record)."""
    eff = EFFECTS[name]
    return eff.mode, eff.signature_text(geometry)


def annotate(items: list, scores: dict, groups: Groups, few_runs: bool, likely: dict | None, state: ModelFit,
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
        if (item["kind"] == "reversal" and scores.get("thermal_backlash") is not None
                and scores["thermal_backlash"].status is ScoreStatus.UNTESTABLE
                and (sc is None or sc.status is not ScoreStatus.UNTESTABLE)):
            name, sc = "thermal_backlash", scores["thermal_backlash"]  # a warm-up changes the reversal between passes
        if sc is not None and sc.status is ScoreStatus.UNTESTABLE:
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


#: test columns made and reduced at a time (N x CHUNK_COLUMNS float64 at most): 16 = four orders in
#: both modes; wider chunks were not faster at 1e5 rows and cost 8 bytes per row per column
CHUNK_COLUMNS = 16
#: most orders the scan of every order (dominant_orders) adds to the fixed list
MAX_SCANNED_PEAKS = 5
#: rows used to judge which orders a partial arc cannot separate (an even subsample)
SEPARATION_ROWS = 20_000


@dataclass(frozen=True)
class ScanContext:
    """What a residual scan needs besides the fit: the measurement's signals, groups, the drive's
    geometry, the level ``alpha``, what varies (``info``), the spec's phase sources, the cells, a
    ``cache`` dict kept between the scans of one measurement (what depends on the angles only), and
    ``run_drift``: each run's offset and drift are in the model already (a guide log's sessions), so
    orders slower than the longest run are theirs and no other slow part is tested."""

    sig: Signals
    groups: Groups
    geometry: DriveGeometry
    alpha: float
    info: DataInfo
    sources: list
    cells: Cells
    cache: dict | None = None
    run_drift: bool = False


@dataclass
class _Plan:
    """One scan: the residual, the model's orthonormal basis (with the slow part over a partial arc), the
    tests (kind, what, mode, recipe), the drive's labels, and where the orders came from."""

    r: np.ndarray
    basis: np.ndarray
    part: tuple
    tests: list
    labels: dict
    scanned: dict  # order -> adjusted p of the scan of every order (orders it added)
    slow: SlowModel | None  # over a partial arc
    coverage: Coverage
    nyquist: float = math.nan
    partial_dirs: dict = field(default_factory=dict)

    @property
    def m(self) -> int:
        return len(self.tests) + (1 if self.slow is not None and self.slow.degree else 0)


def scan_residual(state: ModelFit, ctx: ScanContext) -> list[dict]:
    """Significant structure left in the residual: harmonics at the physical orders, at low orders (up
    to 30 or half the targets) and at the strongest orders of a scan of every order the data resolve
    (:func:`~wormgear_cli.measurement.dominant.dominant_orders`, up to the Nyquist limit), in common and
    differential mode; trends against temperature, load and time; a mean reversal; and, over a partial
    arc, the slow part (a drift in time or a trend over the arc) with its size, with which the
    harmonics are tested.  Orders too slow for the arc, and orders the arc cannot tell from a
    catalogue effect's or a spec source's order, are left to those.  Bonferroni over every test."""
    plan = _plan(state, ctx)
    results = _run_tests(plan, ctx, state)
    items = _order_and_trend_items(plan, ctx, state, results)
    drift = None if ctx.run_drift else _drift_item(plan, ctx, state)
    if drift is not None:
        items.append(drift)
    return _merge_mixed(items, plan.partial_dirs)


def _plan(state: ModelFit, ctx: ScanContext) -> _Plan:
    sig, info, cache = ctx.sig, ctx.info, ctx.cache if ctx.cache is not None else {}
    if "coverage" not in cache:
        cov = coverage(sig.theta)
        slow = slow_model(sig.theta, cov, ctx.groups.pass_run[ctx.groups.pass_id], sig.direction,
                          sig.time if info.time_range > 0 else None, per_run=ctx.run_drift)
        cache["coverage"] = (cov, slow if slow.degree else None)
    cov, slow = cache["coverage"]
    r = state.residual
    extra = [slow.columns] if slow is not None else []
    basis, _ = orthonormal(np.hstack([state.lin, state.jac, *extra]), own=True)
    part = (basis.T @ basis, basis.T @ r, pass_sums(basis, ctx.groups) if basis.shape[1] else
            np.zeros((ctx.groups.passes, 0)))
    labels = dict(physical_orders(ctx.geometry, 3))
    orders, scanned, nyquist = _orders(state, ctx, cov, slow, labels, cache)
    both = len(info.directions) == 2
    tests = []
    for o in orders:
        tests.append(("order", o, "common", ("order", o, False)))
        if both:
            tests.append(("order", o, "differential", ("order", o, True)))
    signals = [(SIGNALS["temperature"].column, sig.temperature, info.temperature_range >= MIN_TEMPERATURE_RANGE),
               (SIGNALS["load"].column, sig.load, info.load_range > 0),
               (SIGNALS["time"].column, sig.time, info.time_range > 0 and (slow is None or slow.kind != "time"))]
    for name, values, varies in signals:
        if not varies:
            continue
        tests.append(("trend", name, "common", ("trend", values, False)))
        if both:
            tests.append(("trend", name, "differential", ("trend", values, True)))
    if both:
        tests.append(("reversal", None, "differential", ("reversal", None, True)))
    return _Plan(r, basis, part, tests, labels, scanned, slow, cov, nyquist)


def _orders(state: ModelFit, ctx: ScanContext, cov, slow, labels: dict, cache: dict) -> tuple[list, dict, float]:
    """(the orders to test, {order added by the scan of every order: its adjusted p}, the Nyquist limit)."""
    sig = ctx.sig
    if "targets" not in cache:
        cache["targets"] = int(group_targets(sig.theta)[1].shape[0])
    top = 0 if ctx.run_drift else min(30, cache["targets"] // 2)  # a guide log: no low orders of a table
    orders = sorted({*map(float, range(1, top + 1)), *labels})
    owned = sorted(set(catalogue_orders(ctx.geometry)) | {float(s.order) for s in ctx.sources})
    if slow is not None:
        # over a partial arc: orders too slow for it are the slow part's; orders the arc cannot tell from an
        # order a catalogue effect or a spec source owns are that order's content
        orders = [o for o in orders if not slow.beyond(cov, o)]
        orders = _separable_from(orders, owned, sig.theta, cov, cache)
    dom = dominant_orders(sig.theta, state.residual, sig.direction, sig.time if ctx.info.time_range > 0 else None,
                          ctx.groups.pass_run[ctx.groups.pass_id],
                          ScanOptions(alpha=ctx.alpha, max_peaks=MAX_SCANNED_PEAKS, drift_per_run=ctx.run_drift))
    scanned = {}
    for p in dom.significant:
        lo, hi = p.group
        if any(lo - 0.5 * (cov.full_turn) <= o <= hi + 0.5 * (cov.full_turn) for o in orders):
            continue  # already tested (or inseparable from one that is)
        k = float(round(p.order)) if cov.full_turn else float(p.order)
        scanned[k] = p.p_adjusted
        orders.append(k)
    key = tuple(orders)
    if cache.get("orders_key") != key:
        cache["orders_key"], cache["orders"] = key, unaliased_orders(sig.theta, orders)[0]
    return cache["orders"], scanned, dom.nyquist


def _separable_from(orders: list, owned: list, theta, cov, cache: dict) -> list:
    """``orders`` without those the arc cannot tell from a different owned order (separation rule)."""
    key = ("separable", tuple(orders), tuple(owned))
    if key in cache:
        return cache[key]
    th = theta if theta.shape[0] <= SEPARATION_ROWS else theta[np.linspace(0, theta.shape[0] - 1,
                                                                            SEPARATION_ROWS).astype(np.int64)]
    close_pairs = [(o, w) for o in orders for w in owned
                   if o != w and abs(o - w) * cov.span < 2.0 * math.pi * (1.0 - 1e-9)]
    drop = set()
    for o, w in close_pairs:
        x = np.column_stack([np.ones_like(th), np.cos(o * th), np.sin(o * th), np.cos(w * th), np.sin(w * th)])
        if canonical_correlations(x.T @ x, 1, 2)[0, 1] >= SEPARATION_CORR:
            drop.add(o)
    cache[key] = [o for o in orders if o not in drop]
    return cache[key]


def _fill(out, recipe, theta, d) -> None:
    """The columns of a test ``recipe`` at angles ``theta``, directions ``d`` (rows or distinct pairs)."""
    kind, what, diff = recipe
    if kind == "order":
        np.multiply(theta, what, out=out[:, 0])
        np.sin(out[:, 0], out=out[:, 1])
        np.cos(out[:, 0], out=out[:, 0])
    elif kind == "trend":
        np.subtract(what, np.mean(what), out=out[:, 0])
    else:
        out[:, 0] = d
    if diff and kind != "reversal":
        out *= d[:, None]


def _width(recipe) -> int:
    return 2 if recipe[0] == "order" else 1


def _chunk_columns(plan: _Plan, ctx: ScanContext, chunk: list, pairs) -> np.ndarray:
    """The chunk's test columns at the rows (N x total)."""
    theta, d = ctx.sig.theta, ctx.sig.direction
    total = sum(_width(c[3]) for c in chunk)
    if pairs is None:
        big = np.empty((theta.shape[0], total))
        _make_columns(big, chunk, lambda out, recipe: _fill(out, recipe, theta, d), d)
        return big
    # every column but the trends at the distinct pairs, spread to the rows at once (a new C-order array:
    # np.take into a given ``out`` copies it first, to leave it untouched on a bad index); the trends per row
    p_theta, p_dir, where = pairs
    at_pairs = np.zeros((p_theta.shape[0], total))
    _make_columns(at_pairs, chunk, lambda out, recipe: None if recipe[0] == "trend" else
                  _fill(out, recipe, p_theta, p_dir), p_dir)
    big = np.take(at_pairs, where, axis=0)
    j = 0
    for c in chunk:
        if c[3][0] == "trend":
            _fill(big[:, j:j + 1], c[3], theta, d)
        j += _width(c[3])
    return big


def _run_tests(plan: _Plan, ctx: ScanContext, state: ModelFit) -> list:
    """Each test's (kind, what, mode, cross, idx, rotation, residualised columns, cell test), chunk by chunk.

    The order columns (and the reversal column) are functions of the angle and the direction: a chunk's
    columns are made once per distinct (angle, direction) pair and spread to the rows.  What depends on
    the angles only (Gram matrix, pass sums) is kept between the scans of one measurement; the
    residualised columns res = big - B (B'big) / n are never formed (B'B = n I): their Gram matrix,
    products with r and pass sums follow from B'big."""
    cache = ctx.cache if ctx.cache is not None else {}
    if "pairs" not in cache:
        found = distinct_pairs(ctx.sig)
        cache["pairs"] = None if found is None else (found.sig.theta, found.sig.direction, found.inverse)
    pairs = cache["pairs"]
    chunk_cache = cache.setdefault("chunks", {})
    cells, d = ctx.cells, ctx.sig.direction
    cell_tester = CellTester(cells, plan.basis, plan.r) if cells.replicated else None
    # a cell holds one direction: with directions of exactly +/-1 the cell means of an order's differential
    # columns are those of its common columns times the cell's direction (the same numbers, half the work)
    cell_dir = cells.means(d) if cell_tester is not None and bool(np.all(np.abs(d) == 1.0)) else None
    results: list = []
    chunk: list = []
    for test in [*plan.tests, None]:
        if test is not None:
            chunk.append(test)
            if sum(_width(c[3]) for c in chunk) < CHUNK_COLUMNS:
                continue
        if not chunk:
            continue
        big = _chunk_columns(plan, ctx, chunk, pairs)
        key = (tuple((c[0], c[1], c[2]) for c in chunk), plan.basis.shape[1])
        if key not in chunk_cache:
            chunk_cache[key] = (big.T @ big, pass_sums(big, ctx.groups), np.einsum("ij,ij->j", big, big))
        results += _chunk_tests(plan, ctx, chunk, big, chunk_cache[key], cell_tester, cell_dir)
        chunk = []
    return results


def _chunk_tests(plan: _Plan, ctx: ScanContext, chunk: list, big, cached, cell_tester, cell_dir) -> list:
    kb = plan.basis.shape[1]
    btb, btr, sb = plan.part
    n_rows = plan.r.shape[0]
    bb, ps_big, norms = cached
    total = big.shape[1]
    cb = plan.basis.T @ big if kb else np.zeros((0, total))
    gram = bb - cb.T @ cb / n_rows
    rr = big.T @ plan.r - cb.T @ btr / n_rows
    ps = ps_big - sb @ cb / n_rows
    sr = pass_sums(plan.r, ctx.groups)
    out = []
    j = 0
    common_means: dict[float, np.ndarray] = {}  # order -> its common-mode cell means
    for kind, what, mode, recipe in chunk:
        q = _width(recipe)
        sl = slice(j, j + q)
        j += q
        g = gram[sl, sl]
        lam, vec = np.linalg.eigh(g)
        # a direction the model (offset, fitted phases, effects) takes up all but MIN_SCAN_SHARE of is not
        # tested: its estimate would be its tiny remainder blown up (on a short span, a smooth drift then
        # shows as many large "harmonics")
        keep = lam > MIN_SCAN_SHARE * float(np.mean(norms[sl]))
        if not np.any(keep):
            continue
        rot = np.eye(1) if q == 1 else vec[:, keep]
        k2 = rot.shape[1]
        xtx = np.zeros((kb + k2, kb + k2))
        xtx[:kb, :kb] = btb
        xtx[kb:, kb:] = rot.T @ g @ rot
        cross = Cross(xtx, np.concatenate([btr, rot.T @ rr[sl]]), float(plan.r @ plan.r),
                      np.hstack([sb, ps[:, sl] @ rot]), sr, ctx.groups)
        res_rot = None
        if kind != "order" or k2 < q:
            res_rot = (big[:, sl] - plan.basis @ cb[:, sl] / n_rows) @ rot if kb else big[:, sl] @ rot
        if kind == "order" and k2 < q:
            assert res_rot is not None
            v = res_rot[:, 0]
            plan.partial_dirs[(what, mode)] = v / max(float(np.linalg.norm(v)), 1e-300)
        # the cell-means test now (its C x q means are not kept for every test)
        cell_test = None
        if kind == "order" and cell_tester:
            if recipe[2] and cell_dir is not None and what in common_means:
                mc = common_means[what] * cell_dir[:, None]
            else:
                mc = ctx.cells.means(big[:, sl])
                if not recipe[2]:
                    common_means[what] = mc
            cell_test = cell_tester.test(means=mc)
        out.append((kind, what, mode, cross, kb + np.arange(k2), rot if k2 == q else None,
                    res_rot if kind != "order" else None, cell_test))
    return out


def _order_and_trend_items(plan: _Plan, ctx: ScanContext, state: ModelFit, results: list) -> list[dict]:
    """The significant tests (Bonferroni over the scan) as report items, with what they mean."""
    m = plan.m
    r = plan.r
    out = []
    for kind, what, mode, cross, idx, full_rot, tcols, cell_test in results:
        if kind == "order":
            vf = fit_at(cross, state.var.gp, state.var.gr)
            w = wald(cross, vf, idx, info=None)
            if ctx.cells.replicated:
                _, df_c, p_c = cell_test
                if p_c > w.p:
                    w = Wald(w.estimate, w.cov, w.F, w.q, min(w.df, df_c), p_c)
        else:
            vf = reml(cross)
            w = wald(cross, vf, idx, containment=containment_df(ctx.groups, plan.basis, tcols))
        p_adj = min(1.0, w.p * m)
        if kind == "order" and what in plan.scanned:
            p_adj = max(p_adj, plan.scanned[what])  # found by searching every order: its search counted
        if p_adj >= ctx.alpha:
            continue
        if tcols is not None:
            # as for the candidates: a trend whose GLS slope makes the residual larger is an artefact of the
            # variance components absorbing what it gets wrong, not structure of the residual
            moved = r - tcols @ w.estimate
            if not float(moved @ moved) < float(r @ r):
                continue
        item = {"kind": kind, "mode": mode, "p_adjusted": p_adj}
        if kind == "order":
            _describe_order(item, what, plan, ctx, cross, idx, full_rot, w, r.shape[0])
        elif kind == "trend":
            unit = SLOPE_UNITS[what]
            item.update(signal=what, slope_arcsec_per_unit=float(w.estimate[0]), unit=unit)
            item["explanation"] = f"a {mode}-mode trend of the residual with {what} ({w.estimate[0]:.4g} arcsec/{unit})"
            if what == "time_s" and not ctx.info.temperature_present:
                item["explanation"] += "; record temperature_C to tell a thermal effect from a plain drift"
        else:
            item.update(mean_reversal_change_arcsec=float(-2.0 * w.estimate[0]))
            item["explanation"] = (f"the mean reversal differs from the spec's by {-2.0 * w.estimate[0]:.3g} "
                                   "arcsec" + (" (more lost motion than modelled)" if w.estimate[0] < 0 else
                                               " (less lost motion than modelled: the spec's backlash is too large)"))
        out.append(item)
    return out


def _describe_order(item: dict, what: float, plan: _Plan, ctx: ScanContext, cross, idx, full_rot, w, n: int) -> None:
    """Amplitude, label and explanation of a significant harmonic of the residual."""

    mode = item["mode"]
    if full_rot is not None:
        # no direction absorbed: by Frisch-Waugh-Lovell these are the joint-fit cos/sin coefficients
        amp = float(np.hypot(*(full_rot @ w.estimate)))
    else:
        g_t = cross.xtx[np.ix_(idx, idx)]
        amp = float(math.sqrt(max(2.0 * float(w.estimate @ g_t @ w.estimate) / n, 0.0)))
    item.update(order=what, amplitude_arcsec=amp)
    if idx.shape[0] < 2:
        item["partial"] = "only the part the fitted phases cannot take up is tested"
    labels = plan.labels
    catalogue = catalogue_orders(ctx.geometry)
    found_by_scan = (f"; found by the scan of every order up to the Nyquist limit of the spacing "
                     f"({plan.nyquist:.4g})" if what in plan.scanned else "")
    if what in labels:
        item["label"] = labels[what]
        same = [s.name for s in ctx.sources if abs(s.order - what) < 1e-9]
        if same:
            item["explanation"] = (f"order {what:g} ({labels[what]}) in {mode} mode that the spec's "
                                   f"{', '.join(same)} cannot produce with their specified sizes and fitted phases")
        elif any(abs(what - o) < 1e-9 for o in catalogue):
            item["explanation"] = (f"order {what:g} ({labels[what]}) in {mode} mode, which the catalogue effect at "
                                   "this order does not explain (a different mode, or not significant on its own)")
        else:
            item["explanation"] = (f"order {what:g} ({labels[what]}) in {mode} mode: the catalogue has no effect at "
                                   "this order")
    else:
        item["label"] = "not an order of any shaft or mesh of this drive"
        item["explanation"] = (f"a {mode}-mode harmonic at order {what:.6g}, which belongs to no shaft or mesh of "
                               "this drive: no catalogue effect has this signature")
    item["explanation"] += found_by_scan


def _drift_item(plan: _Plan, ctx: ScanContext, state: ModelFit) -> dict | None:
    """Over a partial arc, the slow part of the residual (a drift in time or a trend over the arc) tested as one
    group of columns against the model, with its peak-to-peak size; None when not significant."""
    slow = plan.slow
    if slow is None or not slow.degree:
        return None
    basis0, _ = orthonormal(np.hstack([state.lin, state.jac]), own=True)
    cols = slow.columns - basis0 @ (basis0.T @ slow.columns) / basis0.shape[0] if basis0.shape[1] else slow.columns
    kb = basis0.shape[1]
    cross = Cross.build(np.hstack([basis0, cols]), plan.r, ctx.groups)
    vf = reml(cross)
    w = wald(cross, vf, kb + np.arange(cols.shape[1]), containment=containment_df(ctx.groups, basis0, cols))
    p_adj = min(1.0, w.p * plan.m)
    if p_adj >= ctx.alpha:
        return None
    part = cols @ w.estimate
    size = float(np.ptp(part))
    span = math.degrees(plan.coverage.span)
    if slow.kind == "time":
        what = (f"a drift in time of {size:.3g} arcsec peak to peak ({slow.degree}-degree polynomial in "
                f"{slow.signal}), apart from the errors fixed to the angle: the {span:.4g} deg arc is traversed "
                f"{slow.traversals} times")
    else:
        what = (f"slow content over the {span:.4g} deg arc: {size:.3g} arcsec peak to peak ({slow.degree}-degree "
                "polynomial in the angle along the arc; a drift in time and orders whose period is longer than "
                "the arc cannot be told apart on one pass), not a string of harmonics")
    return {"kind": "drift", "mode": "common", "p_adjusted": p_adj, "signal": slow.signal, "degree": slow.degree,
            "peak_to_peak_arcsec": size, "explanation": what}


def _merge_mixed(out: list[dict], partial_dirs: dict) -> list[dict]:
    """Where the fitted phases leave one direction at an order, its "common" and "differential" tests may
    test the same mixed direction: report it once.  Sorted by adjusted p."""
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


def _make_columns(big: np.ndarray, chunk: list, fill, d: np.ndarray) -> None:
    """Write a chunk's test columns into ``big`` side by side (``fill(out, recipe)`` makes one recipe's
    columns; the differential columns of an order made in the same chunk are its common ones times the
    direction ``d``)."""
    j = 0
    made: dict[tuple[float, bool], int] = {}  # (order, differential) -> its first column in big
    for c in chunk:
        recipe = c[3]
        w = 2 if recipe[0] == "order" else 1
        if recipe[0] == "order" and recipe[2] and (recipe[1], False) in made:
            j0 = made[(recipe[1], False)]
            np.multiply(big[:, j0:j0 + w], d[:, None], out=big[:, j:j + w])
        else:
            fill(big[:, j:j + w], recipe)
        if recipe[0] == "order":
            made[(recipe[1], recipe[2])] = j
        j += w


def nuisance_columns(items: list[dict], sig, geometry, state: ModelFit, info: DataInfo,
                     cache: dict | None = None) -> list[tuple[str, np.ndarray, dict]]:
    """(label, columns, scan item) of the structure of a residual scan held as nuisance terms in the model
    every candidate is tested against: significant harmonics at orders no catalogue effect owns (cos/sin of
    the order (N, 2), times the direction for differential mode), and the drift over a partial arc (its
    polynomial columns) when no temperature varies (a drift in time would take up a thermal effect).

    Only orders whose columns the model leaves mostly free (tolerance >= MIN_HELD_TOLERANCE) are
    held, so that strong content at such an order (a worm-mesh harmonic of a multi-start worm, say)
    cannot leak into a catalogue effect whose columns it partly projects onto at unevenly spaced
    targets (issue 10)."""

    owned = catalogue_orders(geometry)
    basis, _ = orthonormal(np.hstack([state.lin, state.jac]), own=True)
    out = []
    for item in items:
        if item["kind"] == "drift":
            if info.temperature_range >= MIN_TEMPERATURE_RANGE or cache is None or "coverage" not in cache:
                continue
            slow = cache["coverage"][1]
            what = "a drift in time" if slow.kind == "time" else "the trend over the arc"
            out.append((f"{what} (polynomial of degree {slow.degree} in {slow.signal})", slow.columns, item))
            continue
        if item["kind"] != "order" or any(abs(item["order"] - o) < 1e-9 for o in owned):
            continue
        o = item["order"]
        cols = np.column_stack([np.cos(o * sig.theta), np.sin(o * sig.theta)])
        if item["mode"] == "differential":
            cols = cols * sig.direction[:, None]
        if tolerance(basis, cols) < MIN_HELD_TOLERANCE:
            continue  # partly taken up by the model: holding it would trade against the phases
        out.append((f"the unexplained order-{o:g} content ({item['mode']} mode)", cols, item))
    return out
