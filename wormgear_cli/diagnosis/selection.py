"""Forward selection of the missing catalogue effects: the core of ``wormgear diagnose``."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from enum import Enum

import numpy as np

from wormgear_cli.diagnosis.augment import augment
from wormgear_cli.diagnosis.candidates import UNPHYSICAL_HINT, candidate, order_aliases, physical_problem
from wormgear_cli.diagnosis.inference import Accepted, final_inference, likely_effect, same_order_range
from wormgear_cli.diagnosis.phases import FitContext, ModelFit, fit_model, phase_sources, sources_total
from wormgear_cli.diagnosis.residuals import noise_floor_rms
from wormgear_cli.diagnosis.runs import DataInfo, Groups, data_info, make_cells, make_groups
from wormgear_cli.diagnosis.scan import annotate, scan_residual, unowned_order_columns
from wormgear_cli.diagnosis.scoring import Score, ScoreStatus, Step, same_order_test
from wormgear_cli.diagnosis.thresholds import INDISTINGUISHABLE, MIN_RUNS, MIN_STABILITY, NEAR_FACTOR, NEARLY
from wormgear_cli.errors import DataError, UsageError
from wormgear_cli.units import ARCSEC


class StopReason(Enum):
    """Why the forward selection stopped."""

    NOTHING_LEFT = "nothing left to test"
    NONE_OBSERVABLE = "no candidate is observable"
    NOT_SIGNIFICANT = "no further candidate is significant"
    MAX_EFFECTS = "--max-effects reached"
    AMBIGUOUS = "ambiguous"
    UNPHYSICAL = "unphysical"
    UNSTABLE = "unstable"
    WORSENS = "worsens"


#: the fields of the report's ``selection.stop`` object for each reason, in order
_STOP_FIELDS = {
    StopReason.NOTHING_LEFT: (),
    StopReason.NONE_OBSERVABLE: (),
    StopReason.NOT_SIGNIFICANT: ("best", "p_adjusted"),
    StopReason.MAX_EFFECTS: ("best",),
    StopReason.AMBIGUOUS: ("candidates", "correlation"),
    StopReason.UNPHYSICAL: ("candidate", "detail", "hint"),
    StopReason.UNSTABLE: ("candidate", "stability", "rivals"),
    StopReason.WORSENS: ("candidate", "p_adjusted", "rms_before_arcsec", "rms_with_arcsec"),
}


@dataclass(frozen=True)
class Stop:
    """Why and where the selection stopped.

    ``best``: the best remaining candidate (NOT_SIGNIFICANT, MAX_EFFECTS);
    ``candidate``: the one that stopped it (UNPHYSICAL, UNSTABLE, WORSENS);
    ``candidates``/``correlation``: the rivals that fit equally well
    (AMBIGUOUS); ``detail``/``hint``: the parameter outside its physical range
    and what it says about the spec; ``stability``/``rivals``: share of
    resamples in which it and its rivals scored best; ``rms_*_arcsec``: the
    RMS gap before and with the rejected candidate [arcsec]; ``max_effects``:
    the --max-effects limit reached."""

    reason: StopReason
    best: str | None = None
    p_adjusted: float | None = None
    candidate: str | None = None
    candidates: tuple = ()
    correlation: float | None = None
    detail: str = ""
    hint: str = ""
    stability: float | None = None
    rivals: tuple = ()
    rms_before_arcsec: float | None = None
    rms_with_arcsec: float | None = None
    max_effects: int | None = None

    def as_dict(self) -> dict:
        """The report's ``selection.stop`` object."""
        text = (f"--max-effects {self.max_effects} reached" if self.reason is StopReason.MAX_EFFECTS
                else self.reason.value)
        out: dict = {"reason": text}
        for key in _STOP_FIELDS[self.reason]:
            value = getattr(self, key)
            out[key] = [dict(v) if isinstance(v, dict) else v for v in value] if isinstance(value, tuple) else value
        return out


@dataclass
class Diagnosis:
    """Everything ``wormgear diagnose`` reports (angles in arcsec).

    ``before``: the fit of the spec (phases, offset, held structure) before any
    effect; once the model has moved on its ``jac`` and ``lin`` are dropped
    (shape (N, 0)), only its phases, coefficients, residual and noise are kept."""

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
    stop: Stop
    unexplained: list
    augmented: dict
    augmented_fitted: np.ndarray
    thermal_prediction: float | None
    few_runs: bool = False
    noise_floor: float = math.nan
    likely: dict | None = None


def _reported_only(fit: ModelFit) -> ModelFit:
    """``fit`` without its (N, m) Jacobian and (N, l) linear columns, once the model has moved on from it
    (the fit before the effects: the report needs its phases, coefficients, residual and noise only)."""
    if fit.jac.shape[1] == 0 and fit.lin.shape[1] == 0:
        return fit
    n = fit.residual.shape[0]
    return replace(fit, jac=np.empty((n, 0)), lin=np.empty((n, 0)))


def diagnose(spec, meas, alpha: float = 0.01, fit_phases: bool = True, max_effects: int = 4,
             resamples: int = 50, progress: Callable | None = None) -> Diagnosis:
    """Fit the spec to a measurement, name the missing catalogue effects, refit.

    Parameters
    ----------
    spec : a loaded drive (:class:`wormgear_cli.spec.loader.Spec`)
    meas : a :class:`wormgear_cli.measurement.reader.Measurement` with measured errors
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
    from wormgear_cli.analysis.accuracy import geometry as drive_geometry
    from wormgear_cli.analysis.simulate import simulate
    from wormgear_cli.physics.effects import EFFECTS

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
    groups = make_groups(meas.direction, meas.run if "run" in meas.present else None,
                         meas.time if "time_s" in meas.present else None)
    if "run" in getattr(meas, "derived", ()):  # the reader numbered the runs where time_s goes backwards
        groups = replace(groups, describe="no run column: runs inferred where time_s goes backwards, one pass per "
                                          "run and direction")
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
    base = simulated_spec - (sources_total(sources, sig, [s.phase for s in sources]) if sources else 0.0)
    spec_psi = [s.phase for s in sources]
    ctx = FitContext(y, sig, groups, base, tuple(sources), tuple(spec_psi))
    if n < len(sources) + 4:
        raise DataError(f"{meas.source}: {n} rows are too few to fit {len(sources)} phase"
                        f"{'s' if len(sources) != 1 else ''} and a zero offset with noise to spare; need at least "
                        f"{len(sources) + 4} rows (more targets or runs)")
    say("fitting phases and offset")
    lin = np.ones((n, 1))
    lin_names = [("the zero offset", slice(0, 1))]
    state = fit_model(ctx, lin, fit_phases)
    before = state
    rss_before = float(before.residual @ before.residual)
    # significant structure at orders no catalogue effect owns is part of the model every candidate is tested
    # against (else it leaks into a catalogue effect whose columns it partly projects onto)
    say("scanning the residual for structure no catalogue effect owns")
    scan_orders: dict = {}
    held = unowned_order_columns(scan_residual(state, sig, groups, g, alpha, info, sources, cells, scan_orders), sig,
                                 g, state)
    for label, cols, _ in held:
        lin_names.append((label, slice(lin.shape[1], lin.shape[1] + cols.shape[1])))
        lin = np.hstack([lin, cols])
    cols = None
    held = [(label, None, item) for label, _, item in held]  # the columns live on in lin only
    if held:
        state = fit_model(ctx, lin, fit_phases, extra_starts=[state.psi])
        before = _reported_only(before)
    fixed = lin.shape[1]
    cands = {name: candidate(name, sig, g) for name in EFFECTS if name not in spec.effects}
    alias_notes = order_aliases(sig.theta, cands, sources, g)
    accepted: list[Accepted] = []
    steps = []
    final_scores: dict[str, Score] = {}
    stop: Stop | None = None
    remaining = dict(cands)
    redo = 0
    while True:
        say(f"scoring {len(remaining)} candidate effects (step {len(steps) + 1})")
        current, current_lin = state, lin

        def nonlinear(cand, current=current, current_lin=current_lin):
            return same_order_test(ctx, current, current_lin, cand, cells)

        step = None  # the previous step's design (N x columns) freed before the next is built
        step = Step(state, remaining, groups, info, lin_names, sources, alias_notes, alpha, cells,
                    nonlinear if fit_phases else None, few_runs=few_runs)
        if step.better_null is not None and redo < 3:
            # a same-order refit showed the phase fit sat in a local minimum: refit from there, score again
            redo += 1
            state = fit_model(ctx, lin, fit_phases, extra_starts=[step.better_null])
            if not accepted:
                before = state
                rss_before = float(before.residual @ before.residual)
            elif before is not state:
                before = _reported_only(before)
            continue
        for name, sc in step.scores.items():
            final_scores[name] = sc
        record = {"step": len(steps) + 1, "tested": len(step.tested),
                  "scores": [{"name": nm, "F": step.scores[nm].wald.F, "df": step.scores[nm].wald.df,
                              "p": step.scores[nm].wald.p, "p_adjusted": step.scores[nm].p_adj}
                             for nm in step.tested]}
        steps.append(record)
        if not step.tested:
            stop = Stop(StopReason.NOTHING_LEFT if accepted else StopReason.NONE_OBSERVABLE)
            break
        best = step.tested[0]
        sc = step.scores[best]
        if sc.p_adj >= alpha:
            stop = Stop(StopReason.NOT_SIGNIFICANT, best=best, p_adjusted=sc.p_adj)
            break
        if len(accepted) >= max_effects:
            stop = Stop(StopReason.MAX_EFFECTS, best=best, max_effects=max_effects)
            break
        twins = [o for o in step.tested if o != best and step.similar.get((best, o), 0) >= INDISTINGUISHABLE
                 and step.scores[o].p_adj < alpha]
        # a twin at an order the target spacing folds onto best's explains the data equally well by construction:
        # best is fitted and named together with it (the report names both); only other twins stop the selection
        folded = {o for o, _ in alias_notes.get(best, []) if o != remaining[best].order}
        twins = [o for o in twins if remaining[o].order not in folded]
        if twins:
            stop = Stop(StopReason.AMBIGUOUS, candidates=(best, *twins),
                        correlation=max(step.similar[(best, o)] for o in twins))
            break
        problem = physical_problem(best, sc.params)
        if problem:
            stop = Stop(StopReason.UNPHYSICAL, candidate=best, detail=problem, hint=UNPHYSICAL_HINT.get(best, ""))
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
        if frac is not None:  # a folded twin scoring best is the same content
            frac += sum(v for k, v in stab.items() if k != best and remaining[k].order in folded)
        if frac is not None and frac < MIN_STABILITY:
            rivals = sorted(((v, k) for k, v in stab.items() if k != best and v > 0), reverse=True)
            stop = Stop(StopReason.UNSTABLE, candidate=best, stability=frac,
                        rivals=tuple({"name": k, "share": v} for v, k in rivals))
            break
        near = [(o, step.similar[(best, o)]) for o in step.tested if o != best
                and step.similar.get((best, o), 0.0) >= NEARLY and remaining[o].order not in folded]
        cand = remaining[best]
        start = lin.shape[1]
        new_lin = np.hstack([lin, cand.columns])
        prev_rss = float(state.residual @ state.residual)
        say(f"refitting with {best}")
        new_state = fit_model(ctx, new_lin, fit_phases, extra_starts=[state.psi])
        new_rss = float(new_state.residual @ new_state.residual)
        if not new_rss < prev_rss * (1.0 - 1e-9):
            # significant in the GLS metric, yet the gap grows once everything is refitted: the estimate follows
            # structure that is not its signature (typically the random effects absorb what it gets wrong)
            stop = Stop(StopReason.WORSENS, candidate=best, p_adjusted=sc.p_adj,
                        rms_before_arcsec=math.sqrt(prev_rss / n), rms_with_arcsec=math.sqrt(new_rss / n))
            record["rejected"] = best
            break
        record["accepted"] = best
        remaining.pop(best)
        lin = new_lin
        lin_names.append((best, slice(start, start + cand.q)))
        state = new_state
        before = _reported_only(before)
        accepted.append(Accepted(best, cand, sc, frac, len(steps),
                                 (prev_rss - new_rss) / rss_before if rss_before else 0.0, tuple(near), stab_note))
    after = state
    # the last step's design (N x columns) is not needed any more: keep its scores only
    last_slices, last_scores = step.slices, step.scores
    step = None
    found = final_inference(after, accepted, lin_names, groups, fittable, fit_phases, fixed)
    for f in found:
        final_scores[f.name] = Score(f.name, ScoreStatus.NAMED)
    for f in found:
        if not f.separable:
            say(f"profiling the size of {f.name} against the phases of its shaft's sources")
            cand = next(a.candidate for a in accepted if a.name == f.name)
            sl = next(sl_ for nm, sl_ in lin_names if nm == f.name)
            same_order_range(f, ctx, after, lin, sl, cand, g)
    likely = None
    if stop.reason in (StopReason.NOT_SIGNIFICANT, StopReason.MAX_EFFECTS) \
            and stop.best in remaining and stop.best in last_slices:
        best = stop.best
        sc = last_scores[best]
        if sc.p_adj < min(NEAR_FACTOR * alpha, 0.5) or stop.reason is StopReason.MAX_EFFECTS:
            say(f"checking whether {best} is a likely further effect")
            likely = likely_effect(ctx, after, lin, lin_names, accepted, found,
                                    best, remaining[best], sc, fittable, fit_phases, len(steps), fixed)
            if likely is not None:
                final_scores[best].status = ScoreStatus.LIKELY
    cands = remaining = None  # the candidates' columns are not needed any more
    say("scanning the residual for structure")
    # what is left, tested with the held structure in the model, plus the held structure itself (as found)
    unexplained = scan_residual(after, sig, groups, g, alpha, info, sources, cells, scan_orders)
    if held:
        unexplained = sorted([*(item for _, _, item in held), *unexplained], key=lambda it: it["p_adjusted"])
    if held:
        # the drive's model without the held structure, which no spec can hold: the named effects at their
        # estimates (as the augmented spec writes them), the phases and the offset refitted
        effects_part = lin[:, fixed:] @ after.beta[fixed:]
        after = fit_model(ctx.replaced(base=ctx.base + effects_part), lin[:, :1], fit_phases,
                          extra_starts=[after.psi, before.psi])
    floor = noise_floor_rms(after, groups, sig.time if "time_s" in meas.present else None)
    unexplained = annotate(unexplained, final_scores, groups, few_runs, likely, after, floor, g)
    augmented, aug_fitted = augment(spec, sig, after, sources, found, fit_phases, y)
    thermal = None
    try:
        from wormgear_cli.physics.thermal import predicted_centre_distance_um_per_K

        predicted = predicted_centre_distance_um_per_K(spec, spec.materials.housing_rise_ratio)
        thermal = None if predicted is None else float(predicted)  # None: a drive without a worm stage
    except (ImportError, AttributeError):
        thermal = None
    return Diagnosis(spec, meas, groups, info, sources, fit_phases, alpha, y - simulated_spec, simulated_spec,
                     before, after, found, final_scores, steps, stop, unexplained, augmented, aug_fitted, thermal,
                     few_runs, floor, likely)

