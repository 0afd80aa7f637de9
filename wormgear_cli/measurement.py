"""Measured (or planned) rotary-table data: read and validate a CSV file.

Format: CSV with a header; lines starting with ``#`` before the header are
comments.  Required columns ``angle_deg`` (target output angle) and
``error_arcsec`` (actual - target); optional ``direction`` (+1/-1),
``run`` (integer), ``load_Nm`` (external torque on the output, positive
pushes the table forward), ``temperature_C``, ``time_s``.  Unknown columns
are kept (for writing rows back) and otherwise ignored.

Every problem raises :class:`DataError` naming the file, the line and the
column.  Internally angles are radians and errors radians.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wormgear_cli.errors import DataError
from wormgear_cli.models.effects import Signals

ARCSEC = math.pi / 648000.0
REQUIRED = ("angle_deg", "error_arcsec")
OPTIONAL = ("direction", "run", "load_Nm", "temperature_C", "time_s")

#: default value of an optional column that is absent
DEFAULTS = {"direction": 1.0, "run": 0.0, "load_Nm": 0.0, "temperature_C": 20.0, "time_s": 0.0}


@dataclass(frozen=True)
class Measurement:
    """A validated measurement.

    Arrays (one entry per row): ``angle`` [rad], ``error`` [rad] (NaN when the
    file had no ``error_arcsec`` and it was not required), ``direction``
    (+1/-1), ``run`` (int), ``load`` [N m], ``temperature`` [degC], ``time``
    [s].  ``present``: the optional columns the file had.  ``header`` and
    ``rows``: the original text cells (to write rows back), ``comments``:
    the leading ``#`` lines.
    """

    source: str
    angle: np.ndarray
    error: np.ndarray
    direction: np.ndarray
    run: np.ndarray
    load: np.ndarray
    temperature: np.ndarray
    time: np.ndarray
    present: frozenset
    header: tuple
    rows: tuple
    comments: tuple

    def __len__(self) -> int:
        return len(self.angle)

    def signals(self) -> Signals:
        """The operating conditions of every row for the simulation."""
        return Signals(self.angle, self.direction, self.load, self.temperature, self.time)

    @property
    def angle_deg(self) -> np.ndarray:
        return np.degrees(self.angle)

    @property
    def error_arcsec(self) -> np.ndarray:
        return self.error / ARCSEC


def read_measurement(path: str | Path, require_error: bool = True) -> Measurement:
    """Read and validate a measurement CSV (see module doc).  Raises DataError."""
    from wormgear_cli.io import read_text_file

    text = read_text_file(path, "a CSV file", DataError, encoding="utf-8-sig")
    name = str(path)
    return parse_measurement(text, name, require_error)


def _split_lines(text: str) -> list[str]:
    r"""Lines as an editor counts them (split at \n, \r\n or \r only), so line numbers match."""
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


#: plausible range of each numeric column (inclusive); a value outside is a data error
RANGES = {
    "angle_deg": (-3.6e6, 3.6e6),  # 10 000 turns either way
    "error_arcsec": (-1e7, 1e7),
    "direction": (-1.0, 1.0),
    "run": (-1e9, 1e9),
    "load_Nm": (-1e9, 1e9),
    "temperature_C": (-100.0, 300.0),
    "time_s": (-1e10, 1e10),
}


def _column(name: str, col: str, cells: list[str], line_numbers: list[int]) -> np.ndarray:
    """Cells of one column as floats; DataError naming the first bad cell.

    Numbers are plain ASCII decimal or exponent notation (no digit separators,
    no other scripts' digits), finite, and within the column's :data:`RANGES`."""
    joined = "".join(cells)
    if "_" in joined or not joined.isascii():
        for k, cell in enumerate(cells):
            if "_" in cell or not cell.isascii():
                raise DataError(f"{name}:{line_numbers[k]}: column {col}: expected a number, got "
                                f"{cell.strip()!r}")
    try:
        arr = np.asarray(cells, dtype=float)
    except ValueError:
        arr = np.empty(len(cells))
        for k, cell in enumerate(cells):
            try:
                arr[k] = float(cell)
            except ValueError:
                raise DataError(f"{name}:{line_numbers[k]}: column {col}: expected a number, got "
                                f"{cell.strip()!r}") from None
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        k = int(bad[0])
        raise DataError(f"{name}:{line_numbers[k]}: column {col}: expected a finite number, got "
                        f"{cells[k].strip()!r}")
    lo, hi = RANGES[col]
    bad = np.flatnonzero((arr < lo) | (arr > hi))
    if bad.size:
        k = int(bad[0])
        raise DataError(f"{name}:{line_numbers[k]}: column {col}: expected a number in [{lo:g}, {hi:g}], got "
                        f"{cells[k].strip()!r}")
    return arr


def parse_measurement(text: str, name: str = "<data>", require_error: bool = True) -> Measurement:
    """Parse CSV text (see :func:`read_measurement`)."""
    lines = _split_lines(text)
    if lines and lines[-1] == "":
        lines.pop()
    comments = []
    start = 0
    while start < len(lines) and (lines[start].lstrip().startswith("#") or not lines[start].strip()):
        if lines[start].strip():
            comments.append(lines[start])
        start += 1
    if start >= len(lines):
        if comments:
            raise DataError(f"{name}:{len(lines) + 1}: no CSV header after the comment lines, expected one "
                            f"with {', '.join(REQUIRED)}")
        raise DataError(f"{name}:1: empty file, expected a CSV header with {', '.join(REQUIRED)}")
    reader = csv.reader(lines[start:], strict=True)
    header_line = start + 1
    try:
        header = [h.strip() for h in next(reader)]
    except csv.Error as exc:
        raise DataError(f"{name}:{header_line}: unreadable CSV header ({exc})") from None
    required = REQUIRED if require_error else REQUIRED[:1]
    missing = [c for c in required if c not in header]
    if missing:
        raise DataError(f"{name}:{header_line}: missing required column{'s' if len(missing) > 1 else ''} "
                        f"{', '.join(missing)} (header has: {', '.join(header) or 'nothing'})")
    dupes = sorted({h for h in header if header.count(h) > 1 and h in REQUIRED + OPTIONAL})
    if dupes:
        raise DataError(f"{name}:{header_line}: column {dupes[0]} appears twice")
    rows = []
    line_numbers = []
    ncols = len(header)
    while True:
        try:
            row = next(reader)
        except StopIteration:
            break
        except csv.Error as exc:
            raise DataError(f"{name}:{start + reader.line_num}: unreadable CSV line ({exc})") from None
        line_no = start + reader.line_num
        if not row or all(not c.strip() for c in row):
            continue
        if row[0].lstrip().startswith("#"):
            continue
        if len(row) != ncols:
            raise DataError(f"{name}:{line_no}: expected {ncols} cells as in the header, got {len(row)}")
        rows.append(tuple(row))
        line_numbers.append(line_no)
    if not rows:
        raise DataError(f"{name}:{header_line}: no data rows after the header")
    if len(rows) < 2:
        raise DataError(f"{name}:{line_numbers[0]}: only one data row; at least two are needed")
    index = {h: i for i, h in enumerate(header)}
    values = {}
    for col in REQUIRED + OPTIONAL:
        if col not in index:
            continue
        j = index[col]
        values[col] = _column(name, col, [row[j] for row in rows], line_numbers)
    if "direction" in values:
        bad = np.flatnonzero((values["direction"] != 1.0) & (values["direction"] != -1.0))
        if bad.size:
            k = bad[0]
            raise DataError(f"{name}:{line_numbers[k]}: column direction: expected +1 or -1, got "
                            f"{rows[k][index['direction']].strip()!r}")
    if "run" in values:
        bad = np.flatnonzero(values["run"] != np.round(values["run"]))
        if bad.size:
            k = bad[0]
            raise DataError(f"{name}:{line_numbers[k]}: column run: expected an integer, got "
                            f"{rows[k][index['run']].strip()!r}")
    angle = values["angle_deg"]
    if np.all(angle == angle[0]):
        raise DataError(f"{name}:{line_numbers[0]}: column angle_deg: all {len(rows)} rows have the same "
                        f"angle ({angle[0]:g}); a measurement needs several targets")
    n = len(rows)

    def col(c):
        return values[c] if c in values else np.full(n, DEFAULTS[c])

    error = values["error_arcsec"] * ARCSEC if "error_arcsec" in values else np.full(n, np.nan)
    return Measurement(
        source=name,
        angle=np.radians(angle),
        error=error,
        direction=col("direction"),
        run=col("run").astype(int),
        load=col("load_Nm"),
        temperature=col("temperature_C"),
        time=col("time_s"),
        present=frozenset(c for c in OPTIONAL if c in values),
        header=tuple(header),
        rows=tuple(rows),
        comments=tuple(comments),
    )
