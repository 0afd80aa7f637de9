"""``wormgear grade``: ISO 1328 tolerances of one gear from its accuracy grade."""

from __future__ import annotations

from typing import Annotated

import typer

from wormgear_cli.cli._app import app
from wormgear_cli.cli.common import (
    OutputOption,
    TableJsonFormat,
    count_type,
    emit,
    json_text,
    output_format,
    render,
    say,
)
from wormgear_cli.cli.helptext import HelpCommand
from wormgear_cli.errors import UsageError


@app.command(cls=HelpCommand)
def grade(
    grade: Annotated[int, typer.Option("--grade", "-g", help="ISO 1328-1:2013 flank tolerance class A (1..11).",
                                       show_default=False)],
    module_mm: Annotated[float, typer.Option("--module-mm", help="Normal module m [mm].", show_default=False)],
    diameter_mm: Annotated[float, typer.Option("--diameter-mm", help="Reference diameter d [mm].",
                                               show_default=False)],
    face_width_mm: Annotated[float, typer.Option("--face-width-mm", help="Face width b [mm].",
                                                 show_default=False)],
    teeth: Annotated[int | None, typer.Option("--teeth", help="Number of teeth z (checked against the "
                                                 "standard's scope; default d/m).", show_default=False,
                                                 click_type=count_type())] = None,
    format: Annotated[TableJsonFormat, typer.Option("--format", "-f", help="Output format.",
                                                    case_sensitive=False)] = TableJsonFormat.table,
    output: OutputOption = None,
):
    """Tolerances of one spur gear from its accuracy grade (ISO 1328-1:2013 and ISO 1328-2:1997).

    Prints f_pT, F_pT, f_HalphaT, f_falphaT, F_alphaT, f_HbetaT, f_fbetaT, F_betaT, F_rT
    (ISO 1328-1:2013, rounded as its 5.2.3) and the radial composite F_i'' and f_i''
    of ISO 1328-2:1997 for the same grade where that standard has it (4..12), in um.
    A gear outside ISO 1328-1's scope is an error (exit 2); outside ISO 1328-2's scope
    the values of its nearest range are given and a warning goes to stderr.

    Example: wormgear grade --grade 6 --module-mm 2 --diameter-mm 100 --face-width-mm 20
    """
    # lazy: keeps physics.iso1328 off `--help`'s start-up
    from wormgear_cli.physics.iso1328 import PART2_GRADES, GradeError, flank_tolerances, radial_composite

    fmt = output_format(format, output)
    problems = [f"{opt}: expected a finite number > 0, got {v:g}" for opt, v in
                (("--module-mm", module_mm), ("--diameter-mm", diameter_mm), ("--face-width-mm", face_width_mm))
                if not v > 0 or v != v or v == float("inf")]
    if problems:
        raise UsageError(problems)
    z = teeth if teeth is not None else round(diameter_mm / module_mm)
    try:
        tol = flank_tolerances(grade, module_mm, diameter_mm, face_width_mm, z)
    except GradeError as exc:
        text = str(exc)
        opt = ("--grade" if text.startswith("grade") else
               {"module": "--module-mm", "diameter": "--diameter-mm", "face_width": "--face-width-mm",
                "teeth": "--teeth"}[text.split(" ", 1)[0]])
        if opt == "--teeth" and teeth is None:  # not given: derived from the diameter and the module
            opt = f"--diameter-mm/--module-mm (z = d/m = {diameter_mm:g}/{module_mm:g} = {z})"
        raise UsageError(f"{opt}: {text}") from None
    if teeth is not None and abs(teeth * module_mm - diameter_mm) > 0.5 * module_mm:
        say(f"warning: --teeth {teeth} with --module-mm {module_mm:g} gives d = z m = {teeth * module_mm:g} "
                   f"mm, not the --diameter-mm {diameter_mm:g} (helical gears: d = z m_n / cos(beta)); the "
                   "tolerances use the given diameter")
    doc = {"standard": "ISO 1328-1:2013", "grade": grade, "module_mm": module_mm, "diameter_mm": diameter_mm,
           "face_width_mm": face_width_mm, "teeth": z,
           "f_pT_um": tol.f_pT, "F_pT_um": tol.F_pT, "f_HalphaT_um": tol.f_HalphaT, "f_falphaT_um": tol.f_falphaT,
           "F_alphaT_um": tol.F_alphaT, "f_HbetaT_um": tol.f_HbetaT, "f_fbetaT_um": tol.f_fbetaT,
           "F_betaT_um": tol.F_betaT, "F_rT_um": tol.F_rT}
    if PART2_GRADES[0] <= grade <= PART2_GRADES[1]:
        rc = radial_composite(grade, module_mm, diameter_mm)
        for w in rc.warnings:
            say(f"warning: {w}")
        doc.update({"F_i2T_um": rc.F_i2T, "f_i2T_um": rc.f_i2T})
    else:
        say(f"note: ISO 1328-2:1997 has no radial composite grade {grade} (grades 4..12)")
        doc.update({"F_i2T_um": None, "f_i2T_um": None})
    if fmt == "json":
        emit(json_text(doc), output)
        return
    render([_table(doc)], output)


_ROWS = (
    ("f_pT_um", "f_pT", "single pitch", "1328-1 eq. (5)"),
    ("F_pT_um", "F_pT", "cumulative pitch", "1328-1 eq. (6)"),
    ("f_HalphaT_um", "f_HalphaT", "profile slope", "1328-1 eq. (7)"),
    ("f_falphaT_um", "f_falphaT", "profile form", "1328-1 eq. (8)"),
    ("F_alphaT_um", "F_alphaT", "total profile", "1328-1 eq. (9)"),
    ("f_HbetaT_um", "f_HbetaT", "helix slope", "1328-1 eq. (10)"),
    ("f_fbetaT_um", "f_fbetaT", "helix form", "1328-1 eq. (11)"),
    ("F_betaT_um", "F_betaT", "total helix", "1328-1 eq. (12)"),
    ("F_rT_um", "F_rT", "runout (0.9 F_pT)", "1328-1 annex"),
    ("F_i2T_um", "F_i''", "total radial composite", "1328-2"),
    ("f_i2T_um", "f_i''", "tooth-to-tooth radial composite", "1328-2"),
)


def _table(doc: dict):
    """The tolerances as a :class:`~wormgear_cli.output.tables.Table`."""
    from wormgear_cli.output.tables import Column, Table  # lazy: keeps output.tables off `grade`'s start-up

    t = Table(f"grade {doc['grade']}: m = {doc['module_mm']:g} mm, d = {doc['diameter_mm']:g} mm, "
              f"b = {doc['face_width_mm']:g} mm, z = {doc['teeth']} [um]",
              [Column("tolerance"), Column("meaning"), Column("value", "right"), Column("source (ISO)")])
    for key, sym, meaning, src in _ROWS:
        v = doc[key]
        t.add_row(sym, meaning, "n/a" if v is None else f"{v:g}", src)
    return t
