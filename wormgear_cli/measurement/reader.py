"""Measured (or planned) rotary-table data: read and validate a CSV file as it comes.

Format: delimited text with a header; lines starting with ``#`` before the
header are comments.  Canonical columns: ``angle_deg`` (target output angle)
and ``error_arcsec`` (actual - target), required; optional ``direction``
(+1/-1), ``run`` (integer), ``load_Nm`` (external torque on the output,
positive pushes the table forward), ``temperature_C``, ``time_s``.  Unknown
columns are kept (for writing rows back) and otherwise ignored.

Files as spreadsheets and instruments write them are accepted:

* delimiter ``,``, ``;`` or tab, found by :class:`csv.Sniffer` on the header
  and the first data lines; where the Sniffer fails or its answer does not
  split every sampled line into the same number of cells, the delimiter is
  the candidate that does (tab, then ``;``, then ``,``);
* decimal comma, when the delimiter is not ``,`` and a sampled numeric cell
  is written ``12,5`` (and none mixes ``,`` and ``.``);
* UTF-8 with or without BOM, LF, CRLF or CR line ends;
* a unit in the header, ``angle (deg)``, ``error [arcmin]``: English base
  names (angle, error, direction, run, load, temperature, time) with a unit
  suffix are recognised, and the unit is used unless an option says
  otherwise;
* any other header through :class:`ReadOptions` ``column_map`` (``--map
  angle_deg=Position``) and the units ``error_unit`` / ``angle_unit``.

Structure the file does not state: without a run column, a new pass starts
where ``time_s`` goes backwards (sessions joined end to end); the derived
run index is used like a run column and said so in ``notes``.

Bounds: at most :data:`MAX_FILE_BYTES` are read; binary content (NUL bytes
or invalid UTF-8 in the first block) is refused before the rest is read.

Every problem raises :class:`DataError` naming the file, the line and the
column.  Internally angles and errors are radians.
"""

from __future__ import annotations

import csv
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wormgear_cli.errors import DataError
from wormgear_cli.physics.effects import Signals
from wormgear_cli.units import RAD_PER_UNIT

#: 1 arcsec [rad] (re-exported from :mod:`wormgear_cli.units`)
ARCSEC = RAD_PER_UNIT["arcsec"]
REQUIRED = ("angle_deg", "error_arcsec")
OPTIONAL = ("direction", "run", "load_Nm", "temperature_C", "time_s")
CANONICAL = REQUIRED + OPTIONAL

#: default value of an optional column that is absent
DEFAULTS = {"direction": 1.0, "run": 0.0, "load_Nm": 0.0, "temperature_C": 20.0, "time_s": 0.0}

#: units accepted for the error and the angle columns
ERROR_UNITS = ("arcsec", "arcmin", "deg", "urad")
ANGLE_UNITS = ("deg", "rad")

#: largest measurement file read [bytes] (256 MiB: 7 to 11 million rows of four columns)
MAX_FILE_BYTES = 256 * 1024 * 1024
#: longest line read [bytes]: no header or row of a measurement is this long; a file of one
#: endless line is refused after this many bytes, not parsed
MAX_LINE_BYTES = 1024 * 1024
#: first block inspected for binary content before the rest is read [bytes]
#: data lines sampled for the delimiter and decimal-comma detection
SNIFF_LINES = 50
#: rows converted per block on the fast path (bounds the temporary memory)
BLOCK_CHARS = 4_000_000


@dataclass(frozen=True)
class ReadOptions:
    """How to read a measurement file whose header or units are not canonical.

    Parameters
    ----------
    column_map : tuple of (str, str)
        (canonical name, header cell as found), e.g. ``(("angle_deg",
        "Position"),)``; a mapped column wins over a recognised one.
    error_unit : str or None
        Unit of the error column, one of :data:`ERROR_UNITS`; None: the unit
        in the header (``error (arcmin)``), else arcsec.
    angle_unit : str or None
        Unit of the angle column, ``deg`` or ``rad``; None: from the header,
        else deg.
    max_bytes : int
        Largest file read [bytes].
    """

    column_map: tuple = ()
    error_unit: str | None = None
    angle_unit: str | None = None
    max_bytes: int = MAX_FILE_BYTES

    def __post_init__(self):
        from wormgear_cli.errors import UsageError

        problems = []
        seen = Counter(c for c, _ in self.column_map)
        for canon, _header in self.column_map:
            if canon not in CANONICAL:
                problems.append(f"--map {canon}=...: unknown column name {canon!r}, expected one of "
                                f"{', '.join(CANONICAL)}")
        for canon, count in seen.items():
            if count > 1 and canon in CANONICAL:
                problems.append(f"--map {canon}=... given {count} times; give each column once")
        if self.error_unit is not None and self.error_unit not in ERROR_UNITS:
            problems.append(f"--error-unit {self.error_unit}: expected one of {', '.join(ERROR_UNITS)}")
        if self.angle_unit is not None and self.angle_unit not in ANGLE_UNITS:
            problems.append(f"--angle-unit {self.angle_unit}: expected one of {', '.join(ANGLE_UNITS)}")
        if problems:
            raise UsageError(problems)


@dataclass(frozen=True)
class Measurement:
    """A validated measurement.

    Arrays (one entry per row): ``angle`` [rad], ``error`` [rad] (NaN when the
    file had no error column and it was not required), ``direction``
    (+1/-1), ``run`` (int), ``load`` [N m], ``temperature`` [degC], ``time``
    [s].  ``present``: the optional columns available to the analysis (read
    from the file, or derived: see ``derived``).  ``derived``: the columns
    inferred rather than read (``run`` from restarts of ``time_s``).
    ``header``: the original header cells; ``rows``: the original text
    cells of every data row (parsed again on demand, to write rows back);
    ``comments``: the leading ``#`` lines.  ``notes``: what the reader
    inferred; ``warnings``: what looks wrong (a likely unit mix-up), each a
    sentence with the likely fix.  ``columns``: canonical name -> header
    cell it was read from; ``units``: the units used for ``angle`` and
    ``error``.
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
    comments: tuple
    derived: frozenset = frozenset()
    notes: tuple = ()
    warnings: tuple = ()
    columns: tuple = ()
    units: tuple = (("angle", "deg"), ("error", "arcsec"))
    _body: str = field(default="", repr=False, compare=False)
    _delimiter: str = field(default=",", repr=False, compare=False)

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

    @property
    def rows(self) -> tuple:
        """The text cells of every data row, in file order (comment and blank lines left out)."""
        reader = csv.reader(self._body.rstrip("\n").split("\n"), delimiter=self._delimiter, strict=True)
        return tuple(tuple(r) for r in reader if r and any(c.strip() for c in r)
                     and not r[0].lstrip().startswith("#"))


# --- reading bytes ------------------------------------------------------------------------------------------


def read_bytes_bounded(path: str | Path, expected: str = "a CSV file", limit: int = MAX_FILE_BYTES) -> str:
    """The UTF-8 text of a user-named input (BOM tolerated), at most ``limit`` bytes.

    The one bounded reader of user files (:func:`wormgear_cli.files.read_text_file`) with the
    measurement's own size limit and error class.

    Raises
    ------
    DataError
        Missing file, directory, unreadable, binary (a NUL byte, refused at the first
        chunk), not UTF-8, larger than ``limit`` (endless inputs such as ``/dev/zero``
        stop at the first chunk or at the limit), or a line longer than :data:`MAX_LINE_BYTES`.
    """
    from wormgear_cli.files import read_text_file

    return read_text_file(path, expected, DataError, encoding="utf-8-sig", max_bytes=limit,
                          max_line_bytes=MAX_LINE_BYTES)


def time_restarts(time) -> np.ndarray | None:
    """(N,) bool, True where ``time`` [s] goes backwards from the previous row (sessions joined
    end to end, each restarting its clock): the start of a new pass.  None without a time column.
    The one definition, used by the reader (derived runs) and by diagnose's run structure."""
    if time is None:
        return None
    t = np.asarray(time, dtype=float)
    out = np.zeros(t.shape[0], dtype=bool)
    out[1:] = t[1:] < t[:-1]
    return out


def read_measurement(path: str | Path, require_error: bool = True, options: ReadOptions | None = None) -> Measurement:
    """Read and validate a measurement file (see the module doc).

    Parameters
    ----------
    path : str or Path
        The CSV file.
    require_error : bool
        Whether the error column is required.
    options : ReadOptions or None
        Column map and units (None: canonical names and units).

    Raises
    ------
    DataError
        One line per problem, naming file, line and column.
    """
    from wormgear_cli.spec.filekind import looks_like_drive

    options = options or ReadOptions()
    text = read_bytes_bounded(path, "a CSV file", options.max_bytes)
    if looks_like_drive(text):  # a drive spec where the data belong: say so, not "missing columns"
        raise DataError(f"{path}: a TOML drive spec, not a measurement; expected a CSV file with a header "
                        "line such as angle_deg,error_arcsec")
    return parse_measurement(text, str(path), require_error, options)


# --- header: recognition, map, suggestions ------------------------------------------------------------------

#: English base names recognised with a unit suffix -> canonical column
_BASES = {"angle": "angle_deg", "position": "angle_deg", "error": "error_arcsec", "deviation": "error_arcsec",
          "direction": "direction", "run": "run", "load": "load_Nm", "torque": "load_Nm",
          "temperature": "temperature_C", "time": "time_s"}
#: unit spellings -> (unit, the canonical columns it fits)
_UNITS = {
    "deg": ("deg", ("angle_deg", "error_arcsec")), "°": ("deg", ("angle_deg", "error_arcsec")),
    "degree": ("deg", ("angle_deg", "error_arcsec")), "degrees": ("deg", ("angle_deg", "error_arcsec")),
    "rad": ("rad", ("angle_deg",)),
    "arcsec": ("arcsec", ("error_arcsec",)), '"': ("arcsec", ("error_arcsec",)), "″": ("arcsec", ("error_arcsec",)),
    "arcmin": ("arcmin", ("error_arcsec",)), "'": ("arcmin", ("error_arcsec",)), "′": ("arcmin", ("error_arcsec",)),
    "urad": ("urad", ("error_arcsec",)), "µrad": ("urad", ("error_arcsec",)), "μrad": ("urad", ("error_arcsec",)),
    "nm": (None, ("load_Nm",)), "n m": (None, ("load_Nm",)), "n·m": (None, ("load_Nm",)),
    "°c": (None, ("temperature_C",)), "c": (None, ("temperature_C",)), "degc": (None, ("temperature_C",)),
    "s": (None, ("time_s",)), "sec": (None, ("time_s",)),
}
#: keywords (several languages) that suggest a canonical column, for the --map hint
_KEYWORDS = {
    "angle_deg": ("angle", "position", "pos", "winkel", "angulo", "ángulo", "posición", "posicion", "angolo",
                  "posizione", "hoek", "kąt", "theta", "target", "soll", "ziel"),
    "error_arcsec": ("error", "deviation", "abweichung", "fehler", "erreur", "écart", "ecart", "desviación",
                     "desviacion", "errore", "deviazione", "afwijking", "błąd", "dev", "err", "ist-soll"),
    "direction": ("direction", "richtung", "sens", "dirección", "direccion", "verso", "richting", "dir"),
    "run": ("run", "lauf", "durchgang", "pass", "cycle", "zyklus", "série", "serie", "ciclo", "passe"),
    "load_Nm": ("load", "torque", "last", "moment", "drehmoment", "charge", "carga", "carico"),
    "temperature_C": ("temperature", "temperatur", "température", "temperatura", "temp"),
    "time_s": ("time", "zeit", "temps", "tiempo", "tempo", "tijd", "t"),
}
_SUFFIX = re.compile(r"^(.*?)\s*[\(\[]\s*([^\)\]]*?)\s*[\)\]]$")


def _split_unit(cell: str) -> tuple[str, str | None]:
    """``"Position (deg)"`` -> ("position", "deg"); no suffix -> (lower-case cell, None)."""
    m = _SUFFIX.match(cell.strip())
    if not m:
        return cell.strip().lower(), None
    return m.group(1).strip().lower(), m.group(2).strip().lower()


def _recognise(cell: str) -> tuple[str | None, str | None]:
    """(canonical column, unit) of a header cell recognised without a map, else (None, None)."""
    if cell in CANONICAL:  # angle_deg and error_arcsec state their unit too (checked against the options)
        return cell, {"angle_deg": "deg", "error_arcsec": "arcsec"}.get(cell)
    base, unit = _split_unit(cell)
    canon = _BASES.get(base)
    if canon is None or unit is None or unit not in _UNITS:
        return None, None
    u, fits = _UNITS[unit]
    if canon not in fits:
        return None, None
    return canon, u


def _guess(cell: str) -> str | None:
    """The canonical column a header cell most likely is (unit suffix first, then keywords), or None."""
    base, unit = _split_unit(cell)
    if unit is not None and unit in _UNITS:
        fits = _UNITS[unit][1]
        if len(fits) == 1:
            return fits[0]
        for canon in fits:
            if any(k == base or base.startswith(k) for k in _KEYWORDS[canon]):
                return canon
        return fits[0]
    words = re.split(r"[^\w°]+", base)
    for canon, keys in _KEYWORDS.items():
        if any(w in keys for w in words if w):
            return canon
    return None


def _quote(cell: str) -> str:
    return cell if re.fullmatch(r"[\w.\-]+", cell) else '"' + cell.replace('"', '\\"') + '"'


def suggest_map(header: list[str], resolved: dict[str, int]) -> list[str]:
    """``--map`` arguments that would fit ``header``, for the columns not yet ``resolved``."""
    used = set(resolved.values())
    out = []
    taken = set(resolved)
    for j, cell in enumerate(header):
        if j in used or not cell:
            continue
        canon = _guess(cell)
        if canon is not None and canon not in taken:
            taken.add(canon)
            out.append((CANONICAL.index(canon), f"--map {canon}={_quote(cell)}"))
    return [s for _, s in sorted(out)]


def _resolve_header(header: list[str], options: ReadOptions, name: str, line: int,
                    required: tuple) -> tuple[dict[str, int], dict[str, str | None]]:
    """Canonical column -> index, and the unit each column's header states."""
    problems = []
    counts = Counter(header)
    index: dict[str, int] = {}
    hunit: dict[str, str | None] = {}
    for j, cell in enumerate(header):
        canon, unit = _recognise(cell)
        if canon is None:
            continue
        if canon in index:
            if header[index[canon]] == cell:
                problems.append(f"{name}:{line}: column {cell} appears twice")
            else:
                problems.append(f"{name}:{line}: columns {header[index[canon]]!r} and {cell!r} both give {canon}; "
                                f"choose one with --map {canon}=...")
            continue
        index[canon] = j
        hunit[canon] = unit
    for canon, cell in options.column_map:
        cell = cell.strip()
        if cell not in counts:
            problems.append(f"{name}:{line}: --map {canon}={_quote(cell)}: no such column (header has: "
                            f"{', '.join(header) or 'nothing'})")
            continue
        if counts[cell] > 1:
            problems.append(f"{name}:{line}: column {cell} appears twice")
            continue
        j = header.index(cell)
        for other, k in list(index.items()):
            if k == j and other != canon:
                del index[other]
        index[canon] = j
        hunit[canon] = _recognise_unit(cell, canon)
    if problems:
        raise DataError(sorted(set(problems), key=problems.index))
    missing = [c for c in required if c not in index]
    if missing:
        hint = suggest_map(header, index)
        fix = f"; try {' '.join(hint)}" if hint else "; name the columns with --map CANONICAL=HEADER"
        raise DataError(f"{name}:{line}: missing required column{'s' if len(missing) > 1 else ''} "
                        f"{', '.join(missing)} (header has: "
                        f"{', '.join(_clipped(h) for h in header) or 'nothing'}){fix}")
    return index, hunit


def _recognise_unit(cell: str, canon: str) -> str | None:
    _, unit = _split_unit(cell)
    if unit is None or unit not in _UNITS:
        return None
    u, fits = _UNITS[unit]
    return u if canon in fits else None


# --- dialect ------------------------------------------------------------------------------------------------

_DELIMS = ("\t", ";", ",")
_COMMA_NUMBER = re.compile(r"^\s*[-+]?\d*,\d+([eE][-+]?\d+)?\s*$")


def detect_dialect(header_line: str, sample: list[str]) -> tuple[str, bool, str]:
    """(delimiter, decimal comma, how it was found) from the header line and sampled data lines.

    :class:`csv.Sniffer` restricted to tab, ``;`` and ``,`` is asked first;
    its answer is kept when it splits the header and every sampled line into
    the same number (>= 2) of cells.  Otherwise the candidate that does so
    (tab, ``;``, ``,`` in that order) is taken ("rule"); a one-column file
    falls back to ``,``.
    """
    lines = [header_line] + [s for s in sample if s.strip() and not s.lstrip().startswith("#")]

    def consistent(d: str) -> bool:
        counts = {len(next(csv.reader([s], delimiter=d))) for s in lines}
        return len(counts) == 1 and counts.pop() >= 2

    how = "sniffer"
    try:
        delim = csv.Sniffer().sniff("\n".join(lines), delimiters="".join(_DELIMS)).delimiter
    except csv.Error:
        delim = None
    if delim is None or not consistent(delim):
        how = "rule"
        delim = next((d for d in _DELIMS if consistent(d)), None)
        if delim is None:
            delim = max(_DELIMS, key=lambda d: header_line.count(d)) if any(d in header_line for d in _DELIMS) else ","
    decimal_comma = False
    if delim != ",":
        cells = [c for s in lines[1:] for c in s.split(delim)]
        decimal_comma = any(_COMMA_NUMBER.match(c) for c in cells) and not any("," in c and "." in c for c in cells)
    return delim, decimal_comma, how


# --- numbers ------------------------------------------------------------------------------------------------

#: plausible range of each numeric column (inclusive, in the canonical unit); a value outside is a data error
RANGES = {
    "angle_deg": (-3.6e6, 3.6e6),  # 10 000 turns either way
    "error_arcsec": (-1e7, 1e7),
    "direction": (-1.0, 1.0),
    "run": (-1e9, 1e9),
    "load_Nm": (-1e9, 1e9),
    "temperature_C": (-100.0, 300.0),
    "time_s": (-1e10, 1e10),
}


def _column(name: str, col: str, cells: list[str], line_numbers: list[int], decimal_comma: bool) -> np.ndarray:
    """Cells of one column as floats; DataError naming the first bad cell.

    Numbers are plain ASCII decimal or exponent notation (no digit separators,
    no other scripts' digits)."""
    if decimal_comma:
        cells = [c.replace(",", ".") for c in cells]
    joined = "".join(cells)
    if "_" in joined or not joined.isascii():
        for k, cell in enumerate(cells):
            if "_" in cell or not cell.isascii():
                raise DataError(f"{name}:{line_numbers[k]}: column {col}: expected a number, got "
                                f"{_shown(cell)}")
    try:
        return np.asarray(cells, dtype=float)
    except ValueError:
        arr = np.empty(len(cells))
        for k, cell in enumerate(cells):
            try:
                arr[k] = float(cell)
            except ValueError:
                raise DataError(f"{name}:{line_numbers[k]}: column {col}: expected a number, got "
                                f"{_shown(cell)}") from None
        return arr


def _clipped(text: str, most: int = 40) -> str:
    """``text`` cut to ``most`` characters for a message, saying how long it was (a cell may be megabytes)."""
    return text if len(text) <= most else f"{text[:most]}... ({len(text)} characters)"


def _shown(cell: str, most: int = 40) -> str:
    """A cell quoted for a message, cut like :func:`_clipped`."""
    cell = cell.strip()
    return repr(cell) if len(cell) <= most else f"{cell[:most]!r}... ({len(cell)} characters)"


def _check_values(name: str, col: str, label: str, arr: np.ndarray, scale: float, line_of, cell_of) -> None:
    """Finite and within :data:`RANGES` (after conversion by ``scale`` to the canonical unit)."""
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        k = int(bad[0])
        raise DataError(f"{name}:{line_of(k)}: column {label}: expected a finite number, got {_shown(str(cell_of(k)))}")
    lo, hi = RANGES[col]
    conv = arr * scale if scale != 1.0 else arr
    bad = np.flatnonzero((conv < lo) | (conv > hi))
    if bad.size:
        k = int(bad[0])
        unit = "" if scale == 1.0 else f" ({col.split('_', 1)[1]})"
        raise DataError(f"{name}:{line_of(k)}: column {label}: expected a number in [{lo:g}, {hi:g}]{unit}, got "
                        f"{cell_of(k)!r}")


def _split_lines(text: str) -> list[str]:
    r"""Lines as an editor counts them (split at \n, \r\n or \r only), so line numbers match."""
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


class _Body:
    """The data lines after the header: fast block conversion, exact messages on the slow path."""

    def __init__(self, body: str, first_line: int, delim: str, ncols: int, name: str):
        self.body, self.first_line, self.delim, self.ncols, self.name = body, first_line, delim, ncols, name
        self._rows = None  # (rows, line numbers) of the slow path
        self.blank_rows: list[int] = []  # line numbers of rows whose every cell is empty (",,,"), left out

    def slow(self):
        if self._rows is None:
            lines_in = self.body.split("\n")
            if lines_in and lines_in[-1] == "":
                lines_in.pop()
            reader = csv.reader(lines_in, delimiter=self.delim, strict=True)
            rows, lines = [], []
            while True:
                try:
                    row = next(reader)
                except StopIteration:
                    break
                except csv.Error as exc:
                    raise DataError(f"{self.name}:{self.first_line - 1 + reader.line_num}: unreadable CSV line "
                                    f"({exc})") from None
                line_no = self.first_line - 1 + reader.line_num
                if not row or all(not c.strip() for c in row) or row[0].lstrip().startswith("#"):
                    if len(row) > 1 and all(not c.strip() for c in row):
                        self.blank_rows.append(line_no)  # delimiters and nothing else: said in the notes
                    continue
                if len(row) != self.ncols:
                    raise DataError(f"{self.name}:{line_no}: expected {self.ncols} cells as in the header, got "
                                    f"{len(row)}")
                rows.append(row)
                lines.append(line_no)
            self._rows = (rows, lines)
        return self._rows

    def fast(self, cols: list[int], decimal_comma: bool) -> np.ndarray | None:
        """All rows of ``cols`` as an (n, len(cols)) array, or None when the slow path must decide."""
        body = self.body
        if not body.isascii() or any(ch in body for ch in ('"', "#", "_")):
            return None
        lines_est = body.count("\n") + (0 if body.endswith("\n") else 1)
        blank = body.count("\n\n") + body.startswith("\n")
        if blank or body.count(self.delim) != (self.ncols - 1) * lines_est:
            return None  # blank lines or a cell count off somewhere: let the slow path decide (and say where)
        parts = []
        pos, size = 0, len(body)
        try:
            while pos < size:
                end = body.find("\n", pos + BLOCK_CHARS)
                end = size if end < 0 else end + 1
                block = body[pos:end]
                if decimal_comma:
                    block = block.replace(",", ".")
                parts.append(np.loadtxt(block.splitlines(), delimiter=self.delim, dtype=float, ndmin=2,
                                        usecols=cols, comments=None, quotechar=None))
                pos = end
        except ValueError:
            return None
        return np.concatenate(parts) if parts else np.empty((0, len(cols)))

    def line_of(self, k: int) -> int:
        """File line number of data row ``k``."""
        if self._rows is None and "\n\n" not in self.body and not self.body.startswith("\n"):
            return self.first_line + k
        return self.slow()[1][k]

    def cell_of(self, k: int, j: int, decimal_comma: bool) -> str:
        line = self.body.split("\n")[self.line_of(k) - self.first_line]
        return next(csv.reader([line], delimiter=self.delim))[j].strip()


def parse_measurement(text: str, name: str = "<data>", require_error: bool = True,
                      options: ReadOptions | None = None) -> Measurement:
    """Parse measurement text (see :func:`read_measurement`)."""
    # the csv module refuses a cell over 128 KiB with its own exception (a traceback, not a DataError);
    # a cell is at most as long as the text, so it is parsed and then judged like any other cell
    limit = csv.field_size_limit()
    csv.field_size_limit(max(limit, len(text) + 1))
    try:
        return _parse_measurement(text, name, require_error, options)
    finally:
        csv.field_size_limit(limit)


def _parse_measurement(text: str, name: str, require_error: bool, options: ReadOptions | None) -> Measurement:
    options = options or ReadOptions()
    if text.startswith("\ufeff"):
        text = text[1:]
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    # comments and blank lines before the header, without splitting the whole text
    pos = 0
    line_no = 1
    comments = []
    size = len(text)
    while pos < size:
        end = text.find("\n", pos)
        end = size if end < 0 else end
        line = text[pos:end]
        if line.strip() and not line.lstrip().startswith("#"):
            break
        if line.strip():
            comments.append(line)
        pos = end + 1
        line_no += 1
    if pos >= size:
        if comments:
            raise DataError(f"{name}:{line_no}: no CSV header after the comment lines, expected one "
                            f"with {', '.join(REQUIRED)}")
        raise DataError(f"{name}:1: empty file, expected a CSV header with {', '.join(REQUIRED)}")
    header_line_no = line_no
    end = text.find("\n", pos)
    end = size if end < 0 else end
    header_text = text[pos:end]
    body = text[end + 1:] if end < size else ""
    del text
    sample_end = 0
    for _ in range(SNIFF_LINES):
        nxt = body.find("\n", sample_end)
        if nxt < 0:
            sample_end = len(body)
            break
        sample_end = nxt + 1
    sample = body[:sample_end].split("\n")
    delim, decimal_comma, how = detect_dialect(header_text, sample)
    try:
        header = [h.strip() for h in next(csv.reader([header_text], delimiter=delim, strict=True))]
    except csv.Error as exc:
        raise DataError(f"{name}:{header_line_no}: unreadable CSV header ({exc})") from None
    required = REQUIRED if require_error else REQUIRED[:1]
    index, hunit = _resolve_header(header, options, name, header_line_no, required)

    data = _Body(body, header_line_no + 1, delim, len(header), name)
    cols = [c for c in CANONICAL if c in index]
    arr = data.fast([index[c] for c in cols], decimal_comma)
    if arr is None:
        rows, line_numbers = data.slow()
        if not rows:
            raise DataError(f"{name}:{header_line_no}: no data rows after the header")
        if len(rows) < 2:
            raise DataError(f"{name}:{line_numbers[0]}: only one data row; at least two are needed")
        values = {c: _column(name, _label(c, header, index), [r[index[c]] for r in rows], line_numbers,
                             decimal_comma) for c in cols}
        del rows
    else:
        if arr.shape[0] == 0:
            raise DataError(f"{name}:{header_line_no}: no data rows after the header")
        if arr.shape[0] < 2:
            raise DataError(f"{name}:{header_line_no + 1}: only one data row; at least two are needed")
        values = {c: np.ascontiguousarray(arr[:, i]) for i, c in enumerate(cols)}
        del arr
    n = len(next(iter(values.values())))

    # units
    notes: list[str] = []
    warnings: list[str] = []
    if data.blank_rows:
        k = len(data.blank_rows)
        first = ", ".join(str(line) for line in data.blank_rows[:3])
        more = f" and {k - 3} more" if k > 3 else ""
        notes.append(f"{k} row{'s' if k != 1 else ''} with every cell empty left out (line{'s' if k != 1 else ''} "
                     f"{first}{more})")
    angle_unit = options.angle_unit or hunit.get("angle_deg") or "deg"
    error_unit = options.error_unit or hunit.get("error_arcsec") or "arcsec"
    for canon, chosen, opt in (("angle_deg", angle_unit, "--angle-unit"), ("error_arcsec", error_unit, "--error-unit")):
        stated = hunit.get(canon)
        if canon in index and stated is not None and stated != chosen and header[index[canon]] == canon:
            # the canonical name is the name the tool asks for, so an explicit option is a deliberate choice:
            # said, not warned about
            notes.append(f"column {canon!r} read in {chosen} ({opt} {chosen}), not in the {stated} its name says")
        elif canon in index and stated is not None and stated != chosen:
            warnings.append(f"column {header[index[canon]]!r} says {stated} but is read as {chosen} ({opt} "
                            f"{chosen}); if the header is right, use {opt} {stated}")
        elif canon in index and stated is not None and header[index[canon]] != canon and not (
                opt == "--angle-unit" and options.angle_unit or opt == "--error-unit" and options.error_unit):
            if stated != ("deg" if canon == "angle_deg" else "arcsec"):
                notes.append(f"column {header[index[canon]]!r} read in {stated}, the unit its header states")
    scale = {"angle_deg": RAD_PER_UNIT[angle_unit] / RAD_PER_UNIT["deg"],
             "error_arcsec": RAD_PER_UNIT[error_unit] / RAD_PER_UNIT["arcsec"]}

    for c in cols:
        _check_values(name, c, _label(c, header, index), values[c], scale.get(c, 1.0), data.line_of,
                      lambda k, j=index[c]: data.cell_of(k, j, decimal_comma))
    if "direction" in values:
        bad = np.flatnonzero((values["direction"] != 1.0) & (values["direction"] != -1.0))
        if bad.size:
            k = int(bad[0])
            raise DataError(f"{name}:{data.line_of(k)}: column {_label('direction', header, index)}: expected "
                            f"+1 or -1, got {data.cell_of(k, index['direction'], decimal_comma)!r}")
    if "run" in values:
        bad = np.flatnonzero(values["run"] != np.round(values["run"]))
        if bad.size:
            k = int(bad[0])
            raise DataError(f"{name}:{data.line_of(k)}: column {_label('run', header, index)}: expected an "
                            f"integer, got {data.cell_of(k, index['run'], decimal_comma)!r}")

    def col(c):
        return values[c] if c in values else np.full(n, DEFAULTS[c])

    present = {c for c in OPTIONAL if c in values}
    derived = set()
    run = col("run").astype(np.int64)
    if "run" not in values and "time_s" in values and n > 1:
        back = np.flatnonzero(time_restarts(values["time_s"])) - 1
        if back.size:
            run = np.zeros(n, dtype=np.int64)
            run[back + 1] = 1
            run = np.cumsum(run)
            present.add("run")
            derived.add("run")
            first = ", ".join(str(data.line_of(int(k) + 1)) for k in back[:3])
            more = f" and {back.size - 3} more" if back.size > 3 else ""
            notes.append(f"no run column: time_s goes backwards at line{'s' if back.size > 1 else ''} {first}{more}, "
                         f"taken as the start of a new pass ({back.size + 1} passes); add a run column to say "
                         "so explicitly")
    angle = values["angle_deg"] * (RAD_PER_UNIT[angle_unit])
    if "error_arcsec" in values:
        error = values["error_arcsec"] * RAD_PER_UNIT[error_unit]
    else:
        error = np.full(n, np.nan)
    warnings += plausibility(angle, error, angle_unit, error_unit, "error_arcsec" in values)
    return Measurement(
        source=name,
        angle=angle,
        error=error,
        direction=col("direction"),
        run=run,
        load=col("load_Nm"),
        temperature=col("temperature_C"),
        time=col("time_s"),
        present=frozenset(present),
        header=tuple(header),
        comments=tuple(comments),
        derived=frozenset(derived),
        notes=tuple(notes),
        warnings=tuple(warnings),
        columns=tuple((c, header[index[c]]) for c in cols),
        units=(("angle", angle_unit), ("error", error_unit)),
        _body=body,
        _delimiter=delim,
    )


def _label(canon: str, header: list[str], index: dict[str, int]) -> str:
    """How a column is named in messages: its canonical name, and the header cell when that differs."""
    cell = header[index[canon]]
    return canon if cell == canon else f"{canon} ({cell!r})"


# --- plausibility -------------------------------------------------------------------------------------------

#: peak-to-peak error that a positioning measurement plausibly has [arcsec]: 0.05" .. 2 deg
PLAUSIBLE_ERROR_P2P = (0.05, 7200.0)


def plausibility(angle: np.ndarray, error: np.ndarray, angle_unit: str, error_unit: str, has_error: bool) -> list[str]:
    """Warnings when the sizes suggest the columns are in another unit than the one used.

    Parameters
    ----------
    angle, error : ndarray [rad], shape (n,)
        As read (converted with ``angle_unit`` / ``error_unit``).
    angle_unit, error_unit : str
        The units used.
    has_error : bool
        Whether the file had an error column.

    Returns
    -------
    list of str
        One sentence per suspicion with the likely fix: an error whose
        peak-to-peak lies outside :data:`PLAUSIBLE_ERROR_P2P` when a
        different unit of :data:`ERROR_UNITS` would bring it inside (e.g.
        degrees or radians read as arcsec); angles read in degrees that all
        lie within +/-2 pi and spread over more than 1 "degree" with at least
        8 distinct values (radians read as degrees).
    """
    out = []
    arc = RAD_PER_UNIT["arcsec"]
    if has_error and error.size:
        p2p = float(np.ptp(error)) / arc
        lo, hi = PLAUSIBLE_ERROR_P2P
        if p2p > 0 and not lo <= p2p <= hi:
            raw = p2p * arc / RAD_PER_UNIT[error_unit]
            fits = [(abs(np.log(raw * RAD_PER_UNIT[u] / arc / 20.0)), u) for u in ERROR_UNITS + ("rad",)
                    if u != error_unit and lo <= raw * RAD_PER_UNIT[u] / arc <= hi]
            if fits:
                u = min(fits)[1]
                fix = (f"--error-unit {u}" if u in ERROR_UNITS
                       else "convert the column (radians) to urad and use --error-unit urad")
                out.append(f"the errors span {p2p:.4g} arcsec peak to peak read as {error_unit}, implausible for a "
                           f"positioning error; if the column is in {u}, use {fix}")
    if angle_unit == "deg" and angle.size:
        deg = np.degrees(angle)
        if (np.max(np.abs(deg)) <= 2 * np.pi + 1e-9 and float(np.ptp(deg)) > 1.0
                and np.unique(deg).size >= 8):
            out.append(f"the angles all lie within +/-2 pi and span {float(np.ptp(deg)):.3g} deg: if they are "
                       "radians, use --angle-unit rad")
    return out
