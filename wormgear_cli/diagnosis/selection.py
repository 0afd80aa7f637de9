"""Forward selection of the missing catalogue effects: the core of ``wormgear diagnose``."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from wormgear_cli.diagnosis.augment import augment
from wormgear_cli.diagnosis.candidates import candidate, order_aliases, physical_problem
from wormgear_cli.diagnosis.inference import Accepted, final_inference, likely_effect, same_order_range
from wormgear_cli.diagnosis.phases import FitContext, ModelFit, fit_model, phase_sources, sources_total
from wormgear_cli.diagnosis.residuals import noise_floor_rms
from wormgear_cli.diagnosis.runs import Cells, DataInfo, Groups, data_info, make_cells, make_groups
from wormgear_cli.diagnosis.scan import ScanContext, annotate, nuisance_columns, scan_residual
from wormgear_cli.diagnosis.scoring import Score, ScoreStatus, Step, same_order_test, score_step
from wormgear_cli.diagnosis.thresholds import INDISTINGUISHABLE, MIN_RUNS, MIN_STABILITY, NEAR_FACTOR, NEARLY
from wormgear_cli.errors import DataError, UsageError
from wormgear_cli.measurement.drift import drift_columns
from wormgear_cli.physics.effects import EFFECTS, train_effects
from wormgear_cli.units import ARCSEC

if TYPE_CHECKING:
    from wormgear_cli.measurement.reader import Measurement
    from wormgear_cli.physics.effects import Signals
    from wormgear_cli.physics.geometry import DriveGeometry
    from wormgear_cli.spec.loader import Spec


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

    ``before``: the baseline, the spec's own sources with fitted phases and the
    zero offset (no nuisance term, no effect); once the model has moved on its
    ``jac`` and ``lin`` are dropped (shape (N, 0)), only its phases,
    coefficients, residual and noise are kept.  ``after``: the spec with the
    named effects, phases and offset refitted, no nuisance term.
    ``nuisance``: the terms fitted alongside during the selection that no
    spec can hold (harmonics no catalogue effect owns, a drift over a partial
    arc), each a dict with ``label``, ``kind``, ``rms_arcsec`` (RMS of its
    fitted part at the rows) and, for a harmonic, ``order``, ``mode`` and
    ``amplitude_arcsec``; ``rms_with_nuisance``: the RMS gap with them in the
    model [arcsec] (None without nuisance terms)."""

    spec: Spec
    meas: Measurement
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
    nuisance: list = field(default_factory=list)
    rms_with_nuisance: float | None = None


@dataclass(frozen=True)
class DiagnoseOptions:
    """Options of :func:`diagnose` (see there)."""

    alpha: float = 0.01
    fit_phases: bool = True
    max_effects: int = 4
    resamples: int = 50
    progress: Callable | None = None
    #: worker processes for the stability check's resamples (the same result whatever the count)
    jobs: int = 1

    def say(self, text: str) -> None:
        if self.progress is not None:
            self.progress(text)


def _reported_only(fit: ModelFit) -> ModelFit:
    """``fit`` without its (N, m) Jacobian and (N, l) linear columns, once the model has moved on from it
    (the fit before the effects: the report needs its phases, coefficients, residual and noise only)."""
    if fit.jac.shape[1] == 0 and fit.lin.shape[1] == 0:
        return fit
    n = fit.residual.shape[0]
    return replace(fit, jac=np.empty((n, 0)), lin=np.empty((n, 0)))


def diagnose(spec, meas, alpha: float = 0.01, fit_phases: bool = True, max_effects: int = 4,
             resamples: int = 50, progress: Callable | None = None, jobs: int = 1) -> Diagnosis:
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
    jobs : worker processes for the stability check's resamples (the same result whatever the count)

    See the module docstring for the model and the selection rules.  Raises
    UsageError for bad options and DataError for data it cannot use.
    """
    opt = DiagnoseOptions(alpha, fit_phases, max_effects, resamples, progress, jobs)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        return _diagnose(spec, meas, opt)


@dataclass
class _Setup:
    """What the spec and the data give before any fit."""

    spec: Spec
    meas: Measurement
    sig: Signals
    y: np.ndarray
    g: DriveGeometry
    groups: Groups
    few_runs: bool
    info: DataInfo
    fittable: list
    sources: list
    cells: Cells
    simulated_spec: np.ndarray
    ctx: FitContext

    @property
    def n(self) -> int:
        return self.y.shape[0]


def _setup(spec, meas, opt: DiagnoseOptions) -> _Setup:
    # lazy: keeps analysis.accuracy, analysis.simulate off `measure`'s start-up
    from wormgear_cli.analysis.accuracy import geometry as drive_geometry
    from wormgear_cli.analysis.simulate import simulate

    if not (0.0 < opt.alpha < 0.5):
        raise UsageError(f"alpha: expected a number in (0, 0.5), got {opt.alpha:g}", parameter="alpha")
    if opt.max_effects < 0:
        raise UsageError(f"max_effects: expected an integer >= 0, got {opt.max_effects}", parameter="max_effects")
    if np.any(np.isnan(meas.error)):
        raise DataError(f"{meas.source}: no error_arcsec column; diagnose needs measured errors")
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
    if getattr(meas, "run_drift", False):
        # each run's offset and drift are fixed terms of the model (base_columns): a random intercept per run
        # or pass would have nothing left to estimate
        groups = Groups(groups.pass_id, groups.pass_size, groups.pass_run, groups.pass_direction, groups.runs,
                        False, False, groups.describe.split(";")[0] + "; each run's offset and drift (a cubic in "
                        "time) fitted as fixed terms, as a guide log's sessions need: no scatter between runs is "
                        "estimated, noise taken as white")
    elif few_runs:
        # one or two runs: scatter between runs and passes cannot be estimated (a variance from one run is
        # meaningless); the noise is taken as white and effects that need replication are not tested
        plural = "s" if groups.runs != 1 else ""
        groups = Groups(groups.pass_id, groups.pass_size, groups.pass_run, groups.pass_direction, groups.runs,
                        False, False, groups.describe.split(";")[0] + f"; {groups.runs} run{plural}, fewer than "
                        f"{MIN_RUNS}: scatter between runs and passes cannot be estimated, noise taken as white")
    info = data_info(meas, groups)
    fittable, _ = phase_sources(spec, g, sig)
    sources = fittable if opt.fit_phases else []
    simulated_spec = simulate(spec, sig) / ARCSEC
    base = simulated_spec - (sources_total(sources, sig, [s.phase for s in sources]) if sources else 0.0)
    ctx = FitContext(y, sig, groups, base, tuple(sources), tuple(s.phase for s in sources))
    if n < len(sources) + 4:
        raise DataError(f"{meas.source}: {n} rows are too few to fit {len(sources)} phase"
                        f"{'s' if len(sources) != 1 else ''} and a zero offset with noise to spare; need at least "
                        f"{len(sources) + 4} rows (more targets or runs)")
    cells = make_cells(sig.theta, sig.direction)
    return _Setup(spec, meas, sig, y, g, groups, few_runs, info, fittable, sources, cells, simulated_spec, ctx)


@dataclass
class _Run:
    """The model as the selection goes: ``state`` with the nuisance terms (the first ``fixed`` columns of
    ``lin``: the offset and the held structure), ``plain`` the same model without them (the spec, the
    named effects and the offset: the model the gap is measured on), ``before`` the baseline."""

    s: _Setup
    opt: DiagnoseOptions
    before: ModelFit
    state: ModelFit
    plain: ModelFit
    lin: np.ndarray
    plain_lin: np.ndarray
    lin_names: list
    base: int = 1  # the columns every model holds (base_columns)
    fixed: int = 1
    held: list = field(default_factory=list)
    scan_orders: dict = field(default_factory=dict)
    accepted: list = field(default_factory=list)
    steps: list = field(default_factory=list)
    scores: dict = field(default_factory=dict)
    remaining: dict = field(default_factory=dict)
    alias_notes: dict = field(default_factory=dict)
    stop: Stop | None = None
    last: tuple = ({}, {})

    @property
    def rss_before(self) -> float:
        return float(self.before.residual @ self.before.residual)


def _diagnose(spec, meas, opt: DiagnoseOptions) -> Diagnosis:
    s = _setup(spec, meas, opt)
    opt.say("fitting phases and offset")
    base, name = base_columns(meas)
    before = fit_model(s.ctx, base, opt.fit_phases)
    run = _Run(s, opt, before, before, before, base, base, [(name, slice(0, base.shape[1]))], base=base.shape[1],
               fixed=base.shape[1])
    _hold_nuisance(run)
    run.remaining = {name: candidate(name, s.sig, s.g) for name in train_effects(s.g) if name not in spec.effects}
    run.alias_notes = order_aliases(s.sig.theta, run.remaining, s.sources, s.g)
    _select(run)
    return _conclude(run)


def base_columns(meas) -> tuple[np.ndarray, str]:
    """The linear columns every model of ``meas`` holds, and their name: the zero offset; for a
    measurement whose runs each have an offset and a drift of their own (``meas.run_drift``: a guide
    log's sessions), those too (a cubic in time per run,
    :func:`~wormgear_cli.measurement.drift.drift_columns`)."""
    ones = np.ones((len(meas), 1))
    if not getattr(meas, "run_drift", False):
        return ones, "the zero offset"

    return np.hstack([ones, drift_columns(meas.time, meas.run)]), "the zero offset and each run's offset and drift"


def _hold_nuisance(run: _Run) -> None:
    """Significant structure at orders no catalogue effect owns, and a drift over a partial arc, become
    nuisance columns of the model every candidate is tested against (else they leak into a catalogue
    effect whose columns they partly project onto); the gap stays measured without them."""
    s, opt = run.s, run.opt
    opt.say("scanning the residual for structure no catalogue effect owns")
    items = scan_residual(run.state, ScanContext(s.sig, s.groups, s.g, opt.alpha, s.info, s.sources, s.cells,
                                                 run.scan_orders, s.meas.run_drift))
    held = nuisance_columns(items, s.sig, s.g, run.state, s.info, run.scan_orders)
    lin, names = run.lin, list(run.lin_names)
    for label, cols, _ in held:
        names.append((label, slice(lin.shape[1], lin.shape[1] + cols.shape[1])))
        lin = np.hstack([lin, cols])
    run.held = [(label, None, item) for label, _, item in held]  # the columns live on in lin only
    run.lin, run.lin_names, run.fixed = lin, names, lin.shape[1]
    if held:
        run.state = fit_model(s.ctx, lin, opt.fit_phases, extra_starts=[run.state.psi])


def _select(run: _Run) -> None:
    """Forward selection: score, decide, refit, until a stop."""
    opt = run.opt
    redo = 0
    step = None
    while True:
        opt.say(f"scoring {len(run.remaining)} candidate effects (step {len(run.steps) + 1})")
        step = None  # the previous step's design (N x columns) freed before the next is built
        step = _score(run)
        if step.better_null is not None and redo < 3:
            # a same-order refit showed the phase fit sat in a local minimum: refit from there, score again
            redo += 1
            _refit_from(run, step.better_null)
            continue
        run.scores.update(step.scores)
        record = {"step": len(run.steps) + 1, "tested": len(step.tested),
                  "scores": [{"name": nm, "F": step.scores[nm].test.F, "df": step.scores[nm].test.df,
                              "p": step.scores[nm].test.p, "p_adjusted": step.scores[nm].p_adj}
                             for nm in step.tested]}
        run.steps.append(record)
        run.stop = _decide(run, step)
        if run.stop is None:
            run.stop = _accept(run, step, record)
        if run.stop is not None:
            break
    # the last step's design (N x columns) is not needed any more: keep its scores only
    run.last = (step.slices, step.scores)


def _score(run: _Run) -> Step:
    s = run.s
    current, current_lin = run.state, run.lin

    def nonlinear(cand, current=current, current_lin=current_lin):
        return same_order_test(s.ctx, current, current_lin, cand, s.cells)

    return score_step(run.state, run.remaining, s.groups, s.info, run.lin_names, s.sources, run.alias_notes,
                      run.opt.alpha, s.cells, nonlinear if run.opt.fit_phases else None, few_runs=s.few_runs)


def _refit_from(run: _Run, psi) -> None:
    """Refit the model (and, before any effect, the baseline) from a better start of the phases."""
    s, opt = run.s, run.opt
    run.state = fit_model(s.ctx, run.lin, opt.fit_phases, extra_starts=[psi])
    plain = fit_model(s.ctx, run.plain_lin, opt.fit_phases, extra_starts=[run.plain.psi, psi]) if run.held \
        else run.state
    if plain.cost < run.plain.cost or not run.held:
        run.plain = plain
    if not run.accepted:
        run.before = run.plain
    elif run.before is not run.state:
        run.before = _reported_only(run.before)


def _decide(run: _Run, step: Step) -> Stop | None:
    """The stop before any refit: nothing to test, nothing significant, the limit, rivals, out of range."""
    opt = run.opt
    if not step.tested:
        return Stop(StopReason.NOTHING_LEFT if run.accepted else StopReason.NONE_OBSERVABLE)
    best = step.tested[0]
    sc = step.scores[best]
    if sc.p_adj >= opt.alpha:
        return Stop(StopReason.NOT_SIGNIFICANT, best=best, p_adjusted=sc.p_adj)
    if len(run.accepted) >= opt.max_effects:
        return Stop(StopReason.MAX_EFFECTS, best=best, max_effects=opt.max_effects)
    twins = [o for o in step.tested if o != best and step.similar.get((best, o), 0) >= INDISTINGUISHABLE
             and step.scores[o].p_adj < opt.alpha]
    # a twin at an order the target spacing folds onto best's explains the data equally well by construction:
    # best is fitted and named together with it (the report names both); only other twins stop the selection
    folded = _folded_orders(run, best)
    twins = [o for o in twins if run.remaining[o].order not in folded]
    if twins:
        return Stop(StopReason.AMBIGUOUS, candidates=(best, *twins),
                    correlation=max(step.similar[(best, o)] for o in twins))
    assert sc.params is not None  # (a tested candidate's parameters are set)
    problem = physical_problem(best, sc.params)
    if problem:
        return Stop(StopReason.UNPHYSICAL, candidate=best, detail=problem, hint=EFFECTS[best].unphysical_hint or "")
    return None


def _folded_orders(run: _Run, best: str) -> set:
    return {o for o, _ in run.alias_notes.get(best, []) if o != run.remaining[best].order}


def _stability(run: _Run, step: Step, best: str) -> tuple[float | None, str]:
    """(share of resamples of whole runs in which ``best`` scores best, or None; the note when not assessed)."""
    opt, groups = run.opt, run.s.groups
    if best in step.nonlinear:
        return None, ("not assessed: its test refits the phases of the spec's sources on its order, which "
                      "resampling does not repeat")
    if opt.resamples <= 0:
        return None, "not assessed (--resamples 0)"
    if groups.runs < MIN_RUNS:
        return None, (f"not assessed: {groups.runs} run{'s' if groups.runs != 1 else ''}; resampling whole "
                      f"runs needs at least {MIN_RUNS}")
    opt.say(f"checking {best} on {opt.resamples} resamples of whole runs")
    stab = step.stability(opt.resamples, opt.alpha, jobs=opt.jobs)
    frac = stab.get(best) if stab else None
    if frac is None:
        return None, ""
    folded = _folded_orders(run, best)
    frac += sum(v for k, v in stab.items() if k != best and run.remaining[k].order in folded)  # same content
    if frac < MIN_STABILITY:
        rivals = sorted(((v, k) for k, v in stab.items() if k != best and v > 0), reverse=True)
        run.stop = Stop(StopReason.UNSTABLE, candidate=best, stability=frac,
                        rivals=tuple({"name": k, "share": v} for v, k in rivals))
    return frac, ""


def _accept(run: _Run, step: Step, record: dict) -> Stop | None:
    """Refit with the best candidate; accept it when the gap shrinks, with and without the nuisance terms."""
    s, opt = run.s, run.opt
    best = step.tested[0]
    sc = step.scores[best]
    frac, stab_note = _stability(run, step, best)
    if run.stop is not None:
        return run.stop
    folded = _folded_orders(run, best)
    near = [(o, step.similar[(best, o)]) for o in step.tested if o != best
            and step.similar.get((best, o), 0.0) >= NEARLY and run.remaining[o].order not in folded]
    cand = run.remaining[best]
    start = run.lin.shape[1]
    new_lin = np.hstack([run.lin, cand.columns])
    prev_rss = float(run.state.residual @ run.state.residual)
    opt.say(f"refitting with {best}")
    new_state = fit_model(s.ctx, new_lin, opt.fit_phases, extra_starts=[run.state.psi])
    new_rss = float(new_state.residual @ new_state.residual)
    plain_lin = np.hstack([run.plain_lin, cand.columns])
    new_plain = (fit_model(s.ctx, plain_lin, opt.fit_phases, extra_starts=[run.plain.psi, new_state.psi])
                 if run.held else new_state)
    plain_prev = float(run.plain.residual @ run.plain.residual)
    plain_new = float(new_plain.residual @ new_plain.residual)
    for old, new in ((prev_rss, new_rss), (plain_prev, plain_new)):
        if not new < old * (1.0 - 1e-9):
            # significant in the GLS metric, yet the gap grows once everything is refitted (or once the
            # nuisance terms are left out): the estimate follows structure that is not its signature
            record["rejected"] = best
            return Stop(StopReason.WORSENS, candidate=best, p_adjusted=sc.p_adj,
                        rms_before_arcsec=math.sqrt(old / s.n), rms_with_arcsec=math.sqrt(new / s.n))
    record["accepted"] = best
    run.remaining.pop(best)
    run.lin, run.plain_lin = new_lin, plain_lin
    run.lin_names.append((best, slice(start, start + cand.q)))
    run.state, run.plain = new_state, new_plain
    run.before = _reported_only(run.before)
    share = (plain_prev - plain_new) / run.rss_before if run.rss_before else 0.0  # against the baseline
    run.accepted.append(Accepted(best, cand, sc, frac, len(run.steps), share, tuple(near), stab_note))
    return None


def _conclude(run: _Run) -> Diagnosis:
    """Inference on the named effects, the likely further effect, the final scan, the model without the
    nuisance terms, the noise floor and the augmented spec."""
    s, opt = run.s, run.opt
    assert run.stop is not None  # (the selection ran to a stop)
    after = run.state
    found = final_inference(after, run.accepted, run.lin_names, s.groups, s.fittable, opt.fit_phases, run.fixed)
    for f in found:
        run.scores[f.name] = Score(f.name, ScoreStatus.NAMED)
    for f in found:
        if not f.separable:
            opt.say(f"profiling the size of {f.name} against the phases of its shaft's sources")
            acc = next(a for a in run.accepted if a.name == f.name)
            sl = next(sl_ for nm, sl_ in run.lin_names if nm == f.name)
            same_order_range(f, s.ctx, after, run.lin, sl, acc.candidate, s.g)
    likely = _likely(run, found)
    run.remaining = {}  # the candidates' columns are not needed any more
    opt.say("scanning the residual for structure")
    # what is left once the named effects are in, tested afresh without the nuisance terms (structure held
    # while the candidates were tested may have been a named effect's content seen from too short an arc)
    unexplained = scan_residual(run.plain, ScanContext(s.sig, s.groups, s.g, opt.alpha, s.info, s.sources, s.cells,
                                                       run.scan_orders, s.meas.run_drift))
    nuisance, rms_with = [], None
    if run.held:
        nuisance = _nuisance_parts(run, after)
        rms_with = float(np.sqrt(np.mean(after.residual**2)))
        # the drive's model without the held structure, which no spec can hold: the named effects at their
        # estimates (as the augmented spec writes them), the phases and the offset refitted
        effects_part = run.lin[:, run.fixed:] @ after.beta[run.fixed:]
        after = fit_model(s.ctx.replaced(base=s.ctx.base + effects_part), run.lin[:, :run.base], opt.fit_phases,
                          extra_starts=[after.psi, run.plain.psi, run.before.psi])
    floor = noise_floor_rms(after, s.groups, s.sig.time if "time_s" in s.meas.present else None)
    unexplained = annotate(unexplained, run.scores, s.groups, s.few_runs, likely, after, floor, s.g)
    augmented, aug_fitted = augment(s.spec, s.sig, after, s.sources, found, opt.fit_phases, s.y, run.base)
    return Diagnosis(s.spec, s.meas, s.groups, s.info, s.sources, opt.fit_phases, opt.alpha, _as_specified(run),
                     s.simulated_spec, run.before, after, found, run.scores, run.steps, run.stop, unexplained,
                     augmented, aug_fitted, _thermal_prediction(s.spec), s.few_runs, floor, likely, nuisance, rms_with)


def _as_specified(run: _Run) -> np.ndarray:
    """The measured error minus the spec's model as specified [arcsec]; each run's offset and drift
    removed (least squares) where the runs have their own (a guide log)."""
    gap = run.s.y - run.s.simulated_spec
    if run.base == 1:
        return gap
    cols = run.lin[:, :run.base]
    return gap - cols @ np.linalg.lstsq(cols, gap, rcond=None)[0]


def _likely(run: _Run, found) -> dict | None:
    stop, s, opt = run.stop, run.s, run.opt
    last_slices, last_scores = run.last
    assert stop is not None  # (the selection ran to a stop)
    best = stop.best
    if not (stop.reason in (StopReason.NOT_SIGNIFICANT, StopReason.MAX_EFFECTS)
            and best is not None and best in run.remaining and best in last_slices):
        return None
    sc = last_scores[best]
    if not (sc.p_adj < min(NEAR_FACTOR * opt.alpha, 0.5) or stop.reason is StopReason.MAX_EFFECTS):
        return None
    opt.say(f"checking whether {best} is a likely further effect")
    likely = likely_effect(s.ctx, run.state, run.lin, run.lin_names, run.accepted, found, best, run.remaining[best],
                           sc, s.fittable, opt.fit_phases, len(run.steps), run.fixed)
    if likely is not None:
        run.scores[best].status = ScoreStatus.LIKELY
    return likely


def _nuisance_parts(run: _Run, state: ModelFit) -> list[dict]:
    """Each held nuisance term as fitted in the final model: its label, kind and size."""
    out = []
    for (label, sl), (_, _, item) in zip(run.lin_names[1:1 + len(run.held)], run.held):
        part = state.lin[:, sl] @ state.beta[sl]
        entry = {"label": label, "kind": item["kind"], "rms_arcsec": float(np.sqrt(np.mean(part**2)))}
        if item["kind"] == "order":
            entry.update(order=item["order"], mode=item["mode"],
                         amplitude_arcsec=float(np.hypot(*state.beta[sl])) if sl.stop - sl.start == 2 else None)
        else:
            entry.update(signal=item.get("signal"), peak_to_peak_arcsec=float(np.ptp(part)))
        out.append(entry)
    return out


def _thermal_prediction(spec) -> float | None:
    try:
        # lazy: keeps physics.thermal off `measure`'s start-up
        from wormgear_cli.physics.thermal import predicted_centre_distance_um_per_K

        predicted = predicted_centre_distance_um_per_K(spec, spec.materials.housing_rise_ratio)
        return None if predicted is None else float(predicted)  # None: a drive without a worm stage
    except (ImportError, AttributeError):
        return None
