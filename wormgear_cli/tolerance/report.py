"""The documents of ``wormgear tolerance``: the JSON report and the samples CSV and NPY (written and read).

CSV: a header ``sample,<varied columns>,<metrics>`` then one row per sample;
varied keys by TOML path in the key's unit ([mm]; elements of an array key as
``path[i]``; phases [deg]), metrics in the run's angle unit.  Numbers are
written in their shortest round-trip form, so a CSV read back gives the very
same floats (``--summarize`` reproduces the run's report exactly).
"""

from __future__ import annotations

import io
import itertools
from collections.abc import Iterator
from pathlib import Path
from typing import NamedTuple

import numpy as np

from wormgear_cli.errors import DataError
from wormgear_cli.tolerance.engine import Block, Setup, Summary, drawn_columns, not_sampled
from wormgear_cli.tolerance.metrics import METRIC_SETS
from wormgear_cli.tolerance.sampling import BLOCK
from wormgear_cli.units import ANGLE_UNITS, RAD_PER_UNIT

#: longest line accepted in a samples CSV (a row holds a few dozen numbers; bounds the read of
#: a file with no line ends, such as /dev/zero)
MAX_LINE_BYTES = 1 << 16


def _clip(text: str, most: int = 60) -> str:
    """``text`` cut to ``most`` characters for a message (a cell may be megabytes long)."""
    return text if len(text) <= most else text[:most] + f"... ({len(text)} characters)"


def _bounded_lines(fh, name: str):
    """The lines of ``fh``, each at most :data:`MAX_LINE_BYTES` long (DataError beyond)."""
    number = 0
    while True:
        line = fh.readline(MAX_LINE_BYTES + 1)
        number += 1
        if not line:
            return
        if len(line) > MAX_LINE_BYTES or "\x00" in line:
            raise DataError(f"{name}: line {number}: binary or longer than {MAX_LINE_BYTES} characters; not a "
                            "samples CSV of wormgear tolerance --format csv")
        yield line


def csv_header(s: Setup) -> str:
    """``sample``, the varied columns, then each metric named with its unit (``total_backlash_arcsec``),
    so that ``--summarize`` reads the values in the unit they were written in."""
    return ",".join(("sample", *s.columns, *(f"{m}_{s.options.unit}" for m in s.metrics))) + "\n"


class SamplesHeader(NamedTuple):
    """The header of a samples CSV: varied ``columns``, ``metric_set`` (a key of METRIC_SETS) and
    the ``unit`` of its metric columns (None for a file written before the columns carried it:
    read in the summarizing run's ``--unit``)."""

    columns: tuple
    metric_set: str
    unit: str | None


def csv_rows(s: Setup, block: Block) -> str:
    """The CSV rows (no header) of one block."""
    cols = [[str(j) for j in range(block.start, block.stop)]]
    cols += [list(map(repr, np.asarray(block.columns[c], dtype=float).tolist())) for c in s.columns]
    cols += [list(map(repr, np.asarray(block.metrics[m], dtype=float).tolist())) for m in s.metrics]
    return "".join(",".join(row) + "\n" for row in zip(*cols))


def read_header(path: Path) -> SamplesHeader:
    """The varied columns of a samples CSV, its metric set and the unit of its metrics."""
    name = str(path)
    expected = "expected a samples CSV of wormgear tolerance --format csv"
    if Path(path).is_dir():
        raise DataError(f"{name}: is a directory, {expected}")
    if not Path(path).exists():
        raise DataError(f"{name}: file not found, {expected}")
    if not Path(path).is_file():  # a pipe (/dev/stdin) cannot be read twice (header, then the samples)
        raise DataError(f"{name}: not a regular file, {expected}; write the samples to a file first "
                        "(--format csv -o FILE)")
    with open(path, "rb") as fh:
        raw = fh.readline(MAX_LINE_BYTES + 1)  # bounded: /dev/zero or a binary file has no end of line
    if len(raw) > MAX_LINE_BYTES or b"\x00" in raw:
        raise DataError(f"{name}: line 1: binary or not a CSV line (over {MAX_LINE_BYTES} bytes or a NUL byte), "
                        f"{expected}")
    try:
        header = raw.decode("utf-8-sig").strip()  # a byte-order mark (spreadsheets) is tolerated
    except UnicodeDecodeError:
        raise DataError(f"{name}: line 1: not UTF-8 text, {expected}") from None
    cols = tuple(header.split(","))
    if not cols or cols[0] != "sample":
        raise DataError(f"{name}: line 1: expected a header starting with \"sample\" "
                        "(a CSV of wormgear tolerance --format csv)")
    for unit in (*ANGLE_UNITS, None):
        for key, names in sorted(METRIC_SETS.items(), key=lambda kv: -len(kv[1])):  # the longest match first
            k = len(names)
            if cols[-k:] == tuple(names if unit is None else (f"{n}_{unit}" for n in names)):
                return SamplesHeader(cols[1:-k], key, unit)
    raise DataError(f"{name}: line 1: expected the metric columns, all in one unit, to end the header "
                    f"({', '.join(n + '_arcsec' for n in METRIC_SETS['all'])}, or the paper, budget or iso part; "
                    f"the unit suffix one of {', '.join('_' + u for u in ANGLE_UNITS)})")


def read_samples(path: Path, s: Setup) -> Iterator[Block]:
    """Blocks of a samples CSV written for ``s`` (same varied columns and metrics).

    Raises :class:`DataError` for other columns, a malformed number or row, or
    sample numbers that are not consecutive (a part missing or given twice)."""
    name = str(path)
    header = read_header(path)
    columns = header.columns
    # metric values in the file's unit -> the run's (exactly 1 when they agree: same sums, same bytes)
    scale = 1.0 if header.unit in (None, s.options.unit) else RAD_PER_UNIT[header.unit] / RAD_PER_UNIT[s.options.unit]
    if columns != s.columns:
        missing = [c for c in s.columns if c not in columns]
        extra = [c for c in columns if c not in s.columns]
        what = (f"missing {missing[0]}" if missing else f"unexpected {extra[0]}" if extra else "in another order")
        raise DataError(f"{name}: line 1: the varied columns differ from this drive's ({what}); summarize with "
                        "the drive and [statistics] the samples were drawn with")
    width = 1 + len(s.columns) + len(s.metrics)
    expected_next = None
    line_no = 1
    with open(path, encoding="utf-8-sig", newline="") as fh:
        source = _bounded_lines(fh, name)
        try:
            next(source)
            first_line = next(source, "")
        except UnicodeDecodeError:
            raise DataError(f"{name}: not UTF-8 text, expected a samples CSV") from None
        if not first_line.strip():
            raise DataError(f"{name}: no sample rows after the header")
        try:
            first = int(first_line.split(",", 1)[0])
        except ValueError:
            raise DataError(f"{name}: line 2: expected a sample number first, got "
                            f"{_clip(first_line.split(',', 1)[0])!r}") from None
        if first != s.start:
            raise DataError(f"{name}: line 2: the samples start at {first}, expected {s.start}: the first part "
                            "is missing (concatenate every --shard part, in order)")
        # chunks end at the random-stream block boundaries, as the run's blocks do (same sums, same bytes)
        pending = [first_line]
        size = BLOCK - first % BLOCK
        while True:
            try:
                lines = pending + list(itertools.islice(source, size - len(pending)))
            except UnicodeDecodeError:
                raise DataError(f"{name}: after line {line_no}: not UTF-8 text, expected a samples CSV") from None
            pending, size = [], BLOCK
            if not lines:
                break
            try:
                data = np.loadtxt(lines, delimiter=",", dtype=float, ndmin=2)
            except ValueError as exc:
                raise DataError(f"{name}: lines {line_no + 1}-{line_no + len(lines)}: not {width} numbers per row "
                                f"({_clip(str(exc).splitlines()[0])})") from None
            finite = np.isfinite(data)
            if not finite.all():
                row, col = np.argwhere(~finite)[0]
                what = ("sample", *s.columns, *s.metrics)[col] if col < width else f"column {col + 1}"
                raise DataError(f"{name}: line {line_no + 1 + int(row)}: {what}: expected a finite number, got "
                                f"{float(data[row, col])!r}")
            if data.shape[1] != width:
                raise DataError(f"{name}: line {line_no + 1}: expected {width} values per row, got {data.shape[1]}")
            sample = data[:, 0]
            start = first if expected_next is None else expected_next
            want = np.arange(start, start + len(sample))
            if not np.array_equal(sample, want):
                bad = int(np.argmax(sample != want))
                raise DataError(f"{name}: line {line_no + 1 + bad}: sample {sample[bad]:g}, expected {want[bad]} "
                                "(samples must be consecutive: a shard missing, repeated or out of order?)")
            expected_next = start + len(sample)
            cols = {c: data[:, 1 + i] for i, c in enumerate(s.columns)}
            mets = {m: data[:, 1 + len(s.columns) + i] for i, m in enumerate(s.metrics)}
            if scale != 1.0:
                mets = {m: v * scale for m, v in mets.items()}
            yield Block(start, expected_next, cols, mets)
            line_no += len(lines)
        assert expected_next is not None  # (the first chunk holds the first sample's line)
        if expected_next != s.stop:
            raise DataError(f"{name}: {expected_next - first} samples ({first} to {expected_next - 1}), expected "
                            f"{s.stop - s.start} (--samples {s.stop - s.start}): a part is missing at the end, or "
                            "give the run's --samples")


# --- the compact samples file (.npy) ------------------------------------------------------------

#: the first bytes of every .npy file (NumPy's format, version 1.0)
NPY_MAGIC = b"\x93NUMPY"


def npy_dtype(s: Setup) -> np.dtype:
    """One record per sample: ``sample`` (int64), then each metric named with its unit (float64,
    little-endian), as the CSV's metric columns.  The varied columns are not stored: they
    come again, bit for bit, from the seed (:func:`~.engine.drawn_columns`)."""
    return np.dtype([("sample", "<i8")] + [(f"{m}_{s.options.unit}", "<f8") for m in s.metrics])


def npy_header(s: Setup) -> bytes:
    """The .npy header of the run's samples (a structured array of :func:`npy_dtype`, one
    record per sample of [start, stop)), written before the rows."""
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": np.lib.format.dtype_to_descr(npy_dtype(s)),
                                               "fortran_order": False, "shape": (s.stop - s.start,)})
    return buf.getvalue()


def npy_rows(s: Setup, block: Block) -> bytes:
    """The records of one block (raw bytes after :func:`npy_header`)."""
    rec = np.empty(block.stop - block.start, npy_dtype(s))
    rec["sample"] = np.arange(block.start, block.stop)
    for m in s.metrics:
        rec[f"{m}_{s.options.unit}"] = block.metrics[m]
    return rec.tobytes()


def is_npy(path: Path) -> bool:
    """True when ``path`` starts like a .npy file."""
    try:
        with open(path, "rb") as fh:
            return fh.read(len(NPY_MAGIC)) == NPY_MAGIC
    except OSError:
        return False


def _open_npy(path: Path) -> np.ndarray:
    name = str(path)
    try:
        data = np.load(path, mmap_mode="r", allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise DataError(f"{name}: not a samples file of wormgear tolerance --format npy ({exc})") from None
    if data.ndim != 1 or data.dtype.names is None or data.dtype.names[0] != "sample":
        raise DataError(f"{name}: not a samples file of wormgear tolerance --format npy (expected one record per "
                        "sample starting with the field sample)")
    return data


def read_npy_header(path: Path) -> SamplesHeader:
    """The metric set and unit of a .npy samples file (its varied columns are not stored: ``()``)."""
    fields = _open_npy(path).dtype.names
    assert fields is not None  # (_open_npy checks that the records have fields)
    names = fields[1:]
    for unit in ANGLE_UNITS:
        for key, metric_names in sorted(METRIC_SETS.items(), key=lambda kv: -len(kv[1])):
            if names == tuple(f"{n}_{unit}" for n in metric_names):
                return SamplesHeader((), key, unit)
    raise DataError(f"{path}: fields {', '.join(names)}: expected the metrics of wormgear tolerance, in one unit")


def read_npy(path: Path, s: Setup) -> Iterator[Block]:
    """Blocks of a .npy samples file written for ``s`` (samples [s.start, s.stop)), the varied
    columns drawn again from the seed.  Raises :class:`DataError` for other metrics or sample
    numbers that are not those of ``s``."""
    name = str(path)
    data = _open_npy(path)
    header = read_npy_header(path)
    assert header.unit is not None  # (a .npy file's field names state the unit)
    if header.metric_set != s.options.metrics:
        raise DataError(f"{name}: holds the {header.metric_set} metrics, expected {s.options.metrics}")
    scale = 1.0 if header.unit == s.options.unit else RAD_PER_UNIT[header.unit] / RAD_PER_UNIT[s.options.unit]
    if data.shape[0] != s.stop - s.start:
        raise DataError(f"{name}: {data.shape[0]} samples, expected {s.stop - s.start} (samples {s.start} to "
                        f"{s.stop - 1})")
    lo = s.start
    while lo < s.stop:
        hi = min(s.stop, (lo // BLOCK + 1) * BLOCK)
        rec = np.array(data[lo - s.start:hi - s.start])
        if not np.array_equal(rec["sample"], np.arange(lo, hi)):
            bad = int(np.argmax(rec["sample"] != np.arange(lo, hi)))
            raise DataError(f"{name}: record {lo - s.start + bad}: sample {int(rec['sample'][bad])}, expected "
                            f"{lo + bad}")
        mets = {m: rec[f"{m}_{header.unit}"].astype(float) for m in s.metrics}
        if scale != 1.0:
            mets = {m: v * scale for m, v in mets.items()}
        yield Block(lo, hi, drawn_columns(s, lo, hi), mets)
        lo = hi


def document(s: Setup, summary: Summary, allocation: dict | None = None, shard: str | None = None) -> dict:
    """The JSON report (contract: ``samples``, ``seed``, ``metrics``, ``yield``, ``sensitivity``)."""
    o = s.options
    varied = {}
    for v in s.varied:
        for e, col in enumerate(v.quantity.columns()):
            if col in s.columns:
                lo, hi = v.bounds(e)
                varied[col] = {"kind": v.quantity.kind.value, "distribution": v.distribution, "low_mm": lo,
                               "high_mm": hi, "cp": v.cp, "cpk": v.cpk, "inspected": v.inspected}
    doc = {
        "drive": s.spec.drive.name,
        "samples": summary.samples,
        "seed": int(o.seed),
        "unit": o.unit,
        "plan": {"kind": o.plan, "target_angles_deg": [float(x) for x in s.targets_deg]}
        if any(m.startswith("iso230") for m in s.metrics) else None,
        "metrics": {
            m: {**summary.described[m], "corner": summary.corner[m], "rss": summary.rss[m]} for m in s.metrics
        },
        "yield": {k: {"value": y.value, "low": y.low, "high": y.high, "passing": y.k}
                  for k, y in summary.yields.items()},
        "sensitivity": {
            m: (None if summary.sensitivity[m] is None else {**summary.sensitivity[m][0],
                                                              "remainder": summary.sensitivity[m][1]})
            for m in s.metrics
        },
        "varied": varied,
        "phases": "uniform in [0, 360) deg",
    }

    skipped = not_sampled(s.spec)
    if skipped:
        doc["not_sampled"] = skipped
    if shard is not None:
        doc["shard"] = {"part": shard, "first_sample": s.start, "stop_sample": s.stop}
    if allocation is not None:
        doc["allocation"] = allocation
    return doc


def short_key(column: str) -> str:
    """A varied column shortened to fit 80 columns: without the top section and the unit suffix
    (assembly.wheel_eccentricity_mm -> wheel_eccentricity; a stage key as sN.KEY:
    stage.2.wheel.runout_mm -> s2.wheel.runout); the JSON keeps the full TOML path."""
    head, _, rest = column.partition(".")
    number, _, key = rest.partition(".")
    if head == "stage" and number.isdigit() and key:
        rest, head = f"s{number}.{key}", "stage"
    name = rest if head in ("gear_pair", "worm_pair", "assembly", "stage") and rest else column
    return name.replace("_mm[", "[").removesuffix("_mm")


#: a key's first-order share shown by the table and the plot when it reaches this in some metric
SHARE_SHOWN = 0.005


def variance_rows(sensitivity: dict) -> tuple[list[str], list[tuple[str, list[float]]]]:
    """(metrics, rows) of the variance-share view of a tolerance document's ``sensitivity``: each
    key whose first-order share reaches :data:`SHARE_SHOWN` in some metric, with its share per
    metric, then ``remainder`` (1 - the shares shown: the rest and the interactions).  Metrics
    without indices (None) are left out."""
    sens = {m: v for m, v in sensitivity.items() if v is not None}
    if not sens:
        return [], []
    keys = [k for k in next(iter(sens.values())) if k != "remainder"]
    shown = [k for k in keys if any(sens[m].get(k, 0.0) >= SHARE_SHOWN for m in sens)]
    rows = [(k, [sens[m][k] for m in sens]) for k in shown]
    rows.append(("remainder", [1.0 - sum(sens[m][k] for k in shown) for m in sens]))
    return list(sens), rows
