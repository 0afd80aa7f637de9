"""``wormgear analyze``, ``wormgear check`` and ``wormgear new``."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    AngleUnit,
    DriveArgument,
    FormatOption,
    OutputOption,
    TableFormat,
    TextJsonFormat,
    UnitOption,
    announce_written,
    csv_text,
    emit,
    fmt_angle,
    json_text,
    load_drive,
    output_format,
    output_path_type,
    render,
    say,
    stdout_is_terminal,
    warn_if_absurd,
)
from wormgear_cli.cli.helptext import HelpCommand
from wormgear_cli.errors import SpecError, UsageError, quote
from wormgear_cli.files import after_commit, atomic_write, names_a_descriptor, read_text_file
from wormgear_cli.units import to_unit


@app.command(cls=HelpCommand)
def analyze(
    drive: DriveArgument,
    format: FormatOption = TableFormat.table,
    unit: UnitOption = AngleUnit.arcsec,
    output: OutputOption = None,
):
    """Transmission error and backlash of each stage and of the whole drive.

    Stage values are at each stage's own output shaft, as the paper reports
    them; totals are at the drive output (each stage divided by the product
    of the ratios after it: for the paper's drive, the worm stage by i_c).

    Example: wormgear analyze configs/mch50.toml --unit deg --format json
    """
    # lazy: keeps analysis.accuracy, output.analyze off `analyze`'s start-up
    from wormgear_cli.analysis.accuracy import analyze as run
    from wormgear_cli.output.analyze import document
    spec = load_drive(drive)
    result = run(spec)
    warn_if_absurd(result.angles, drive, strict=True)
    unit = getattr(unit, "value", unit)
    fmt = output_format(format, output)
    if fmt == "csv":
        # lazy: keeps analysis.figures off `analyze`'s start-up
        from wormgear_cli.analysis.figures import FIGURE_COLUMNS, figures

        m = result.metrics(unit)
        m.update({k: float(to_unit(v, unit)) for k, v in figures(spec, result).items()})  # the sign-off figures
        cols = ["drive", "unit", *result.columns[0], *result.columns[1], *FIGURE_COLUMNS]
        emit(csv_text(cols, [[result.drive, unit, *(m[c] for c in cols[2:])]]), output, [drive])
        return
    report = document(spec, result, unit)
    if fmt == "json":
        emit(json_text(report), output, [drive])
    else:
        render(_tables(report, unit) + _budget_tables(report, unit), output, [drive])


def _table(title: str, headers, left=(0,)):
    """A :class:`~wormgear_cli.output.tables.Table` titled ``title``: the columns at the ``left``
    positions aligned left (the first: the quantity), the numbers right."""
    from wormgear_cli.output.tables import Column, Table  # lazy: keeps output.tables off `analyze`'s start-up

    return Table(title, [Column(h, "left" if i in left else "right") for i, h in enumerate(headers)])


def _budget_tables(r: dict, unit: str) -> list:
    from rich.markup import escape  # lazy: keeps rich.markup off `analyze`'s start-up

    a = lambda x: fmt_angle(x, unit)  # noqa: E731
    spurs = [st for st in r["stages"] if st["kind"] == "spur"]
    kin = f" ({spurs[-1]['kinematics']} kinematics)" if spurs else ""
    bt = _table(f"full error budget, TE at the output [{unit}]{kin}",
                ("source", "kind", "order", "amplitude", "origin", "share"), left=(0, 1, 4))
    for ln in r["budget"]:
        bt.add_row(ln["source"], ln["kind"], f"{ln['order']:g}", a(ln["amplitude"]), ln["origin"],
                   f"{ln['share_pct']:.1f} %")
    t = r["total_with_budget"]
    note = escape(f"total_with_budget, TE amplitude (zero to peak): linear sum "
                  f"{a(t['transmission_error_amplitude_linear'])}, statistical "
                  f"{a(t['transmission_error_amplitude_statistical'])}, phased peak "
                  f"{a(t['transmission_error_amplitude_peak'])}; range (peak to peak) of the phased curve "
                  f"{a(t['transmission_error_range_peak'])} {unit} (docs/budget.md); the paper's total above is "
                  "unchanged")
    for off in r.get("budget_offsets", ()):
        note += escape(f"\n{off['source']}: its curve's constant mean {a(off['offset'])} {unit} is no positioning "
                       "error (a shift of every position) and is in no total")
    # the values in the keys' own unit (_mm), as the spec writes them
    vt = _table("values used", ("key", "value [mm]", "origin"), left=(0, 2))
    for v in r["values_used"]:
        vt.add_row(v["key"], f"{round(v['value_um'] / 1000.0, 9):g}", v["origin"])
    return [bt, note, vt]


def _legacy(r: dict) -> bool:
    """A drive of one worm stage followed by one spur stage: its tables keep the paper's names."""
    return [st["kind"] for st in r["stages"]] == ["worm", "spur"]


def _stage_title(r: dict, st: dict) -> str:
    if _legacy(r):
        return (f"gear stage (spur, i_c = {st['ratio']:g}), at the output" if st["kind"] == "spur"
                else f"worm stage (worm ratio {st['ratio']:g}), at the wheel")
    where = "at the output" if st["ratio_after"] == 1.0 else "at its output shaft"
    return f"stage {st['stage']}: {st['name']} ({st['kind']}, ratio {st['ratio']:g}), {where}"


def _spur_table(r: dict, st: dict, unit: str, title: str) -> list:
    from rich.markup import escape  # lazy: keeps rich.markup off `analyze`'s start-up

    a = lambda x: fmt_angle(x, unit)  # noqa: E731
    c, tp, bp = st["contribution"], st["transmission_error_parts"], st["backlash_parts"]
    at_output = st["ratio_after"] != 1.0
    gt = _table(title, ("quantity", "eccentricity", "deformation", "value") + (("at output",) if at_output else ())
                + ("share of total",))
    for q, parts in (("transmission_error", tp), ("backlash", bp)):
        first = a(parts["eccentricity"]) if "eccentricity" in parts else f"residual {a(parts['residual'])}"
        row = [q.replace("_", " "), first, a(parts["deformation"]), a(st[q])]
        gt.add_row(*row, *((a(c[q]),) if at_output else ()), f"{c[q + '_pct']:.1f} %")
    share = "n/a (no eccentric part)" if st["load_share_pct"] is None else f"{st['load_share_pct']:.2f} %"
    note = escape(f"TE maximum at pinion angle {st['phi_at_max_deg']:.1f} deg; load adds "
                  f"{share} to it (delta1 = {st['deflection_um']:.3f} um, "
                  f"{r['deflection_model']})")
    if bp.get("thickness", 0.0) > 0.0:
        note += escape(f"; {st['kinematics']} kinematics: backlash includes the tooth-thickness allowances "
                       f"{a(bp['thickness'])}")
    if "residual" in bp:
        note += escape(f"; {st['anti_backlash']}: clearance set to the residual {a(bp['residual'])}")
    return [gt, note]


def _worm_table(r: dict, st: dict, unit: str, title: str) -> list:
    from rich.markup import escape  # lazy: keeps rich.markup off `analyze`'s start-up

    a = lambda x: fmt_angle(x, unit)  # noqa: E731
    c, tp, wp = st["contribution"], st["transmission_error_parts"], st["backlash_parts"]
    wt = _table(title, ("quantity", "central", "+/- envelope", "bound", "at output", "share of total"))
    wt.add_row("transmission error", a(tp["deformation"]), a(tp["envelope_halfwidth"]), a(st["transmission_error"]),
               a(c["transmission_error"]), f"{c['transmission_error_pct']:.1f} %")
    if "residual" in wp:
        wt.add_row("backlash", a(wp["deformation"] + wp["residual"]), a(0.0), a(st["backlash"]), a(c["backlash"]),
                   f"{c['backlash_pct']:.1f} %")
        note = escape(f"central TE = deformation (delta2 = {st['deflection_um']:.3f} um); backlash = deformation "
                      f"{a(wp['deformation'])} + the {st['anti_backlash']} worm's residual {a(wp['residual'])}")
        return [wt, note]
    wt.add_row("backlash", a(wp["deformation"] + wp["profile"] + wp["thickness"]), a(wp["envelope_halfwidth"]),
               a(st["backlash"]), a(c["backlash"]), f"{c['backlash_pct']:.1f} %")
    note = escape(f"central TE = deformation (delta2 = {st['deflection_um']:.3f} um); central backlash = "
                  f"deformation {a(wp['deformation'])} + profile {a(wp['profile'])} + thickness "
                  f"{a(wp['thickness'])}")
    return [wt, note]


def _belt_table(r: dict, st: dict, unit: str, title: str) -> list:
    from rich.markup import escape  # lazy: keeps rich.markup off `analyze`'s start-up

    a = lambda x: fmt_angle(x, unit)  # noqa: E731
    c, tp, bp = st["contribution"], st["transmission_error_parts"], st["backlash_parts"]
    bt = _table(title, ("quantity", "stretch", "other", "value", "at output", "share of total"))
    bt.add_row("transmission error", a(tp["stretch"]), a(tp["periodic"]), a(st["transmission_error"]),
               a(c["transmission_error"]), f"{c['transmission_error_pct']:.1f} %")
    bt.add_row("backlash", a(bp["stretch"]), a(bp["clearance"]), a(st["backlash"]), a(c["backlash"]),
               f"{c['backlash_pct']:.1f} %")
    note = escape(f"other: the periodic sources (TE; root-sum-square per order, summed over orders) and the "
                  f"tooth clearance (backlash); effective tension {st['effective_tension_N']:g} N, belt stretch "
                  f"{st['stretch_um']:.3f} um")
    return [bt, note]


def _parts_table(r: dict, st: dict, unit: str, title: str) -> list:
    """The table of a stage of another kind: its TE and backlash, their parts by name."""
    a = lambda x: fmt_angle(x, unit)  # noqa: E731
    c = st["contribution"]
    t = _table(title, ("quantity", "parts", "value", "at output", "share of total"), left=(0, 1))
    for q, parts in (("transmission_error", st["transmission_error_parts"]), ("backlash", st["backlash_parts"])):
        shown = ", ".join(f"{k} {a(v)}" for k, v in parts.items())
        t.add_row(q.replace("_", " "), shown, a(st[q]), a(c[q]), f"{c[q + '_pct']:.1f} %")
    return [t]


#: stage kind -> its table; a kind not listed gets :func:`_parts_table`
_STAGE_TABLES = {"spur": _spur_table, "worm": _worm_table, "belt": _belt_table}


def _tables(r: dict, unit: str) -> list:
    a = lambda x: fmt_angle(x, unit)  # noqa: E731
    out: list = []
    back = r["stages"][::-1]  # from the output back to the motor
    for k, st in enumerate(back):
        title = f"{_stage_title(r, st)} [{unit}]"
        out += _STAGE_TABLES.get(st["kind"], _parts_table)(r, st, unit, f"{r['drive']}: {title}" if k == 0 else title)
    labels = []
    for st in back:
        if _legacy(r):
            labels.append("gear stage" if st["kind"] == "spur" else "worm stage / i_c")
        else:
            labels.append(st["name"] if st["ratio_after"] == 1.0 else f"{st['name']} / {st['ratio_after']:g}")
    tt = _table(f"total at the output (ratio {r['ratios']['total']:g}) [{unit}]", ("quantity", *labels, "total"))
    t = r["total"]
    for q in ("transmission_error", "backlash"):
        tt.add_row(q.replace("_", " "), *(a(st["contribution"][q]) for st in back), a(t[q]))
    out.append(tt)
    return out


@app.command(cls=HelpCommand)
def check(
    drives: Annotated[list[Path], typer.Argument(help="One or more drive specs (TOML).", show_default=False,
                                                metavar="DRIVE.toml...")],
    format: Annotated[TextJsonFormat, typer.Option("--format", "-f", help="Output format.")] = TextJsonFormat.text,
    output: OutputOption = None,
):
    """Validate drive specs and check their [requirements].

    Exit 0: every file valid and within its requirements; 1: a requirement
    exceeded (one line each: file, key, limit, value); 2: a spec invalid.
    Invalid files are reported on stderr, verdicts on stdout.

    Example: wormgear check configs/*.toml --format json
    """
    from wormgear_cli.workflows.check import check_file  # lazy: keeps workflows.check off `analyze`'s start-up

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
                                           metavar="NEW.toml", click_type=output_path_type("NEW.toml", "drive.toml"))],
    name: Annotated[str | None, typer.Option("--name", help="Drive name (default: file name).")] = None,
    stages: Annotated[str, typer.Option("--stages", help="The stages' kinds from the motor to the output, comma "
                                        "separated: worm, spur, belt (e.g. worm | belt,worm | spur,worm | "
                                        "worm,spur).", metavar="KINDS")] = "worm,spur",
):
    """Write a complete, commented drive template to start from.

    One [[stage]] table per kind in --stages, listed from the motor to the
    output.  Worm and spur stages hold the paper's MCH50 values (those of
    configs/mch50.toml: Table 1, the paper's loads, and that file's
    assumptions), a belt stage an EQ6-class mount's motor reduction; every
    value says its source, derived keys are comments holding their derived
    value.  The default, worm,spur, is the MCH50 drive.  It never overwrites an
    existing file (not even one that appears while it is written).  - (or
    /dev/stdout) writes it to stdout, as everywhere else.

    Example: wormgear new my-mount.toml --stages belt,worm && wormgear analyze my-mount.toml
    """
    # lazy: keeps spec.stages, spec.template off `analyze`'s start-up
    from wormgear_cli.spec.stages import MAX_STAGES, STAGE_KINDS
    from wormgear_cli.spec.template import template

    if name is not None and not name.isprintable():
        raise UsageError("--name: expected a single-line name without control characters")
    kinds = tuple(k.strip() for k in stages.split(","))
    for k in kinds:
        if k not in STAGE_KINDS:
            raise UsageError(f"--stages: unknown stage kind {k!r} in {stages!r}; expected kinds from "
                             f"{', '.join(STAGE_KINDS)}, comma separated, e.g. belt,worm")
    if len(kinds) > MAX_STAGES:
        raise UsageError(f"--stages: at most {MAX_STAGES} stages, got {len(kinds)}")
    if str(path) == "-" or names_a_descriptor(path):  # stdout (or a descriptor), as everywhere
        emit(template(name or "drive", kinds), path)
        return
    path = _spec_name(path)
    if path.exists() or path.is_symlink():
        raise UsageError(f"{quote(path)}: already exists; wormgear new never overwrites a file")

    atomic_write(path, template(name or quote(path.stem), kinds), exclusive=True)
    announce_written(path)
    after_commit(lambda: say(f"edit it, then run: wormgear check {quote(path)}"))


def _spec_name(path: Path) -> Path:
    """The file ``new`` writes: ``path``, with ``.toml`` added when it has no suffix; a suffix
    other than ``.toml`` is refused with the name to use (every command reads drives as TOML)."""
    if path.suffix.lower() == ".toml" or path.is_dir():  # a directory: refused as it is, below
        return path
    if not path.suffix or not path.name.strip("."):
        return path.with_name(path.name + ".toml")
    raise UsageError(f"{quote(path)}: a drive spec is a .toml file; name it {path.with_suffix('.toml').name} (or "
                     f"{path.name}.toml)")


@app.command(cls=HelpCommand)
def upgrade(
    drive: Annotated[Path, typer.Argument(help="Drive spec of the legacy two-table form (TOML).", show_default=False,
                                          metavar="OLD.toml")],
    output: OutputOption = None,
):
    """Rewrite a drive file of the legacy two-table form as [[stage]] tables.

    The [gear_pair], [worm_pair], [assembly] and [loads] tables become two
    [[stage]] tables listed from the motor to the output (the worm pair, then
    the spur pair); every value is kept as written, comments travel with their
    keys, and the result is checked to give the same drive.  The output goes to
    stdout, or to -o FILE (never the input).

    Example: wormgear upgrade configs/mch50.toml -o mch50-stages.toml
    """
    # lazy: keeps spec.toml, spec.upgrade off `analyze`'s start-up
    from wormgear_cli.spec.toml import MAX_SPEC_BYTES
    from wormgear_cli.spec.upgrade import upgrade_text

    text = read_text_file(drive, "a TOML drive file", SpecError, encoding="utf-8-sig", max_bytes=MAX_SPEC_BYTES)
    result = upgrade_text(text, str(drive))
    if result.note:
        say(f"note: {quote(drive)}: {result.note}")
    emit(result.text, output, [drive])
