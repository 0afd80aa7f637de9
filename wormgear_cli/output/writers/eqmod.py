"""EQMOD / EQASCOM periodic error correction (PEC) file.

EQASCOM reads it thus: the first line is always skipped (written here as ``# caption``);
``!WormPeriod=`` (seconds, rounded to whole seconds) must come before the data and
``!StepsPerWorm=`` is optional (the mount's own value is used otherwise); other ``#`` lines are
comments; each data line is ``time motor PE`` separated by single spaces, one line per second
of the worm period, PE in arcsec of RA axis.  Every WormPeriod lines make one cycle; the cycles
are averaged and a linear drift across the cycle is taken off (the curve written here is one
cycle with its drift already removed, so that step changes it by at most the curve's change
over one second).  The motor column gives the RA motor position (modulo the steps per worm)
at which each row is played back: it phases the curve to the worm.
"""

from __future__ import annotations

import math

#: decimals of the PE column [arcsec] (as EQASCOM writes its own files)
PE_DECIMALS = 4


def write(curve, options) -> str:
    """The file's text from a :class:`~wormgear_cli.compensation.pec.PecCurve`."""
    arcsec = math.pi / 648000.0
    steps = options.steps_per_worm
    caption = " ".join((options.caption or "PEC curve by wormgear compensate").split())
    lines = [f"# {caption}", f"!WormPeriod={curve.rows}"]
    if steps:
        lines.append(f"!StepsPerWorm={int(steps)}")
    lines.append(f"# time - motor - PE [arcsec of RA axis], drift removed; row 0 = worm phase 0 (RA axis at "
                 f"{math.degrees(curve.reference) % 360.0:.4f} deg in the record)")
    pe = (curve.pe / arcsec).tolist()
    for t in range(curve.rows):
        motor = (t * int(steps)) // curve.rows if steps else t
        value = f"{pe[t]:.{PE_DECIMALS}f}"
        if value.strip("-0.") == "":
            value = "0." + "0" * PE_DECIMALS
        lines.append(f"{t} {motor} {value}")
    return "\n".join(lines) + "\n"


def instructions(options) -> list[str]:
    """How EQASCOM loads the file."""
    path = options.path or "FILE"
    return [f"EQASCOM: PEC > load {path}, then enable PEC (gain 1, phase 0 to begin with)"]
