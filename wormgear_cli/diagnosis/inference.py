"""Final inference on the named effects: tests and 95 % intervals in the final model,
the range of sizes of a same-order effect (profile of the GLS cost), and the
likely further effect that narrowly missed the level."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from wormgear_cli.diagnosis.candidates import Candidate, CandidateKind, candidate_params, physical_problem
from wormgear_cli.diagnosis.design import orthonormal, residualise
from wormgear_cli.diagnosis.mixed import Cross, Wald, containment_df, contrast_df, reml, t_ppf, variance_info, wald
from wormgear_cli.diagnosis.phases import FitContext, ModelFit, PhaseSource, effect_contrib, fit_model
from wormgear_cli.diagnosis.scoring import Score
from wormgear_cli.diagnosis.thresholds import INDISTINGUISHABLE, NEAR_SHARE
from wormgear_cli.physics.effects import EFFECTS, params_to_keys


def wrap_deg(x: float) -> float:
    v = (math.degrees(x) + 180.0) % 360.0 - 180.0
    return 180.0 if v == -180.0 else v


def _sig6(x: float) -> float:
    return float(f"{x:.6g}")


def augmented_params(found: Found) -> dict:
    """A named effect's parameters keyed as in the catalogue (rounded as written)."""
    eff = EFFECTS[found.name]
    keys = params_to_keys(found.name, found.params)
    out = {}
    for p in eff.params:
        v = keys[p.key]
        if p.name == eff.phase:
            v = wrap_deg(v * p.scale)
            v = round(v, 4)
        else:
            v = _sig6(v)
        out[p.key] = v
    return out


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
    kind: CandidateKind
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


@dataclass(frozen=True)
class Accepted:
    """An effect accepted by the selection: its ``candidate`` and ``score`` at the step
    it was accepted (``step``, 1-based), its ``stability`` (share of resamples in
    which it scored best; None: not assessed, ``stability_note`` says why), the
    ``share`` of the gap its refit removed, and the tested candidates ``near`` it
    as (name, canonical correlation)."""

    name: str
    candidate: Candidate
    score: Score
    stability: float | None
    step: int
    share: float
    near: tuple = ()
    stability_note: str = ""


def final_inference(state: ModelFit, accepted: list[Accepted], lin_names, groups, sources, fit_phases=True,
                    fixed: int = 1) -> list[Found]:
    """Each named effect tested and bounded in the final model (every other term as nuisance).

    The first ``fixed`` linear columns (the zero offset, and any unexplained
    structure held in the model) are nuisance; the named effects follow, in
    ``lin_names`` order."""
    if not accepted:
        return []
    lin = state.lin
    nuis, _ = orthonormal(np.hstack([lin[:, :fixed], state.jac]), own=True)
    kb = nuis.shape[1]
    eff_cols = lin[:, fixed:]
    rms = np.sqrt(np.mean(eff_cols**2, axis=0))
    scale = 1.0 / np.where(rms > 0, rms, 1.0)
    y_lin = state.residual + eff_cols @ state.beta[fixed:]
    cross = Cross.build(np.hstack([nuis, eff_cols * scale]), y_lin, groups)
    vf = reml(cross)
    vinfo = variance_info(cross, vf)
    out = []
    design = np.hstack([nuis, eff_cols * scale])
    effect_names = [(nm, sl) for nm, sl in lin_names if sl.start >= fixed]
    for acc, (_, sl) in zip(accepted, effect_names):
        name, cand, sc, frac, step_no = acc.name, acc.candidate, acc.score, acc.stability, acc.step
        share, near, stab_note = acc.share, acc.near, acc.stability_note
        idx = np.arange(kb + sl.start - fixed, kb + sl.stop - fixed)
        rest = np.delete(design, idx, axis=1)
        cont = containment_df(groups, rest, residualise(orthonormal(rest)[0], design[:, idx]))
        w = wald(cross, vf, idx, containment=cont, info=vinfo)
        sc_ = scale[sl.start - fixed:sl.stop - fixed]
        beta = state.beta[sl]
        cov = w.cov * np.outer(sc_, sc_)
        params = candidate_params(cand, beta)
        eff = EFFECTS[name]
        amp_key = next(p.key for p in eff.params if p.name == eff.amplitude)
        amp_p = eff.param(amp_key)
        intervals = {}
        if cand.kind is CandidateKind.PERIODIC:
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
            if cand.kind is CandidateKind.RECIPROCAL:
                lo, hi = (1.0 / hi if hi > 0 else math.inf), (1.0 / lo if lo > 0 else math.inf)
                if lo > hi:
                    lo, hi = hi, lo
            intervals[amp_key] = (lo / amp_p.scale, hi / amp_p.scale)
        same_fitted = fit_phases and cand.order is not None and any(
            abs(s.order - cand.order) < 1e-9 and s.amplitude > 1e-9 for s in sources)
        if same_fitted:
            # traded against the fitted phases of the sources on this order: no meaningful interval
            intervals = {}
            w = Wald(w.estimate, w.cov, sc.test.F, sc.test.q, sc.test.df, sc.test.p)
        f = Found(name, cand.kind, params, intervals, w.p, min(1.0, w.p * len(accepted)), w.df, share, frac,
                  step_no, stability_note=stab_note, separable=not same_fitted,
                  fixed_keys=[p.key for p in eff.params if p.name in cand.fixed])
        f.signature_rms = float(np.sqrt(np.mean((lin[:, sl] @ beta) ** 2)))
        if cand.order is not None:
            same = [s.name for s in sources if abs(s.order - cand.order) < 1e-9 and s.amplitude > 1e-9]
            if same and fit_phases:
                # the note with the range of sizes that fit as well is added by same_order_range
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


def same_order_range(f: Found, ctx: FitContext, state: ModelFit, lin, sl, cand: Candidate, geometry,
                     steps: int = 5) -> None:
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
    y, sig, base, sources = ctx.y, ctx.sig, ctx.base, ctx.sources
    eff = EFFECTS[cand.name]
    order = cand.order
    assert order is not None  # (a same-order effect is periodic)
    same = [j for j, src in enumerate(sources) if abs(src.order - order) < 1e-9]
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
                srcs = [*same_src, PhaseSource(f"effect:{cand.name}", "", float(order), a * unit, ph_fit,
                                               effect_contrib(eff, {**cand.fixed, eff.amplitude: a}, geometry))]
            fm = fit_model(ctx.replaced(base=base2, sources=tuple(srcs), spec_psi=tuple(start)), lin2, True,
                           extra_starts=[start], variance=state.var)
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


def likely_effect(ctx: FitContext, state: ModelFit, lin, lin_names, accepted: list[Accepted], found, name: str,
                  cand: Candidate, sc: Score, fittable, fit_phases, step_no, fixed: int = 1) -> dict | None:
    """A candidate that missed the significance level narrowly (or the --max-effects limit): refit with it.

    When it would remove at least NEAR_SHARE of the remaining mean-square gap
    it is reported as a likely further effect, and every named effect's
    interval is widened to cover its interval in that larger model too (the
    named effect's estimate may be biased by what is left out).  Returns the
    report entry, or None."""
    n = ctx.n
    rss = float(state.residual @ state.residual)
    alt_lin = np.hstack([lin, cand.columns])
    alt = fit_model(ctx, alt_lin, fit_phases, extra_starts=[state.psi])
    rss_alt = float(alt.residual @ alt.residual)
    gain = (rss - rss_alt) / rss if rss > 0 else 0.0
    if not gain >= NEAR_SHARE:
        return None
    alt_names = [*lin_names, (name, slice(lin.shape[1], lin.shape[1] + cand.q))]
    alt_found = final_inference(alt, [*accepted, Accepted(name, cand, sc, None, step_no, gain)], alt_names, ctx.groups,
                                fittable, fit_phases, fixed)
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
