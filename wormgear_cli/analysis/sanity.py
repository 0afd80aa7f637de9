"""No NaN, no overflow, no absurd number without a word: the guard on the model's results.

Every input the spec accepts is finite and inside its key's range, yet combinations at the
edges of those ranges (a 0.05 mm module on a one-tooth pinion, a 10 mm centre-distance
error, 10^8 N on a worm) take the paper's small-angle models far outside what they describe.
The commands pass their angles through :func:`check_angles` before writing them: a value that
is not finite is an error (exit 2, one line); an error or lost motion of more than a full
turn of the output is impossible for the nominal drive (``strict``: an error, exit 2) and one
warning line for an ensemble (sweeps and sampled drives, where some points may lie beyond).
Which inputs are implausible or impossible, and why, is the plausibility checks' business
(:mod:`wormgear_cli.spec.plausibility`, at load); this guard only makes sure no such number
leaves silently.  No I/O.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from wormgear_cli.analysis import accuracy
from wormgear_cli.errors import SpecError

#: an output error or lost motion larger than this [rad] (one turn) is no positioning error
FULL_TURN = 2.0 * math.pi

#: what the messages advise
_CHECK = "check modules, teeth, centre distances and loads"


def check_angles(values: Mapping[str, object], source: str = "", strict: bool = False) -> str | None:
    """Refuse non-finite angles; describe absurd ones.

    Parameters
    ----------
    values : mapping of str to float or array
        Quantity name -> angle(s) [rad] (zero-to-peak or peak-to-peak, as the caller's
        output states; only the magnitude is checked).
    source : str
        The drive file, for the message.
    strict : bool
        The values are the nominal drive's own (analyze, check, simulate): beyond a full turn
        is an error, not a warning.

    Returns
    -------
    str or None
        One warning line when any magnitude exceeds :data:`FULL_TURN` (naming up to three
        quantities and their largest value in degrees), else None.

    Raises
    ------
    SpecError
        A value is NaN or infinite (overflow): one line naming the quantity; with ``strict``,
        also a magnitude beyond a full turn.
    """
    over = []
    where = f"{source}: " if source else ""
    for name, v in values.items():
        a = np.abs(np.asarray(v, dtype=float))
        if a.size == 0:
            continue
        finite = np.isfinite(a)
        if not finite.all():
            bad = int(a.size - np.count_nonzero(finite))
            of = f" ({bad} of {a.size} values)" if a.size > 1 else ""
            raise SpecError(f"{where}the model gives no finite {name}{of} for these inputs: they lie outside "
                            f"what it describes; {_CHECK}")
        peak = float(a.max())
        if peak > FULL_TURN:
            over.append((peak, name))
    if not over:
        return None
    over.sort(reverse=True)
    named = ", ".join(f"{name} {math.degrees(peak):.4g} deg" for peak, name in over[:3])
    more = f" and {len(over) - 3} more" if len(over) > 3 else ""
    line = (f"{where}{named}{more}: more than a full turn, so the inputs lie far outside what the model "
            f"describes; {_CHECK}")
    if strict:
        raise SpecError(line.replace("more than a full turn, so", "more than a full turn, which no drive can have:"))
    return line


def check_drive(spec, source: str = "") -> None:
    """Refuse a drive whose own figures no drive can have: the one check of every command that
    evaluates a drive (analyze, check, simulate, synth, tolerance, sweep, compare, diagnose), so
    that none of them works on a spec the others refuse.

    The nominal drive is analysed (:func:`wormgear_cli.analysis.accuracy.analyze`) and its angles
    checked with ``strict`` (:func:`check_angles`).

    Raises
    ------
    SpecError
        An angle of the nominal drive is not finite or beyond a full turn (one line naming
        ``source``, the drive file).
    """
    check_angles(accuracy.analyze(spec).angles, source, strict=True)
