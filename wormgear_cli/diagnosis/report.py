"""The report of ``wormgear diagnose``: verdict, status of every catalogue effect, the JSON document."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from wormgear_cli.diagnosis.candidates import (
    REPLICATION_REMEDY,
    CandidateKind,
    aliased_effects,
    candidate,
    candidate_params,
    effect_order,
)
from wormgear_cli.diagnosis.inference import augmented_params, wrap_deg
from wormgear_cli.diagnosis.residuals import (
    gap_summary,
    iso_figures,
    noise_floor,
    order_tables,
    target_run_cells,
    versus,
)
from wormgear_cli.diagnosis.scoring import ScoreStatus
from wormgear_cli.diagnosis.selection import Diagnosis, StopReason, diagnose
from wormgear_cli.diagnosis.thresholds import EXCESS_FACTOR, MISMATCH_NOISE, MISMATCH_RATIO, UNIT_RATIO_TOLERANCE
from wormgear_cli.measurement.checks import guide_log_findings, structure_findings
from wormgear_cli.measurement.guidelog_options import is_guide_log
from wormgear_cli.measurement.iso230 import group_targets
from wormgear_cli.measurement.reader import ERROR_UNITS
from wormgear_cli.physics.effects import EFFECTS, geometry_absent_reason, params_to_keys, train_effects
from wormgear_cli.physics.signals import SIGNALS
from wormgear_cli.units import ARCSEC, RAD_PER_UNIT


def _status(diag: Diagnosis, twins: dict) -> list[dict]:
    # lazy: keeps analysis.accuracy off `measure`'s start-up
    from wormgear_cli.analysis.accuracy import geometry as drive_geometry

    stop = diag.stop
    out = []
    named = {f.name for f in diag.found}
    twin_of = {t["name"]: (owner, t) for owner, items in twins.items() for t in items}
    g = drive_geometry(diag.spec)
    for name in EFFECTS:
        entry: dict[str, Any] = {"name": name}
        absent = geometry_absent_reason(name, g)
        if absent is not None:
            entry.update(status="not_in_train", reason=f"not a candidate: {absent}")
            out.append(entry)
            continue
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
            if name in twins:
                text = _twin_text(name, _effect_order(name, diag), twins[name])
                entry["reason"] = text + ("; " + entry["reason"] if "reason" in entry else "")
                entry["indistinguishable_from"] = [t["name"] for t in twins[name]]
                entry["remedy"] = FOLD_REMEDY + ("; " + entry["remedy"] if "remedy" in entry else "")
        elif name in twin_of:
            owner, t = twin_of[name]
            entry.update(status="indistinguishable",
                         reason=_twin_text(name, t["order"], [{"name": owner, "order": _effect_order(owner, diag)}])
                         + f" (fitted and reported as {owner})", remedy=FOLD_REMEDY)
            if "estimate" in t:
                entry["estimate"] = t["estimate"]
        elif sc is None:
            entry.update(status="unobservable", reason="not scored")
        elif sc.status in (ScoreStatus.UNOBSERVABLE, ScoreStatus.UNTESTABLE):
            entry.update(status=sc.status.value, reason=sc.reason)
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
            if stop.reason is StopReason.AMBIGUOUS and name in stop.candidates:
                others = [c for c in stop.candidates if c != name]
                entry.update(status="indistinguishable",
                             reason=f"fits as well as {', '.join(others)} (signatures correlate "
                                    f"{stop.correlation:.3f})", remedy=_separate_hint([name, *others]))
            elif stop.reason is StopReason.UNPHYSICAL and stop.candidate == name:
                entry.update(status="unphysical", reason=stop.detail)
                if stop.hint:
                    entry["remedy"] = stop.hint
            elif stop.reason is StopReason.UNSTABLE and stop.candidate == name:
                entry.update(status="unstable",
                             reason=f"best in only {100 * (stop.stability or 0.0):.0f} % of resamples of whole runs")
            elif stop.reason is StopReason.WORSENS and stop.candidate == name:
                entry.update(status="rejected",
                             reason=f"significant, but fitting it makes the RMS gap larger "
                                    f"({stop.rms_before_arcsec:.3g} -> {stop.rms_with_arcsec:.3g} arcsec): its "
                                    "estimate follows structure that is not its signature (see unexplained)")
            elif _not_reached(diag, name, sc):
                entry.update(status="not_reached", reason=_not_reached_reason(diag, sc),
                             remedy=("rerun with a larger --max-effects" if stop.reason is StopReason.MAX_EFFECTS
                                     else f"settle {_stopper(stop)} first (see its reason), then rerun"))
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


def _stopper(stop) -> str:
    """The candidate (or rivals) the selection stopped at, for messages."""
    if stop.reason is StopReason.AMBIGUOUS:
        return " / ".join(stop.candidates)
    return getattr(stop, "candidate", None) or "the selection's stop"


def _not_reached(diag: Diagnosis, name: str, sc) -> bool:
    """Significant (adjusted p < alpha) but not taken, because the selection stopped before it: at a
    candidate it could not accept (unphysical, unstable, ambiguous, worsening the fit) or at
    --max-effects.  Such a candidate is not "not significant"."""
    stop = diag.stop
    if stop.reason in (StopReason.NOT_SIGNIFICANT, StopReason.NOTHING_LEFT, StopReason.NONE_OBSERVABLE):
        return False
    if getattr(stop, "candidate", None) == name or name in (getattr(stop, "candidates", None) or ()):
        return False
    p = sc.p_adj
    return p is not None and math.isfinite(p) and p < diag.alpha and not sc.same_order


def _not_reached_reason(diag: Diagnosis, sc) -> str:
    stop = diag.stop
    why = ("--max-effects was reached" if stop.reason is StopReason.MAX_EFFECTS
           else f"the selection stopped at {_stopper(stop)} ({stop.reason.value})")
    return f"significant (adjusted p = {sc.p_adj:.2g}) but not taken: {why}"


def folded_twins(diag: Diagnosis) -> dict[str, list[dict]]:
    """Per named effect, the catalogue effects at orders these targets fold onto its order
    (:func:`~wormgear_cli.diagnosis.candidates.aliased_effects`): they explain the data equally well.

    Each twin: ``name``, ``order``, and (for an effect whose size is determined) ``estimate``, the twin's
    parameters that reproduce the named effect's fitted signature at the measured angles (least squares
    of the named signature on the twin's columns), keyed as in the catalogue."""
    # lazy: keeps analysis.accuracy off `measure`'s start-up
    from wormgear_cli.analysis.accuracy import geometry as drive_geometry

    g = drive_geometry(diag.spec)
    names = [n for n in train_effects(g) if n not in diag.spec.effects]
    out = {}
    sig = None
    for f in diag.found:
        twins = aliased_effects(diag.meas.angle, f.name, names, g)
        if not twins:
            continue
        items = []
        for name, order in twins:
            item = {"name": name, "order": order}
            if f.separable and f.kind is CandidateKind.PERIODIC:
                sig = sig if sig is not None else diag.meas.signals()
                own, twin = candidate(f.name, sig, g), candidate(name, sig, g)
                assert own is not None  # (a separable periodic effect's signature is linear)
                eff = EFFECTS[f.name]
                amp, ph = f.params[eff.amplitude], f.params[eff.phase]
                signature = own.columns @ np.array([amp * math.cos(ph), amp * math.sin(ph)])
                if twin is not None:
                    beta = np.linalg.lstsq(twin.columns, signature, rcond=None)[0]
                    item["estimate"] = _keys(name, candidate_params(twin, beta))
            items.append(item)
        out[f.name] = items
    return out


def _twin_text(name: str, order: float, twins: list[dict]) -> str:
    others = " or ".join(f"{t['name']} (order {t['order']:g})" for t in twins)
    orders = ", ".join(f"{t['order']:g}" for t in twins)
    return (f"indistinguishable here from {others}: these targets fold order{'s' if len(twins) > 1 else ''} "
            f"{orders} onto order {order:g}, so either explains the data equally well")


FOLD_REMEDY = "measure with irregular target spacing (or a dense scan) to tell them apart"


def _effect_order(name: str, diag: Diagnosis) -> float:
    """The order of periodic effect ``name`` on the diagnosed drive."""
    # lazy: keeps analysis.accuracy off `measure`'s start-up
    from wormgear_cli.analysis.accuracy import geometry as drive_geometry

    order = effect_order(name, drive_geometry(diag.spec))
    if order is None:
        raise ValueError(f"{name} is not a periodic effect")
    return order


def _keys(name, params) -> dict:
    return {k: float(v) for k, v in params_to_keys(name, params).items()}


def _separate_hint(names) -> str:
    """How to measure so that the catalogue effects among ``names`` can be told apart: both directions while
    a signal varies when two of them need it in different modes, else the first one's ``separate_hint``."""
    effs = [eff for name, eff in EFFECTS.items() if name in set(names)]
    modes: dict[str, set] = {}
    for eff in effs:
        if eff.needs is not None:
            modes.setdefault(eff.needs, set()).add(eff.mode)
    for needs, seen in modes.items():
        if len(seen) > 1 and SIGNALS[needs].varied_by:
            return f"measure both directions during {SIGNALS[needs].varied_by}"
    return next((eff.separate_hint for eff in effs if eff.separate_hint),
                "measure with irregular target spacing or a dense scan, in both directions")


def over_prediction(diag: Diagnosis, order: float, data_rows: list | None) -> tuple[float, float] | None:
    """(the least the spec's sources at ``order`` can produce together with free phases [arcsec], the data's
    amplitude there [arcsec]) when the spec predicts more at the order than the data hold, else None.

    Sources on one order add as vectors: with free phases their sum ranges from max(0, A_max - (sum of
    the others)) to the sum of the amplitudes; the data's amplitude is the common mode of the measured
    error at the order (:func:`~wormgear_cli.diagnosis.residuals.order_table`)."""
    amps = [s.amplitude for s in diag.sources if abs(s.order - order) < 1e-9 and s.amplitude > 1e-9]
    if not amps or not data_rows:
        return None
    least = max(0.0, max(amps) - (sum(amps) - max(amps)))
    row = next((r for r in data_rows if abs(r["order"] - order) < 1e-9 and r.get("identifiable")), None)
    if row is None or "common_arcsec" not in row:
        return None
    data = abs(float(row["common_arcsec"]))
    return (least, data) if least > data else None


def _verdict(diag: Diagnosis, twins: dict, data_rows: list | None = None) -> str:
    found = [f for f in diag.found if f.separable]
    mixed = [f for f in diag.found if not f.separable]
    parts = []

    def named(f):
        if f.name not in twins:
            return f.name
        orders = ", ".join(f"{t['order']:g}" for t in twins[f.name])
        return (" or ".join([f.name, *(t["name"] for t in twins[f.name])])
                + f" (indistinguishable here: these targets fold order {orders} onto order "
                f"{_effect_order(f.name, diag):g}; {FOLD_REMEDY})")

    if found:
        parts.append(f"missing effect{'s' if len(found) > 1 else ''} found: " + ", ".join(named(f) for f in found))
    for f in mixed:
        key, (lo, hi) = next(iter(f.intervals.items())) if f.intervals else ("size", (math.nan, math.nan))
        order = _effect_order(f.name, diag)
        folded = "".join(f" or {t['name']} at order {t['order']:g}" for t in twins.get(f.name, []))
        also = ", ".join(f"{t['order']:g}" for t in twins.get(f.name, []))
        where = f" (where these targets also put order {also})" if also else ""
        over = over_prediction(diag, order, data_rows)
        if over is not None:
            head = (f"the spec predicts more at order {order:g} than the data hold (its sources there give at least "
                    f"{over[0]:.3g} arcsec with any phases, the data {over[1]:.3g}){where}: {f.name} ")
            tail = " set against them fits as well"
        else:
            head = f"missing content at order {order:g}{where} that the spec's sources cannot produce: {f.name} "
            tail = ""
        parts.append(head + f"({key} anywhere from {lo:.3g} to {hi:.3g}){folded}{tail} or a "
                     + ("smaller " if over is not None else "larger ") + " or ".join(f.indistinguishable_from)
                     + " (indistinguishable here: measure their runouts directly, enter the phases and rerun with "
                     "--keep-phases" + (f"; {FOLD_REMEDY}" if also else "") + ")")
    untestable = [n for n, sc in diag.candidates.items() if sc.status is ScoreStatus.UNTESTABLE]
    if not diag.found and diag.stop.reason is StopReason.MAX_EFFECTS:
        parts.append("no effect named (--max-effects reached)")
    elif not diag.found:
        text = "no missing effect found"
        if untestable:
            text += " that these data can test"
        elif diag.unexplained:
            text += " in the catalogue"
        stop = diag.stop
        if stop.reason is StopReason.AMBIGUOUS:
            text += (f" that the data can single out: {' or '.join(stop.candidates)} fit equally well")
        elif stop.reason is StopReason.UNPHYSICAL:
            text += f" ({stop.candidate} would fit only with {stop.detail})"
        elif stop.reason is StopReason.UNSTABLE:
            text += f" ({stop.candidate} is significant but not stable under resampling of runs)"
        elif stop.reason is StopReason.WORSENS:
            text += (f" ({stop.candidate} tests significant, but fitting it makes the RMS gap larger: "
                     f"{stop.rms_before_arcsec:.3g} -> {stop.rms_with_arcsec:.3g} arcsec)")
        parts.append(text)
    elif diag.stop.reason is StopReason.WORSENS:
        parts.append(f"{diag.stop.candidate} was rejected: fitting it makes the RMS gap larger")
    waiting = [(n, sc) for n, sc in diag.candidates.items()
               if n not in {f.name for f in diag.found} and sc.status not in (ScoreStatus.UNOBSERVABLE,
                                                                             ScoreStatus.UNTESTABLE)
               and _not_reached(diag, n, sc)]
    if waiting:
        why = ("--max-effects reached" if diag.stop.reason is StopReason.MAX_EFFECTS
               else f"the selection stopped at {_stopper(diag.stop)}")
        parts.append("significant but not taken (" + why + "): "
                     + ", ".join(f"{n} (adjusted p = {sc.p_adj:.2g})" for n, sc in waiting))
    if untestable:
        runs = diag.groups.runs
        parts.append(f"untestable with {runs} run{'s' if runs != 1 else ''}: {', '.join(untestable)} "
                     f"({REPLICATION_REMEDY})")
    if diag.likely is not None and diag.likely["name"] not in {n for n, _ in waiting}:
        parts.append(f"likely {'further ' if diag.found else ''}effect: {diag.likely['name']} (adjusted p = "
                     f"{diag.likely['p_adjusted']:.2g}, short of the level; see unexplained)")
    check = gap_check(diag)
    if not check["after_not_above_before"]:
        parts.append(f"the named effects do not shrink the gap against the spec alone ({check['before_rms_arcsec']:.3g}"
                     f" -> {check['after_rms_arcsec']:.3g} arcsec RMS): they were sized with the nuisance terms in the "
                     "model (see nuisance)")
    others = [u for u in diag.unexplained if u["kind"] != "likely_effect"]
    if others:
        text = "the residual keeps structure no catalogue effect explains"
        excess = next((u for u in others if u["kind"] == "excess"), None)
        if excess is not None:
            text += (f" ({excess['rms_arcsec']:.3g} arcsec RMS against a noise floor of "
                     f"{excess['noise_floor_arcsec']:.3g})")
        parts.append(text + " (see unexplained)")
    return "; ".join(parts)


def data_findings(meas) -> list:
    """What the file does not state and looks wrong (exact duplicate rows, time going backwards inside a
    pass, one direction only, targets repeated without a direction column, the reader's unit warnings):
    ``measure``'s checks (:func:`wormgear_cli.measurement.checks.structure_findings`), the one definition."""
    if is_guide_log(meas):
        return guide_log_findings(meas)
    tgt, _ = group_targets(meas.angle)
    findings, _ = structure_findings(meas, tgt)
    return findings


def _data_verdict(findings) -> list[str]:
    """The verdict-line parts of the data checks: the unit warnings in full, the others as measure says them."""
    out = []
    for f in findings:
        if f.kind == "units":
            out.append(f"check the units: {f.text}")
        elif f.verdict:
            out.append(f.verdict)
    return out


def gap_check(diag: Diagnosis) -> dict:
    """The invariant of the report: the gap after the named effects is no larger than the gap of the spec's
    own sources with fitted phases (both without nuisance terms), RMS over all rows [arcsec]."""
    y = diag.meas.error / ARCSEC
    before = float(np.sqrt(np.mean(diag.before.residual**2)))
    after = float(np.sqrt(np.mean((y - diag.augmented_fitted) ** 2)))
    return {"before_rms_arcsec": before, "after_rms_arcsec": after,
            "after_not_above_before": bool(after <= before * (1.0 + 1e-6) + 1e-12)}


def _rms_item(diag: Diagnosis, noise: float) -> dict | None:
    """The spec's predicted variation over the measured rows against the data's (each about its mean): an
    item when the spec, its phases fitted, predicts MISMATCH_RATIO times more variation than the data hold,
    and by MISMATCH_NOISE times the noise (a check that needs no resolved order: single runs, short arcs)."""
    y = diag.meas.error / ARCSEC
    model = diag.before.fitted
    spec_v = float(np.sqrt(np.mean((model - np.mean(model)) ** 2)))
    data_v = float(np.sqrt(np.mean((y - np.mean(y)) ** 2)))
    if spec_v >= MISMATCH_RATIO * data_v and spec_v - data_v >= MISMATCH_NOISE * noise:
        return {"what": "RMS of the predicted error over the measured rows (phases fitted)", "spec_arcsec": spec_v,
                "data_arcsec": data_v}
    return None


def spec_mismatch(diag: Diagnosis, repeat_arcsec: float | None, tables=None) -> dict | None:
    """Whether the spec's predicted error is far from the data (a spec of another drive, or a unit mix-up).

    Compared on the measurement itself, not on a fitted effect: the
    amplitude of the common and the differential mode at every physical
    order the targets resolve and at which the spec's model has content
    (the model with its phases fitted, so only sizes count), and the mean
    reversal (twice the differential offset).  An item is out of line when spec and data differ
    by at least MISMATCH_RATIO and by at least MISMATCH_NOISE times the
    repeatability (the pooled scatter over runs per target and direction;
    the noise floor without repeated runs).  Whether catalogue effects then
    close the gap does not matter: an effect that cancels what the spec
    predicts at its own order patches a wrong spec, it is not found.

    Returns None, or {"items": [...], "gap_after_arcsec", "repeat_arcsec",
    "scale": data/spec size ratio (geometric mean over the items), "units":
    (column unit, unit read) when every item's ratio is within
    UNIT_RATIO_TOLERANCE of the ratio of those two units, else None}.
    ``tables``: the :func:`order_table` of the measured error and of the
    fitted model before the effects, when already made (else made here)."""
    # lazy: keeps analysis.accuracy off `measure`'s start-up
    from wormgear_cli.analysis.accuracy import geometry as drive_geometry

    meas = diag.meas
    noise = repeat_arcsec if repeat_arcsec else diag.noise_floor
    if noise is None or not math.isfinite(noise) or noise <= 0:
        return None
    y = meas.error / ARCSEC
    gap_after = float(np.sqrt(np.mean((y - diag.augmented_fitted) ** 2)))
    g = drive_geometry(diag.spec)
    data_rows, model_rows = tables if tables is not None else order_tables(meas, [y, diag.before.fitted], g)
    data_t = {r["order"]: r for r in data_rows}
    model_t = {r["order"]: r for r in model_rows}
    items = []

    def out_of_line(spec_v, data_v):
        lo, hi = sorted((abs(spec_v), abs(data_v)))
        return hi - lo >= MISMATCH_NOISE * noise and hi >= MISMATCH_RATIO * lo

    for order, m in model_t.items():
        d = data_t.get(order)
        if order == 0.0 or d is None or not (m.get("identifiable") and d.get("identifiable")):
            continue
        for mode, key in (("", "common_arcsec"), ("differential ", "differential_arcsec")):
            if key not in m or key not in d:
                continue
            spec_a, data_a = m[key], d[key]
            if spec_a >= MISMATCH_NOISE * noise and out_of_line(spec_a, data_a):
                items.append({"what": f"{mode}amplitude at order {order:g} ({m['label']})", "spec_arcsec": spec_a,
                              "data_arcsec": data_a})
    m0, d0 = model_t.get(0.0, {}), data_t.get(0.0, {})
    if "differential_arcsec" in m0 and "differential_arcsec" in d0:
        spec_b, data_b = -2.0 * m0["differential_arcsec"], -2.0 * d0["differential_arcsec"]
        if out_of_line(spec_b, data_b) or (spec_b * data_b < 0 and min(abs(spec_b), abs(data_b))
                                           >= MISMATCH_NOISE * noise):
            items.append({"what": "mean reversal (reverse - forward; ISO 230-2 B_mean has the other sign)",
                          "spec_arcsec": spec_b, "data_arcsec": data_b})
    rms = _rms_item(diag, noise) if not items else None  # the fallback when no order or reversal shows it
    if rms is not None:
        items.append(rms)
    if not items:
        return None
    ratios = [abs(it["data_arcsec"]) / abs(it["spec_arcsec"]) for it in items
              if it["spec_arcsec"] and it["data_arcsec"]]
    scale = float(np.exp(np.mean(np.log(ratios)))) if ratios else None
    units = None
    read = dict(meas.units).get("error", "arcsec")
    if ratios and len(ratios) == len(items) and read in RAD_PER_UNIT and "error" not in meas.stated_units:
        # (never against a unit the file states: a header 'error (deg)' is taken at its word)
        # every item scaled alike, by the ratio of two units: a column in unit c read as unit `read`
        for c in ERROR_UNITS:
            unit_ratio = RAD_PER_UNIT[read] / RAD_PER_UNIT[c]
            if c != read and all(abs(math.log(r / unit_ratio)) <= math.log(UNIT_RATIO_TOLERANCE) for r in ratios):
                units = (c, read)
    return {"items": items, "gap_after_arcsec": gap_after, "repeat_arcsec": noise, "scale": scale, "units": units}


def _mismatch_text(mm: dict, spec_name: str, found) -> str:
    """The verdict when the spec's predicted error is far from the data: what looks wrong, with the numbers."""
    said = "; ".join(f"{it['what']}: the spec gives {it['spec_arcsec']:.3g} arcsec, the data {it['data_arcsec']:.3g}"
                     for it in mm["items"])
    gap = (f"{mm['gap_after_arcsec']:.3g} arcsec RMS stays unexplained against a repeatability of "
           f"{mm['repeat_arcsec']:.2g} arcsec" if mm["gap_after_arcsec"] > EXCESS_FACTOR * mm["repeat_arcsec"]
           else f"repeatability {mm['repeat_arcsec']:.2g} arcsec")
    text = (f"the drive spec does not describe these data ({said}; {gap}): check that the spec is the drive "
            "measured (its ratios, tolerances, clearances) and the unit of the error column")
    if mm["units"] is not None:
        col, read = mm["units"]
        factor = 1.0 / mm["scale"] if mm["scale"] < 1 else mm["scale"]
        text += (f"; the data are about {factor:.3g} times {'smaller' if mm['scale'] < 1 else 'larger'} than the "
                 f"spec predicts: if the error column is in {col} (read as {read}), use --error-unit {col}")
    if found:
        text += ("; not naming " + ", ".join(f"{f.name} ({100 * f.share:.0f} % of the gap)" for f in found)
                 + ": against a spec that does not fit, a catalogue effect takes up what it can")
    return text


def report(diag: Diagnosis) -> dict:
    """The JSON document of ``wormgear diagnose`` (angles in arcsec, effect parameters keyed as in the catalogue)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        return _report(diag)


def _report(diag: Diagnosis) -> dict:
    # lazy: keeps analysis.accuracy off `measure`'s start-up
    from wormgear_cli.analysis.accuracy import geometry as drive_geometry

    g = drive_geometry(diag.spec)
    meas = diag.meas
    y = meas.error / ARCSEC
    resid_after = y - diag.augmented_fitted
    twins = folded_twins(diag)
    # the order tables of the residual before and after, and (for the plausibility check) of the
    # measured error and the fitted model: one joint design for all four
    orders_before, orders_after, orders_data, orders_model = order_tables(
        meas, [diag.before.residual, resid_after, y, diag.before.fitted], g)
    pair_cells = target_run_cells(meas)
    info = diag.info
    doc = {
        "drive": diag.spec.drive.name,
        "data": str(meas.source),
        "rows": len(meas),
        "verdict": _verdict(diag, twins, orders_data),
        "effects_found": [_found_item(diag, f, twins) for f in diag.found],
        "gap_as_specified": gap_summary(meas, diag.as_specified, pair_cells),
        "gap_before": gap_summary(meas, diag.before.residual, pair_cells),
        "gap_after": gap_summary(meas, resid_after, pair_cells),
        "gap_check": gap_check(diag),
        "nuisance": _nuisance_doc(diag),
        "unexplained": _over_predicted_items(diag, orders_data),
        "candidates": _status(diag, twins),
        "fit": _fit_doc(diag),
        "noise": {"before": noise_floor(meas, diag.before.residual, diag.before.var, diag.groups),
                  "after": noise_floor(meas, resid_after, diag.after.var, diag.groups),
                  "floor_arcsec": diag.noise_floor if math.isfinite(diag.noise_floor) else None},
        "orders": {"before": orders_before, "after": orders_after},
        "residual_vs": {"before": versus(meas, diag.before.residual, info), "after": versus(meas, resid_after, info)},
        "iso230": None if is_guide_log(meas) else {
            "measured": iso_figures(meas, y), "simulated_before": iso_figures(meas, diag.before.fitted),
            "simulated_after": iso_figures(meas, diag.augmented_fitted)},
        "signals": _signals_doc(meas, info),
        "selection": {"alpha": diag.alpha, "steps": diag.steps, "stop": diag.stop.as_dict(),
                      "method": "forward selection; Wald F-test with REML run/pass random intercepts and "
                                "Satterthwaite df, Bonferroni over the candidates of each step; stability by "
                                "cluster bootstrap of whole runs; a candidate whose refit does not shrink the "
                                "RMS gap (with and without the nuisance terms) is rejected; fewer than 3 runs: "
                                "white noise, effects needing replication untestable"},
    }
    _plausibility(diag, doc, (orders_data, orders_model))
    _data_checks(diag, doc)
    return doc


def _found_item(diag: Diagnosis, f, twins: dict) -> dict:
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
        ratio = float(diag.spec.materials.housing_rise_ratio)
        basis = ("housing, worm and wheel warming alike (housing_rise_ratio = 1)" if ratio == 1.0 else
                 f"worm and wheel at the measured temperature, the housing rising {ratio:g} K per K of it "
                 "(housing_rise_ratio)")
        item["prediction"] = {"centre_distance_um_per_K": pred, "inside_interval": bool(lo <= pred <= hi),
                              "fitted_over_predicted": fitted / pred if pred else None,
                              "housing_rise_ratio": ratio,
                              "basis": basis + ", expansion from the spec's [materials]"}
    if f.name in twins:
        item["indistinguishable_from"] += [t["name"] for t in twins[f.name]]
        item["aliased_with"] = twins[f.name]
        item["notes"].append(_twin_text(f.name, _effect_order(f.name, diag), twins[f.name])
                             + "".join(f"; as {t['name']}: " + ", ".join(f"{k} = {v:.4g}" for k, v in
                                                                         t["estimate"].items())
                                       for t in twins[f.name] if "estimate" in t)
                             + f" ({FOLD_REMEDY})")
    return item


def _fit_doc(diag: Diagnosis) -> dict:
    phases = []
    for s, psi in zip(diag.sources, diag.after.psi):
        same = [t.name for t in diag.sources if abs(t.order - s.order) < 1e-9 and t is not s]
        phases.append({"source": s.name, "key": s.key, "order": s.order, "amplitude_arcsec": s.amplitude,
                       "specified_deg": wrap_deg(s.phase), "fitted_deg": round(wrap_deg(float(psi)), 4),
                       "shares_order_with": same})
    return {
        "phases_fitted": bool(diag.fit_phases),
        "zero_offset_before_arcsec": diag.before.offset,
        "zero_offset_after_arcsec": diag.after.offset,
        "phases": phases,
        "note": ("sources on one shaft share an order: only their combined vector is determined, the "
                 "individual phases are one of several equivalent solutions") if any(p["shares_order_with"]
                                                                                   for p in phases) else "",
    }


def _nuisance_doc(diag: Diagnosis) -> dict | None:
    """The nuisance terms fitted alongside during the selection, each labelled, and the gap with them."""
    if not diag.nuisance:
        return None
    return {"terms": diag.nuisance, "rms_with_arcsec": diag.rms_with_nuisance,
            "note": "fitted alongside the candidates during the selection so that they cannot leak into a catalogue "
                    "effect; no drive spec holds them: the gap before and after (and each effect's share of it) is "
                    "measured without them"}


def _over_predicted_items(diag: Diagnosis, data_rows: list) -> list:
    """The unexplained items, where a harmonic at an order of the spec's sources is in fact over-predicted
    (the spec's sources give more there than the data hold), said so."""
    out = []
    for item in diag.unexplained:
        if item["kind"] == "order" and "cannot produce with their specified sizes" in item.get("explanation", ""):
            over = over_prediction(diag, item["order"], data_rows)
            if over is not None:
                item = dict(item)
                item["over_predicted"] = True
                item["explanation"] = (f"order {item['order']:g} ({item.get('label', '')}) in {item['mode']} mode: "
                                       f"the spec predicts more here than the data hold (its sources give at least "
                                       f"{over[0]:.3g} arcsec with any phases, the data {over[1]:.3g}): check the "
                                       "spec's tolerances of the parts on this shaft")
        out.append(item)
    return out


def _signals_doc(meas, info) -> dict:
    return {"directions": list(info.directions),
            "temperature_C": [float(np.min(meas.temperature)), float(np.max(meas.temperature))]
            if info.temperature_present else None,
            "load_Nm": [float(np.min(meas.load)), float(np.max(meas.load))] if info.load_present else None,
            "time_s": [float(np.min(meas.time)), float(np.max(meas.time))] if "time_s" in meas.present else None,
            "temperature_time_correlation": None if math.isnan(info.temperature_time_corr)
            else info.temperature_time_corr}


def _plausibility(diag: Diagnosis, doc: dict, tables) -> None:
    mismatch = spec_mismatch(diag, doc["noise"]["before"]["repeat_std_arcsec"], tables)
    doc["plausibility"] = None
    if mismatch is None:
        return
    doc["plausibility"] = {
        "spec_fits_data": False, "items": mismatch["items"],
        "gap_after_arcsec": mismatch["gap_after_arcsec"], "repeatability_arcsec": mismatch["repeat_arcsec"],
        "data_over_spec": mismatch["scale"],
        "likely_units": None if mismatch["units"] is None else {"column": mismatch["units"][0],
                                                               "read_as": mismatch["units"][1]},
        "effects_not_named": [f.name for f in diag.found]}
    doc["verdict"] = _mismatch_text(mismatch, diag.spec.drive.name, diag.found)
    for item in doc["effects_found"]:
        item["notes"].append("not named in the verdict: the drive spec does not describe these data "
                             "(see plausibility)")


def _data_checks(diag: Diagnosis, doc: dict) -> None:
    meas, info = diag.meas, diag.info
    checks = data_findings(meas)
    data_warning = next((f.text for f in checks if f.kind in ("repeated_targets", "mixed_directions")), None)
    if data_warning:
        doc["signals"]["data_warning"] = data_warning
    doc["signals"]["checks"] = [{"kind": f.kind, "text": f.text or f.verdict, "warning": f.warning} for f in checks]
    flags = _data_verdict(checks)
    if flags:
        doc["verdict"] = "; ".join([doc["verdict"], *flags]) if doc["verdict"] else "; ".join(flags)
    if info.temperature_present and not math.isnan(info.temperature_time_corr) and \
            abs(info.temperature_time_corr) > 0.95:
        doc["signals"]["warning"] = (f"temperature and time correlate {info.temperature_time_corr:.2f}: a "
                                     "common-mode thermal_drift cannot be told apart from a plain drift over "
                                     "time; heating and cooling separates them")


@dataclass(frozen=True)
class DiagnoseResult:
    """What ``wormgear diagnose`` computes: the ``diagnosis``, its JSON ``document``
    (the report) and, when asked for, the augmented spec as TOML text (``spec_toml``)."""

    diagnosis: Diagnosis
    document: dict
    spec_toml: str | None


def run_diagnose(spec, meas, *, alpha: float = 0.01, fit_phases: bool = True, max_effects: int = 4,
                 resamples: int = 50, progress=None, data_name: str = "",
                 write_spec: str | None = None, jobs: int = 1) -> DiagnoseResult:
    """Diagnose ``meas`` against ``spec`` and assemble the report.

    Parameters as :func:`wormgear_cli.diagnosis.diagnose`; ``data_name``
    names the measurement in the augmented spec's header; ``write_spec``: the
    file the augmented spec will be written to (recorded in the report's
    ``augmented_spec``; None: no spec text is made); ``jobs``: worker processes for the
    stability check's resamples.  Raises UsageError and
    DataError as :func:`~wormgear_cli.diagnosis.diagnose`."""
    diag = diagnose(spec, meas, alpha=alpha, fit_phases=fit_phases, max_effects=max_effects, resamples=resamples,
                    progress=progress, jobs=jobs)
    doc = report(diag)
    doc["augmented_spec"] = None if write_spec is None else str(write_spec)
    text = augmented_toml(diag, data_name) if write_spec is not None else None
    return DiagnoseResult(diag, doc, text)


def augmented_toml(diag: Diagnosis, data_name: str = "") -> str:
    """The augmented spec as TOML text, with a comment header saying what changed."""
    import tomli_w  # lazy: keeps tomli_w off `measure`'s start-up

    from wormgear_cli.errors import quote  # names on one comment line: a line break cannot start TOML

    lines = [f"# {quote(diag.spec.drive.name)}: written by wormgear diagnose from {quote(diag.spec.source)}"
             + (f" and {quote(data_name)}" if data_name else "")]
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
