"""The measurement record and what every input format shares: :class:`Measurement`, :class:`ReadOptions`,
the canonical columns and their units, the bounded file read, time restarts.

The readers themselves are a registry of input formats (:mod:`wormgear_cli.measurement.readers`:
delimited tables, TwinCAT Scope exports, ...); each one turns the text of a file into a
:class:`Measurement`.  Canonical columns: ``angle_deg`` (target output angle) and ``error_arcsec``
(actual - target), required; or, instead of the error, ``actual_deg`` (the actual position: the
error is actual - target, wrapped to +/-180 deg); optional ``direction`` (+1/-1 or a direction
word), ``run`` (integer), ``load_Nm`` (external torque on the output, positive pushes the table
forward), ``temperature_C``, ``time_s``, and ``velocity`` (its sign gives the direction where the
file has none; standstill rows are left out).  Internally angles and errors are radians.

The names the former single reader module held (``read_measurement``, ``parse_measurement``,
``detect_dialect``, ``suggest_map``, ``plausibility``) still import from here, with a
DeprecationWarning naming their new home.
"""

from __future__ import annotations

import csv
import importlib
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wormgear_cli.errors import DataError, UsageError, moved
from wormgear_cli.files import read_text_file
from wormgear_cli.measurement.guidelog_options import GuideLogOptions
from wormgear_cli.physics.effects import Signals
from wormgear_cli.physics.signals import CONDITIONS, SIGNALS
from wormgear_cli.units import RAD_PER_UNIT

#: 1 arcsec [rad] (re-exported from :mod:`wormgear_cli.units`)
ARCSEC = RAD_PER_UNIT["arcsec"]
REQUIRED = ("angle_deg", "error_arcsec")
#: the optional columns: the direction, the run, and a column per operating condition (physics.signals)
OPTIONAL = (SIGNALS["direction"].column, "run", *(s.column for s in CONDITIONS))
#: columns read only to form others: the actual position (-> error) and the velocity (-> direction)
FORMING = ("actual_deg", "velocity")
CANONICAL = REQUIRED + OPTIONAL + FORMING

#: default value of an optional column that is absent
DEFAULTS = {SIGNALS["direction"].column: SIGNALS["direction"].default, "run": 0.0,
            **{s.column: s.default for s in CONDITIONS}}

#: units accepted for the error and the angle columns
ERROR_UNITS = ("arcsec", "arcmin", "deg", "urad", "mrad", "rad")
ANGLE_UNITS = ("deg", "rad")

#: largest measurement file read [bytes] (256 MiB: 7 to 11 million rows of four columns)
MAX_FILE_BYTES = 256 * 1024 * 1024
#: longest line read [bytes]: no header or row of a measurement is this long; a file of one
#: endless line is refused after this many bytes, not parsed
MAX_LINE_BYTES = 1024 * 1024
#: data lines sampled for the delimiter and decimal-comma detection
SNIFF_LINES = 50
#: characters (bytes, for a file) of the data lines read and converted per block: a block's
#: temporaries (its text, its cells) are the reader's only memory besides the typed columns
BLOCK_CHARS = 1 << 20


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
    input_format : str or None
        Name of an input format of :data:`wormgear_cli.measurement.readers.FORMATS`; None:
        detected from the content.
    require_error : bool
        Whether the error (or the actual position) is required; False for planned angles
        (``simulate --at``).
    block_chars : int
        Characters (bytes, for a file) of data lines read per block (:data:`BLOCK_CHARS`; a
        small value in tests puts block boundaries everywhere).
    guidelog : GuideLogOptions
        Sessions to read and values a PHD2 guide log may lack (``--session``, ``--pixel-scale``,
        ``--dec-deg``, ``--guide-rate``); given for a file of another format: a UsageError.
    """

    column_map: tuple = ()
    error_unit: str | None = None
    angle_unit: str | None = None
    max_bytes: int = MAX_FILE_BYTES
    input_format: str | None = None
    require_error: bool = True
    block_chars: int = BLOCK_CHARS
    guidelog: GuideLogOptions = GuideLogOptions()

    def __post_init__(self):
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
    cells of every data row (read again from the file when asked for, to write rows back);
    ``comments``: the leading ``#`` lines.  ``notes``: what the reader
    inferred; ``warnings``: what looks wrong (a likely unit mix-up), each a
    sentence with the likely fix.  ``columns``: canonical name -> header
    cell it was read from; ``units``: the units used for ``angle`` and
    ``error``.  ``preamble``: metadata lines before the header that are not
    ``#`` comments (skipped, said in ``notes``); ``stated_units``: which of
    "angle" and "error" have a unit the file states (a unit in the header, an
    instrument's unit row, an error formed from stated positions) or an option
    gives: never argued against; ``input_format``: the name of the format read;
    ``run_drift``: each run's errors have an offset and a drift in time of their
    own (a guide log's sessions: the reconstruction starts from an unknown
    offset, the drift changes over the night), so the analyses fit an offset
    and a drift per run.
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
    preamble: tuple = ()
    stated_units: frozenset = frozenset()
    input_format: str = "csv"
    run_drift: bool = False
    #: the rows' cells as a sequence read on demand (:class:`~wormgear_cli.measurement.readers.text.Rows`)
    _cells: object = field(default=None, repr=False, compare=False)
    #: a reader without a block source: the data lines' text, their delimiter and the indices of its data
    #: rows that are rows of the measurement (None: all)
    _body: str = field(default="", repr=False, compare=False)
    _delimiter: str = field(default=",", repr=False, compare=False)
    _kept: object = field(default=None, repr=False, compare=False)

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
    def rows(self):
        """The text cells of every row of the measurement (tuples of str), in file order (comment and
        blank lines, and rows the reader left out, are not rows): a sequence read from the file when it
        is asked for (``rows[a:b]`` reads only those rows), not kept in memory."""
        if self._cells is not None:
            return self._cells
        reader = csv.reader(self._body.rstrip("\n").split("\n"), delimiter=self._delimiter, strict=True)
        rows = tuple(tuple(r) for r in reader if r and any(c.strip() for c in r)
                     and not r[0].lstrip().startswith("#"))
        return rows if self._kept is None else tuple(rows[k] for k in np.asarray(self._kept).tolist())


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


#: names that moved to the readers (module -> names); imported on first use, with a DeprecationWarning
_MOVED = {
    "wormgear_cli.measurement.readers": ("read_measurement", "parse_measurement"),
    "wormgear_cli.measurement.readers.text": ("detect_dialect",),
    "wormgear_cli.measurement.readers.header": ("suggest_map",),
    "wormgear_cli.measurement.readers.plausibility": ("plausibility", "PLAUSIBLE_ERROR_P2P"),
    "wormgear_cli.measurement.readers.values": ("RANGES",),
}


def __getattr__(name: str):
    for module, names in _MOVED.items():
        if name in names:
            moved(f"wormgear_cli.measurement.reader.{name}", f"{module}.{name}")
            return getattr(importlib.import_module(module), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
