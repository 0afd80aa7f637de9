"""Cells to numbers: numeric columns, direction words, and the checks every value passes.

Numbers are plain ASCII decimal or exponent notation (no digit separators, no other scripts'
digits).  A direction is +1/-1 or a word as instruments and spreadsheets write it (up/down,
forward/reverse, fwd/rev, +/-, pos/neg, plus/minus, CW/CCW, and a few German and French words);
whether clockwise is forward is taken from the data (ISO 230-2: forward is the positive direction of
travel), see :func:`orient_rotation`.  Vectorised over the distinct cells (numpy), no I/O.
"""

from __future__ import annotations

import numpy as np

from wormgear_cli.errors import DataError
from wormgear_cli.physics.signals import CONDITIONS, SIGNALS

#: plausible range of each numeric column (inclusive, in the canonical unit); a value outside is a data error
RANGES = {
    "angle_deg": (-3.6e6, 3.6e6),  # 10 000 turns either way
    "actual_deg": (-3.6e6, 3.6e6),
    "error_arcsec": (-1e7, 1e7),
    "direction": (SIGNALS["direction"].lo, SIGNALS["direction"].hi),
    "run": (-1e9, 1e9),
    **{s.column: (s.lo, s.hi) for s in CONDITIONS},  # load, temperature, time: their records' ranges
    "velocity": (-1e12, 1e12),
}

#: direction words read as forward (+1) and reverse (-1), lower case
FORWARD_WORDS = ("+", "up", "fwd", "forward", "forwards", "pos", "positive", "plus", "incr", "increasing",
                 "ascending", "vor", "vorwärts", "vorwaerts", "auf", "avant")
REVERSE_WORDS = ("-", "down", "rev", "reverse", "backward", "backwards", "back", "neg", "negative", "minus",
                 "decr", "decreasing", "descending", "rück", "rückwärts", "rueckwaerts", "zurück", "ab", "arrière")
#: rotation words: which of them is forward depends on the viewpoint, so it is taken from the data
CLOCKWISE_WORDS = ("cw", "clockwise", "im uhrzeigersinn")
COUNTER_WORDS = ("ccw", "acw", "counterclockwise", "counter-clockwise", "anticlockwise", "anti-clockwise",
                 "gegen uhrzeigersinn", "gegen den uhrzeigersinn")
#: the accepted spellings, as messages list them
DIRECTION_HINT = "+1 or -1 or a direction word (up/down, forward/reverse, fwd/rev, +/-, pos/neg, CW/CCW)"


def shown(cell: str, most: int = 40) -> str:
    """A cell quoted for a message, cut to ``most`` characters saying how long it was."""
    cell = cell.strip()
    return repr(cell) if len(cell) <= most else f"{cell[:most]!r}... ({len(cell)} characters)"


def lenient_floats(cells: list[str], decimal_comma: bool) -> tuple[np.ndarray, int | None, int | None]:
    """Cells of one column as floats, NaN where a cell is not a number, and the first bad cells of
    the two kinds a message names, in this order: (values, index of the first cell with a digit
    separator ``_`` or a non-ASCII character, index of the first other cell that is not a number).
    A column is judged whole (over every block of a file): a cell of the first kind anywhere is
    named before one of the second."""
    if decimal_comma:
        cells = [c.replace(",", ".") for c in cells]
    joined = "".join(cells)
    odd = None
    if "_" in joined or not joined.isascii():
        odd = next(k for k, cell in enumerate(cells) if "_" in cell or not cell.isascii())
    try:
        return np.asarray(cells, dtype=float), odd, None
    except ValueError:
        arr = np.empty(len(cells))
        bad = None
        for k, cell in enumerate(cells):
            try:
                arr[k] = float(cell)
            except ValueError:
                arr[k] = np.nan
                bad = k if bad is None else bad
        return arr, odd, bad


def not_a_number(name: str, line: int, col: str, cell: str, decimal_comma: bool) -> DataError:
    """The message for a cell that is not a number (as read: a decimal comma made a point)."""
    if decimal_comma:
        cell = cell.replace(",", ".")
    return DataError(f"{name}:{line}: column {col}: expected a number, got {shown(cell)}")


def plain_number(cell: str) -> bool:
    """Whether a cell reads as a number (decimal point or comma); a direction column of such cells
    only is a column of numbers (+1/-1), else of words."""
    try:
        float(cell.replace(",", "."))
    except ValueError:
        return False
    return True


def direction_cells(cells, decimal_comma: bool) -> tuple[np.ndarray, np.ndarray, bool, int | None, int | None]:
    """Direction cells as they are in the file -> (+1, -1 or NaN where not a direction; True where a
    rotation word; whether every cell reads as a number; the first cells that are not numbers, of
    the two kinds of :func:`lenient_floats`, named when the column is numbers).  Each distinct cell
    is judged once."""
    uniq, inverse = np.unique(np.asarray(cells, dtype=str), return_inverse=True)
    inverse = np.ravel(inverse)
    value, rotation = direction_tokens(uniq)
    distinct = uniq.tolist()
    plain = all(plain_number(c) for c in distinct)
    flags = np.zeros((2, len(distinct)), dtype=bool)  # (a digit separator or non-ASCII, another non-number)
    for u, cell in enumerate(distinct):
        _, odd, bad = lenient_floats([cell], decimal_comma)
        flags[:, u] = odd is not None, bad is not None
    firsts = [int(np.flatnonzero(f[inverse])[0]) if f.any() else None for f in flags]
    return value[inverse], rotation[inverse], plain, firsts[0], firsts[1]


def direction_tokens(tokens) -> tuple[np.ndarray, np.ndarray]:
    """Direction cells (strings) -> (values: +1, -1, or NaN where not a direction; rotation: True
    where the cell is a rotation word, CW +1 and CCW -1 before :func:`orient_rotation`)."""
    tokens = np.asarray(tokens, dtype=str)
    uniq, inverse = np.unique(np.char.lower(np.char.strip(tokens)), return_inverse=True)
    value = np.full(uniq.size, np.nan)
    rotation = np.zeros(uniq.size, dtype=bool)
    for i, tok in enumerate(uniq.tolist()):
        if tok in FORWARD_WORDS or tok in REVERSE_WORDS:
            value[i] = 1.0 if tok in FORWARD_WORDS else -1.0
        elif tok in CLOCKWISE_WORDS or tok in COUNTER_WORDS:
            value[i], rotation[i] = (1.0 if tok in CLOCKWISE_WORDS else -1.0), True
        else:
            try:
                v = float(tok.replace(",", "."))
            except ValueError:
                continue
            if v in (1.0, -1.0):
                value[i] = v
    inverse = np.ravel(inverse)
    return value[inverse], rotation[inverse]


def orient_rotation(direction: np.ndarray, rotation: np.ndarray, angle: np.ndarray, run: np.ndarray) -> tuple[
        np.ndarray, str]:
    """Rotation words made forward or reverse from the data, and a sentence saying how.

    ISO 230-2 calls forward the positive direction of travel: the rotation word whose rows move to
    larger angles (median step between consecutive rows of the same word and run) is forward.  When
    the rows cannot tell (one angle per word and run), counter-clockwise is forward (the right-hand
    rule about the axis, seen from its positive end), and the sentence says so."""
    if not np.any(rotation):
        return direction, ""
    votes = 0.0
    for sign in (1.0, -1.0):  # CW rows, then CCW rows, each in file order within its runs
        idx = np.flatnonzero(rotation & (direction == sign))
        step = np.diff(angle[idx])[(run[idx][1:] == run[idx][:-1])]
        step = step[step != 0]
        if step.size:
            votes += sign * float(np.median(np.sign(step)))
    vote = float(np.sign(votes))
    out = direction.copy()
    if vote > 0:
        return out, "direction words CW/CCW: the CW rows move to larger angles, so CW is forward (+1)"
    if vote < 0:
        out[rotation] = -out[rotation]
        return out, "direction words CW/CCW: the CCW rows move to larger angles, so CCW is forward (+1)"
    out[rotation] = -out[rotation]
    return out, ("direction words CW/CCW: the rows do not show which one moves to larger angles; CCW is taken "
                 "as forward (+1, the right-hand rule about the axis): if CW is your forward direction, write "
                 "+1/-1 instead")


#: rows judged at a time by the checks (their temporaries stay a few hundred kB whatever the file)
BLOCK = 1 << 16


def first_row(bad, n: int, block: int = BLOCK) -> int | None:
    """The first index ``k`` < ``n`` where ``bad(a, b)`` (a bool array for rows ``a`` to ``b - 1``) is
    True, judged ``block`` rows at a time; None when there is none."""
    for a in range(0, n, block):
        hit = np.flatnonzero(bad(a, min(a + block, n)))
        if hit.size:
            return a + int(hit[0])
    return None


def check_range(name: str, col: str, label: str, arr: np.ndarray, scale: float, line_of, cell_of) -> None:
    """Finite and within :data:`RANGES` (after conversion by ``scale`` to the canonical unit)."""
    n = arr.shape[0]
    k = first_row(lambda a, b: ~np.isfinite(arr[a:b]), n)
    if k is not None:
        raise DataError(f"{name}:{line_of(k)}: column {label}: expected a finite number, got {shown(str(cell_of(k)))}")
    lo, hi = RANGES[col]

    def outside(a, b):
        conv = arr[a:b] * scale if scale != 1.0 else arr[a:b]
        return (conv < lo) | (conv > hi)

    k = first_row(outside, n)
    if k is not None:
        unit = "" if scale == 1.0 else f" ({col.split('_', 1)[1]})"
        raise DataError(f"{name}:{line_of(k)}: column {label}: expected a number in [{lo:g}, {hi:g}]{unit}, got "
                        f"{cell_of(k)!r}")
