"""``wormgear diagnose``: where the model and a measurement disagree, which catalogue effect is missing."""

from __future__ import annotations

import importlib.util
from dataclasses import replace
from pathlib import Path
from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    AngleUnit,
    DriveArgument,
    JobsOption,
    OutputOption,
    Stages,
    TableJsonFormat,
    announce_written,
    count_type,
    emit,
    fmt_angle,
    jobs_count,
    json_text,
    load_drive,
    output_format,
    output_path_type,
    render,
)
from wormgear_cli.cli.helptext import HelpCommand
from wormgear_cli.cli.read_options import (
    AngleUnitOption,
    DecDegOption,
    ErrorUnitOption,
    GuideRateOption,
    InputFormatOption,
    MapOption,
    PixelScaleOption,
    SessionOption,
    check_rows_memory,
    read_options,
)
from wormgear_cli.errors import UsageError
from wormgear_cli.files import atomic_write, check_outputs
from wormgear_cli.measurement.readers import read_measurement
from wormgear_cli.units import ARCSEC, RAD_PER_UNIT

#: peak memory per row of a measurement file in ``diagnose`` (the model's columns, the fits and
#: their resamples; 1.4 GB for 10^6 rows, bench/bench_limits.py) [bytes]
DIAGNOSE_BYTES_PER_ROW = 1500

#: --unit of diagnose: the table and the plot follow it; the JSON report keeps arcsec (keys end in _arcsec)
DiagnoseUnitOption = Annotated[AngleUnit, typer.Option(
    "--unit", "-u", help="Unit of the angles in the table report and the plot. The JSON report is always in "
    "arcsec (its keys end in _arcsec).", case_sensitive=False)]


@app.command(cls=HelpCommand)
def diagnose(
    drive: DriveArgument,
    data: Annotated[Path, typer.Argument(
        help="Measured data, read as it is (a table: angle_deg, error_arcsec or actual_deg; optional direction, "
        "run, load_Nm, temperature_C, time_s, velocity; or an instrument export, see --input-format).",
        show_default=False, metavar="DATA.csv")],
    output: OutputOption = None,
    write_spec: Annotated[Path | None, typer.Option(
        "--write-spec", help="Also write the augmented drive spec to FILE.toml (TOML written from the parsed "
        "spec: the fitted phases and an [effects.NAME] table per named effect; the input's comments are not "
        "kept); never the input files.", show_default=False,
        click_type=output_path_type("--write-spec", "drive.toml"))] = None,
    format: Annotated[TableJsonFormat, typer.Option("--format", "-f", help="Output format of the report.",
                                                    case_sensitive=False)] = TableJsonFormat.table,
    unit: DiagnoseUnitOption = AngleUnit.arcsec,
    column_map: MapOption = None,
    error_unit: ErrorUnitOption = None,
    angle_unit: AngleUnitOption = None,
    input_format: InputFormatOption = "auto",
    session: SessionOption = None,
    pixel_scale: PixelScaleOption = None,
    dec_deg: DecDegOption = None,
    guide_rate: GuideRateOption = None,
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Also draw measured vs simulated and the residual, before and after, to FILE "
        "(.png, .svg or .pdf; needs matplotlib).", show_default=False,
        click_type=output_path_type("--plot", "plot.png"))] = None,
    alpha: Annotated[float, typer.Option(
        "--alpha", help="Family-wise significance level of each selection step (Bonferroni over the "
        "candidates tested), 0 < alpha < 0.5.")] = 0.01,
    keep_phases: Annotated[bool, typer.Option(
        "--keep-phases", help="Hold the spec's phases (known from a direct measurement) instead of fitting "
        "them; only the zero offset and effects are fitted.")] = False,
    max_effects: Annotated[int, typer.Option("--max-effects", help="Name at most this many effects.",
                                             click_type=count_type(0, 20))] = 4,
    resamples: Annotated[int, typer.Option(
        "--resamples", help="Resamples of whole runs for the stability check (0: skip it).",
        click_type=count_type(0, 10_000))] = 50,
    jobs: JobsOption = 1,
):
    """Find where the model and a measurement disagree and name the missing effect.

    Fits only what a drawing cannot know (the phases of the spec's periodic
    sources and one zero offset), shows the residual in common and
    differential mode, by order and against load, temperature and time,
    then scores every catalogue effect the spec lacks (GLS with run-to-run
    noise, Bonferroni, stability under resampling of runs), names those the
    data support, refits and shows the gap shrink.  Exit 0 whether or not an
    effect is found; 2 for bad input.

    Example: wormgear diagnose configs/mch50.toml configs/mch50-warm.csv --write-spec mch50-warm.toml
    """
    # lazy: keeps diagnosis.report, spec.filekind off `--help`'s start-up
    from wormgear_cli.diagnosis.report import run_diagnose
    from wormgear_cli.spec.filekind import kind_of_file

    if kind_of_file(drive) == "table" and kind_of_file(data) == "drive":
        raise UsageError(f"the arguments look swapped: {drive} is a measurement and {data} a drive spec; diagnose "
                         f"takes the drive first: wormgear diagnose {data} {drive}")
    unit = getattr(unit, "value", unit)
    fmt = output_format(format, output)
    inputs = (drive, data)
    output = _check_paths(drive, data, output, write_spec, plot)
    spec = load_drive(drive)
    check_rows_memory(data, DIAGNOSE_BYTES_PER_ROW, "diagnose")
    meas = read_measurement(data, options=read_options(column_map, error_unit, angle_unit, input_format, session,
                                                       pixel_scale, dec_deg, guide_rate))

    def run(progress=None):
        return run_diagnose(spec, meas, alpha=alpha, fit_phases=not keep_phases, max_effects=max_effects,
                            resamples=resamples, jobs=jobs_count(jobs), progress=progress, data_name=str(data),
                            write_spec=None if write_spec is None else str(write_spec))

    with Stages("diagnosing") as stages:  # shown on a terminal once the work has run a second
        result = run(progress=stages.update)
    doc = result.document
    figure = None
    if plot is not None:
        from wormgear_cli.plots.diagnose import draw  # lazy: keeps plots.diagnose off `--help`'s start-up

        figure = draw(result.diagnosis, doc, unit)
    if write_spec is not None and result.spec_toml is not None:
        atomic_write(write_spec, result.spec_toml, inputs)
        announce_written(write_spec)
    if plot is not None and figure is not None:
        from wormgear_cli.plots.diagnose import save  # lazy: keeps plots.diagnose off `--help`'s start-up

        save(figure, plot)
        announce_written(plot)
    if fmt == "json":
        emit(json_text(doc), output, inputs)
    else:
        render(_tables(doc, unit), output, inputs)


def _check_paths(drive: Path, data: Path, output: Path | None, write_spec: Path | None,
                 plot: Path | None) -> Path | None:
    """Refuse outputs that would overwrite an input or each other, and a plot or spec file of the wrong
    kind, before any work; returns ``output`` (None for stdout)."""
    if output is not None and str(output) == "-":
        output = None
    check_outputs([(output, "-o"), (write_spec, "--write-spec"), (plot, "--plot")], (drive, data))
    if plot is not None:
        from wormgear_cli.plots import INSTALL_HINT, check_plot_path  # lazy: keeps plots off `--help`'s start-up

        check_plot_path(plot)
        if importlib.util.find_spec("matplotlib") is None:
            raise UsageError(INSTALL_HINT)
    if write_spec is not None and Path(write_spec).suffix.lower() != ".toml":
        raise UsageError(f"{write_spec}: --write-spec writes a drive spec; expected a file name ending in .toml")
    return output


def _tables(doc: dict, unit: str) -> list:
    """The report as tables (:class:`~wormgear_cli.output.tables.Table`) and lines (every angle converted
    from arcsec to ``unit``; effect parameters stay in their catalogue units)."""
    from wormgear_cli.output.tables import Table  # lazy: keeps output.tables off `--help`'s start-up

    v = _View(unit)
    out = _head(doc, v) + [_gap_table(doc, v)] + _nuisance_lines(doc, v) + _effect_parts(doc, v)
    out += _candidate_parts(doc, v) + _unexplained_parts(doc, v) + _fit_parts(doc, v) + _noise_parts(doc, v)
    out += _order_parts(doc, v) + _versus_parts(doc, v) + ([_iso_table(doc, v)] if doc["iso230"] is not None else [])
    for t in out:
        if isinstance(t, Table):
            _keep_numbers_whole(t)
    return out


class _View:
    """Formatting shared by the tables of one report (angles from arcsec to ``unit``)."""

    def __init__(self, unit: str):
        self.unit = unit
        self.factor = ARCSEC / RAD_PER_UNIT[unit]

    def a(self, x) -> str:
        return "-" if x is None else fmt_angle(x * self.factor, self.unit)

    @staticmethod
    def table(title: str, cols: list[str], left=(0,)):
        """A :class:`~wormgear_cli.output.tables.Table`: the columns at the ``left`` positions aligned left
        (the labels), the numbers right."""
        from wormgear_cli.output.tables import Column, Table  # lazy: keeps output.tables off `--help`'s start-up

        return Table(title, [Column(c, "left" if i in left else "right") for i, c in enumerate(cols)])


def _head(doc: dict, v: _View) -> list:
    from rich.markup import escape  # lazy: keeps rich.markup off `--help`'s start-up

    from wormgear_cli.physics.signals import SIGNALS  # lazy: keeps physics off `--help`'s start-up

    sig = doc["signals"]
    runs = doc["noise"]["before"]["runs"]
    parts = [f"{doc['rows']} rows", f"{runs} run{'s' if runs != 1 else ''}",
             "both directions" if len(sig["directions"]) == 2 else "one direction"]
    for key, name, u in ((SIGNALS[s].column, s, SIGNALS[s].unit) for s in ("temperature", "load")):
        if sig.get(key):
            lo, hi = sig[key]
            parts.append(f"{name} {lo:g} to {hi:g} {u}" if hi > lo else f"{name} {lo:g} {u}")
    out = [escape(f"{doc['drive']} vs {doc['data']}: " + ", ".join(parts)), escape(f"verdict: {doc['verdict']}")]
    if sig.get("warning"):
        out.append(escape(f"note: {sig['warning']}"))
    if sig.get("data_warning"):
        out.append(escape(f"note: {sig['data_warning']}"))
    return out


def _gap_table(doc: dict, v: _View):
    a = v.a
    gt = v.table(f"gap: measured - simulated [{v.unit}]", ["", "as specified", "before (phases fitted)",
                                                          "after (effects added)"])
    for key, label in (("rms_arcsec", "RMS"), ("max_arcsec", "max |.|"), ("common_rms_arcsec", "common mode RMS"),
                       ("common_max_arcsec", "common mode max"), ("differential_rms_arcsec", "differential RMS"),
                       ("differential_max_arcsec", "differential max")):
        gt.add_row(label, a(doc["gap_as_specified"][key]), a(doc["gap_before"][key]), a(doc["gap_after"][key]))
    return gt


def _nuisance_lines(doc: dict, v: _View) -> list:
    """The nuisance terms, apart from the gap (which is measured without them)."""
    from rich.markup import escape  # lazy: keeps rich.markup off `--help`'s start-up

    nu = doc.get("nuisance")
    if not nu:
        return []
    out = [escape(f"fitted alongside the candidates as nuisance terms (no drive spec holds them; the gap above is "
                  f"without them; with them the RMS gap is {v.a(nu['rms_with_arcsec'])} {v.unit}):")]
    for term in nu["terms"]:
        size = (f"amplitude {v.a(term['amplitude_arcsec'])}" if term.get("amplitude_arcsec") is not None
                else f"{v.a(term.get('peak_to_peak_arcsec'))} peak to peak")
        out.append(escape(f"  {term['label']}: {size}, RMS {v.a(term['rms_arcsec'])} [{v.unit}]"))
    return out


def _effect_parts(doc: dict, v: _View) -> list:
    from rich.markup import escape  # lazy: keeps rich.markup off `--help`'s start-up

    if not doc["effects_found"]:
        return []
    et = v.table("effects found", ["effect / parameter", "value", "95 % interval"])
    for e in doc["effects_found"]:
        et.add_row(e["name"] + ("" if e["separable"] else " (size not separable)"), "", "")
        for key, value in e["parameters"].items():
            iv = e["interval_95"].get(key)
            if iv:
                span = f"{iv[0]:.4g} to {iv[1]:.4g}" + ("" if e["separable"] else " (fit as well)")
            elif key in e["fixed_parameters"]:
                span = "fixed"
            else:
                span = "not determined"
            et.add_row(f"  {key}", f"{value:.4g}", span)
    out = [et]
    for e in doc["effects_found"]:
        stab = (f"best in {100 * e['stability']:.0f} % of resamples of whole runs" if e["stability"] is not None
                else f"stability {e['stability_note'] or 'not assessed'}")
        out.append(escape(f"{e['name']}: explains {e['gap_share_pct']:.1f} % of the gap (p = {e['p_value']:.2g}, "
                          f"df {e['df']:.3g}; {stab})"))
        if "prediction" in e:
            pr = e["prediction"]
            out.append(escape(
                f"{e['name']}: physics predicts {pr['centre_distance_um_per_K']:.3g} um/K ({pr['basis']}); "
                f"fitted/predicted = {pr['fitted_over_predicted']:.2f}; the prediction is "
                f"{'inside' if pr['inside_interval'] else 'outside'} the 95 % interval"))
        for note in e["notes"]:
            out.append(escape(f"{e['name']}: {note}"))
    return out


def _candidate_parts(doc: dict, v: _View) -> list:
    from rich.markup import escape  # lazy: keeps rich.markup off `--help`'s start-up

    ct = v.table("catalogue effects", ["effect", "status", "p (adjusted)", "why"], left=(0, 1, 3))
    for c in doc["candidates"]:
        p = c.get("p_adjusted")
        ct.add_row(c["name"], c["status"], "-" if p is None else f"{p:.2g}", c.get("reason", ""))
    out = [ct]
    for c in doc["candidates"]:
        if c.get("remedy"):
            out.append(escape(f"{c['name']}: {c['remedy']}"))
    return out


def _unexplained_row(u: dict, v: _View) -> tuple[str, str]:
    """(what, size) of an unexplained item."""
    a = v.a
    if u["kind"] == "order":
        return f"order {u['order']:.6g}", a(u["amplitude_arcsec"])
    if u["kind"] == "trend":
        return f"trend with {u['signal']}", f"{u['slope_arcsec_per_unit'] * v.factor:.4g}/{u['unit']}"
    if u["kind"] == "likely_effect":
        return f"likely effect {u['name']}", f"RMS {a(u['rms_arcsec'])} -> {a(u['rms_with_arcsec'])}"
    if u["kind"] == "excess":
        return "residual above the noise floor", f"RMS {a(u['rms_arcsec'])}"
    if u["kind"] == "drift":
        what = "drift in time" if u["signal"] in ("time_s", "row order") else "trend over the arc"
        return what, f"{a(u['peak_to_peak_arcsec'])} p-p"
    return "mean reversal", a(u["mean_reversal_change_arcsec"])


def _unexplained_parts(doc: dict, v: _View) -> list:

    if not doc["unexplained"]:
        return []
    ut = v.table(f"unexplained residual (after) [{v.unit}]", ["what", "mode", "size", "p (adjusted)", "note"],
                 left=(0, 4))
    for u in doc["unexplained"]:
        what, size = _unexplained_row(u, v)
        p = u.get("p_adjusted")
        ut.add_row(what, u["mode"], size, "-" if p is None else f"{p:.2g}", u["explanation"])
    return [ut]


def _fit_parts(doc: dict, v: _View) -> list:
    from rich.markup import escape  # lazy: keeps rich.markup off `--help`'s start-up

    a, out = v.a, []
    fit = doc["fit"]
    if fit["phases"]:
        pt = v.table("phases of the spec's periodic sources [deg]" + ("" if fit["phases_fitted"] else " (held)"),
                     ["source", "order", "amplitude", "specified", "fitted"])
        for p in fit["phases"]:
            pt.add_row(p["source"], f"{p['order']:g}", a(p["amplitude_arcsec"]), f"{p['specified_deg']:.2f}",
                       f"{p['fitted_deg']:.2f}")
        out.append(pt)
        if fit["note"]:
            out.append(escape(fit["note"]))
    out.append(escape(f"zero offset: {a(fit['zero_offset_before_arcsec'])} before, "
                      f"{a(fit['zero_offset_after_arcsec'])} after [{v.unit}]"))
    return out


def _noise_parts(doc: dict, v: _View) -> list:
    from rich.markup import escape  # lazy: keeps rich.markup off `--help`'s start-up

    a = v.a
    nt = v.table(f"noise [{v.unit}]", ["", "before", "after"])
    nb, na = doc["noise"]["before"], doc["noise"]["after"]
    for key, label in (("repeat_std_arcsec", "repeatability (std over runs)"), ("white_arcsec", "white"),
                       ("pass_arcsec", "per pass"), ("run_arcsec", "per run"), ("total_arcsec", "total")):
        nt.add_row(label, a(nb[key]), a(na[key]))
    out = [nt]
    if doc["noise"].get("floor_arcsec") is not None:
        out.append(escape(f"noise floor (point-to-point noise within passes"
                          f"{'' if nb['runs'] < 3 else ' and scatter between passes and runs'}): "
                          f"{a(doc['noise']['floor_arcsec'])} [{v.unit}]"))
    out.append(escape(f"run structure: {nb['structure']} ({nb['passes']} pass{'es' if nb['passes'] != 1 else ''}, "
                      f"{nb['runs']} run{'s' if nb['runs'] != 1 else ''})"))
    return out


def _order_parts(doc: dict, v: _View) -> list:
    from rich.markup import escape  # lazy: keeps rich.markup off `--help`'s start-up

    a = v.a
    ot = v.table(f"residual at the physical orders [{v.unit}]", ["order", "shaft or mesh", "common before",
                                                                 "common after", "diff. before", "diff. after"],
                 left=(0, 1))
    unresolved = []
    for b, f in zip(doc["orders"]["before"], doc["orders"]["after"]):
        label = "constant" if b["order"] == 0 else b["label"]
        if not b["identifiable"]:
            unresolved.append(f"{b['order']:g}")
            continue
        ot.add_row(f"{b['order']:g}", label, a(b["common_arcsec"]), a(f["common_arcsec"]),
                   a(b.get("differential_arcsec")), a(f.get("differential_arcsec")))
    out = [ot]
    if unresolved:
        out.append(escape(f"not resolved at these targets (aliased, or too few targets for all orders): orders "
                          f"{', '.join(unresolved)}"))
    return out


def _versus_parts(doc: dict, v: _View) -> list:
    vs = doc["residual_vs"]
    if not vs["before"]:
        return []
    vt = v.table(f"residual slope against the signals [{v.unit} per unit]",
                 ["signal", "range", "common before", "common after", "differential before", "differential after"])
    for key, b in vs["before"].items():
        f = vs["after"][key]
        lo, hi = b["range"]
        s = lambda x: "-" if x is None else f"{x * v.factor:.4g}"  # noqa: E731
        vt.add_row(key, f"{lo:g} to {hi:g}", s(b["slope_common"]), s(f["slope_common"]),
                   s(b.get("slope_differential")), s(f.get("slope_differential")))
    return [vt]


def _iso_table(doc: dict, v: _View):
    a = v.a
    it = v.table(f"ISO 230-2 figures [{v.unit}]", ["figure", "measured", "simulated before", "simulated after"])
    iso = doc["iso230"]
    for key, label in (("A", "A accuracy"), ("B", "B reversal"), ("E", "E systematic"), ("M", "M mean bidirectional"),
                       ("R", "R repeatability")):
        it.add_row(label, a(iso["measured"][key]), a(iso["simulated_before"][key]), a(iso["simulated_after"][key]))
    return it


def _keep_numbers_whole(t) -> None:
    """Let a narrow terminal fold words and headers, never cut a number: the number columns
    (right-aligned) are at least as wide as their longest cell, so only the text columns give
    way (every column folds instead of ending in an ellipsis: :func:`~wormgear_cli.cli.common.render`)."""
    for j, col in enumerate(t.columns):
        cells = [row[j] if j < len(row) else "" for row in t.rows]
        if col.justify == "right" and cells:
            t.columns[j] = replace(col, min_width=max(len(c) for c in cells if isinstance(c, str)))
