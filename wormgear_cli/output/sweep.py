"""Outputs of ``wormgear sweep``: CSV (streamed block by block), JSON documents and tables.

The (i, l) CSV is mostly number formatting: blocks of the grid are computed in order and
formatted by two worker threads (numpy releases the GIL) with the vectorised
:func:`wormgear_cli.output.formats.csv_block`, at most three blocks in flight, so memory stays
constant however large the grid.  Angles are converted to the output unit here.
"""

from __future__ import annotations

import io
from collections import deque
from collections.abc import Callable, Iterator

import numpy as np

from wormgear_cli.analysis import sweep as core
from wormgear_cli.analysis.sweep import ANGLE_COLUMNS, CHUNK_POINTS, INTEGER_COLUMNS, best_points, findings
from wormgear_cli.batch.pool import ordered_map
from wormgear_cli.output.formats import csv_block, csv_text, fmt_angle
from wormgear_cli.output.tables import Cell, Column, Table
from wormgear_cli.spec.loader import with_values
from wormgear_cli.units import to_unit

#: heat-map size shown in the table (rows = i values, columns = l values): every value up to
#: these counts (a map wider than the terminal is split into parts), an even stride beyond
TABLE_ROWS, TABLE_COLS = 21, 12
#: rows of the --param table
TABLE_PARAM_ROWS = 40
#: --param CSV rows produced at a time (about 0.1 s of work)
CSV_PARAM_BATCH = 100
#: cell styles of the heat map, from the lowest fifth of the values to the highest
HEAT_STYLES = ("bold green", "green", "yellow", "dark_orange", "bold red")

Progress = Callable[[int], None] | None


# --- (i, l) CSV ------------------------------------------------------------------------------


def column_values(name: str, values, unit: str):
    """A column in output units: angles [rad] -> ``unit``, the rest as they are."""
    return to_unit(values, unit) if name in ANGLE_COLUMNS else values


def csv_header(columns) -> bytes:
    return (",".join(columns) + "\n").encode()


def csv_rows(columns, block: dict, unit: str) -> bytes:
    """CSV rows (no header) of one block of points."""
    return csv_block([column_values(c, block[c], unit) for c in columns])


def _csv_chunk(state, span: tuple[int, int]) -> bytes:
    """CSV rows of one chunk of grid points, computed and formatted (a worker's task)."""
    sw, unit = state
    return csv_rows(sw.columns, sw.chunk(*span), unit)


def ratio_distance_csv(sw, start: int, stop: int, unit: str, progress: Progress = None,
                       jobs: int = 1) -> Iterator[bytes]:
    """CSV bytes of grid points [start, stop) of ``sw``: the header, then each block in order
    (computed here, formatted by two worker threads, at most three blocks in flight; with
    ``jobs`` > 1 computed and formatted by that many worker processes)."""
    from concurrent.futures import Future, ThreadPoolExecutor  # lazy: keeps concurrent.futures off `sweep`'s start-up

    yield csv_header(sw.columns)
    if jobs > 1:
        spans = sw.spans(start, stop)
        for text, (a, b) in zip(ordered_map(_csv_chunk, (sw, unit), spans, jobs), spans):
            if progress is not None:
                progress(b - a)
            yield text
        return
    with ThreadPoolExecutor(max_workers=2) as pool:
        pending: deque[Future[bytes]] = deque()
        for block in sw.chunks(start, stop, progress=progress):
            pending.append(pool.submit(csv_rows, sw.columns, block, unit))
            if len(pending) >= 3:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()


def collected_csv(sw, data: dict, unit: str) -> bytes:
    """CSV of collected points, formatted a block at a time into one buffer (formatting every
    column at once would need ~500 bytes per point)."""
    buf = io.BytesIO()
    buf.write(csv_header(sw.columns))
    for a in range(0, data["_point"].size, CHUNK_POINTS):
        buf.write(csv_rows(sw.columns, {c: data[c][a:a + CHUNK_POINTS] for c in sw.columns}, unit))
    return buf.getvalue()


def joined(chunks: Iterator[bytes]) -> bytes:
    """All chunks in one buffer (getvalue() hands it over without a copy: ~1x the text in
    memory, where joining a list of chunks would need 2x)."""
    buf = io.BytesIO()
    for c in chunks:
        buf.write(c)
    return buf.getvalue()


# --- (i, l) JSON -----------------------------------------------------------------------------


def _point_dict(sw, data, k, unit) -> dict:
    out = {}
    for c in sw.columns:
        v = column_values(c, data[c][k], unit)
        out[c] = int(v) if c in INTEGER_COLUMNS else float(v)
    return out


def _shard_doc(shard, start, stop, total) -> dict:
    return {"k": shard[0], "n": shard[1], "first_point": start, "stop_point": stop, "total_points": total}


def ratio_distance_json(sw, data: dict, unit: str, shard, start: int, stop: int) -> dict:
    """The JSON document of collected points [start, stop) (``shard`` (K, N) or None)."""
    doc = {
        "drive": sw.spec.drive.name,
        "unit": unit,
        "hold": sw.hold,
        "stage": sw.stage.index,
        "module_mm": sw.module,
        "min_pinion_teeth": sw.min_teeth,
        "grid": {"i": sw.i_values.tolist(), "l_mm": sw.l_values.tolist()},
        "columns": list(sw.columns),
    }
    cols = [(c, column_values(c, data[c], unit)) for c in sw.columns]
    conv = [(v.astype(int).tolist() if c in INTEGER_COLUMNS else v.tolist()) for c, v in cols]
    n = data["_point"].size
    doc["points"] = [dict(zip(sw.columns, row)) for row in zip(*conv)] if n else []
    if sw.module is not None:
        doc["skipped"] = int((stop - start) - n)
    if shard is not None:
        doc["shard"] = _shard_doc(shard, start, stop, sw.size)
        return doc
    doc["summary"] = {
        "points": n,
        "best": {key: _point_dict(sw, data, k, unit) for key, k in best_points(data).items()},
        "findings_model": "continuous (no tooth snapping)" if sw.module is not None else "as swept",
        "findings": findings(sw),
    }
    return doc


# --- (i, l) tables ---------------------------------------------------------------------------


def subsample(n: int, k: int) -> np.ndarray:
    """Up to ``k`` evenly spread indices of ``n`` (first and last included)."""
    return np.unique(np.linspace(0, n - 1, min(n, k)).round().astype(int))


def every_kth(n: int, most: int) -> tuple[np.ndarray, int]:
    """(indices, k) of the values of an axis a heat map shows: all ``n`` (k = 1) when they are
    at most ``most``, else every k-th from the first, with the smallest k that fits, and the last
    value always (so the map keeps its even steps and both ends)."""
    if n <= most:
        return np.arange(n), 1
    k = -(-(n - 1) // (most - 1))
    idx = np.arange(0, n, k)
    if idx[-1] != n - 1:
        idx = np.append(idx[:most - 1], n - 1)
    return idx, k


def _shown(name: str, values, idx, k: int) -> str:
    """What a subsampled axis shows, in words: 'l = 100, 140, ..., 300 (6 of 21: every 4th and the last)'."""
    n = values.size
    listed = [f"{values[j]:g}" for j in idx]
    text = ", ".join(listed) if len(listed) <= 4 else f"{listed[0]}, {listed[1]}, ..., {listed[-1]}"
    ordinal = {2: "2nd", 3: "3rd"}.get(k, f"{k}th")
    last = "" if (n - 1) % k == 0 else " and the last"
    return f"{name} = {text} ({idx.size} of {n}: every {ordinal}{last})"


def grid2d(sw, data: dict, name: str) -> np.ndarray:
    """Full (n_i, n_l) array of a column, NaN at skipped points."""
    grid = np.full(sw.size, np.nan)
    grid[data["_point"]] = data[name]
    return grid.reshape(sw.i_values.size, sw.l_values.size)


def _heat_table(sw, data, name, label, unit, rows, cols) -> Table:
    grid = to_unit(grid2d(sw, data, name), unit)[np.ix_(rows, cols)]
    finite = grid[np.isfinite(grid)]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 0.0)
    t = Table(f"{label} [{unit}]: rows i, columns l [mm]",
              [Column("i \\ l", "right")] + [Column(f"{sw.l_values[c]:g}", "right") for c in cols])
    for r_pos, r in enumerate(rows):
        cells = []
        for c_pos in range(len(cols)):
            v = grid[r_pos, c_pos]
            if not np.isfinite(v):
                cells.append(Cell("-", "dim"))
                continue
            band = 0 if hi <= lo else min(len(HEAT_STYLES) - 1, int((v - lo) / (hi - lo) * len(HEAT_STYLES)))
            cells.append(Cell(fmt_angle(float(v), unit), HEAT_STYLES[band]))
        t.add_row(f"{sw.i_values[r]:g}", *cells)
    return t


def ratio_distance_tables(sw, data: dict, unit: str) -> list:
    """Heat maps of gear TE and total TE, the best designs, and the paper's findings."""
    rows, k_i = every_kth(sw.i_values.size, TABLE_ROWS)
    cols, k_l = every_kth(sw.l_values.size, TABLE_COLS)
    hold = "normal forces held" if sw.hold == "force" else "output torque held"
    snap = f", snapped to whole teeth at m = {sw.module:g} mm (min {sw.min_teeth} teeth)" if sw.module else ""
    involute = sw.stage.kinematics == "involute"
    stage = "involute stage" if involute else "paper's Delta phi_cc"
    which = "gear TE" if sw.spec.form == "legacy" or len(sw.spec.stages) == 2 and sw.stage.index == 2 else \
        f"TE of stage {sw.stage.index} ({sw.stage.name})"
    g = _heat_table(sw, data, "gear_transmission_error", f"{sw.spec.drive.name}: {which} ({stage})",
                    unit, rows, cols)
    shown = []
    if rows.size < sw.i_values.size:
        shown.append(_shown("i", sw.i_values, rows, k_i))
    if cols.size < sw.l_values.size:
        shown.append(_shown("l", sw.l_values, cols, k_l))
    caption = f"{hold}{snap}"
    if shown:
        caption += f"; showing {' and '.join(shown)}; all points: --format csv"
    if sw.module:
        caption += "; '-' = skipped (too few teeth)"
    g.caption = caption
    out = [g, _heat_table(sw, data, "total_transmission_error", "total TE at the output", unit, rows, cols)]
    if sw.figures:  # what is signed off: the budget's statistical amplitude and the acceptance test's E
        out += [_heat_table(sw, data, "budget_amplitude_statistical", "budget, statistical total (amplitude)",
                            unit, rows, cols),
                _heat_table(sw, data, "iso230_E", "ISO 230-2 E on the [test_plan] (range)", unit, rows, cols)]
    n = data["_point"].size
    columns = [Column("best by"), Column("i", "right"), Column("l [mm]", "right")]
    if sw.module:
        columns.append(Column("z1/z2", "right"))
    columns += [Column(f"{c} [{unit}]", "right") for c in ("gear TE", "total TE", "total backlash")]
    summary = Table(f"summary ({n} design{'s' if n != 1 else ''}" + (f", {sw.size - n} skipped" if sw.module else "")
                    + ")", columns)
    for key, k in best_points(data).items():
        iv = data["i_used"][k] if sw.module else data["i"][k]
        lv = data["l_used_mm"][k] if sw.module else data["l_mm"][k]
        cells = [{"total_transmission_error": "total TE", "gear_transmission_error": "gear TE"}[key],
                 f"{iv:.4g}", f"{lv:.5g}"]
        if sw.module:
            cells.append(f"{int(data['z1'][k])}/{int(data['z2'][k])}")
        cells += [fmt_angle(float(to_unit(data[c][k], unit)), unit)
                  for c in ("gear_transmission_error", "total_transmission_error", "total_backlash")]
        summary.add_row(*cells)
    out.append(summary)
    f = Table("the paper's findings on this grid" + (" (continuous model)" if sw.module else "")
              + (", with the involute stage" if involute else ""),
              [Column("check"), Column("finding")])
    for item in findings(sw):
        f.add_row({True: "holds", False: "FAILS", None: "n/a"}[item["holds"]], item["statement"])
    out.append(f)
    return out


# --- --param sweeps --------------------------------------------------------------------------


def param_columns(axes, spec=None) -> list:
    """CSV/JSON columns of a --param sweep: the keys, then every analyze metric of ``spec``'s train (its
    CSV columns: :attr:`~wormgear_cli.analysis.accuracy.Analysis.columns`; without ``spec``, a worm +
    spur drive's), then the sign-off figures (:data:`~wormgear_cli.analysis.figures.FIGURE_COLUMNS`:
    the budget's totals and the ISO 230-2 figures, as analyze's CSV)."""
    # lazy: keeps analysis.accuracy, analysis.figures off `sweep`'s start-up
    from wormgear_cli.analysis.accuracy import INFO_COLUMNS, METRIC_COLUMNS
    from wormgear_cli.analysis.figures import FIGURE_COLUMNS

    if spec is None or tuple(s.kind for s in spec.stages) == ("worm", "spur"):
        return [ax.key for ax in axes] + list(METRIC_COLUMNS) + list(INFO_COLUMNS) + list(FIGURE_COLUMNS)
    from wormgear_cli.analysis.accuracy import analyze  # lazy: keeps analysis.accuracy off `sweep`'s start-up

    angle, info = analyze(spec).columns  # names of the stages' parts: the same at every point of the grid
    return [ax.key for ax in axes] + list(angle) + list(info) + list(FIGURE_COLUMNS)


def stage_te_column(spec) -> str:
    """The column of the output stage's own TE: ``gear_transmission_error`` for a worm + spur drive,
    else ``NAME_transmission_error`` of the last stage."""
    if tuple(s.kind for s in spec.stages) == ("worm", "spur"):
        return "gear_transmission_error"
    return f"{spec.stages[-1].name}_transmission_error"


def _param_batch(state, span: tuple[int, int]) -> list:
    """The rows of points [a, b) of a --param sweep (a worker's task)."""
    spec, axes, unit = state
    return list(param_table_rows(spec, axes, *span, unit))


def param_table_rows(spec, axes, start: int, stop: int, unit: str, progress: Progress = None,
                     jobs: int = 1) -> Iterator[list]:
    """One row per point [start, stop): the key values, then the metrics in ``unit``; with
    ``jobs`` > 1 batches of :data:`CSV_PARAM_BATCH` points are computed by worker processes."""
    if jobs > 1:
        spans = [(a, min(stop, a + CSV_PARAM_BATCH)) for a in range(start, stop, CSV_PARAM_BATCH)]
        for rows, (a, b) in zip(ordered_map(_param_batch, (spec, axes, unit), spans, jobs), spans):
            if progress is not None:
                progress(b - a)
            yield from rows
        return
    from wormgear_cli.analysis.figures import figures  # lazy: keeps analysis.figures off `sweep`'s start-up

    columns = param_columns(axes, spec)
    n = len(axes)
    keys = [ax.key for ax in axes]
    for values, result in core.param_rows(spec, axes, start, stop, progress=progress):
        m = result.metrics(unit)
        m.update({k: float(to_unit(v, unit)) for k, v in figures(with_values(spec, dict(zip(keys, values))),
                                                                result).items()})
        yield list(values) + [m[c] for c in columns[n:]]


def param_csv(spec, axes, start: int, stop: int, unit: str, progress: Progress = None,
              jobs: int = 1) -> Iterator[str]:
    """CSV text of points [start, stop): the header, then batches of :data:`CSV_PARAM_BATCH`
    rows as they are computed (no rows held)."""
    columns = param_columns(axes, spec)
    yield csv_text(columns, [])
    batch = []
    for row in param_table_rows(spec, axes, start, stop, unit, progress, jobs):
        batch.append(row)
        if len(batch) >= CSV_PARAM_BATCH:
            yield csv_text(columns, batch, header=False)
            batch = []
    yield csv_text(columns, batch, header=False)


def _lowest(rows, j: int, unit: str, where: str) -> str:
    """A summary cell: the lowest value of column ``j`` and where, or that every point gives it."""
    low = rows[min(range(len(rows)), key=lambda q: rows[q][j])][j]
    same = len(rows) > 1 and all(fmt_angle(r[j], unit) == fmt_angle(low, unit) for r in rows)
    return f"{fmt_angle(low, unit)} {unit} at {'every point' if same else where}"


def _best_row(columns, rows, column: str = "total_transmission_error") -> int:
    j = columns.index(column)
    return min(range(len(rows)), key=lambda q: rows[q][j])


def param_json(spec, axes, rows: list, unit: str, shard, start: int, stop: int) -> dict:
    """The JSON document of a --param sweep's rows [start, stop)."""
    columns = param_columns(axes, spec)
    doc = {"drive": spec.drive.name, "unit": unit,
           "params": [{"key": ax.key, "values": list(ax.values)} for ax in axes],
           "columns": columns, "points": [dict(zip(columns, r)) for r in rows]}
    if shard is not None:
        doc["shard"] = _shard_doc(shard, start, stop, core.param_size(axes))
    elif rows:
        doc["summary"] = {"points": len(rows),
                          "best": {c: dict(zip(columns, rows[_best_row(columns, rows, c)]))
                                   for c in ("total_transmission_error", "budget_amplitude_statistical", "iso230_A")}}
    return doc


def param_tables(spec, axes, rows: list, unit: str) -> list:
    """Up to :data:`TABLE_PARAM_ROWS` points with TE and backlash, and the best point."""
    keys = [ax.key for ax in axes]
    columns = param_columns(axes, spec)
    te_col = stage_te_column(spec)
    idx = [columns.index(c) for c in (te_col, "total_transmission_error", "total_backlash")]
    picks: np.ndarray | list[int] = subsample(len(rows), TABLE_PARAM_ROWS) if rows else []
    t = Table(f"{spec.drive.name}: sweep of {', '.join(keys)} [{unit}]",
              [Column(k, "right") for k in keys] + [Column(c, "right")
                                                   for c in (te_col.removesuffix("_transmission_error") + " TE",
                                                             "total TE", "total backlash")])
    for p in picks:
        r = rows[p]
        t.add_row(*(f"{v:g}" for v in r[:len(keys)]), *(fmt_angle(r[j], unit) for j in idx))
    if len(picks) < len(rows):
        t.caption = f"showing {len(picks)} of {len(rows)} points (all points and metrics: --format csv)"
    out = [t]
    if rows:
        k = _best_row(columns, rows)
        j = columns.index("total_transmission_error")
        best = ", ".join(f"{key} = {rows[k][n]:g}" for n, key in enumerate(keys))
        b = Table("summary", [Column("what"), Column("value")], show_header=False)
        b.add_row("points", str(len(rows)))
        b.add_row("lowest total TE", _lowest(rows, j, unit, best))
        for what, col in (("lowest budget TE", "budget_amplitude_statistical"), ("lowest ISO A", "iso230_A")):
            k, j = _best_row(columns, rows, col), columns.index(col)
            where = ", ".join(f"{key} = {rows[k][q]:g}" for q, key in enumerate(keys))
            b.add_row(what, _lowest(rows, j, unit, where))
        out.append(b)
    return out
