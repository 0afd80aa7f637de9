"""Which column of a table is which: header cells recognised (any case; the unit in brackets, after a
slash, after `` in `` or as a last ``_`` suffix), ``--map``, and the ``--map`` a header would need.

Recognised without a map: the canonical names in any case (``Angle_Deg``, ``DIRECTION``); English
base names with a unit (``angle (deg)``, ``error [arcmin]``, ``Time / s``, ``target position
(deg)``, ``actual (deg)``); the unit-free columns by name alone (``Direction``, ``run``,
``velocity``).  A column in encoder counts (``Position (counts)``) is never taken, suggested or
accepted as an angle: counts need a conversion the file does not state.  Pure text, no I/O.
"""

from __future__ import annotations

import re
from collections import Counter

from wormgear_cli.errors import DataError
from wormgear_cli.measurement.reader import CANONICAL, REQUIRED
from wormgear_cli.measurement.readers.text import NUMBER

#: English base names recognised with a unit (or, for unit-free columns, alone) -> canonical column
_BASES = {
    "angle": "angle_deg", "position": "angle_deg", "target": "angle_deg", "target position": "angle_deg",
    "target angle": "angle_deg", "nominal": "angle_deg", "nominal position": "angle_deg",
    "nominal angle": "angle_deg", "commanded position": "angle_deg", "set position": "angle_deg",
    "setpoint": "angle_deg",
    "actual": "actual_deg", "actual position": "actual_deg", "actual angle": "actual_deg",
    "measured": "actual_deg", "measured position": "actual_deg", "measured angle": "actual_deg",
    "error": "error_arcsec", "deviation": "error_arcsec", "position error": "error_arcsec",
    "angular error": "error_arcsec", "angle error": "error_arcsec",
    "direction": "direction", "run": "run", "load": "load_Nm", "torque": "load_Nm",
    "temperature": "temperature_C", "time": "time_s", "timestamp": "time_s",
    "velocity": "velocity", "speed": "velocity", "actual velocity": "velocity",
}
#: canonical columns recognised by their base name alone, without a unit
UNIT_FREE = ("direction", "run", "velocity")
_ANGLES = ("angle_deg", "actual_deg", "error_arcsec")
#: unit spellings -> (unit, the canonical columns it fits)
_UNITS = {
    "deg": ("deg", _ANGLES), "°": ("deg", _ANGLES), "degree": ("deg", _ANGLES), "degrees": ("deg", _ANGLES),
    "rad": ("rad", _ANGLES), "radian": ("rad", _ANGLES), "radians": ("rad", _ANGLES),
    "mrad": ("mrad", ("error_arcsec",)),
    "arcsec": ("arcsec", ("error_arcsec",)), '"': ("arcsec", ("error_arcsec",)), "″": ("arcsec", ("error_arcsec",)),
    "arcmin": ("arcmin", ("error_arcsec",)), "'": ("arcmin", ("error_arcsec",)), "′": ("arcmin", ("error_arcsec",)),
    "urad": ("urad", ("error_arcsec",)), "µrad": ("urad", ("error_arcsec",)), "μrad": ("urad", ("error_arcsec",)),
    "nm": (None, ("load_Nm",)), "n m": (None, ("load_Nm",)), "n·m": (None, ("load_Nm",)),
    "°c": (None, ("temperature_C",)), "c": (None, ("temperature_C",)), "degc": (None, ("temperature_C",)),
    "s": ("s", ("time_s",)), "sec": ("s", ("time_s",)), "ms": ("ms", ("time_s",)), "min": ("min", ("time_s",)),
    "h": ("h", ("time_s",)), "filetime": ("filetime", ("time_s",)),
}
#: unit spellings of encoder counts: such a column is not an angle in any unit the tool reads
COUNT_UNITS = ("counts", "count", "cts", "cnt", "inc", "incr", "increments", "ticks", "steps", "pulses", "lsb",
               "digits", "bits", "raw")
#: unit spellings of lengths: a column in one holds a linear axis's position or error, not an angle
LENGTH_UNITS = ("mm", "um", "µm", "μm", "micron", "microns", "micrometre", "micrometres", "micrometer",
                "micrometers", "cm", "m", "in", "inch", "inches", "thou", "mil", "mils")
#: keywords (several languages) that suggest a canonical column, for the --map hint
_KEYWORDS = {
    "angle_deg": ("angle", "position", "pos", "winkel", "angulo", "ángulo", "posición", "posicion", "angolo",
                  "posizione", "hoek", "kąt", "theta", "target", "soll", "ziel", "sollposition", "nominal"),
    "error_arcsec": ("error", "deviation", "abweichung", "fehler", "erreur", "écart", "ecart", "desviación",
                     "desviacion", "errore", "deviazione", "afwijking", "błąd", "dev", "err", "ist-soll"),
    "direction": ("direction", "richtung", "sens", "dirección", "direccion", "verso", "richting", "dir"),
    "run": ("run", "lauf", "durchgang", "pass", "cycle", "zyklus", "série", "serie", "ciclo", "passe"),
    "load_Nm": ("load", "torque", "last", "moment", "drehmoment", "charge", "carga", "carico"),
    "temperature_C": ("temperature", "temperatur", "température", "temperatura", "temp"),
    "time_s": ("time", "zeit", "temps", "tiempo", "tempo", "tijd", "t"),
    "actual_deg": ("actual", "ist", "istposition", "measured", "gemessen", "réel", "reel", "mesuré", "mesure"),
    "velocity": ("velocity", "speed", "geschwindigkeit", "vitesse", "velocidad", "velocità", "vel"),
}
#: longest header cell a --map hint names (a longer one is not a column name anyone types)
MAX_SUGGESTED = 100
_SUFFIX = re.compile(r"^(.*?)\s*[\(\[]\s*([^\)\]]*?)\s*[\)\]]$")
_SLASH = re.compile(r"^(.*?\S)\s*/\s*([^/]+?)$")
_IN = re.compile(r"^(.*?\S)\s+in\s+(\S+)$", re.IGNORECASE)
_UNDERSCORE = re.compile(r"^(.*?[^_\s])_([^_\s]+)$")


def _known(unit: str) -> bool:
    """Whether ``unit`` (lower case) is a unit spelling the tool knows: an angle, time, load or temperature
    it reads, or a length or encoder counts it refuses as an angle."""
    return unit in _UNITS or unit in LENGTH_UNITS or unit in COUNT_UNITS


def split_unit(cell: str) -> tuple[str, str | None]:
    """``"Position (deg)"``, ``"Position [deg]"``, ``"Position / deg"``, ``"Position in deg"``,
    ``"Position_deg"`` -> ("position", "deg"); no unit -> (lower-case cell, None).  A unit in brackets
    is taken as written; after ``/``, `` in `` or a last ``_`` only a unit the tool knows (an angle,
    time, load, temperature, length or counts), so ``run_1`` keeps its name.  Underscores and runs of
    spaces in the base read as one space."""
    text = cell.strip()
    base, unit = text, None
    m = _SUFFIX.match(text)
    if m:
        base, unit = m.group(1), m.group(2).strip().lower()
    else:
        for form in (_SLASH, _IN, _UNDERSCORE):
            m = form.match(text)
            if m and form is _UNDERSCORE and m.group(2).lower() == "in":  # angle_in: the input side, not inches
                continue
            if m and _known(m.group(2).strip().lower()):
                base, unit = m.group(1), m.group(2).strip().lower()
                break
    return " ".join(base.replace("_", " ").split()).lower(), unit


def is_counts(cell: str) -> bool:
    """Whether a header cell states encoder counts as its unit (``Position (counts)``, ``enc [inc]``)."""
    return split_unit(cell)[1] in COUNT_UNITS


def recognise(cell: str) -> tuple[str | None, str | None]:
    """(canonical column, unit) of a header cell recognised without a map, else (None, None)."""
    low = cell.strip().lower()
    for known in CANONICAL:  # the canonical names in any case; angle_deg and error_arcsec state a unit too
        if low == known.lower():
            return known, {"angle_deg": "deg", "actual_deg": "deg", "error_arcsec": "arcsec", "time_s": "s"}.get(known)
    base, unit = split_unit(cell)
    canon = _BASES.get(base)
    if canon is None:
        return None, None
    if canon in UNIT_FREE:
        return canon, None
    if unit is None or unit not in _UNITS:
        return None, None
    u, fits = _UNITS[unit]
    return (canon, u) if canon in fits else (None, None)


def canonical_unit(canon: str) -> str | None:
    """The unit a canonical name states (``error_arcsec``: arcsec), None for unit-free columns."""
    return recognise(canon)[1]


def stated_unit(cell: str, canon: str) -> str | None:
    """The unit a header cell states for ``canon`` (``"Abweichung (arcmin)"`` -> arcmin), else None."""
    _, unit = split_unit(cell)
    if unit is None or unit not in _UNITS:
        return None
    u, fits = _UNITS[unit]
    return u if canon in fits else None


def _guess(cell: str) -> str | None:
    """The canonical column a header cell most likely is (unit suffix first, then keywords), or None."""
    base, unit = split_unit(cell)
    if unit in COUNT_UNITS or unit in LENGTH_UNITS:
        return None
    if unit is not None and unit in _UNITS:
        fits = _UNITS[unit][1]
        if len(fits) == 1:
            return fits[0]
        for exact in (True, False):
            for canon in fits:
                if any(k == base or (not exact and base.startswith(k)) for k in _KEYWORDS[canon]):
                    return canon
        return fits[0]
    words = re.split(r"[^\w°]+", base)
    for canon, keys in _KEYWORDS.items():
        if any(w in keys for w in words if w):
            return canon
    return None


def quote(cell: str) -> str:
    """A header cell as it is typed after ``--map NAME=`` in a shell."""
    return cell if re.fullmatch(r"[\w.\-]+", cell) else '"' + cell.replace('"', '\\"') + '"'


def looks_like_counts(cells: list[str]) -> bool:
    """Whether sampled cells are whole numbers of an encoder's size (an angle column holds few whole
    numbers beyond two turns): at least 4 cells, every one an integer, the largest above 720."""
    values = []
    for c in cells:
        c = c.strip()
        if not re.fullmatch(r"[-+]?\d+", c):
            return False
        values.append(abs(int(c)))
    return len(values) >= 4 and max(values) > 720


def _fits(canon: str, cells: list[str] | None) -> bool:
    """Whether sampled cells could be column ``canon``: numbers (a direction may be words), and no
    encoder counts for an angle."""
    if cells is None:
        return True
    cells = [c for c in cells if c.strip()]
    if not cells:
        return False
    if canon == "direction":
        return True
    if not all(NUMBER.match(c) for c in cells):
        return False
    return not (canon in _ANGLES and looks_like_counts(cells))


def suggest_map(header: list[str], resolved: dict[str, int], sample=None) -> list[str]:
    """``--map`` arguments that would fit ``header``, for the columns not yet ``resolved``.

    ``sample(j)``: sampled cells of column ``j`` (None: not checked).  A column is suggested only
    when its cells fit (numbers; never a column of encoder counts as an angle), so a metadata value
    mistaken for a header is not proposed."""
    used = set(resolved.values())
    out = []
    taken = set(resolved)
    if "error_arcsec" in taken:
        taken.add("actual_deg")
    for j, cell in enumerate(header):
        if j in used or not cell or len(cell) > MAX_SUGGESTED:
            continue
        canon = _guess(cell)
        if canon is None or canon in taken or not _fits(canon, None if sample is None else sample(j)):
            continue
        taken.add(canon)
        if canon == "actual_deg":
            taken.add("error_arcsec")
        elif canon == "error_arcsec":
            taken.add("actual_deg")
        out.append((CANONICAL.index(canon), f"--map {canon}={quote(cell)}"))
    return [s for _, s in sorted(out)]


def _clipped(text: str, most: int = 40) -> str:
    """``text`` cut to ``most`` characters for a message, saying how long it was (a cell may be megabytes)."""
    return text if len(text) <= most else f"{text[:most]}... ({len(text)} characters)"


def _find_mapped(header: list[str], counts: Counter, cell: str) -> int | str:
    """Index of the header cell named by a --map (exact, else the one cell equal in any case), or a problem."""
    if counts[cell] > 1:
        return f"column {cell} appears twice"
    if cell in counts:
        return header.index(cell)
    folded = [j for j, h in enumerate(header) if h.lower() == cell.lower()]
    if len(folded) == 1:
        return folded[0]
    return ""


def resolve_header(header: list[str], column_map, name: str, line: int, required: tuple, defaults=(),
                   sample=None, hint: str = "") -> tuple[dict[str, int], dict[str, str | None]]:
    """Canonical column -> index, and the unit each column's header states.

    ``column_map``: (canonical, header cell) pairs of ``--map`` (they win); ``defaults``: the
    format's own assignment (canonical, header cell), used where neither a map nor a recognised
    header gives the column; ``required``: canonical columns that must be found (``error_arcsec``
    is satisfied by ``actual_deg``); ``sample(j)``: cells of column ``j`` for the hint; ``hint``: the
    format's own advice when no ``--map`` can be guessed.

    Raises
    ------
    DataError
        A column twice, two columns for one name, a --map naming no column, a column of encoder
        counts read as an angle, a required column missing (with the header found and a --map
        that fits).
    """
    problems = []
    counts = Counter(header)
    index: dict[str, int] = {}
    hunit: dict[str, str | None] = {}
    for j, cell in enumerate(header):
        canon, unit = recognise(cell)
        if canon is None:
            continue
        if canon in index:
            if header[index[canon]] == cell:
                problems.append(f"{name}:{line}: column {cell} appears twice")
            elif header[index[canon]].strip().lower() == canon.lower():
                continue  # the canonical name wins over another spelling of it (angle_deg beside angle_rad)
            elif cell.strip().lower() == canon.lower():
                index[canon], hunit[canon] = j, unit
            else:
                problems.append(f"{name}:{line}: columns {header[index[canon]]!r} and {cell!r} both give {canon}; "
                                f"choose one with --map {canon}=...")
            continue
        index[canon] = j
        hunit[canon] = unit
    mapped = {canon for canon, _ in column_map}
    for canon, cell in defaults:
        if canon not in index and canon not in mapped and cell in counts and header.index(cell) not in index.values():
            index[canon] = header.index(cell)
            hunit[canon] = stated_unit(cell, canon)
    for canon, cell in column_map:
        cell = cell.strip()
        at = _find_mapped(header, counts, cell)
        if isinstance(at, str):
            problems.append(f"{name}:{line}: " + (at or f"--map {canon}={quote(cell)}: no such column (header has: "
                                                   f"{', '.join(header) or 'nothing'})"))
            continue
        for other, k in list(index.items()):
            if k == at and other != canon:
                del index[other]
        index[canon] = at
        hunit[canon] = stated_unit(header[at], canon)
        said = split_unit(header[at])[1]
        if said in _UNITS and canon not in _UNITS[said][1] and said not in LENGTH_UNITS:
            takes = sorted({u for u, fits in _UNITS.values() if u and canon in fits})
            problems.append(f"{name}:{line}: column {header[at]!r} states {said}, a unit {canon} is not read in "
                            f"(it takes {', '.join(takes) or 'no unit'}): convert it in a column of its own, or map "
                            "the column it belongs to")
    for canon, j in index.items():
        unit = split_unit(header[j])[1]
        if canon in (*_ANGLES, "error_arcsec") and unit in LENGTH_UNITS:
            problems.append(f"{name}:{line}: column {header[j]!r} states a length ({unit}), not an angle: a rotary "
                            f"axis's {'error' if canon == 'error_arcsec' else 'position'} is read as an angle; "
                            "convert it (angle = arc length / the radius it was measured at) in a column of its own "
                            f"and read that as {canon}")
    for canon in _ANGLES:
        if canon in index and is_counts(header[index[canon]]):
            problems.append(f"{name}:{line}: column {header[index[canon]]!r} holds encoder counts, not an angle: "
                            f"convert it to degrees (counts x 360 / counts per turn) in a column of its own and "
                            f"read that as {canon}")
    if problems:
        raise DataError(sorted(set(problems), key=problems.index))
    missing = [c for c in required if c not in index and not (c == "error_arcsec" and "actual_deg" in index)]
    if missing:
        guessed = suggest_map(header, index, sample)
        lengths = [h for h in header if split_unit(h)[1] in LENGTH_UNITS]
        fix = (f"; try {' '.join(guessed)}" if guessed else f"; {hint}" if hint
               else "; name the columns with --map CANONICAL=HEADER")
        if lengths:  # not proposed: a length read as an angle gives numbers, all wrong
            fix += (f" ({', '.join(map(quote, lengths))} state{'s' if len(lengths) == 1 else ''} a length, not an "
                    "angle: convert it to one, arc length / the radius it was measured at, in a column of its own)")
        raise DataError(f"{name}:{line}: missing required column{'s' if len(missing) > 1 else ''} "
                        f"{', '.join(missing)} (header has: "
                        f"{', '.join(_clipped(h) for h in header) or 'nothing'}){fix}")
    return index, hunit


__all__ = ["REQUIRED", "canonical_unit", "is_counts", "recognise", "resolve_header", "split_unit", "stated_unit",
           "suggest_map"]
