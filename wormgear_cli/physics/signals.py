"""The operating signals: what a drive's error changes with besides the angle.

One record per signal (:data:`SIGNALS`): its name (a field of
:class:`~wormgear_cli.physics.effects.Signals` and the value of an effect's
``needs``), the measurement column that records it, the column's unit, the value
assumed when a file has no such column, the range a reader accepts as plausible,
the unit of a residual trend's slope per unit of the signal, and how a measurement
makes it vary.  The readers' optional columns and ``diagnose``'s data checks read
these records; a new signal is one record here (and its field in ``Signals``).

Pure data, no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class OperatingSignal:
    """One operating signal.

    ``name``: field of ``Signals`` and value of ``Effect.needs``; ``column``: the
    measurement column [``unit``]; ``default``: its value where a file has no such
    column; ``lo``, ``hi``: the plausible range a reader accepts (inclusive, in
    ``unit``); ``slope_unit``: the denominator of a residual trend's slope (arcsec per
    ``slope_unit``; "" for a signal no trend is taken against); ``varied_by``: how a
    measurement makes the signal vary, as a hint names it ("" when there is no single
    way)."""

    name: str
    column: str
    unit: str
    default: float
    lo: float
    hi: float
    slope_unit: str = ""
    varied_by: str = ""


#: the operating signals, by name (the direction of travel, then the conditions a drive runs under)
SIGNALS: dict[str, OperatingSignal] = {
    s.name: s
    for s in (
        OperatingSignal("direction", "direction", "", 1.0, -1.0, 1.0),
        OperatingSignal("load", "load_Nm", "N m", 0.0, -1e9, 1e9, "N m", "load steps"),
        OperatingSignal("temperature", "temperature_C", "degC", 20.0, -100.0, 300.0, "K", "the warm-up"),
        OperatingSignal("time", "time_s", "s", 0.0, -1e10, 1e10, "s"),
    )
}

#: the conditions (every signal but the direction): continuous, a residual trend is tested against each
CONDITIONS: tuple[OperatingSignal, ...] = tuple(s for s in SIGNALS.values() if s.name != "direction")

#: trend-slope unit of each condition's column
SLOPE_UNITS: dict[str, str] = {s.column: s.slope_unit for s in CONDITIONS}
