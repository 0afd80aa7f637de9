"""A table of cells -> :class:`~wormgear_cli.measurement.reader.Measurement`: what every tabular input
format shares once it has found its header and its data lines.

Steps (each its own function): which column is which (:func:`~.header.resolve_header`), the cells as
numbers (a fast vectorised path, exact messages on the slow one), the units (from the options, the
header, the format), the checks every value passes, and the columns formed from others:

* the error as actual - target where the file has positions instead of a deviation, wrapped to
  +/-180 deg (a rotary axis: 359.9 deg against 0.1 deg is -0.2 deg);
* the direction from the sign of a velocity where the file has no direction column, rows at
  standstill (velocity exactly 0) left out and said;
* rotation words (CW/CCW) made forward or reverse from the data;
* the time in seconds from a time column in ms, min, h or FILETIME (100 ns ticks since 1601,
  counted from the first row);
* passes where ``time_s`` goes backwards, without a run column.

Everything inferred is said in the record's ``notes``; what looks wrong in its ``warnings``.
"""

from __future__ import annotations

import datetime
import math
from dataclasses import dataclass, field

import numpy as np

from wormgear_cli.errors import DataError
from wormgear_cli.measurement.reader import (
    CANONICAL,
    DEFAULTS,
    OPTIONAL,
    REQUIRED,
    Measurement,
    ReadOptions,
    time_restarts,
)
from wormgear_cli.measurement.readers.header import canonical_unit, resolve_header
from wormgear_cli.measurement.readers.plausibility import plausibility, size_note
from wormgear_cli.measurement.readers.text import DelimitedBody
from wormgear_cli.measurement.readers.values import (
    BLOCK,
    DIRECTION_HINT,
    check_range,
    first_row,
    not_a_number,
    orient_rotation,
)
from wormgear_cli.units import RAD_PER_UNIT

#: seconds per unit of a time column
TIME_SCALE = {None: 1.0, "s": 1.0, "ms": 1e-3, "min": 60.0, "h": 3600.0, "filetime": 1e-7}
#: FILETIME ticks (100 ns) from 1601-01-01 to 1970-01-01
FILETIME_UNIX_EPOCH = 116_444_736_000_000_000


@dataclass
class TableSource:
    """What a tabular format found: ``header`` (cells, stripped) on file line ``header_line``, the data
    lines (``body``), whether numbers use a decimal comma; ``comments`` (``#`` lines) and
    ``preamble`` (metadata lines) before the header; ``notes`` about the layout; ``defaults``: the
    format's own (canonical, header cell) assignment, used where no map or recognised header gives
    the column; ``units``: canonical -> unit the format states (an instrument's unit row);
    ``format_name``: the registry name; ``hint``: the format's advice for a missing column when no
    ``--map`` can be guessed."""

    name: str
    header: list
    header_line: int
    body: DelimitedBody
    decimal_comma: bool = False
    comments: tuple = ()
    preamble: tuple = ()
    notes: list = field(default_factory=list)
    defaults: tuple = ()
    units: dict = field(default_factory=dict)
    format_name: str = "csv"
    hint: str = ""


def _label(canon: str, header: list, index: dict) -> str:
    """How a column is named in messages: its canonical name, and the header cell when that differs."""
    cell = header[index[canon]]
    return canon if cell == canon else f"{canon} ({cell!r})"


def _cells(src: TableSource, index: dict, cols: list) -> tuple[dict, np.ndarray | None]:
    """The columns ``cols`` of every data row as floats (the direction as +1, -1 or NaN where a cell is
    no direction), and where the direction is a rotation word (None: nowhere).  DataError for no or
    one data row, a cell that is not a number (the first of the first column that has one)."""
    body, name = src.body, src.name
    direction = cols.index("direction") if "direction" in cols else None
    got = body.read([index[c] for c in cols], src.decimal_comma, direction)
    if got.n == 0:
        raise DataError(f"{name}:{src.header_line}: no data rows after the header")
    if got.n < 2:
        raise DataError(f"{name}:{body.line_of(0)}: only one data row; at least two are needed")
    for i, c in enumerate(cols):
        if i == direction and not got.plain:  # words: judged as directions below
            continue
        k = got.odd[i] if got.odd[i] is not None else got.bad[i]
        if k is not None:
            raise not_a_number(name, body.line_of(k), _label(c, src.header, index), body.cell_of(k, index[c]),
                               src.decimal_comma)
    return dict(zip(cols, got.values)), got.rotation


def _directions(src: TableSource, index: dict, values: dict) -> None:
    """DataError at the first direction cell that is no direction."""
    if "direction" not in values:
        return
    bad = np.flatnonzero(~np.isfinite(values["direction"]))
    if bad.size:
        k = int(bad[0])
        raise DataError(f"{src.name}:{src.body.line_of(k)}: column {_label('direction', src.header, index)}: "
                        f"expected {DIRECTION_HINT}, got {src.body.cell_of(k, index['direction'])!r}")


@dataclass
class _Units:
    angle: str
    actual: str
    error: str
    stated: set
    notes: list
    warnings: list


def _units(src: TableSource, options: ReadOptions, index: dict, hunit: dict) -> _Units:
    """The units used for the angle, the actual position and the error, which of them are stated, and
    what is said about them (a header unit against an option, a unit read from the header)."""
    header = src.header
    for canon, unit in src.units.items():
        if canon in index and hunit.get(canon) is None:
            hunit[canon] = unit
    angle_unit = options.angle_unit or hunit.get("angle_deg") or "deg"
    actual_unit = options.angle_unit or hunit.get("actual_deg") or angle_unit
    error_unit = options.error_unit or hunit.get("error_arcsec") or "arcsec"
    notes: list = []
    warnings: list = []
    stated: set = set()
    for canon, chosen, opt, given in (("angle_deg", angle_unit, "--angle-unit", options.angle_unit),
                                      ("error_arcsec", error_unit, "--error-unit", options.error_unit)):
        said = hunit.get(canon)
        if canon not in index:
            continue
        cell = header[index[canon]]
        canonical_name = cell.lower() == canon.lower()
        if given or (said is not None and not canonical_name):
            stated.add(canon.split("_")[0])
        if said is not None and said != chosen and canonical_name:
            # the canonical name is the name the tool asks for, so an explicit option is a deliberate choice:
            # said, not warned about
            notes.append(f"column {canon!r} read in {chosen} ({opt} {chosen}), not in the {said} its name says")
        elif said is not None and said != chosen:
            warnings.append(f"column {cell!r} says {said} but is read as {chosen} ({opt} {chosen}); if the header "
                            f"is right, use {opt} {said}")
        elif said is not None and not canonical_name and not given and said != canonical_unit(canon):
            notes.append(f"column {cell!r} read in {said}, the unit its header states")
    return _Units(angle_unit, actual_unit, error_unit, stated, notes, warnings)


def _time(src: TableSource, index: dict, hunit: dict, values: dict, notes: list) -> None:
    """``time_s`` in seconds, from a time column in s, ms, min, h or FILETIME ticks (then counted from
    the first row, said in ``notes``)."""
    if "time_s" not in values:
        return
    unit = hunit.get("time_s")
    t = values["time_s"]
    if unit == "filetime":
        first = float(t[0])
        values["time_s"] = (t - first) * TIME_SCALE[unit]

        when = datetime.datetime.fromtimestamp((first - FILETIME_UNIX_EPOCH) * 1e-7, datetime.UTC)
        notes.append(f"time from the FILETIME column {src.header[index['time_s']]!r} (100 ns ticks), counted from "
                     f"the first row ({when:%Y-%m-%d %H:%M:%S} UTC)")
    elif TIME_SCALE.get(unit, 1.0) != 1.0:
        values["time_s"] = t * TIME_SCALE[unit]


def _check(src: TableSource, index: dict, values: dict, scale: dict) -> None:
    """Every value finite and within its range; runs whole numbers."""
    body = src.body
    for c, arr in values.items():
        if c == "direction":
            continue
        check_range(src.name, c, _label(c, src.header, index), arr, scale.get(c, 1.0), body.line_of,
                    lambda k, j=index[c]: body.cell_of(k, j))
    if "run" in values:
        k = first_row(lambda a, b: values["run"][a:b] != np.round(values["run"][a:b]), values["run"].shape[0])
        if k is not None:
            raise DataError(f"{src.name}:{body.line_of(k)}: column {_label('run', src.header, index)}: expected an "
                            f"integer, got {body.cell_of(k, index['run'])!r}")


def _moving(src: TableSource, index: dict, values: dict, notes: list, derived: set) -> np.ndarray | None:
    """The direction from the sign of the velocity where the file has no direction column; the rows
    kept (indices; None: all), standstill rows (velocity exactly 0) left out and said."""
    if "velocity" not in values:
        return None
    cell = src.header[index["velocity"]]
    v = values.pop("velocity")
    if "direction" in values:
        notes.append(f"column {cell!r} (velocity) not used: the direction column gives the direction")
        return None
    keep = v != 0.0
    values["direction"] = np.where(v > 0, 1.0, -1.0)
    derived.add("direction")
    if np.all(keep):
        notes.append(f"direction from the sign of {cell!r}")
        return None
    kept = np.flatnonzero(keep)
    if kept.size < 2:
        raise DataError(f"{src.name}:{src.header_line}: {kept.size} row{'s' if kept.size != 1 else ''} in motion "
                        f"({cell!r} not 0); at least two are needed")
    still = np.flatnonzero(~keep)
    notes.append(f"direction from the sign of {cell!r}; {still.size} standstill row{'s' if still.size != 1 else ''} "
                 f"(velocity 0) left out ({_row_lines(src, still)})")
    for c in list(values):
        values[c] = values[c][kept]
    return kept


def _row_lines(src: TableSource, rows: np.ndarray) -> str:
    """``lines 4, 5, 9 and 12 more``: the file lines of data rows ``rows`` (the first three named)."""
    first = [src.body.line_of(int(k)) for k in rows[:3]]
    more = f" and {rows.size - 3} more" if rows.size > 3 else ""
    return f"line{'s' if rows.size != 1 else ''} {', '.join(str(x) for x in first)}{more}"


def _error(src: TableSource, index: dict, values: dict, u: _Units, notes: list, angle: np.ndarray) -> np.ndarray | None:
    """The error [rad]: the error column in its unit, else actual - target (``angle`` [rad]) wrapped to
    +/-180 deg (the error's unit is then the positions'), else None.  The columns read are made radians
    in place (the same numbers as a new array, without one)."""
    if "error_arcsec" in values:
        if "actual_deg" in values:
            notes.append(f"column {src.header[index['actual_deg']]!r} (actual position) not used: the file has an "
                         "error column")
        error = values.pop("error_arcsec")
        error *= RAD_PER_UNIT[u.error]
        return error
    if "actual_deg" not in values:
        return None
    raw = values.pop("actual_deg")
    raw *= RAD_PER_UNIT[u.actual]
    raw -= angle
    error = raw + math.pi
    np.mod(error, 2.0 * math.pi, out=error)
    error -= math.pi
    wrapped = sum(int(np.count_nonzero(np.abs(error[a:a + BLOCK] - raw[a:a + BLOCK]) > math.pi))
                  for a in range(0, error.shape[0], BLOCK))
    u.error = u.actual
    u.stated.add("error")  # the positions' unit: --error-unit does not apply, so none is proposed
    notes.append(f"error formed as actual - target: {src.header[index['actual_deg']]!r} - "
                 f"{src.header[index['angle_deg']]!r}, in {u.actual}, wrapped to +/-180 deg"
                 + (f" ({wrapped} row{'s' if wrapped != 1 else ''} across 0/360 deg)" if wrapped else ""))
    return error


def _passes(src: TableSource, values: dict, n: int, kept, notes: list, present: set, derived: set) -> np.ndarray:
    """The run of every row: the run column, else passes where ``time_s`` goes backwards (said), else 0."""
    if "run" in values:
        return values.pop("run").astype(np.int64)
    run = np.zeros(n, dtype=np.int64)
    if "time_s" not in values or n < 2:
        return run
    restarts = time_restarts(values["time_s"])
    assert restarts is not None  # (a time column is given)
    back = np.flatnonzero(restarts) - 1
    if not back.size:
        return run
    run[back + 1] = 1
    present.add("run")
    derived.add("run")
    rows = back + 1 if kept is None else kept[back + 1]
    notes.append(f"no run column: time_s goes backwards at {_row_lines(src, rows)}, taken as the start of a new "
                 f"pass ({back.size + 1} passes); add a run column to say so explicitly")
    return np.cumsum(run)


def build_measurement(src: TableSource, options: ReadOptions) -> Measurement:
    """The :class:`Measurement` of a table (see the module doc).

    Raises
    ------
    DataError
        One line per problem, naming the file, the line and the column.
    """
    required = REQUIRED if options.require_error else REQUIRED[:1]
    index, hunit = resolve_header(src.header, options.column_map, src.name, src.header_line, required,
                                  src.defaults, sample=src.body.sample_cells, hint=src.hint)
    cols = [c for c in CANONICAL if c in index]
    values, rotation = _cells(src, index, cols)
    notes: list = list(src.notes)
    if src.body.blank_count:
        k = src.body.blank_count
        first = ", ".join(str(line) for line in src.body.blank_rows[:3])
        more = f" and {k - 3} more" if k > 3 else ""
        notes.append(f"{k} row{'s' if k != 1 else ''} with every cell empty left out (line{'s' if k != 1 else ''} "
                     f"{first}{more})")
    u = _units(src, options, index, hunit)
    notes += u.notes
    _time(src, index, hunit, values, notes)
    _directions(src, index, values)
    scale = {"angle_deg": RAD_PER_UNIT[u.angle] / RAD_PER_UNIT["deg"],
             "actual_deg": RAD_PER_UNIT[u.actual] / RAD_PER_UNIT["deg"],
             "error_arcsec": RAD_PER_UNIT[u.error] / RAD_PER_UNIT["arcsec"]}
    _check(src, index, values, scale)
    derived: set = set()
    kept = _moving(src, index, values, notes, derived)
    if kept is not None and rotation is not None:
        rotation = rotation[kept]
    n = values["angle_deg"].shape[0]
    present = {c for c in OPTIONAL if c in values} | ({"direction"} if "direction" in derived else set())
    run = _passes(src, values, n, kept, notes, present, derived)
    angle = values.pop("angle_deg")
    angle *= RAD_PER_UNIT[u.angle]
    read_error = "error_arcsec" in values
    error = _error(src, index, values, u, notes, angle)
    has_error = error is not None
    if error is None:
        error = np.broadcast_to(np.float64(np.nan), (n,))
    direction = values["direction"] if "direction" in values else np.full(n, DEFAULTS["direction"])
    if rotation is not None and np.any(rotation):
        direction, said = orient_rotation(direction, rotation, angle, run)
        notes.append(said)
    warnings = u.warnings + plausibility(angle, error, u.angle, u.error, has_error, "error" in u.stated,
                                         "angle" in u.stated)
    if has_error and "error" in u.stated:
        how = ("as the positions it is formed from" if not read_error else
               "as --error-unit says" if options.error_unit else "as the header states")
        sized = size_note(error, u.error, how)
        if sized:
            notes.append(sized)

    def col(c):  # an absent column: its default, one value seen n times (no memory per row; read-only)
        return values[c] if c in values else np.broadcast_to(np.float64(DEFAULTS[c]), (n,))

    return Measurement(
        source=src.name, angle=angle, error=error, direction=direction, run=run, load=col("load_Nm"),
        temperature=col("temperature_C"), time=col("time_s"), present=frozenset(present),
        header=tuple(src.header), comments=tuple(src.comments), derived=frozenset(derived), notes=tuple(notes),
        warnings=tuple(warnings), columns=tuple((c, src.header[index[c]]) for c in cols),
        units=(("angle", u.angle), ("error", u.error)), preamble=tuple(src.preamble),
        stated_units=frozenset(u.stated), input_format=src.format_name, _cells=src.body.rows(kept))
