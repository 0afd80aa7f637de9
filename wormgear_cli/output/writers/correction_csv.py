"""CSV correction table for any other controller: angle, correction forward, correction reverse.

Header ``angle_deg,correction_forward_<unit>,correction_reverse_<unit>``; one row per table
point; the correction is the value to add to the commanded position (minus the error), in the
chosen unit; numbers with 12 significant digits.
"""

from __future__ import annotations

from wormgear_cli.output.formats import csv_block
from wormgear_cli.units import to_unit


def write(table, options) -> str:
    """The file's text from a :class:`~wormgear_cli.compensation.table.CorrectionTable`."""
    unit = options.unit
    header = f"angle_deg,correction_forward_{unit},correction_reverse_{unit}\n"
    body = csv_block([table.angle_deg, to_unit(table.forward, unit) + 0.0, to_unit(table.reverse, unit) + 0.0])
    return header + body.decode("ascii")
