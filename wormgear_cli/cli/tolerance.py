"""``wormgear tolerance``: statistical tolerance analysis (Monte Carlo over built drives)."""

from __future__ import annotations

from enum import Enum
from pathlib import Path
from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    AngleUnit,
    DriveArgument,
    JobsOption,
    OutputOption,
    PartOutput,
    Progress,
    ShardOption,
    UnitOption,
    announce_written,
    count_type,
    fmt_angle,
    is_stdout,
    jobs_count,
    json_text,
    load_drive,
    output_file,
    output_format,
    output_path_type,
    render,
    say,
    shard_part,
    warn_if_absurd,
    write_stdout,
)
from wormgear_cli.cli.helptext import HelpCommand
from wormgear_cli.errors import UsageError
from wormgear_cli.files import atomic_stream, refuse_input, refuse_same_outputs

#: seconds per sample (a loaded 2-core machine), for deciding whether a progress bar is worth showing
_SECONDS_PER_SAMPLE = {"paper": 2e-6, "budget": 1.5e-6, "paper+budget": 3.5e-6, "iso": 1e-5, "all": 1.4e-5}

LABELS = {"total_transmission_error": "total TE", "total_backlash": "backlash", "iso230_E": "ISO E",
          "iso230_B": "ISO B", "iso230_M": "ISO M", "iso230_A": "ISO A", "budget_linear": "budget lin",
          "budget_statistical": "budget stat", "budget_rss": "budget rss"}
SHORT = {"total_transmission_error": "TE", "total_backlash": "BL", "iso230_E": "E", "iso230_B": "B",
         "iso230_M": "M", "iso230_A": "A", "budget_linear": "lin",
         "budget_statistical": "stat", "budget_rss": "rss"}


class MetricSet(str, Enum):
    paper = "paper"
    budget = "budget"
    paper_budget = "paper+budget"
    iso = "iso"
    all = "all"


class ToleranceFormat(str, Enum):
    table = "table"
    json = "json"
    csv = "csv"
    npy = "npy"


class PlanKind(str, Enum):
    iso = "iso"
    dense = "dense"


@app.command(cls=HelpCommand)
def tolerance(
    drive: DriveArgument,
    samples: Annotated[int, typer.Option("--samples", "-n", help="Number of built drives to sample (N >= 1, e.g. "
                                         "20000 or 1e6).", click_type=count_type())]
    = 100_000,
    seed: Annotated[int, typer.Option("--seed", help="Seed of every random number (same seed, same output).")] = 0,
    metrics: Annotated[MetricSet, typer.Option(
        "--metrics", help="paper: total TE and backlash as analyze; iso: ISO 230-2 E, B, M, A of the simulated "
        "acceptance test; budget: the full budget's TE, linear and rss rules; paper+budget; all: every "
        "metric.", case_sensitive=False)] = MetricSet.all,
    plan: Annotated[PlanKind, typer.Option(
        "--plan", help="Acceptance test: iso (irregular targets as synth plans them with --seed) or dense "
        "(--points even angles).", case_sensitive=False)] = PlanKind.iso,
    targets: Annotated[int, typer.Option("--targets", help="Targets of the iso plan.", click_type=count_type())] = 24,
    points: Annotated[int, typer.Option("--points", help="Angles of the dense plan.", click_type=count_type())] = 360,
    target_yield: Annotated[float | None, typer.Option(
        "--target-yield", help="Yield to aim at (0 < P < 1; default: [requirements] min_yield): rank the "
        "tolerances by the yield one step of tightening gains.", show_default=False)] = None,
    shard: ShardOption = None,
    jobs: JobsOption = 1,
    summarize: Annotated[Path | None, typer.Option(
        "--summarize", help="Report on the samples of this CSV (concatenated --format csv parts) or .npy file "
        "instead of drawing; give the run's --samples, --seed, --plan, --targets and --unit.",
        show_default=False)] = None,
    format: Annotated[ToleranceFormat, typer.Option(
        "--format", "-f", help="Output format: the report (table, json) or the samples (csv, or npy: the metrics "
        "as binary columns, with -o).", case_sensitive=False)] = ToleranceFormat.table,
    unit: UnitOption = AngleUnit.arcsec,
    output: OutputOption = None,
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Also draw histograms with limits and percentiles, and the sensitivity bars, to FILE "
        "(.png, .svg or .pdf; needs matplotlib).", show_default=False,
        click_type=output_path_type("--plot", "plot.png"))] = None,
):
    """Statistical tolerance analysis: what fraction of built drives passes, and which tolerance to tighten.

    Each sample is one built drive: every toleranced key drawn from its
    distribution (radial magnitudes Rayleigh, signed deviations normal with
    the tolerance at 3 sigma, others uniform; override per key in a
    [statistics] table), truncated at its tolerance, every phase uniform.
    Reports each metric's mean, std and percentiles beside the corner case
    (analyze) and the RSS estimate, the yield of each [requirements] limit
    with its 95 % interval, and the first-order sensitivity indices.

    Example: wormgear tolerance configs/mch50.toml --target-yield 0.99
    """
    from dataclasses import replace  # lazy: keeps dataclasses off `tolerance --help`'s start-up

    from wormgear_cli.tolerance import engine, report, study  # lazy: keeps tolerance.engine off `--help`'s start-up

    fmt = output_format(format, output)
    unit = getattr(unit, "value", unit)
    metric_set = getattr(metrics, "value", metrics)
    part = shard_part(shard)
    k_n = (part.k, part.n) if part is not None else None
    _check_usage(drive, fmt, output, plot, summarize, target_yield, sharded=k_n is not None)
    spec = load_drive(drive)
    n_rows = None
    if summarize is not None:
        metric_set = (report.read_npy_header if report.is_npy(summarize) else report.read_header)(summarize).metric_set
    options = engine.Options(samples=samples, seed=seed, metrics=metric_set, plan=getattr(plan, "value", plan),
                             targets=targets, points=points, unit=unit, shard=k_n, jobs=jobs_count(jobs))
    if summarize is not None:
        options = replace(options, samples=max(samples, 1), shard=None)
    s = engine.setup(spec, options)
    if summarize is None:
        _say_long_run(s.stop - s.start, metric_set)
    target = target_yield if target_yield is not None else spec.requirements.min_yield
    inputs = [drive] + ([summarize] if summarize is not None else [])

    out = PartOutput("tolerance", drive, output, part, part_parameters(options, fmt), s.start, s.stop,
                     options.samples) if fmt != "table" else PartOutput("tolerance", drive, output, None, {}, 0, 0, 0)
    if out.done():
        return
    summary = _summary(s, out, inputs, fmt, summarize)
    if summarize is not None:
        n_rows = summary.samples
    if target_yield is not None and engine.metrics_for_limits(spec) is None:
        raise UsageError(f"--target-yield needs a limit in [requirements] ({engine.LIMIT_KEYS}) to count the "
                         "yield against")
    runs = engine.allocation_runs(s, target, n_rows if n_rows is not None else samples)
    with Progress(runs[1] if runs else 0, allocation_seconds(spec, runs), "allocation") as bar:
        doc = study.finish(s, summary, target_yield, n_rows if n_rows is not None else samples,
                           part.label if part is not None else None, bar.advance)
    warn_if_absurd({LABELS.get(m, m): [x for x in (r["mean"], r["percentiles"]["max"]) if x is not None]
                    for m, r in doc["metrics"].items()}, drive, unit)
    if plot is not None:
        from wormgear_cli.plots.tolerance import draw  # lazy: keeps plots.tolerance off `--help`'s start-up

        draw(doc, summary.plot_values, engine.limits(s), plot, LABELS)
        announce_written(plot)
    if fmt == "json":
        out.emit(json_text(doc), inputs)
    elif fmt == "table":
        render(_tables(doc, target), output, inputs)


def _summary(s, out: PartOutput, inputs: list, fmt: str, summarize: Path | None):
    """The run's summary: read from the samples of ``summarize``, or drawn (streamed out as they are drawn
    for the csv and npy formats)."""
    from wormgear_cli.tolerance import engine, report  # lazy: keeps tolerance.engine off `--help`'s start-up

    if summarize is not None:
        read = report.read_npy if report.is_npy(summarize) else report.read_samples
        return engine.summarize(s, lambda: read(summarize, s))
    if fmt in ("csv", "npy"):
        return _samples_run(s, out, inputs, fmt)
    seconds = (s.stop - s.start) * _SECONDS_PER_SAMPLE[s.options.metrics]
    with Progress(s.stop - s.start, seconds, "tolerance") as bar:
        return engine.run(s, progress=bar.advance)


def _check_usage(drive: Path, fmt: str, output: Path | None, plot: Path | None, summarize: Path | None,
                 target_yield: float | None, sharded: bool) -> None:
    """The options that cannot go together, and the plot's path, checked before any work."""
    if summarize is not None and sharded:
        raise UsageError("--summarize cannot be combined with --shard (merge the parts: wormgear merge)")
    if summarize is not None and fmt in ("csv", "npy"):
        raise UsageError("--summarize reports on samples: use --format table or json")
    if fmt == "npy" and is_stdout(output):
        raise UsageError("--format npy writes binary columns: give -o FILE.npy")
    if plot is not None:
        from wormgear_cli.plots import check_plot_path  # lazy: keeps plots off `--help`'s start-up

        check_plot_path(plot)
        refuse_input(plot, [drive] + ([summarize] if summarize is not None else []), "--plot")
        refuse_same_outputs([(output, "-o"), (plot, "--plot")])
    if target_yield is not None and not 0.0 < target_yield < 1.0:
        raise UsageError(f"--target-yield: expected a number in (0, 1), got {target_yield:g}")


def allocation_seconds(spec, runs: tuple[int, int] | None) -> float:
    """Expected seconds of the allocation's ``runs`` (samples per run, runs), for the progress bar."""
    from wormgear_cli.tolerance import engine  # lazy: keeps tolerance.engine off `--help`'s start-up

    metric_set = engine.metrics_for_limits(spec)
    return runs[0] * runs[1] * _SECONDS_PER_SAMPLE[metric_set] if runs and metric_set is not None else 0.0


#: sample counts above this say their expected time on stderr before they start
LONG_RUN_SAMPLES = 10**8


def _say_long_run(n: int, metric_set: str) -> None:
    """A run of more than :data:`LONG_RUN_SAMPLES` samples asks for no confirmation, but says
    on stderr how long it is expected to take (from :data:`_SECONDS_PER_SAMPLE`)."""
    if n <= LONG_RUN_SAMPLES:
        return
    seconds = n * _SECONDS_PER_SAMPLE[metric_set]
    hours, minutes = divmod(round(seconds / 60.0), 60)
    took = f"{hours} h {minutes:02d} min" if hours else f"{max(minutes, 1)} min"
    say(f"note: {n} samples are expected to take about {took} ({_SECONDS_PER_SAMPLE[metric_set] * 1e6:.3g} us "
        f"each with --metrics {metric_set} on a 2-core machine); --samples sets the count, --shard K/N splits "
        "the run")


def part_parameters(options, fmt: str) -> dict:
    """The options that make a part's bytes (its manifest's parameters; not --jobs, not the part)."""
    return {"samples": int(options.samples), "seed": int(options.seed), "metrics": options.metrics,
            "plan": options.plan, "targets": int(options.targets), "points": int(options.points),
            "unit": options.unit, "format": fmt}


def _samples_run(s, out: PartOutput, inputs, fmt: str):
    """Stream the samples (CSV, or the .npy records) block by block (stdout, or -o through a
    staged file renamed at the end) and return the summary; memory stays constant whatever the
    sample count.  A part written with -o gets its manifest."""
    from wormgear_cli.tolerance import engine, report  # lazy: keeps tolerance.engine off `--help`'s start-up

    output = output_file(out.output)
    seconds = (s.stop - s.start) * (_SECONDS_PER_SAMPLE[s.options.metrics] + 4e-6)
    # every CSV part carries the header; concatenate with it once (tail -n +2)
    header, rows = (report.csv_header(s), report.csv_rows) if fmt == "csv" else (report.npy_header(s),
                                                                                report.npy_rows)
    with Progress(s.stop - s.start, seconds, "tolerance") as bar:
        if output is None:
            write_stdout(header)  # checked: a full disk is exit 2, a closed pipe a quiet stop
            return engine.run(s, on_block=write_stdout, progress=bar.advance, render=rows)

        with atomic_stream(output, tuple(inputs)) as write:
            write = out.hash.wrap(write)
            write(header)
            summary = engine.run(s, on_block=write, progress=bar.advance, render=rows)
    announce_written(output)
    out.finish(inputs)
    return summary


def _tables(doc: dict, target) -> list:
    """The report: a heading line, the metric tables, the yields, the variance shares and the allocation
    (:class:`~wormgear_cli.output.tables.Table`), then notes."""
    from rich.markup import escape  # lazy: keeps rich.markup off `--help`'s start-up

    # lazy: keeps output.tables, tolerance.report off `--help`'s start-up
    from wormgear_cli.output.tables import Column, Table
    from wormgear_cli.tolerance.report import short_key, variance_rows

    unit = doc["unit"]
    a = lambda x: "n/a" if x is None else fmt_angle(x, unit)  # noqa: E731

    def table(title: str, headers: tuple[str, ...], left: int = 1, padding: int = 1) -> Table:
        return Table(title, [Column(h, "left" if i < left else "right") for i, h in enumerate(headers)],
                     box="simple_head", padding=padding)

    out: list = []
    # the heading as its own line: a table title would wrap at the (narrower) table's width
    out.append(escape(f"{doc['drive']}: {doc['samples']} sampled drives, seed {doc['seed']} [{unit}]"))
    t1 = table("", ("metric", "mean", "std", "p50", "p90", "p95", "p99"))
    t2 = table(f"worst case / RSS / Monte Carlo [{unit}]", ("metric", "corner", "RSS", "p99.73", "max"))
    for m, r in doc["metrics"].items():
        p = r["percentiles"]
        t1.add_row(LABELS[m], a(r["mean"]), a(r["std"]), a(p["50"]), a(p["90"]), a(p["95"]), a(p["99"]))
        t2.add_row(LABELS[m], a(r["corner"]), a(r["rss"]), a(p["99.73"]), a(p["max"]))
    out += [t1, t2]
    if doc["yield"]:
        t3 = table("yield (fraction of drives within the limit, 95 % interval)",
                   ("requirement", "yield", "interval", *(("vs target",) if target is not None else ())))
        for key, y in doc["yield"].items():
            row = [key.replace("requirements.", "") if key != "all" else "all limits", _pct(y["value"]),
                   f"{_pct(y['low'])} - {_pct(y['high'])}"]
            if target is not None:
                # lazy: keeps tolerance.statistics off `--help`'s start-up
                from wormgear_cli.tolerance.statistics import Yield

                row.append(Yield(y["passing"], doc["samples"], y["value"], y["low"], y["high"]).verdict(target))
            t3.add_row(*row)
        out.append(t3)
    metrics, shares = variance_rows(doc["sensitivity"])
    if shares:
        t4 = table("variance share (first-order index)", ("key ", *(SHORT[m] for m in metrics)), padding=0)
        for k, values in shares:
            t4.add_row("remainder (rest and interactions)" if k == "remainder" else short_key(k),
                       *(f"{v:.2f}" for v in values))
        out.append(t4)
    alloc = doc.get("allocation")
    if alloc:
        t5 = table(f"tighten one tolerance (yield now {_pct(alloc['yield']['value'])}, target {_pct(alloc['target'])})",
                   ("key", "step", "yield", "gain"), left=2)
        for st in alloc["steps"][:8]:
            t5.add_row(short_key(st["key"]), st["step"], _pct(st["yield"]["value"]), f"{100 * st['gain']:+.2f} %")
        out.append(t5)
        head, _, rest = alloc["answer"].partition(": ")  # the answer on two lines within 80 columns
        out.append(escape(f"{head}:\n  {rest}" if rest else head))
    notes = []
    if doc.get("shard"):
        notes.append(f"shard {doc['shard']['part']}: samples {doc['shard']['first_sample']} to "
                     f"{doc['shard']['stop_sample'] - 1}")
    for key, why in doc.get("not_sampled", {}).items():
        notes.append(f"{key.replace('requirements.', '')}: no yield, {why}")
    loose = [short_key(k) for k, v in doc.get("varied", {}).items() if not v.get("inspected", True)]
    notes.append("laws: inspected, truncated at the tolerance" + (f", except (uninspected, the whole law): "
                                                                  f"{', '.join(loose)}" if loose else ", every key"))
    notes.append("corner: every tolerance at its limit (analyze; ISO figures: phases aligned)")
    notes.append("RSS: root-sum-square of the single contributions")
    out += [escape(n) for n in notes]
    return out


def _pct(x: float) -> str:
    return f"{100 * x:.2f} %"
