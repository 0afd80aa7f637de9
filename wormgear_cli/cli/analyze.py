"""``wormgear analyze``, ``wormgear check`` and ``wormgear new``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    DriveArgument,
    FormatOption,
    OutputOption,
    TextJsonFormat,
    UnitOption,
    csv_text,
    emit,
    fmt_angle,
    json_text,
    output_format,
    render,
    say,
    stdout_is_terminal,
    warn_if_absurd,
)
from wormgear_cli.cli.helptext import HelpCommand


@app.command(cls=HelpCommand)
def analyze(
    drive: DriveArgument,
    format: FormatOption = "table",
    unit: UnitOption = "arcsec",
    output: OutputOption = None,
):
    """Transmission error and backlash of each stage and of the whole drive.

    Stage values are at each stage's own output shaft, as the paper reports
    them; totals are at the drive output (worm stage divided by i_c = z1/z2).

    Example: wormgear analyze configs/mch50.toml --unit deg --format json
    """
    from wormgear_cli.analysis.accuracy import INFO_COLUMNS, METRIC_COLUMNS
    from wormgear_cli.analysis.accuracy import analyze as run
    from wormgear_cli.output.analyze import document
    from wormgear_cli.spec.loader import load_spec

    spec = load_spec(drive)
    result = run(spec)
    warn_if_absurd(result.angles, drive)
    unit = getattr(unit, "value", unit)
    fmt = output_format(format, output)
    if fmt == "csv":
        m = result.metrics(unit)
        cols = ["drive", "unit", *METRIC_COLUMNS, *INFO_COLUMNS]
        emit(csv_text(cols, [[result.drive, unit, *(m[c] for c in cols[2:])]]), output, [drive])
        return
    report = document(spec, result, unit)
    if fmt == "json":
        emit(json_text(report), output, [drive])
    else:
        render(_tables(report, unit) + _budget_tables(report, unit), output, [drive])


def _budget_tables(r: dict, unit: str) -> list:
    from rich.markup import escape
    from rich.table import Table

    a = lambda x: fmt_angle(x, unit)  # noqa: E731
    bt = Table(title=escape(f"full error budget, TE at the output [{unit}] ({r['stages']['gear']['kinematics']} "
                            "kinematics)"), title_justify="left")
    for col in ("source", "kind", "order", "amplitude", "origin", "share"):
        bt.add_column(col, justify="left" if col in ("source", "kind", "origin") else "right")
    for ln in r["budget"]:
        bt.add_row(ln["source"], ln["kind"], f"{ln['order']:g}", a(ln["amplitude"]), ln["origin"],
                   f"{ln['share_pct']:.1f} %")
    t = r["total_with_budget"]
    note = escape(f"total_with_budget: linear sum {a(t['transmission_error_linear'])}, root-sum-square "
                  f"{a(t['transmission_error_rss'])}, phased peak {a(t['transmission_error_peak'])} {unit} "
                  "(docs/budget.md); the paper's total above is unchanged")
    vt = Table(title="values used", title_justify="left")
    for col in ("key", escape("value [mm]"), "origin"):  # in the keys' own unit (_mm), as the spec writes them
        vt.add_column(col, justify="right" if col.startswith("value") else "left")
    for v in r["values_used"]:
        vt.add_row(v["key"], f"{round(v['value_um'] / 1000.0, 9):g}", v["origin"])
    return [bt, note, vt]


def _tables(r: dict, unit: str) -> list:
    from rich.markup import escape
    from rich.table import Table

    g, w, t = r["stages"]["gear"], r["stages"]["worm"], r["total"]
    a = lambda x: fmt_angle(x, unit)  # noqa: E731
    out = []
    gt = Table(title=escape(f"{r['drive']}: gear stage (spur, i_c = {r['ratios']['gear']:g}), at the output [{unit}]"),
               title_justify="left")
    for col in ("quantity", "eccentricity", "deformation", "value", "share of total"):
        gt.add_column(col, justify="left" if col == "quantity" else "right")
    gt.add_row("transmission error", a(g["transmission_error_parts"]["eccentricity"]),
               a(g["transmission_error_parts"]["deformation"]), a(g["transmission_error"]),
               f"{g['contribution']['transmission_error_pct']:.1f} %")
    gt.add_row("backlash", a(g["backlash_parts"]["eccentricity"]), a(g["backlash_parts"]["deformation"]),
               a(g["backlash"]), f"{g['contribution']['backlash_pct']:.1f} %")
    share = "n/a (no eccentric part)" if g["load_share_pct"] is None else f"{g['load_share_pct']:.2f} %"
    gear_note = escape(f"TE maximum at pinion angle {g['phi_at_max_deg']:.1f} deg; load adds "
                  f"{share} to it (delta1 = {g['deflection_um']:.3f} um, "
                  f"{r['deflection_model']})")
    if g["backlash_parts"].get("thickness", 0.0) > 0.0:
        gear_note += escape(f"; {g['kinematics']} kinematics: backlash includes the tooth-thickness allowances "
                            f"{a(g['backlash_parts']['thickness'])}")
    out += [gt, gear_note]
    wt = Table(title=escape(f"worm stage (worm ratio {r['ratios']['worm']:g}), at the wheel [{unit}]"),
               title_justify="left")
    for col in ("quantity", "central", "+/- envelope", "bound", "at output", "share of total"):
        wt.add_column(col, justify="left" if col == "quantity" else "right")
    wp = w["backlash_parts"]
    wt.add_row("transmission error", a(w["transmission_error_parts"]["deformation"]),
               a(w["transmission_error_parts"]["envelope_halfwidth"]), a(w["transmission_error"]),
               a(w["contribution"]["transmission_error"]), f"{w['contribution']['transmission_error_pct']:.1f} %")
    wt.add_row("backlash", a(wp["deformation"] + wp["profile"] + wp["thickness"]), a(wp["envelope_halfwidth"]),
               a(w["backlash"]), a(w["contribution"]["backlash"]), f"{w['contribution']['backlash_pct']:.1f} %")
    worm_note = escape(f"central TE = deformation (delta2 = {w['deflection_um']:.3f} um); central backlash = "
                  f"deformation {a(wp['deformation'])} + profile {a(wp['profile'])} + thickness "
                  f"{a(wp['thickness'])}")
    out += [wt, worm_note]
    tt = Table(title=escape(f"total at the output (ratio {r['ratios']['total']:g}) [{unit}]"), title_justify="left")
    tt.add_column("quantity")
    tt.add_column("gear stage", justify="right")
    tt.add_column("worm stage / i_c", justify="right")
    tt.add_column("total", justify="right")
    tt.add_row("transmission error", a(g["transmission_error"]), a(w["contribution"]["transmission_error"]),
               a(t["transmission_error"]))
    tt.add_row("backlash", a(g["backlash"]), a(w["contribution"]["backlash"]), a(t["backlash"]))
    out.append(tt)
    return out


@app.command(cls=HelpCommand)
def check(
    drives: Annotated[list[Path], typer.Argument(help="One or more drive specs (TOML).", show_default=False,
                                                metavar="DRIVE.toml...")],
    format: Annotated[TextJsonFormat, typer.Option("--format", "-f", help="Output format.")] = "text",
    output: OutputOption = None,
):
    """Validate drive specs and check their [requirements].

    Exit 0: every file valid and within its requirements; 1: a requirement
    exceeded (one line each: file, key, limit, value); 2: a spec invalid.
    Invalid files are reported on stderr, verdicts on stdout.

    Example: wormgear check configs/*.toml --format json
    """
    from wormgear_cli.workflows.check import check_file

    fmt = output_format(format, output)
    checks = [check_file(path) for path in drives]
    for c in checks:
        for p in c.problems:
            say(f"error: {p}")
        for w in c.warnings:
            say(f"warning: {w}")
    invalid = any(not c.valid for c in checks)
    failed = any(c.valid and not c.passed for c in checks)
    results = [c.to_dict() for c in checks]
    lines = [ln for c in checks for ln in c.findings]
    if fmt == "json":
        emit(json_text({"files": results, "passed": not (invalid or failed)}), output, drives)
    elif lines:
        if output is None and stdout_is_terminal():  # on a screen, long findings wrap at spaces;
            import shutil  # piped or to a file, one finding per line (grep)
            import textwrap

            width = shutil.get_terminal_size((80, 24)).columns
            lines = [textwrap.fill(ln, width, subsequent_indent="    ", break_long_words=False,
                                   break_on_hyphens=False) for ln in lines]
        from wormgear_cli.errors import escape  # a file name is shown, never run by the terminal

        emit("\n".join(escape(ln, "\n") for ln in lines) + "\n", output, drives)
    if invalid:
        raise typer.Exit(2)
    if failed:
        raise typer.Exit(1)


@app.command(cls=HelpCommand)
def new(
    path: Annotated[Path, typer.Argument(help="File to create (must not exist); a name without a suffix gets "
                                           ".toml; - writes the template to stdout.", show_default=False,
                                           metavar="NEW.toml")],
    name: Annotated[str | None, typer.Option("--name", help="Drive name (default: file name).")] = None,
):
    """Write a complete, commented drive template to start from.

    The template is the paper's MCH50 drive (the values of configs/mch50.toml:
    Table 1, the paper's loads, and that file's assumptions); derived keys are
    comments holding their derived value.  It never overwrites an existing file
    (not even one that appears while it is written).  - (or /dev/stdout) writes
    it to stdout, as everywhere else.

    Example: wormgear new my-table.toml && wormgear analyze my-table.toml
    """
    from wormgear_cli.errors import UsageError, quote
    from wormgear_cli.files import atomic_write, names_a_descriptor
    from wormgear_cli.spec.template import template

    if name is not None and not name.isprintable():
        raise UsageError("--name: expected a single-line name without control characters")
    if str(path) == "-" or names_a_descriptor(path):  # stdout (or a descriptor), as everywhere
        emit(template(name or "drive"), path)
        return
    path = _spec_name(path)
    if path.exists() or path.is_symlink():
        raise UsageError(f"{quote(path)}: already exists; wormgear new never overwrites a file")
    from wormgear_cli.cli.common import announce_written
    from wormgear_cli.files import after_commit

    atomic_write(path, template(name or quote(path.stem)), exclusive=True)
    announce_written(path)
    after_commit(lambda: say(f"edit it, then run: wormgear check {quote(path)}"))


def _spec_name(path: Path) -> Path:
    """The file ``new`` writes: ``path``, with ``.toml`` added when it has no suffix; a suffix
    other than ``.toml`` is refused with the name to use (every command reads drives as TOML)."""
    from wormgear_cli.errors import UsageError, quote

    if path.suffix.lower() == ".toml" or path.is_dir():  # a directory: refused as it is, below
        return path
    if not path.suffix or not path.name.strip("."):
        return path.with_name(path.name + ".toml")
    raise UsageError(f"{quote(path)}: a drive spec is a .toml file; name it {path.with_suffix('.toml').name} (or "
                     f"{path.name}.toml)")
