"""Scoring every candidate against the current model (one step of the selection).

Wald F-test of each candidate's columns given the model (REML under the
alternative), the cell-means check, the same-order refit test for effects
on the order of sources with fitted phases, Bonferroni adjustment, the
similarity of signatures and the cluster-bootstrap stability check.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from wormgear_cli.batch.pool import ordered_map
from wormgear_cli.diagnosis.candidates import Candidate, candidate_params, needs_problem, replication_problem
from wormgear_cli.diagnosis.design import canonical_q, orthonormal, r2, residualise, tolerance
from wormgear_cli.diagnosis.mixed import CellTester, Cross, VarFit, Wald, containment_df, f_sf, reml, wald
from wormgear_cli.diagnosis.phases import FitContext, ModelFit, gls_cost, levenberg_marquardt
from wormgear_cli.diagnosis.runs import Cells, DataInfo, Groups, cell_level, pass_sums
from wormgear_cli.diagnosis.thresholds import MIN_TOLERANCE


class ScoreStatus(str, Enum):
    """What became of a candidate (its value is the status written in the report)."""

    TESTED = "tested"
    UNOBSERVABLE = "unobservable"  #: these data cannot show it
    UNTESTABLE = "untestable"  #: too few runs to test it
    NAMED = "named"
    LIKELY = "likely"


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
    status: ScoreStatus
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


    @property
    def test(self) -> Wald:
        """The Wald test of a tested candidate (ValueError for one that was not tested)."""
        if self.wald is None:
            raise ValueError(f"{self.name} was not tested")
        return self.wald

    @property
    def fit(self) -> VarFit:
        """The REML fit under the alternative of a linearly tested candidate (ValueError otherwise)."""
        if self.var is None:
            raise ValueError(f"{self.name} has no REML fit of its own")
        return self.var


def _blocks(lin_names, sources, jac, lin) -> list[tuple[str, Callable[[], np.ndarray]]]:
    """Named parts of the current model, for saying what absorbs a candidate: (label, columns()),
    the columns taken only when asked for (a source's Jacobian columns are gathered copies)."""
    out = [(name, _columns(lin, sl)) for name, sl in lin_names]
    orders: dict[float, list[int]] = {}
    for j, s in enumerate(sources):
        orders.setdefault(s.order, []).append(j)
    for order, idx in orders.items():
        names = ", ".join(sources[j].name for j in idx)
        out.append((f"the fitted phase{'s' if len(idx) > 1 else ''} of the spec's order-{order:g} "
                    f"source{'s' if len(idx) > 1 else ''} ({names})", _columns(jac, idx)))
    return out


def _columns(a: np.ndarray, idx) -> Callable[[], np.ndarray]:
    """``a[:, idx]``, taken when called."""
    return lambda: a[:, idx]


@dataclass
class Step:
    """Scores of every candidate against the current model (one selection step; :func:`score_step`).

    ``basis`` the orthonormal model columns (with untestable candidates' signatures as nuisance
    columns); ``slices`` each linearly tested candidate's columns in ``design`` = [basis, the
    candidates' columns scaled to unit RMS] and ``cross`` its cross products; ``tested`` the tested
    candidates, best first; ``nonlinear`` those tested by a same-order refit; ``similar`` how alike
    two tested candidates' signatures are once the model is projected out; ``better_null``: phases
    that fit the null model better (a same-order refit found them), else None."""

    state: ModelFit
    groups: Groups
    basis: np.ndarray
    scores: dict[str, Score]
    slices: dict[str, slice]
    design: np.ndarray
    cross: Cross
    tested: list[str]
    nonlinear: set[str]
    similar: dict[tuple[str, str], float]
    better_null: np.ndarray | None = None

    def stability(self, resamples: int, alpha: float, seed: int = 0, jobs: int = 1) -> dict[str, float]:
        """Share of cluster-bootstrap resamples (whole runs) in which each tested candidate scores best.

        ``jobs`` > 1: the resamples are scored by that many worker processes (the same
        resamples, drawn here, and the same arithmetic: the same shares)."""
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
        sums = np.vstack([pass_sums(z[:, j], g) for j in range(k)]).T
        rng = np.random.default_rng(seed)
        counts = rng.multinomial(g.runs, np.full(g.runs, 1.0 / g.runs), size=resamples).astype(float)
        kb = self.basis.shape[1]
        tests = []
        for name in names:
            sc, sl = self.scores[name], self.slices[name]
            tests.append((np.r_[np.arange(kb), np.arange(sl.start, sl.stop)], sl.stop - sl.start, sc.fit.gp,
                          sc.fit.gr, sc.test.df))
        state = _Resampling(grams, sums, counts, g, k, kb, tests)
        size = max(1, -(-resamples // (4 * max(1, jobs))))
        spans = [(a, min(resamples, a + size)) for a in range(0, resamples, size)]
        pvals = np.full((resamples, len(names)), 1.0)
        chi2 = np.zeros((resamples, len(names)))
        for (c2, pv), (a, b) in zip(ordered_map(_score_resamples, state, spans, jobs), spans):
            chi2[a:b], pvals[a:b] = c2, pv
        # best in a resample: the largest chi^2 among the candidates significant there (else the smallest p)
        sig_ = pvals * len(names) < alpha
        score = np.where(sig_, chi2, -pvals)
        best = np.argmax(np.where(np.any(sig_, axis=1, keepdims=True), np.where(sig_, chi2, -np.inf), score), axis=1)
        return {name: float(np.mean(best == j)) for j, name in enumerate(names)}


def score_step(state: ModelFit, cands: dict, groups: Groups, info: DataInfo, lin_names, sources,
               alias_notes: dict, alpha: float, cells: Cells, nonlinear: Callable | None = None,
               few_runs: bool = False) -> Step:
    """Score every candidate of ``cands`` (name -> :class:`Candidate`, None: not linear in its
    parameters) against the current model ``state``: the Wald F-test of its columns given the model
    (REML under the alternative), the cell-means check where the data are replicated, the same-order
    refit (``nonlinear``) for candidates on the order of sources with fitted phases, Bonferroni
    adjustment at ``alpha``, the ranking and the similarity of the tested candidates' signatures.

    ``few_runs``: fewer than MIN_RUNS runs; candidates that need replication between runs are then
    untestable, and their signatures enter every other test as nuisance columns."""
    blocks = _blocks(lin_names, sources, state.jac, state.lin)
    scores: dict[str, Score] = {}
    basis0, _ = orthonormal(np.hstack([state.lin, state.jac]), own=True)
    untestable = _untestable(cands, groups, info, alias_notes, basis0, scores, blocks) if few_runs else []
    basis = orthonormal(np.hstack([state.lin, state.jac, *untestable]), own=True)[0] if untestable else basis0
    del basis0
    kb = basis.shape[1]
    width = kb
    tested_cols = []
    q_factors: dict[str, np.ndarray] = {}
    slices: dict[str, slice] = {}
    nonlinear_names: list[str] = []
    better_null = None
    for name, cand in cands.items():
        if name in scores:
            continue
        if cand is None:
            scores[name] = Score(name, ScoreStatus.UNOBSERVABLE, "its signature is not linear in its parameters")
            continue
        sc = scores[name] = Score(name, ScoreStatus.TESTED, aliases=alias_notes.get(name, []))
        why = _aliased(sc, cand, info, alias_notes)
        same = [s for s in sources if cand.order is not None and abs(s.order - cand.order) < 1e-9
                and s.amplitude > 1e-9]
        if why is None and same and nonlinear is not None:
            better_null = _same_order(sc, cand, same, nonlinear, better_null)
            nonlinear_names.append(name)
            continue
        if why is None:
            why = _absorbed(sc, cand, basis, blocks)
        if why is not None:
            sc.status = ScoreStatus.UNOBSERVABLE
            if ": " in why and not sc.remedy:
                why, sc.remedy = why.split(": ", 1)
            sc.reason = why
            continue
        rms = np.sqrt(np.mean(cand.columns**2, axis=0))
        sc.scale = 1.0 / np.where(rms > 0, rms, 1.0)
        resid_cols = residualise(basis, cand.columns)
        sc.containment = containment_df(groups, basis, resid_cols)
        # its signature with the model projected out, kept as a Q factor for the similarity of candidates
        q_factors[name] = np.linalg.qr(resid_cols)[0]
        del resid_cols
        slices[name] = slice(width, width + cand.q)
        width += cand.q
        tested_cols.append(cand.columns * sc.scale)
    # [basis, each tested candidate's columns scaled to unit RMS] (np.hstack: its memory layout, C or Fortran,
    # is what the products downstream follow bit for bit); the scaled copies are freed once in it
    design = np.hstack([basis, *tested_cols]) if tested_cols else basis
    del tested_cols
    cross = Cross.build(design, state.residual, groups)
    _wald_tests(scores, cands, slices, cross, basis, state, cells)
    tested = list(slices) + nonlinear_names
    for n in tested:
        scores[n].p_adj = min(1.0, scores[n].test.p * len(tested))

    # forward selection takes the significant candidate that improves the fit most (Wald chi^2 = F q,
    # the drop in GLS residual in units of the noise); insignificant ones follow by p
    def rank(n):
        w = scores[n].test
        return (0, -w.F * w.q) if scores[n].p_adj < alpha else (1, w.p)

    tested = sorted(tested, key=rank)
    similar = _similarity(tested, q_factors, basis, cands)
    return Step(state, groups, basis, scores, slices, design, cross, tested, set(nonlinear_names), similar,
                better_null)


def _untestable(cands: dict, groups: Groups, info: DataInfo, alias_notes: dict, basis0: np.ndarray,
                scores: dict[str, Score], blocks: list) -> list[np.ndarray]:
    """With fewer than MIN_RUNS runs, effects that need replication between runs cannot be tested; they may
    still be there, so every other candidate is tested with their signatures as nuisance columns: their
    scores are added to ``scores``, their signatures to ``blocks``, and their columns returned."""
    untestable_cols = []
    for name, cand in cands.items():
        if cand is None or needs_problem(name, cand.needs, info) is not None:
            continue
        if alias_notes.get(name) and any(a[0] == 0.0 for a in alias_notes[name]):
            continue
        problem = replication_problem(cand, basis0, groups, info)
        if problem is not None:
            scores[name] = Score(name, ScoreStatus.UNTESTABLE, problem[0], problem[1],
                                 aliases=alias_notes.get(name, []))
            untestable_cols.append(cand.columns)
            blocks.append((f"{name}'s signature (untestable with {groups.runs} run"
                           f"{'s' if groups.runs != 1 else ''})", _given(cand.columns)))
    return untestable_cols


def _given(columns: np.ndarray) -> Callable[[], np.ndarray]:
    return lambda: columns


def _aliased(sc: Score, cand: Candidate, info: DataInfo, alias_notes: dict) -> str | None:
    """Why these data cannot show the candidate (a signal it needs is missing, or its order falls on a
    constant at these targets), the remedy set on ``sc``; None when nothing stands in the way."""
    why = needs_problem(sc.name, cand.needs, info)
    if why is None and alias_notes.get(sc.name) and any(a[0] == 0.0 for a in alias_notes[sc.name]):
        assert cand.order is not None  # (aliasing notes are made for periodic candidates only)
        why = f"order {cand.order:g} falls on a constant at these targets (aliased by the target spacing)"
        sc.remedy = ("use irregular target spacing or a dense scan with more than "
                     f"{2 * cand.order:g} points per revolution")
    return why


def _same_order(sc: Score, cand: Candidate, same: list, nonlinear: Callable, better_null):
    """The spec's sources on this order have fixed sizes and free phases: a linearised test would call any
    content at this order absorbed; the phases are refit with the candidate instead (the result on ``sc``).
    Returns the better null phases the refit found, else ``better_null`` as it was."""
    sc.same_order = [s.name for s in same]
    sc.reach = float(sum(s.amplitude for s in same))
    t = nonlinear(cand)
    sc.wald = Wald(t.beta, np.full((cand.q, cand.q), np.nan), t.F, cand.q, t.df, t.p)
    sc.beta = t.beta
    sc.params = candidate_params(cand, t.beta)
    return t.better_null if t.better_null is not None else better_null


def _absorbed(sc: Score, cand: Candidate, basis: np.ndarray, blocks: list) -> str | None:
    """The candidate's tolerance against the model (on ``sc``); when the model absorbs it, what does
    (``sc.absorbed_by``, the remedy for fitted phases) and the reason, else None."""
    sc.tolerance = tolerance(basis, cand.columns)
    if not sc.tolerance < MIN_TOLERANCE:  # (NaN: not absorbed)
        return None
    sc.absorbed_by = [label for label, blk in blocks if r2(blk(), cand.columns) > 0.5] or \
        [label for label, _ in blocks]
    if any("fitted phase" in a for a in sc.absorbed_by):
        sc.remedy = ("the spec's sources on this shaft take up any content at this order by "
                     "changing their phases: measure their runout and phase directly (dial "
                     "indicator), enter the phases in the spec and rerun with --keep-phases")
    return "absorbed by " + " and ".join(sc.absorbed_by)


def _wald_tests(scores: dict[str, Score], cands: dict, slices: dict[str, slice], cross: Cross,
                basis: np.ndarray, state: ModelFit, cells: Cells) -> None:
    """The Wald test of each linearly tested candidate given the basis (REML under the alternative); with
    replicated cells the lack-of-fit-aware cell-means test must agree too (the larger p is kept)."""
    kb = basis.shape[1]
    cell_tester = None
    for name, sl in slices.items():
        sc = scores[name]
        idx = np.r_[np.arange(kb), np.arange(sl.start, sl.stop)]
        sub = cross.take(idx)
        vf = reml(sub)
        w = wald(sub, vf, np.arange(kb, kb + cands[name].q), containment=sc.containment)
        if cells.replicated and cell_level(cands[name].columns, cells):
            if cell_tester is None:
                cell_tester = CellTester(cells, basis, state.residual)
            _, df_c, p_c = cell_tester.test(cands[name].columns)
            if p_c > w.p:
                w = Wald(w.estimate, w.cov, w.F, w.q, min(w.df, df_c), p_c)
                sc.cell_test = True
        sc.wald, sc.var = w, vf
        sc.beta = w.estimate * sc.scale
        sc.params = candidate_params(cands[name], sc.beta)


def _similarity(tested: list[str], q_factors: dict[str, np.ndarray], basis: np.ndarray,
                cands: dict) -> dict[tuple[str, str], float]:
    """How alike the signatures of the tested candidates are, once the model is projected out (both orders
    of each pair)."""
    similar: dict[tuple[str, str], float] = {}
    for n in tested:
        if n not in q_factors:
            q_factors[n] = np.linalg.qr(residualise(basis, cands[n].columns))[0]
    for i, a in enumerate(tested):
        for b in tested[i + 1:]:
            similar[(a, b)] = similar[(b, a)] = canonical_q(q_factors[a], q_factors[b])
    return similar


@dataclass(frozen=True)
class _Resampling:
    """What scoring the resamples of :meth:`Step.stability` needs: per-pass Gram matrices and
    sums of [design, residual], the resamples' run counts, the groups, the widths, and per
    tested candidate (its columns with the basis, q, variance ratios, denominator df)."""

    grams: np.ndarray
    sums: np.ndarray
    counts: np.ndarray
    groups: Groups
    k: int
    kb: int
    tests: list


def _score_resamples(r: _Resampling, span: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Wald chi^2 and p of every tested candidate in resamples [a, b) (a worker's task)."""
    a, b = span
    chi2 = np.zeros((b - a, len(r.tests)))
    pvals = np.full((b - a, len(r.tests)), 1.0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        for row in range(b - a):
            _score_one(r, a + row, chi2[row], pvals[row])
    return chi2, pvals


def _score_one(r: _Resampling, b: int, chi2: np.ndarray, pvals: np.ndarray) -> None:
    """Fill one resample's row of chi^2 and p (see :func:`_score_resamples`)."""
    g, k, kb = r.groups, r.k, r.kb
    rc = r.counts[b]
    pc = rc[g.pass_run]
    gram = np.einsum("p,pij->ij", pc, r.grams)
    for j, (idx, q, gp, gr, df) in enumerate(r.tests):
        cr = Cross(gram[np.ix_(idx, idx)], gram[idx, k - 1], gram[k - 1, k - 1], r.sums[:, idx],
                   r.sums[:, k - 1], g, pc, rc)
        if cr.n - cr.k < 2:
            continue
        A, bb, c, _ = cr.weighted([gp], [gr])
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
        chi2[j] = F * q
        pvals[j] = f_sf(F, q, df)


@dataclass(frozen=True)
class SameOrderTest:
    """F-test of a candidate on the order of sources with fitted phases: ``F``, ``df``
    (denominator), ``p``; ``beta`` (q,) its column coefficients in the refit;
    ``better_null`` (m,) phases [rad] that fit the null model better than the
    current fit (None: the current fit was the best)."""

    F: float
    df: float
    p: float
    beta: np.ndarray
    better_null: np.ndarray | None


def same_order_test(ctx: FitContext, state: ModelFit, lin, cand: Candidate, cells: Cells) -> SameOrderTest:
    """Test a candidate that shares its order with sources whose phases are fitted.

    Refits the phases with the candidate's columns added and compares the GLS
    residual (at the current variance ratios): F = (cost0 - cost1) / q /
    (cost1 / (n - k1)), k1 the phases plus linear columns.  With repeated
    runs the same comparison on the cell means (lack of fit as error) must
    agree; the larger p is kept."""
    gp, gr = state.var.gp, state.var.gr
    lin1 = np.hstack([lin, cand.columns])
    # the candidate's columns are linear: from the null optimum (candidate at zero) the refit moves continuously
    alt = levenberg_marquardt(ctx, state.psi, lin1, gp, gr, True)
    n = ctx.n
    q = cand.q
    k1 = lin1.shape[1] + len(ctx.sources)
    cost0 = gls_cost(state.residual, ctx.groups, gp, gr)
    # the refit may have found phases the null fit missed: the null must get the same chance
    null = levenberg_marquardt(ctx, alt.psi, lin, gp, gr, True, parts=alt.parts)
    better = None
    if null.cost < cost0 * (1.0 - 1e-6):
        better = null.psi
        cost0 = null.cost
        state_resid = null.residual
    else:
        state_resid = state.residual
    dof = max(n - k1, 1)
    F = max(cost0 - alt.cost, 0.0) / q / max(alt.cost / dof, 1e-300)
    p = f_sf(F, q, dof)
    df = float(dof)
    if cells.replicated and cells.cells - k1 > 0:
        m0, m1 = cells.means(state_resid), cells.means(alt.residual)
        r0, r1 = float(m0 @ m0), float(m1 @ m1)
        dfc = cells.cells - k1
        Fc = max(r0 - r1, 0.0) / q / max(r1 / dfc, 1e-300)
        pc = f_sf(Fc, q, dfc)
        if pc > p:
            F, p, df = Fc, pc, float(dfc)
    return SameOrderTest(F, df, p, alt.beta[lin.shape[1]:], better)
