"""The Monte Carlo run: samples in blocks, shards, and the summary of the samples.

Samples are drawn and evaluated one random-stream block
(:data:`~wormgear_cli.tolerance.sampling.BLOCK` samples) at a time and their
statistics accumulated block by block (:class:`Accumulator`): moments, yield
counts and sensitivity sums need no per-sample storage; exact percentiles keep
the metric values up to :data:`~wormgear_cli.tolerance.statistics.IN_MEMORY_SAMPLES`
samples and beyond that run a second pass (the streams are counter-based, so
the same samples come again).  ``--summarize`` feeds the rows of a samples CSV
through the same summary, in the same block boundaries, so its report equals
the run's byte for byte.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from wormgear_cli.analysis.accuracy import analyze
from wormgear_cli.analysis.synth import Plan, plan_angles
from wormgear_cli.batch import shards
from wormgear_cli.batch.pool import MAX_JOBS, ordered_map
from wormgear_cli.drive.registry import aligned_phases, build
from wormgear_cli.errors import SpecError, UsageError
from wormgear_cli.tolerance import metrics as metrics_mod
from wormgear_cli.tolerance import statistics as stats
from wormgear_cli.tolerance.quantities import Varied, layout, varied_quantities
from wormgear_cli.tolerance.sampling import BLOCK, draw
from wormgear_cli.units import RAD_PER_UNIT, to_unit

if TYPE_CHECKING:
    from wormgear_cli.spec.loader import Spec

PLANS = ("iso", "dense")
#: most samples of one run (or one shard)
MAX_SAMPLES = 10**10
#: requirement attribute -> metric it limits (the paper's totals and the full budget's linear and
#: statistical totals; ``max_budget_rss``, deprecated, is judged against the statistical total as
#: ``check`` judges it); the other limits are not sampled (:data:`NOT_SAMPLED`)
YIELD_REQUIREMENTS = {"max_transmission_error": "total_transmission_error", "max_backlash": "total_backlash",
                      "max_budget_linear": "budget_linear", "max_budget_statistical": "budget_statistical",
                      "max_budget_rss": "budget_statistical"}
#: requirement attribute -> why its yield is not estimated
NOT_SAMPLED = {
    "max_budget_peak": "the peak rule searches one output turn per sample; its yield is not estimated "
    "(the linear rule bounds it: peak <= linear)",
    **{f"max_{stage}_{what}": "stage limits are checked by wormgear check, not sampled"
       for stage in ("gear", "worm") for what in ("transmission_error", "backlash")},
}
#: a stage's own limits (its keys), not sampled
STAGE_LIMITS = ("max_transmission_error_arcsec", "max_backlash_arcsec")


@dataclass(frozen=True)
class Options:
    """Options of a tolerance run.

    ``samples`` N (>= 1); ``seed`` (>= 0); ``metrics``: "paper", "iso" or "all";
    ``plan``: "iso" (``targets`` irregular targets, as ``synth`` plans them with
    this seed) or "dense" (``points`` even angles); ``unit``: angle unit of the
    outputs; ``shard``: (K, N) or None; ``jobs``: worker processes (the samples are the
    same whatever the count: the blocks of the random streams are computed in parallel).
    """

    samples: int = 100_000
    seed: int = 0
    metrics: str = "all"
    plan: str = "iso"
    targets: int = 24
    points: int = 360
    unit: str = "arcsec"
    shard: tuple[int, int] | None = None
    jobs: int = 1

    def check(self) -> None:
        if isinstance(self.samples, bool) or not 1 <= int(self.samples) <= MAX_SAMPLES:
            raise UsageError(f"--samples: expected an integer in [1, {MAX_SAMPLES}], got {self.samples}")
        if not 0 <= int(self.seed) < 2**63:
            raise UsageError(f"--seed: expected a non-negative integer, got {self.seed}")
        if self.metrics not in metrics_mod.METRIC_SETS:
            raise UsageError(f"--metrics: expected one of {', '.join(metrics_mod.METRIC_SETS)}, got {self.metrics!r}")
        if self.plan not in PLANS:
            raise UsageError(f"--plan: expected one of {', '.join(PLANS)}, got {self.plan!r}")
        if not 2 <= self.targets <= 10_000:
            raise UsageError(f"--targets: expected an integer in [2, 10000], got {self.targets}")
        if not 2 <= self.points <= 100_000:
            raise UsageError(f"--points: expected an integer in [2, 100000], got {self.points}")
        if self.unit not in RAD_PER_UNIT:
            raise UsageError(f"--unit: expected one of {', '.join(RAD_PER_UNIT)}, got {self.unit!r}")
        if self.shard is not None:
            k, n = self.shard
            if not (1 <= n <= self.samples and 1 <= k <= n):
                raise UsageError(f"--shard {k}/{n}: expected 1 <= K <= N <= --samples ({self.samples})")
        if not 1 <= int(self.jobs) <= MAX_JOBS:
            raise UsageError(f"--jobs: expected a whole number from 1 to {MAX_JOBS}, got {self.jobs}")


def parse_shard(text: str) -> tuple[int, int]:
    """``K/N`` -> (K, N); :class:`UsageError` naming ``--shard`` when malformed or K outside 1..N."""
    part = shards.parse(text)
    return part.k, part.n


def shard_range(samples: int, shard: tuple[int, int] | None) -> tuple[int, int]:
    """Samples [start, stop) of shard K of N: contiguous parts, floor((K-1) S / N) .. floor(K S / N)."""
    return (0, samples) if shard is None else shards.bounds(samples, *shard)


def plan_targets(options: Options) -> np.ndarray:
    """Test targets [deg]: ``synth``'s iso plan for this seed (its first random stream), or a dense scan."""
    if options.plan == "dense":
        return plan_angles(Plan(kind="dense", points=options.points, runs=1))
    rng = np.random.default_rng(np.random.SeedSequence(int(options.seed)).spawn(4)[0])
    return plan_angles(Plan(kind="iso", targets=options.targets, runs=1), rng)


@dataclass(frozen=True)
class Setup:
    """A prepared run: ``varied`` quantities, output ``columns`` (varied key columns with a
    tolerance > 0, then the phases) with their ``bounds`` in CSV units ([mm]; phases
    [deg]), the ``metrics`` computed, the samples [``start``, ``stop``), the test
    ``targets_deg`` and the metric :class:`~.metrics.Context`."""

    spec: Spec
    options: Options
    varied: tuple
    columns: tuple
    bounds: dict
    metrics: tuple
    start: int
    stop: int
    targets_deg: np.ndarray
    context: metrics_mod.Context = field(repr=False)
    layout: object = field(default=None, repr=False)


def setup(spec, options: Options, varied: tuple[Varied, ...] | None = None) -> Setup:
    """Check ``options``, read the spec's ``[statistics]`` and prepare the run."""
    options.check()
    varied = varied_quantities(spec) if varied is None else varied
    columns, bounds = [], {}
    for v in varied:
        for e, col in enumerate(v.quantity.columns()):
            if v.tolerance[e] > 0:
                columns.append(col)
                bounds[col] = v.bounds(e)
    sized = {v.path for v in varied if any(t > 0 for t in v.tolerance)}
    targets = plan_targets(options)
    dwell = 10.0 if options.plan == "iso" else 0.5
    ctx = metrics_mod.context(spec, varied, np.radians(targets), dwell)
    lay = layout(spec, ctx.registry)
    for p in lay.phases:
        if p in lay.phase_size and not sized.intersection(lay.phase_size[p]):
            continue  # the source has no size in this spec: its phase is drawn but not an output column
        columns.append(p)
        bounds[p] = (0.0, 360.0)
    start, stop = shard_range(int(options.samples), options.shard)
    return Setup(spec, options, tuple(varied), tuple(columns), bounds, metrics_mod.METRIC_SETS[options.metrics],
                 start, stop, targets, ctx, lay)


@dataclass(frozen=True)
class Block:
    """Samples [start, stop): ``columns`` name -> values as written to the CSV
    ([mm]; phases [deg]) and ``metrics`` name -> values [the run's unit]."""

    start: int
    stop: int
    columns: dict
    metrics: dict


def _columns(s: Setup, d) -> dict:
    """The output columns of a draw: values [mm], phases [deg]."""
    return {c: (np.degrees(d.phases[c]) if c in d.phases else d.values[c]) for c in s.columns}


def drawn_columns(s: Setup, start: int, stop: int) -> dict:
    """The varied columns of samples [start, stop) as the run draws them (no metric evaluated):
    the compact samples file keeps only the metrics, these come again from the seed."""
    return _columns(s, draw(s.varied, s.options.seed, start, stop, s.layout))


def block(s: Setup, b: int) -> Block:
    """Random-stream block ``b`` of the run (the part of it in the run's samples), drawn and evaluated."""
    lo, hi = max(s.start, b * BLOCK), min(s.stop, (b + 1) * BLOCK)
    d = draw(s.varied, s.options.seed, lo, hi, s.layout)
    m = metrics_mod.evaluate(s.context, d.values, d.phases, s.metrics)
    return Block(lo, hi, _columns(s, d), {k: to_unit(v, s.options.unit) for k, v in m.items()})


def rebatch(parts: Iterable[Block]) -> Iterator[Block]:
    """Consecutive blocks joined at the random-stream block boundaries (a part of a sharded run
    may end inside a block): the summary of the joined blocks is the unsharded run's, to the bit."""
    pending: list[Block] = []
    for blk in parts:
        pending.append(blk)
        if blk.stop % BLOCK == 0:
            yield _join(pending)
            pending = []
    if pending:
        yield _join(pending)


def _join(blocks: list[Block]) -> Block:
    if len(blocks) == 1:
        return blocks[0]
    for a, b in zip(blocks, blocks[1:]):
        if a.stop != b.start:
            raise UsageError(f"samples {a.stop} to {b.start - 1} are missing between two parts")
    first = blocks[0]
    return Block(first.start, blocks[-1].stop,
                 {c: np.concatenate([b.columns[c] for b in blocks]) for c in first.columns},
                 {m: np.concatenate([b.metrics[m] for b in blocks]) for m in first.metrics})


def _rendered_block(state, b: int) -> tuple[Block, object]:
    s, render = state
    blk = block(s, b)
    return blk, render(s, blk)


def blocks(s: Setup, progress: Callable[[int], None] | None = None,
           render: Callable[[Setup, Block], object] | None = None) -> Iterator:
    """The run's samples, one random-stream block (or the part of it in the shard) at a time, in
    order; with ``options.jobs`` > 1 the blocks are computed by that many worker processes
    (:func:`~wormgear_cli.batch.pool.ordered_map`: the same blocks, the same bytes).  With
    ``render`` (a module-level function, e.g. the CSV rows of a block) the items are
    (block, ``render(s, block)``), rendered where the block was computed."""
    ids = range(s.start // BLOCK, (s.stop - 1) // BLOCK + 1)
    items = ordered_map(block, s, ids, s.options.jobs) if render is None else \
        ordered_map(_rendered_block, (s, render), ids, s.options.jobs)
    for item in items:
        yield item
        if progress is not None:
            blk = item if render is None else item[0]
            progress(blk.stop - blk.start)


def limits(s: Setup) -> dict[str, tuple[str, float]]:
    """Requirement key -> (metric, limit [the run's unit]) for the limits on computed metrics."""
    out = {}
    for attr, metric in YIELD_REQUIREMENTS.items():
        limit = getattr(s.spec.requirements, attr)
        if limit is not None and metric in s.metrics:
            out[f"requirements.{attr}_arcsec"] = (metric, float(to_unit(limit, s.options.unit)))
    return out


#: samples per metric kept for the histograms of ``--plot`` (the first ones)
PLOT_SAMPLES = 200_000


class Accumulator:
    """Streaming statistics of the blocks: moments, exact order statistics (bounded memory),
    yield counts and the sensitivity sums; nothing per sample beyond
    :data:`~.statistics.IN_MEMORY_SAMPLES` values per metric and :data:`PLOT_SAMPLES` for plots."""

    def __init__(self, s: Setup):
        self.setup = s
        self.centres: dict[str, float] | None = None  # sums about the first sample's values (against cancellation)
        self.moments: dict[str, stats.Moments] | None = None
        self.order = {m: stats.OrderStatistics() for m in s.metrics}
        self.bins = stats.BinSums(s.columns, s.metrics)
        self.limits = limits(s)
        self.passing = dict.fromkeys(self.limits, 0)
        self.passing_all = 0
        self.plot: dict[str, list[np.ndarray]] = {m: [] for m in s.metrics}
        self.n = 0

    def add(self, block: Block) -> None:
        s = self.setup
        n = block.stop - block.start
        if self.centres is None:
            self.centres = {m: float(block.metrics[m][0]) for m in s.metrics}
            self.moments = {m: stats.Moments(self.centres[m]) for m in s.metrics}
        assert self.moments is not None  # (set with the centres, by the first block)
        for m in s.metrics:
            y = np.asarray(block.metrics[m], dtype=float)
            self.moments[m].add(y)
            self.order[m].add(y)
            if self.n < PLOT_SAMPLES:
                self.plot[m].append(y[:PLOT_SAMPLES - self.n])
        self.bins.add({c: stats.bin_index(block.columns[c], *s.bounds[c]) for c in s.columns},
                      {m: np.asarray(block.metrics[m], dtype=float) - self.centres[m] for m in s.metrics})
        ok_all = np.ones(n, dtype=bool)
        for key, (metric, limit) in self.limits.items():
            ok = np.asarray(block.metrics[metric]) <= limit
            self.passing[key] += int(np.count_nonzero(ok))
            ok_all &= ok
        self.passing_all += int(np.count_nonzero(ok_all))
        self.n += n


@dataclass(frozen=True)
class Summary:
    """The statistics of a run: ``samples``, per-metric ``described`` (mean, std, percentiles),
    ``corner`` and ``rss`` [unit], ``yields`` (requirement key or "all" -> :class:`~.statistics.Yield`),
    ``sensitivity`` (metric -> (column -> index, remainder) or None), ``plot_values`` (the first
    :data:`PLOT_SAMPLES` values per metric, for histograms)."""

    samples: int
    described: dict
    corner: dict
    rss: dict
    yields: dict
    sensitivity: dict
    plot_values: dict | None = field(default=None, repr=False, compare=False)


def summarize(s: Setup, source: Callable[[], Iterator[Block]]) -> Summary:
    """The summary of the blocks ``source()`` yields (called a second time, for the exact
    percentiles, when more than :data:`~.statistics.IN_MEMORY_SAMPLES` samples are summarized)."""
    corner, rss = reference_values(s)
    acc = Accumulator(s)
    for block in source():
        acc.add(block)
    if any(o.needs_second_pass for o in acc.order.values()):
        for o in acc.order.values():
            o.start_second_pass()
        for block in source():
            for m, o in acc.order.items():
                o.collect(block.metrics[m])
    assert acc.moments is not None  # (set by the first block: a run has at least one sample)
    described = {m: {"mean": acc.moments[m].mean, "std": acc.moments[m].std,
                     "percentiles": acc.order[m].percentiles()} for m in s.metrics}
    yields = {k: stats.binomial_yield(acc.passing[k], acc.n) for k in acc.limits}
    if acc.limits:
        yields["all"] = stats.binomial_yield(acc.passing_all, acc.n)
    sens = {m: acc.bins.indices(m, acc.moments[m]) for m in s.metrics}
    plot = {m: np.concatenate(p) if p else np.empty(0) for m, p in acc.plot.items()}
    return Summary(acc.n, described, corner, rss, yields, sens, plot)


def run(s: Setup, on_block: Callable | None = None, progress: Callable[[int], None] | None = None,
        render: Callable[[Setup, Block], object] | None = None) -> Summary:
    """Draw and evaluate every sample of the setup; ``on_block`` sees each block of the first
    pass (CSV writing), or with ``render`` what ``render(s, block)`` made of it (in the worker
    processes of ``--jobs``); a second pass (large runs) recomputes the same samples silently."""
    first = [True]

    def source():
        if first[0]:
            first[0] = False
            for item in blocks(s, progress, render):
                blk, shown = (item, item) if render is None else item
                if on_block is not None:
                    on_block(shown)
                yield blk
        else:
            yield from blocks(s)

    return summarize(s, source)


# --- corner case and root-sum-square estimate ------------------------------------------------


def _aligned(spec, quantity: str, registry=None) -> dict[str, np.ndarray]:
    reg = registry if registry is not None else build(spec)
    a = aligned_phases(spec, quantity, reg)  # sources without a size are left out there: 90 deg, as the sinusoids
    # keyed by the sampled phases' paths (the file's form)
    return {src.phase_path: np.array([a.get(src.name, 0.5 * math.pi)]) for src in reg.periodic(True)}


def _values_at(varied, which: str | None) -> dict[str, np.ndarray]:
    """One sample: every column at its upper limit (which="all"), at 0 (None), or only
    quantity ``which`` at its upper limit."""
    out = {}
    for v in varied:
        for e, col in enumerate(v.quantity.columns()):
            at_limit = which == "all" or which == v.path
            out[col] = np.array([v.tolerance[e] if at_limit else 0.0])
    return out


def reference_values(s: Setup) -> tuple[dict, dict]:
    """Corner case and RSS estimate per metric [unit].

    Corner: every tolerance at its limit -- for the paper's totals
    :func:`wormgear_cli.analysis.accuracy.analyze` of the spec itself; for the ISO
    figures the simulated test with every tolerance at its limit and the
    phases aligned (``simulation.aligned_phases``: "reversal" for B, "error"
    otherwise).  RSS: f0 + sqrt(sum_k (f_k - f0)^2), f0 the metric with every
    varied quantity at 0, f_k with quantity k alone at its limit (the classic
    root-sum-square stack-up of the single contributions).
    """
    unit = s.options.unit
    corner, rss = {}, {}
    paper = analyze(s.spec).angles
    groups = [None] + [v.path for v in s.varied if any(t > 0 for t in v.tolerance)]
    for metric in s.metrics:
        quantity = "reversal" if metric == "iso230_B" else "error"
        ph = _aligned(s.spec, quantity, s.context.registry)

        def f(which):
            return float(metrics_mod.evaluate(s.context, _values_at(s.varied, which), ph, (metric,))[metric][0])  # noqa: B023

        corner[metric] = float(to_unit(paper[metric] if metric in paper else f("all"), unit))
        f0 = f(None)
        deltas = [f(g) - f0 for g in groups[1:]]
        rss[metric] = float(to_unit(f0 + math.sqrt(math.fsum(d * d for d in deltas)), unit))
    return corner, rss


# --- yield only (allocation, check) ----------------------------------------------------------


def limit_yields(s: Setup, progress: Callable[[int], None] | None = None) -> dict[str, stats.Yield]:
    """The fraction of the setup's samples meeting each sampled limit (keyed as :func:`limits`)
    and every limit at once (``"all"``), streamed (nothing kept)."""
    lim = limits(s)
    counts = dict.fromkeys([*lim, "all"], 0)
    n = 0
    for block in blocks(s, progress):
        every = np.ones(block.stop - block.start, dtype=bool)
        for key, (metric, limit) in lim.items():
            ok = block.metrics[metric] <= limit
            counts[key] += int(np.count_nonzero(ok))
            every &= ok
        counts["all"] += int(np.count_nonzero(every))
        n += block.stop - block.start
    return {key: stats.binomial_yield(k, n) for key, k in counts.items()}


def joint_yield(s: Setup) -> stats.Yield:
    """The fraction of the setup's samples meeting every limit, streamed (nothing kept)."""
    return limit_yields(s)["all"]


def metrics_for_limits(spec) -> str | None:
    """The cheapest ``--metrics`` set that covers the spec's sampled limits (:data:`YIELD_REQUIREMENTS`):
    "paper", "budget" or "paper+budget"; None without such a limit."""
    needed = {metric for attr, metric in YIELD_REQUIREMENTS.items() if getattr(spec.requirements, attr) is not None}
    if not needed:
        return None
    for name in ("paper", "budget", "paper+budget"):
        if needed <= set(metrics_mod.METRIC_SETS[name]):
            return name
    return "all"


def not_sampled(spec) -> dict[str, str]:
    """Requirement key -> why the spec's limit gets no yield estimate (:data:`NOT_SAMPLED`): the budget's
    peak rule, and each stage's own limits (by their paths in the file, output -> motor)."""
    out = {f"requirements.{a}_arcsec": why for a, why in NOT_SAMPLED.items()
           if a == "max_budget_peak" and getattr(spec.requirements, a) is not None}
    for stage in spec.stages[::-1]:
        for key, attr in zip(STAGE_LIMITS, ("max_transmission_error", "max_backlash")):
            if getattr(stage, attr) is not None:
                out[stage.paths[key]] = NOT_SAMPLED["max_gear_backlash"]
    return out


#: the limits a yield is counted against, for messages
LIMIT_KEYS = ", ".join(f"{a}_arcsec" for a in YIELD_REQUIREMENTS)


# --- the yield requirement of ``check`` --------------------------------------------------------

#: samples ``check`` draws for a ``min_yield`` requirement (seed 0)
CHECK_SAMPLES = 100_000


@dataclass(frozen=True)
class YieldCheck:
    """``requirements.min_yield`` against the estimated joint yield: ``target``, the
    :class:`~.statistics.Yield` and the verdict ("pass", "fail", "undecided")."""

    target: float
    estimate: stats.Yield
    verdict: str

    @property
    def passed(self) -> bool:
        return self.verdict == "pass"

    def line(self) -> str:
        y = self.estimate
        shown = f"yield {100 * y.value:.2f} % (95 % interval {100 * y.low:.2f} - {100 * y.high:.2f} %, {y.n} samples)"
        if self.verdict == "undecided":
            return (f"UNDECIDED requirements.min_yield: target {100 * self.target:g} % lies inside the interval of "
                    f"the {shown}; run wormgear tolerance with more --samples")
        return f"{'ok' if self.passed else 'FAIL'} requirements.min_yield: target {100 * self.target:g} %, {shown}"

    def to_dict(self) -> dict:
        y = self.estimate
        return {"key": "requirements.min_yield", "target": self.target, "value": y.value, "low": y.low,
                "high": y.high, "samples": y.n, "verdict": self.verdict, "passed": self.passed}


def check_yield(spec, samples: int = CHECK_SAMPLES, seed: int = 0) -> YieldCheck | None:
    """The ``min_yield`` requirement of ``spec`` (None when absent): the joint yield of the
    sampled limits (:data:`YIELD_REQUIREMENTS`) from ``samples`` drives.  A target inside the 95 %
    interval is undecided (and fails).  Raises SpecError when there is no limit to count
    against, or for a bad ``[statistics]`` table."""
    target = spec.requirements.min_yield
    if target is None:
        return None
    chosen = metrics_for_limits(spec)
    if chosen is None:
        raise SpecError(f"{spec.source}: requirements.min_yield: needs a limit to count the yield against "
                        f"({LIMIT_KEYS})")
    est = joint_yield(setup(spec, Options(samples=samples, seed=seed, metrics=chosen)))
    return YieldCheck(float(target), est, est.verdict(float(target)))


#: samples of each allocation run (the ranking needs the yield to about 0.1 %, not the whole run)
ALLOCATION_SAMPLES = 100_000


def allocation_runs(s: Setup, target: float | None, samples: int) -> tuple[int, int] | None:
    """(samples per run, number of runs) of the allocation due for ``s``, or None when none is
    due: no target yield, a shard (a part cannot rank the whole), or no limit to count against."""
    if target is None or s.options.shard is not None or metrics_for_limits(s.spec) is None:
        return None
    return min(samples, ALLOCATION_SAMPLES), 1 + len(s.varied)
