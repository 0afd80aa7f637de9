"""Text formats shared by every command and by the Python API: numbers, CSV, JSON, tables.

No I/O, no typer, no rich.  The CLI renders what these functions build; a notebook can use
them to get exactly the bytes the CLI writes.

* :func:`fmt_number`, :func:`csv_text`: CSV of Python values (shortest round-trip floats).
* :func:`format_g`, :func:`csv_block`: vectorised ``'%.12g'`` CSV of numpy columns (the
  sweep's 10^6-row files).
* :func:`json_text`: deterministic JSON (NaN/inf -> null).
* :func:`fmt_angle`: an angle for a table cell, at the unit's natural resolution.
* Tables as data (:class:`Table`, :class:`Column`, :class:`Cell`) live in
  :mod:`wormgear_cli.output.tables` (still importable from here).
"""

from __future__ import annotations

import io
import json
import math
from collections.abc import Iterable
from typing import TYPE_CHECKING

from wormgear_cli.errors import DataError

if TYPE_CHECKING:  # numpy is imported where the fast formatter first runs
    import numpy as np

#: significant digits of numbers in the sweep's (i, l) CSV ('%.12g'; ~1e-12 relative)
CSV_DIGITS = 12


def __getattr__(name: str):
    # the table classes moved to wormgear_cli.output.tables (one topic per module, and ``analyze``
    # does not pay for three dataclasses it does not draw); the old names still work
    if name in ("Cell", "Column", "Table"):
        from wormgear_cli.output import tables  # lazy: an old name, resolved on first use

        return getattr(tables, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: version of the layout of every JSON document the commands write (CHANGELOG.md lists what changed);
#: 2: stages as a list from the motor to the output (analyze), budget lines with their stage
SCHEMA_VERSION = 2


def json_text(doc) -> str:
    """Deterministic JSON (key order as built, shortest round-trip floats, NaN/inf -> null).  A
    document (a dict) carries ``schema_version`` (:data:`SCHEMA_VERSION`) as its first key."""
    if isinstance(doc, dict) and "schema_version" not in doc:
        doc = {"schema_version": SCHEMA_VERSION, **doc}
    return json.dumps(_clean(doc), indent=2, allow_nan=False) + "\n"


def _clean(obj):
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if hasattr(obj, "item") and not isinstance(obj, (str, bytes)):
        return _clean(obj.item())
    return obj


def fmt_number(x) -> str:
    """CSV number: shortest repr that round-trips; integers as integers; None (undefined) empty;
    text through :func:`wormgear_cli.errors.csv_cell` (a leading ``= + - @`` neutralised)."""
    if x is None:
        return ""
    if isinstance(x, bool):
        return str(int(x))
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if not math.isfinite(x):
            return ""
        return repr(float(x))  # float(): numpy's float64 is a float whose repr names its type
    if hasattr(x, "item"):
        return fmt_number(x.item())
    from wormgear_cli.errors import csv_cell  # text: never a spreadsheet formula or a control character

    return csv_cell(str(x))


def csv_text(columns: list[str], rows: Iterable[Iterable], header: bool = True) -> str:
    """CSV text (stdlib csv, "\\n" line ends) of ``rows``, numbers by :func:`fmt_number`.

    Raises DataError for a cell holding a line break (:func:`one_row_per_line`)."""
    import csv  # only the CSV paths pay for it (start-up of ``analyze --format json``)

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    if header:
        w.writerow(columns)
    for row in rows:
        w.writerow([fmt_number(v) for v in row])
    return one_row_per_line(buf.getvalue())


def one_row_per_line(text: str) -> str:
    """``text`` (CSV) unchanged, or DataError when a quoted cell holds a line break.

    Every reader of the tool refuses such a cell with its line number (a cell split over lines would
    be joined into another value: ``"1<newline>2"`` read as 12), so no writer writes one.  Checked only
    where the text holds a quote (a cell with a line break is always quoted)."""
    if '"' in text:
        for k, line in enumerate(text.split("\n"), start=1):
            if line.count('"') % 2:
                raise DataError(f"CSV output line {k}: a cell would hold a line break ({line[:40]!r}...); each "
                                "row must be one line for the file to read back")
    return text


def fmt_angle(x: float, unit: str) -> str:
    """Angle for tables: 4 significant digits beyond the unit's natural scale."""
    if unit == "deg":
        return f"{x:.5f}"
    if unit == "arcmin":
        return f"{x:.3f}"
    if unit == "arcsec":
        return f"{x:.2f}"
    return f"{x:.1f}"


# --- fast deterministic number formatting ----------------------------------------------------
#
# CSV of 10^6 rows is mostly number formatting; Python's per-value repr costs ~1 us each.
# These functions produce exactly '%.{digits}g' % v for every value, vectorised: the decimal
# mantissa is one rounded scaling (rows whose scaled mantissa is within the scaling's error of
# a rounding tie are handed to Python, so the result is exact), its digits come from a 4-digit
# lookup table, and each field is laid out in a fixed-width byte matrix whose unused bytes are
# 0 and deleted at the end.


def _tables():
    import numpy as np  # lazy: keeps numpy off `analyze`'s start-up

    global _DIGITS4, _POW10
    if _DIGITS4 is None:
        _DIGITS4 = np.frombuffer("".join(f"{k:04d}" for k in range(10000)).encode(), dtype=np.uint32).copy()
        _POW10 = np.array([float(f"1e{k}") for k in range(-330, 331)])  # exact decimal -> nearest double
    return _DIGITS4, _POW10


_DIGITS4: np.ndarray | None = None  # built on first use (numpy is imported lazily)
_POW10: np.ndarray | None = None


def format_g(x, digits: int = CSV_DIGITS):
    """'%.{digits}g' % v for every v of ``x`` as an (n, W) uint8 matrix of ASCII bytes, unused
    bytes 0 (NaN gives an empty field).  1 <= digits <= 15."""
    import numpy as np  # lazy: keeps numpy off `analyze`'s start-up

    p = int(digits)
    if not 1 <= p <= 15:
        raise ValueError("digits must be in 1..15")
    digits4, pow10 = _tables()
    x = np.ascontiguousarray(x, dtype=float).ravel()
    n = x.size
    a = np.abs(x)
    finite = np.isfinite(x)
    zero = a == 0.0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        e = np.floor(np.log10(np.where(finite & ~zero, a, 1.0))).astype(np.int64)
        e = np.clip(e, -320, 320)
        e -= a < pow10[e + 330]
        e += a >= pow10[np.minimum(e + 331, 660)]
        sh = p - 1 - e
        ok = finite & ~zero & (np.abs(e) <= 280)  # the rest (|x| < 1e-280 or > 1e280) by Python
        sh = np.where(ok, sh, 0)
        scaled = np.where(sh >= 0, a * pow10[np.clip(sh, 0, 330) + 330], a / pow10[np.clip(-sh, 0, 330) + 330])
        scaled = np.where(ok, scaled, 0.0)
        rounded = np.rint(scaled)
    # one rounding of the scaling: error < 2^-52 * 10^p; near-ties go to Python (exact)
    ok &= np.abs(scaled - rounded) < 0.5 - 1e-3 * 10.0 ** (p - 12)
    m = np.where(ok, rounded, 0.0).astype(np.int64)
    up = m >= 10 ** p
    m = np.where(up, m // 10, m)
    e = np.where(up, e + 1, e)
    hi, lo = np.divmod(m, 10 ** 8)
    d4 = np.empty((n, 4), np.uint32)
    d4[:, 0] = digits4[hi // 10000]
    d4[:, 1] = digits4[hi % 10000]
    d4[:, 2] = digits4[lo // 10000]
    d4[:, 3] = digits4[lo % 10000]
    raw = d4.view(np.uint8)[:, 16 - p:]  # all p digits
    nz = raw != 48
    k = np.where(m == 0, 1, p - np.argmax(nz[:, ::-1], axis=1))  # significant digits kept
    dig = raw * (np.arange(p)[None, :] < k[:, None])  # trailing zeros -> 0 (deleted)
    width = 1 + max(p + 1, p + 5, p + 7)
    out = np.zeros((n, width), np.uint8)
    out[:, 0] = (np.signbit(x) & finite) * np.uint8(ord("-"))
    dot = np.uint8(ord("."))
    sci = ok & ((e < -4) | (e >= p))
    idx = np.flatnonzero(sci)
    if idx.size:
        sub = np.zeros((idx.size, width), np.uint8)
        ds, ks, es = dig[idx], k[idx], e[idx]
        sub[:, 1] = ds[:, 0]
        sub[:, 2] = (ks > 1) * dot
        sub[:, 3:2 + p] = ds[:, 1:]
        sub[:, 2 + p] = ord("e")
        sub[:, 3 + p] = np.where(es < 0, ord("-"), ord("+"))
        ae = np.abs(es)
        sub[:, 4 + p] = (ae >= 100) * (48 + ae // 100)
        sub[:, 5 + p] = 48 + (ae // 10) % 10
        sub[:, 6 + p] = 48 + ae % 10
        out[idx, 1:] = sub[:, 1:]
    pos = ok & ~sci
    for ev in np.unique(e[pos]):
        sel = pos & (e == ev)
        full = bool(sel.all())
        idx = np.empty(0, np.intp) if full else np.flatnonzero(sel)  # (rows of this exponent, when not all)
        ds, rs, ks = (dig, raw, k) if full else (dig[idx], raw[idx], k[idx])
        sub = out if full else np.zeros((idx.size, width), np.uint8)
        if ev >= 0:
            ni = int(ev) + 1
            sub[:, 1:1 + ni] = rs[:, :ni]
            sub[:, 1 + ni] = (ks > ni) * dot
            sub[:, 2 + ni:2 + p] = ds[:, ni:]
        else:
            z = -int(ev) - 1
            sub[:, 1] = 48
            sub[:, 2] = dot
            sub[:, 3:3 + z] = 48
            sub[:, 3 + z:3 + z + p] = ds
        if not full:
            out[idx, 1:] = sub[:, 1:]
    out[zero & finite, 1] = 48
    for j in np.flatnonzero(~ok & ~zero):
        v = float(x[j])
        text = b"" if v != v else (b"%.*g" % (p, v))
        out[j, :] = 0
        out[j, :len(text)] = np.frombuffer(text, np.uint8)
    if n:
        used = np.flatnonzero(out.any(axis=0))
        out = out[:, :used[-1] + 1] if used.size else out[:, :1]
        if out.shape[1] > 1 and not out[:, 0].any():
            out = out[:, 1:]
    return out


def csv_block(columns, digits: int = CSV_DIGITS) -> bytes:
    """CSV rows (no header) of equal-length numeric columns, each value '%.{digits}g'."""
    import numpy as np  # lazy: keeps numpy off `analyze`'s start-up

    fields = [format_g(c, digits) for c in columns]
    n = fields[0].shape[0] if fields else 0
    if n == 0:
        return b""
    width = sum(f.shape[1] + 1 for f in fields)
    rows = np.empty((n, width), np.uint8)
    o = 0
    for j, f in enumerate(fields):
        rows[:, o:o + f.shape[1]] = f
        o += f.shape[1]
        rows[:, o] = ord(",") if j < len(fields) - 1 else ord("\n")
        o += 1
    return rows.tobytes().translate(None, b"\x00")
