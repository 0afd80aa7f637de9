"""The TwinCAT Scope CSV export (``twincat-scope``), read as the instrument writes it.

Layout (Beckhoff TwinCAT 3 Scope View, "Export to csv"): a metadata block of ``key;value`` lines
(``Name``, ``File``, ``Starttime of export``, trigger information), then one line per channel
property (``Name;ch1;ch2;...``, ``SymbolComment``, ``Data-Type``, ``SampleTime``, ``Unit``, ...),
blank lines, and the data rows: a time stamp and one value per channel.  The time is a FILETIME
(100 ns ticks since 1601, "Full Timestamp") or milliseconds from the first sample; a line ``EOF``
may close the file.  The separator is the export's setting (``;`` by default); numbers may use a
decimal comma.

The channels are given their roles from their names (``--map`` overrides any of them): a velocity
channel (``fActVelocity``: its sign gives the direction, standstill rows are left out), and two
position channels, the reference (a set point, target, command, or an internal/open-loop counter:
the target angle) and the measured one (resolver, encoder, laser: the actual angle); the error is
actual - target, wrapped to +/-180 deg.  Positions are in axis units: degrees unless the ``Unit``
row or ``--angle-unit`` says otherwise.
"""

from __future__ import annotations

import re

from wormgear_cli.errors import DataError
from wormgear_cli.measurement.reader import Measurement, ReadOptions
from wormgear_cli.measurement.readers.header import quote, stated_unit
from wormgear_cli.measurement.readers.source import TextSource
from wormgear_cli.measurement.readers.table import TableSource, build_measurement
from wormgear_cli.measurement.readers.text import NUMBER, DelimitedBody, decimal_comma, split_cells

#: channel-name words of a velocity
_VELOCITY = re.compile(r"velo|speed|geschw|\bvel\b", re.I)
#: channel-name words of a position
_POSITION = re.compile(r"pos|angle|winkel", re.I)
#: channel-name words of the reference position (the target)
_REFERENCE = re.compile(r"set|target|soll|command|\bcmd\b|nominal|counter|internal|\bref|demand|open.?loop", re.I)
#: channel-name words of the measured position (the actual)
_MEASURED = re.compile(r"resolver|encoder|measured|laser|feedback|external|\bist\b|sensor", re.I)
#: a time cell above this is a FILETIME (100 ns ticks since 1601), below milliseconds from the first sample
FILETIME_FLOOR = 1e15


def looks_like_twincat_scope(head: str) -> bool:
    """A first line ``Name<sep>...`` and, among the metadata, ``SampleTime`` and ``SymbolName`` or
    ``Data-Type`` lines with the same separator."""
    first = next((line for line in head.split("\n", 64) if line.strip()), "")
    if not first.startswith("Name") or len(first) < 5 or first[4] not in ";,\t":
        return False
    sep = first[4]
    keys = {line.split(sep, 1)[0].strip() for line in head.split("\n", 200)[:200] if sep in line}
    return "SampleTime" in keys and ("SymbolName" in keys or "Data-Type" in keys)


def _metadata(source, name: str) -> tuple[str, list[tuple[int, list[str]]], int]:
    """(separator, metadata lines as (line number, cells), line number of the first data row): the
    metadata ends at the first line whose first cell is a number."""
    sep = source.head(5)[4]
    meta: list[tuple[int, list[str]]] = []
    line_no = 0
    for line_no, line in source.lines():
        if line.strip():
            cells = split_cells(line, sep, name, line_no)
            if cells and NUMBER.match(cells[0]):
                return sep, meta, line_no
            meta.append((line_no, [c.strip() for c in cells]))
    raise DataError(f"{name}:{line_no + 1}: no data rows after the TwinCAT Scope metadata (expected rows of a time "
                    "stamp and one value per channel)")


def _channels(meta, name: str) -> tuple[int, list[str], dict]:
    """(line of the channel ``Name`` line, channel names, property -> one cell per channel)."""
    at = max((i for i, (_, cells) in enumerate(meta) if cells and cells[0] == "Name"), default=None)
    if at is None:
        raise DataError(f"{name}:1: TwinCAT Scope export without a channel 'Name' line")
    line, cells = meta[at]
    names = cells[1:]
    while names and not names[-1]:
        names.pop()
    seen: dict = {}
    unique = []
    for n in names:  # two channels of one name: told apart by their position
        seen[n] = seen.get(n, 0) + 1
        unique.append(n if seen[n] == 1 else f"{n} #{seen[n]}")
    props = {cells[0]: cells[1:1 + len(names)] for _, cells in meta[at + 1:] if cells}
    return line, unique, props


def _roles(names: list[str], props: dict) -> tuple[tuple, str, str]:
    """The default (canonical, channel) assignment from the channel names, a sentence naming it, and
    the advice when the target and the actual position cannot be told apart."""
    comments = props.get("SymbolComment", [""] * len(names))
    velocity = [n for n in names if _VELOCITY.search(n)]
    positions = [n for n in names if n not in velocity and _POSITION.search(n)]
    roles = []
    if len(velocity) == 1:
        roles.append(("velocity", velocity[0]))
    if len(positions) == 1:
        roles.append(("angle_deg", positions[0]))
    elif len(positions) >= 2:
        def score(n):
            text = n + " " + (comments[names.index(n)] if names.index(n) < len(comments) else "")
            return len(_REFERENCE.findall(text)) - len(_MEASURED.findall(text))

        ranked = sorted(positions, key=score, reverse=True)
        if score(ranked[0]) > score(ranked[1]) and score(ranked[-1]) < score(ranked[-2]):
            roles += [("angle_deg", ranked[0]), ("actual_deg", ranked[-1])]
    said = {"angle_deg": "target", "actual_deg": "actual position", "velocity": "velocity"}
    text = ", ".join(f"{n!r} as the {said[c]}" for c, n in roles)
    hint = ""
    if len(positions) >= 2 and "actual_deg" not in dict(roles):
        hint = ("the channel names do not say which position is the target (a set point or counter) and which "
                f"the actual (a resolver or encoder): name them, e.g. --map angle_deg={quote(positions[0])} "
                f"--map actual_deg={quote(positions[1])}")
    return tuple(roles), text, hint


def read_twincat_scope(text: str, name: str, options: ReadOptions) -> Measurement:
    """Read a TwinCAT Scope CSV export (see the module doc); ``text`` with ``\\n`` line ends, no BOM."""
    return read_twincat_source(TextSource(text, name, options.block_chars), name, options)


def read_twincat_source(source, name: str, options: ReadOptions) -> Measurement:
    """Read a TwinCAT Scope CSV export from a source (:mod:`~.source`: a file read block by block)."""
    sep, meta, first_line = _metadata(source, name)
    header_line, names, props = _channels(meta, name)
    body = DelimitedBody(source, first_line, sep, 0, name, end_tag="EOF")
    lines = body.head_lines(50)
    first = split_cells(lines[0] if lines else "", sep, name, first_line)
    if len(first) == len(names) + 1:
        stamp = float(first[0].replace(",", "."))
        header = ["time (FILETIME)" if stamp > FILETIME_FLOOR else "time (ms)"] + names
    elif len(first) == len(names):
        header = list(names)
    else:
        raise DataError(f"{name}:{first_line}: {len(first)} cells per data row for {len(names)} channels "
                        f"({', '.join(names)}): export with one time column (Timelines: 'For each sampletime') "
                        "or none")
    body.ncols = len(header)
    units = {}
    for canon in ("angle_deg", "actual_deg"):
        stated = {stated_unit(f"x ({u})", canon) for u in props.get("Unit", []) if u and u != "(None)"}
        stated.discard(None)
        if len(stated) == 1:
            units[canon] = stated.pop()
    roles, said, hint = _roles(names, props)
    meta_lines = [cells for _, cells in meta]
    export = next((c[1] for c in meta_lines if c and c[0] == "Name" and len(c) > 1), "")
    notes = [f"TwinCAT Scope export {export!r}: metadata block skipped (lines 1-{first_line - 1}), {len(names)} "
             f"channels" + (f"; read {said} (another choice: --map angle_deg=CHANNEL --map actual_deg=CHANNEL)"
                            if said else "")]
    if not units and any(c in dict(roles) for c in ("angle_deg", "actual_deg")) and not options.angle_unit:
        notes.append("the export states no position unit (Unit (None)): positions read in degrees, as for a "
                     "rotary axis; use --angle-unit rad if they are radians")
    src = TableSource(name=name, header=header, header_line=header_line, body=body,
                      decimal_comma=decimal_comma(lines, sep), comments=(),
                      preamble=tuple(sep.join(cells) for cells in meta_lines), notes=notes, defaults=roles,
                      units=units, format_name="twincat-scope", hint=hint)
    return build_measurement(src, options)
