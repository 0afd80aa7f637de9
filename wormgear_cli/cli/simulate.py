"""``wormgear simulate`` (the model's error curve) and ``wormgear synth`` (synthetic measurements)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    AngleUnit,
    CsvJsonFormat,
    DriveArgument,
    JobsOption,
    OutputOption,
    UnitOption,
    announce_written,
    count_type,
    emit,
    jobs_count,
    json_text,
    load_drive,
    output_format,
    output_path_type,
    warn_if_absurd,
)
from wormgear_cli.cli.helptext import HelpCommand
from wormgear_cli.errors import UsageError
from wormgear_cli.files import check_memory, refuse_input, refuse_same_outputs


class Phases(str, Enum):
    spec = "spec"
    aligned_error = "aligned-error"
    aligned_reversal = "aligned-reversal"


class PlanKind(str, Enum):
    iso = "iso"
    dense = "dense"


class RunNoiseKind(str, Enum):
    offset = "offset"
    drift = "drift"


#: peak memory per row of ``synth`` (arrays of every column, the rounded copies and the CSV
#: text; 7.1 GB for 10^7 rows, bench/bench_limits.py) [bytes]
SYNTH_BYTES_PER_ROW = 750
#: peak memory per output angle of ``simulate`` (both curves, their sources and the CSV text;
#: 1.08 GB for 3 x 10^6 angles) [bytes]
SIMULATE_BYTES_PER_POINT = 400
#: peak memory per line of a ``simulate --at`` file (its rows read, simulated and written back
#: with their cells; 590 MB for 10^6 rows) [bytes]
SIMULATE_AT_BYTES_PER_ROW = 650

PlotOption = Annotated[Path | None, typer.Option(
    "--plot", help="Also draw the curves to FILE (.png, .svg or .pdf; needs matplotlib).",
    show_default=False, click_type=output_path_type("--plot", "plot.png"))]


@app.command(cls=HelpCommand)
def simulate(
    drive: DriveArgument,
    points: Annotated[int, typer.Option("--points", "-n", help="Dense scan: number of output angles.",
                                        click_type=count_type(2, 10_000_000))] = 3600,
    revs: Annotated[float, typer.Option("--revs", help="Dense scan: output turns covered (angles from 0, "
                                        "end excluded; 0 < R <= 1000).")] = 1.0,
    at: Annotated[Path | None, typer.Option(
        "--at", help="Evaluate at every row of this CSV (angle_deg; optional direction, load_Nm, "
        "temperature_C, time_s) and write the rows back with a simulated_error_<unit> column.",
        show_default=False)] = None,
    temperature_c: Annotated[float, typer.Option(
        "--temperature-C", help="Drive temperature [degC] for the dense scan, and for --at rows when the "
        "file has no temperature_C column.")] = 20.0,
    load_nm: Annotated[float, typer.Option(
        "--load-Nm", help="External torque on the output [N m] (positive pushes the table forward) for the "
        "dense scan, and for --at rows when the file has no load_Nm column.")] = 0.0,
    phases: Annotated[Phases, typer.Option(
        "--phases", help="Source phases: as in the spec, or aligned so every source peaks at 0 deg "
        "(aligned-error: common-mode peaks; aligned-reversal: lost-motion peaks).",
        case_sensitive=False)] = Phases.spec,
    effect: Annotated[list[str] | None, typer.Option(
        "--effect", "-e", help="Add an effect: NAME or NAME:key=value,key=value (catalogue units; "
        "repeatable; overrides the spec's [effects.NAME] keys).", show_default=False)] = None,
    format: Annotated[CsvJsonFormat, typer.Option("--format", "-f", help="Output format.",
                                                  case_sensitive=False)] = CsvJsonFormat.csv,
    unit: UnitOption = AngleUnit.arcsec,
    output: OutputOption = None,
    plot: PlotOption = None,
    jobs: JobsOption = 1,
):
    """The drive's predicted error over the output angle, forward and reverse.

    Every error source of the spec at its own order and phase (gear
    eccentricity at the pinion order, worm-stage sources at the wheel or
    worm order), lost motion as the direction-dependent part, tooth
    deflection under load, plus every [effects.*] table of the spec.
    Dense scan CSV columns: angle_deg, forward_<unit>, reverse_<unit>,
    common_<unit> (mean of both), lost_motion_<unit> (reverse - forward).

    Example: wormgear simulate configs/mch50.toml --points 720 -o curve.csv
    """
    # lazy: keeps analysis.synth, workflows.simulate off `--help`'s start-up
    from wormgear_cli.analysis.synth import parse_effects
    from wormgear_cli.workflows import simulate as report

    unit = getattr(unit, "value", unit)
    fmt = output_format(format, output)
    phases = getattr(phases, "value", phases)
    for name, value in (("--temperature-C", temperature_c), ("--load-Nm", load_nm)):
        if not math.isfinite(value):
            raise UsageError(f"{name}: expected a finite number, got {value}")
    if not (math.isfinite(revs) and 0.0 < revs <= 1000.0):
        raise UsageError(f"--revs: expected a number in (0, 1000], got {revs:g}")
    if not -100.0 <= temperature_c <= 300.0:
        raise UsageError(f"--temperature-C: expected a number in [-100, 300] [degC], got {temperature_c:g}")
    if plot is not None:
        from wormgear_cli.plots import check_plot_path  # lazy: keeps plots off `--help`'s start-up

        check_plot_path(plot)
    requested = parse_effects(effect)
    spec = load_drive(drive)
    effects = report.effect_params(spec, requested)
    inputs = [drive] + ([at] if at is not None else [])

    refuse_same_outputs([(output, "-o"), (plot, "--plot")])
    if at is None:
        check_memory(points * SIMULATE_BYTES_PER_POINT, f"simulate --points {points}", "lower --points")
    else:
        # lazy: keeps cli.read_options off `simulate --help`'s start-up
        from wormgear_cli.cli.read_options import check_rows_memory

        check_rows_memory(at, SIMULATE_AT_BYTES_PER_ROW, "simulate --at")
    if at is not None:
        result = report.at_rows(spec, at, unit, fmt, temperature_c, load_nm, phases, effects, jobs_count(jobs))
    else:
        result = report.dense(spec, points, revs, unit, fmt, temperature_c, load_nm, phases, effects)
    c = result.curves
    warn_if_absurd({"forward error": c["forward"], "reverse error": c["reverse"]} if c["kind"] == "dense"
                   else {"simulated error": c["simulated"]}, drive, unit)
    if plot is not None:
        from wormgear_cli.plots.simulate import plot_simulation  # lazy: keeps plots.simulate off `--help`'s start-up

        refuse_input(plot, inputs, "--plot")
        plot_simulation(result.curves, plot)
        announce_written(plot)
    emit(result.text, output, inputs)


@app.command(cls=HelpCommand)
def synth(
    drive: DriveArgument,
    output: OutputOption = None,
    truth: Annotated[Path | None, typer.Option(
        "--truth", help="Write the truth (phases, effects with parameters, noise, seed, plan) to this JSON "
        "file; it never goes into the data.", show_default=False,
        click_type=output_path_type("--truth", "truth.json"))] = None,
    seed: Annotated[int, typer.Option("--seed", help="Seed of every random number (same seed, same bytes).",
                                      min=0)] = 0,
    plan: Annotated[PlanKind, typer.Option("--plan", help="iso: irregularly spaced targets; dense: an even "
                                           "scan.", case_sensitive=False)] = PlanKind.iso,
    targets: Annotated[int, typer.Option("--targets", help="iso plan: target positions.",
                                         click_type=count_type(2, 100_000))] = 24,
    points: Annotated[int, typer.Option("--points", help="dense plan: angles per pass.",
                                        click_type=count_type(2, 10_000_000))] = 3600,
    runs: Annotated[int, typer.Option("--runs", help="Runs; each is one forward then one reverse pass.",
                                      click_type=count_type(1, 10_000))] = 5,
    revs: Annotated[float, typer.Option("--revs", help="Output turns spanned by the targets (0 < R <= 1000).")
                    ] = 1.0,
    dwell_s: Annotated[float | None, typer.Option(
        "--dwell-s", help="Time per point [s] (default 10 for iso, 0.5 for dense).", min=0.0,
        show_default=False)] = None,
    jitter: Annotated[float, typer.Option("--jitter", help="iso plan: target jitter, +/- this fraction of the "
                                          "mean spacing (0 <= J < 0.5).")] = 0.25,
    cycles: Annotated[int, typer.Option("--cycles", help="Measure the block of --runs runs this many times "
                                        "(runs numbered on), e.g. repeated as the table warms.",
                                        click_type=count_type(1, 1000))] = 1,
    cycle_gap_s: Annotated[float, typer.Option("--cycle-gap-s", help="Time between cycles [s]; the table "
                                               "keeps running, no rows are recorded.", min=0.0)] = 0.0,
    effect: Annotated[list[str] | None, typer.Option(
        "--effect", "-e", help="Add an effect: NAME or NAME:key=value,key=value (catalogue units; "
        "repeatable; overrides the spec's [effects.NAME] keys).", show_default=False)] = None,
    spec_effects: Annotated[bool, typer.Option("--spec-effects/--no-spec-effects",
                                               help="Include the spec's [effects.*] tables.")] = True,
    noise_arcsec: Annotated[float, typer.Option("--noise-arcsec", help="White noise per point, standard "
                                                "deviation [arcsec].", min=0.0)] = 0.0,
    run_noise_arcsec: Annotated[float, typer.Option("--run-noise-arcsec", help="Run-correlated noise, "
                                                    "standard deviation per run [arcsec].", min=0.0)] = 0.0,
    run_noise: Annotated[RunNoiseKind, typer.Option("--run-noise", help="Kind of run-correlated noise: offset "
                                                    "(constant per run) or drift (linear within each run).",
                                                    case_sensitive=False)] = RunNoiseKind.offset,
    temperature: Annotated[str, typer.Option(
        "--temperature", help="Temperature programme [degC]: constant:T | warmup:START:END:TAU_s | "
        "cycle:START:PEAK:TAU_s[:SWITCH_s] | mesh-warmup:START:END:TAU_s:SHARE:LAG_s (recorded at the "
        "worm mesh; the housing rises SHARE of it, LAG_s behind).")] = "constant:20",
    load: Annotated[str, typer.Option("--load", help="Load programme [N m]: constant:L | steps:L1:L2:... "
                                      "(one level per run, cycling).")] = "constant:0",
    random_phases: Annotated[bool, typer.Option("--random-phases", help="Draw every source phase from the "
                                                "seed instead of using the spec's.")] = False,
    offset_arcsec: Annotated[float, typer.Option("--offset-arcsec", help="Constant zero offset added to "
                                                 "every error [arcsec].")] = 0.0,
    plot: PlotOption = None,
):
    """Measured-like data from the model: try a measurement plan before measuring.

    Writes CSV with angle_deg, error_arcsec, direction, run, load_Nm,
    temperature_C, time_s (and '#' lines saying how it was made, not the
    truth).  Each run goes forward through the targets, then back.

    Example: wormgear synth configs/mch50.toml -o data.csv --truth truth.json --seed 1 --temperature warmup:20:30:1800
    """
    _synth(drive, output, truth, plot, SynthOptions(
        seed=seed, plan=getattr(plan, "value", plan), targets=targets, points=points, runs=runs, revs=revs,
        dwell_s=dwell_s, jitter=jitter, cycles=cycles, cycle_gap_s=cycle_gap_s,
        effect=tuple(effect) if effect is not None else None, spec_effects=spec_effects,
        noise_arcsec=noise_arcsec, run_noise_arcsec=run_noise_arcsec, run_noise=getattr(run_noise, "value", run_noise),
        temperature=temperature, load=load, random_phases=random_phases, offset_arcsec=offset_arcsec))


@dataclass(frozen=True)
class SynthOptions:
    """The ``synth`` command's options as given (checked and parsed by :func:`_synth`): the seed, the
    plan's (``plan`` "iso" or "dense", ``targets``, ``points``, ``runs``, ``revs``, ``dwell_s`` [s] or None,
    ``jitter``, ``cycles``, ``cycle_gap_s`` [s]), the effects (``effect``: the ``--effect`` texts,
    ``spec_effects``), the noise [arcsec] (``run_noise``: "offset" or "drift"), the ``temperature`` and
    ``load`` programmes' texts, ``random_phases`` and ``offset_arcsec``."""

    seed: int
    plan: str
    targets: int
    points: int
    runs: int
    revs: float
    dwell_s: float | None
    jitter: float
    cycles: int
    cycle_gap_s: float
    effect: tuple[str, ...] | None
    spec_effects: bool
    noise_arcsec: float
    run_noise_arcsec: float
    run_noise: str
    temperature: str
    load: str
    random_phases: bool
    offset_arcsec: float


def _synth(drive: Path, output: Path | None, truth: Path | None, plot: Path | None, o: SynthOptions) -> None:
    """``synth``: check the options and the paths, draw the data, write the CSV (and the truth, the plot)."""
    # lazy: keeps analysis.synth off `--help`'s start-up
    from wormgear_cli.analysis.synth import (
        Noise,
        Plan,
        format_csv,
        parse_effects,
        parse_load,
        parse_temperature,
        synthesize,
    )

    for name, value in (("--noise-arcsec", o.noise_arcsec), ("--run-noise-arcsec", o.run_noise_arcsec),
                        ("--offset-arcsec", o.offset_arcsec), ("--dwell-s", o.dwell_s),
                        ("--cycle-gap-s", o.cycle_gap_s)):
        if value is not None and not math.isfinite(value):
            raise UsageError(f"{name}: expected a finite number, got {value}")
    temp_prog = parse_temperature(o.temperature)
    load_prog = parse_load(o.load)
    effects = parse_effects(o.effect)
    if plot is not None:
        from wormgear_cli.plots import check_plot_path  # lazy: keeps plots off `--help`'s start-up

        check_plot_path(plot)
    outs = [p for p in (output, truth, plot) if p is not None]

    refuse_same_outputs([(output, "-o"), (truth, "--truth"), (plot, "--plot")])

    for p in outs:
        refuse_input(p, [drive], "name")
    spec = load_drive(drive)
    the_plan = Plan(kind=o.plan, targets=o.targets, points=o.points, runs=o.runs, revolutions=o.revs,
                    dwell_s=o.dwell_s, jitter=o.jitter, cycles=o.cycles, cycle_gap_s=o.cycle_gap_s)
    _check_synth_memory(the_plan)
    result = synthesize(
        spec,
        plan=the_plan,
        effects=effects,
        noise=Noise(o.noise_arcsec, o.run_noise_arcsec, o.run_noise),
        seed=o.seed,
        temperature=temp_prog,
        load=load_prog,
        random_phases=o.random_phases,
        include_spec_effects=o.spec_effects,
        offset_arcsec=o.offset_arcsec,
    )
    warn_if_absurd({"error": result.columns["error_arcsec"]}, drive, "arcsec")
    text = format_csv(result)
    if plot is not None:
        from wormgear_cli.plots.simulate import plot_synthesis  # lazy: keeps plots.simulate off `--help`'s start-up

        plot_synthesis(result, spec.drive.name, plot)
        announce_written(plot)
    emit(text, output, [drive])
    if truth is not None:
        emit(json_text(result.truth), truth, [drive] + ([output] if output is not None else []))


def _check_synth_memory(plan) -> None:
    """Refuse, before drawing, a plan whose rows the machine cannot hold (one line naming the options)."""
    dense = plan.kind == "dense"
    per_pass, option = (plan.points, "--points") if dense else (plan.targets, "--targets")
    rows = per_pass * 2 * plan.runs * plan.cycles
    sizes = f"{option} {per_pass} x --runs {plan.runs}" + (f" x --cycles {plan.cycles}" if plan.cycles > 1 else "")
    check_memory(rows * SYNTH_BYTES_PER_ROW, f"synth: {sizes} x 2 directions ({rows:,} rows)",
                 f"lower {option}, --runs or --cycles")
