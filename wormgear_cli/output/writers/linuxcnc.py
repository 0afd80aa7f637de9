"""LinuxCNC joint compensation file (``[JOINT_n] COMP_FILE``).

One triplet per line, separated by single spaces, no header or comment line (LinuxCNC's reader
stops silently at the first line that is not three numbers), the nominal positions strictly
increasing, at most 256 lines per joint.  A rotary joint's values are in degrees.

* ``COMP_FILE_TYPE = 1``: ``nominal correction_positive correction_negative``, the correction
  added to the commanded position when moving in the positive (negative) direction, i.e.
  minus the error.
* ``COMP_FILE_TYPE = 0``: ``nominal actual_positive actual_negative``, the position actually
  reached when the nominal one is commanded moving in each direction (nominal + error);
  LinuxCNC turns it into the correction nominal - actual.

LinuxCNC interpolates linearly between the lines per direction and holds the end values beyond
the first and last line; at rest it keeps the correction of the last direction moved.
"""

from __future__ import annotations

import math

#: decimals of the nominal position and of the values [deg]
NOMINAL_DECIMALS = 6
VALUE_DECIMALS = 9
#: most lines LinuxCNC reads per joint (EMCMOT_COMP_SIZE)
MAX_LINES = 256


def write(table, options) -> str:
    """The file's text from a :class:`~wormgear_cli.compensation.table.CorrectionTable`."""
    if len(table) > MAX_LINES:
        raise ValueError(f"a LinuxCNC table holds at most {MAX_LINES} lines, got {len(table)}")
    if options.file_type not in (0, 1):
        raise ValueError("COMP_FILE_TYPE is 0 or 1")
    deg = 180.0 / math.pi
    lines = []
    for a, f, r in zip(table.angle_deg.tolist(), (table.forward * deg).tolist(), (table.reverse * deg).tolist()):
        if options.file_type == 0:
            f, r = a - f, a - r  # the position reached: nominal + error = nominal - correction
        lines.append(f"{a:.{NOMINAL_DECIMALS}f} {_value(f)} {_value(r)}")
    return "\n".join(lines) + "\n"


def _value(x: float) -> str:
    text = f"{x:.{VALUE_DECIMALS}f}"
    return "0." + "0" * VALUE_DECIMALS if text.strip("-0.") == "" else text  # no "-0.000000000"


def instructions(options) -> list[str]:
    """The INI lines that load the file (section of the rotary joint, number n to fill in)."""
    path = options.path or "FILE"
    return ["[JOINT_n]    (the rotary joint's section)",
            f"COMP_FILE = {path}",
            f"COMP_FILE_TYPE = {options.file_type}"]
