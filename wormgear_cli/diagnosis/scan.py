"""What no catalogue effect explains: significant harmonics, trends and a reversal change
left in the residual, annotated with what the run structure and the candidates say."""

from __future__ import annotations

import math

import numpy as np

from wormgear_cli.diagnosis.candidates import REPLICATION_REMEDY, unaliased_orders
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


#: the catalogue effect whose signature a pattern of the residual scan is
def _signature_of(item: dict, geometry) -> str | None:
    from wormgear_cli.physics.effects import EFFECTS

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
    from wormgear_cli.physics.effects import EFFECTS

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


def scan_residual(state: ModelFit, sig, groups, geometry, alpha, info: DataInfo, sources, cells: Cells,
                  orders_cache: dict | None = None) -> list[dict]:
    """Significant structure left in the residual: harmonics at physical and low
    orders (common and differential mode), trends against temperature, load and
    time, and a mean reversal; Bonferroni over every test made.  ``orders_cache``:
    a dict that keeps the orders the targets resolve between scans of one
    measurement (they depend on the angles only)."""
    from wormgear_cli.measurement.harmonics import physical_orders
    from wormgear_cli.measurement.iso230 import group_targets
    from wormgear_cli.physics.effects import EFFECTS

    catalogue_orders = [float(e.order(geometry)) for e in EFFECTS.values() if e.order is not None]
    r = state.residual
    basis, _ = orthonormal(np.hstack([state.lin, state.jac]), own=True)
    part = (basis.T @ basis, basis.T @ r, pass_sums(basis, groups) if basis.shape[1] else np.zeros((groups.passes, 0)))
    theta, d = sig.theta, sig.direction
    both = len(info.directions) == 2
    labels = dict(physical_orders(geometry, 3))
    n_targets = int(group_targets(theta)[1].shape[0])
    top = min(30, n_targets // 2)
    orders = sorted({*map(float, range(1, top + 1)), *labels})
    if orders_cache is not None and "orders" in orders_cache:
        keep = orders_cache["orders"]
    else:
        keep, _ = unaliased_orders(theta, orders)
        if orders_cache is not None:
            orders_cache["orders"] = keep
    # test columns are made a chunk at a time (never all N x 2K at once) from these recipes
    tests = []
    for o in keep:
        tests.append(("order", o, "common", ("order", o, False)))
        if both:
            tests.append(("order", o, "differential", ("order", o, True)))
    signals = [("temperature_C", sig.temperature, info.temperature_range >= MIN_TEMPERATURE_RANGE, "K"),
               ("load_Nm", sig.load, info.load_range > 0, "N m"),
               ("time_s", sig.time, info.time_range > 0, "s")]
    for name, values, varies, _unit in signals:
        if not varies:
            continue
        tests.append(("trend", name, "common", ("trend", values, False)))
        if both:
            tests.append(("trend", name, "differential", ("trend", values, True)))
    if both:
        tests.append(("reversal", None, "differential", ("reversal", None, True)))

    def width(recipe):
        return 2 if recipe[0] == "order" else 1

    # the order columns (and the reversal column) are functions of the angle and the direction: a chunk's
    # columns are made once per distinct (angle, direction) pair and spread to the rows by one np.take
    if orders_cache is not None and "pairs" in orders_cache:
        pairs = orders_cache["pairs"]
    else:
        found = distinct_pairs(sig)
        pairs = None if found is None else (found.sig.theta, found.sig.direction, found.inverse)
        if orders_cache is not None:
            orders_cache["pairs"] = pairs

    def fill(out, recipe, theta=theta, d=d):
        # out: (rows, width) columns of the recipe at angles theta, directions d (rows or distinct pairs)
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

    m = len(tests)
    out = []
    kb = basis.shape[1]
    btb, btr, sb = part
    sr = pass_sums(r, groups)
    results = []
    chunk: list = []
    partial_dirs: dict = {}

    # per chunk of test columns: what depends on the angles only (Gram matrix, pass sums, cell means) is
    # kept between the scans of one measurement; the residualised columns res = big - B (B'big) / n are never
    # formed (B'B = n I), their Gram matrix, products with r and pass sums follow from B'big
    chunk_cache = orders_cache.setdefault("chunks", {}) if orders_cache is not None else {}
    n_rows = r.shape[0]
    cell_tester = CellTester(cells, basis, r) if cells.replicated else None
    # a cell holds one direction: with directions of exactly +/-1 the cell means of an order's differential
    # columns are those of its common columns times the cell's direction (the same numbers, half the work)
    cell_dir = cells.means(d) if cell_tester is not None and bool(np.all(np.abs(d) == 1.0)) else None

    def flush():
        if not chunk:
            return
        key = tuple((c[0], c[1], c[2]) for c in chunk)
        total = sum(width(c[3]) for c in chunk)
        if pairs is not None:
            # every column but the trends at the distinct pairs, spread to the rows at once (a new C-order
            # array: np.take into a given ``out`` copies it first, to leave it untouched on a bad index);
            # the trends per row
            p_theta, p_dir, where = pairs
            at_pairs = np.zeros((p_theta.shape[0], total))
            _make_columns(at_pairs, chunk, lambda out, recipe: None if recipe[0] == "trend" else
                          fill(out, recipe, p_theta, p_dir), p_dir)
            big = np.take(at_pairs, where, axis=0)
            at_pairs = None
            j = 0
            for c in chunk:
                if c[3][0] == "trend":
                    fill(big[:, j:j + 1], c[3])
                j += width(c[3])
        else:
            big = np.empty((n_rows, total))
            _make_columns(big, chunk, fill, d)
        if key not in chunk_cache:
            chunk_cache[key] = (big.T @ big, pass_sums(big, groups), np.einsum("ij,ij->j", big, big))
        bb, ps_big, norms = chunk_cache[key]
        cb = basis.T @ big if kb else np.zeros((0, total))
        gram = bb - cb.T @ cb / n_rows
        rr = big.T @ r - cb.T @ btr / n_rows
        ps = ps_big - sb @ cb / n_rows
        j = 0
        common_means = {}
        for kind, what, mode, recipe in chunk:
            q = width(recipe)
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
            cross = Cross(xtx, np.concatenate([btr, rot.T @ rr[sl]]), float(r @ r), np.hstack([sb, ps[:, sl] @ rot]),
                          sr, groups)
            res_rot = None
            if kind != "order" or k2 < q:
                res_rot = (big[:, sl] - basis @ cb[:, sl] / n_rows) @ rot if kb else big[:, sl] @ rot
            if kind == "order" and k2 < q:
                v = res_rot[:, 0]
                partial_dirs[(what, mode)] = v / max(float(np.linalg.norm(v)), 1e-300)
            # the cell-means test now (its C x q means are not kept for every test)
            cell_test = None
            if kind == "order" and cell_tester:
                if recipe[2] and cell_dir is not None and what in common_means:
                    mc = common_means[what] * cell_dir[:, None]
                else:
                    mc = cells.means(big[:, sl])
                    if not recipe[2]:
                        common_means[what] = mc
                cell_test = cell_tester.test(means=mc)
            results.append((kind, what, mode, cross, kb + np.arange(k2), rot if k2 == q else None,
                            res_rot if kind != "order" else None, cell_test))
        chunk.clear()

    for test in tests:
        chunk.append(test)
        if sum(width(c[3]) for c in chunk) >= CHUNK_COLUMNS:
            flush()
    flush()
    n = r.shape[0]
    for kind, what, mode, cross, idx, full_rot, tcols, cell_test in results:
        if kind == "order":
            vf = fit_at(cross, state.var.gp, state.var.gr)
            w = wald(cross, vf, idx, info=None)
            if cells.replicated:
                _, df_c, p_c = cell_test
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


def _make_columns(big: np.ndarray, chunk: list, fill, d: np.ndarray) -> None:
    """Write a chunk's test columns into ``big`` side by side (``fill(out, recipe)`` makes one recipe's
    columns; the differential columns of an order made in the same chunk are its common ones times the
    direction ``d``)."""
    j = 0
    made = {}
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


def unowned_order_columns(items: list[dict], sig, geometry, state: ModelFit) -> list[tuple[str, np.ndarray, dict]]:
    """(label, columns, scan item) of the significant harmonics of a residual scan at orders no catalogue
    effect owns: cos/sin of the order (N, 2), times the direction for differential mode.

    Only orders whose columns the model leaves mostly free (tolerance >= MIN_HELD_TOLERANCE) are
    held in the model every candidate is tested against, so that strong content at such an
    order (a worm-mesh harmonic of a multi-start worm, say) cannot leak into a catalogue
    effect whose columns it partly projects onto at unevenly spaced targets (issue 10)."""
    from wormgear_cli.physics.effects import EFFECTS

    owned = [float(e.order(geometry)) for e in EFFECTS.values() if e.order is not None]
    basis, _ = orthonormal(np.hstack([state.lin, state.jac]), own=True)
    out = []
    for item in items:
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
