"""Which sweeps may run: option combinations and the size policy of ``wormgear sweep``.

No I/O, no typer, no rich.  Every check here runs before anything is built or loaded, from
the options and the axes' sizes alone, and raises :class:`UsageError` with one line naming
the option, the limit and what to do instead.
"""

from __future__ import annotations

from wormgear_cli.analysis.sweep import MAX_PARAM_POINTS, check_param_axes, param_size, shard_bounds
from wormgear_cli.errors import UsageError


def check_options(*, params: list, i: str | None, l_mm: str | None, module_mm: float | None,
                  hold: str | None, min_teeth: int | None, shard: str | None, fmt: str,
                  plot: bool, stage: int | None = None, figures: bool = False) -> None:
    """Refuse option combinations that cannot run (UsageError naming them)."""
    if figures and params:
        raise UsageError("--figures is for --i/--l-mm sweeps; a --param sweep carries the budget and ISO 230-2 "
                         "figures already")
    if figures and module_mm is None and (i is not None or l_mm is not None):
        raise UsageError("--figures needs --module-mm: the budget and ISO 230-2 figures are those of whole-tooth "
                         "designs (give the module to snap to, e.g. --module-mm 2)")
    if params and (i is not None or l_mm is not None or module_mm is not None or hold is not None
                   or min_teeth is not None or stage is not None):
        raise UsageError("--param cannot be combined with --i, --l-mm, --stage, --module-mm, --hold or "
                         "--min-pinion-teeth; run two sweeps (--param names its stage in the key: "
                         "stage.N.KEY)")
    if not params and i is None and l_mm is None:
        raise UsageError("nothing to sweep: give --i START:STOP:N and/or --l-mm START:STOP:N, "
                         "or --param KEY=START:STOP:N")
    if min_teeth is not None and module_mm is None:
        raise UsageError("--min-pinion-teeth applies only with --module-mm")
    if shard is not None and fmt == "table":
        raise UsageError("--shard works with --format csv or json (a table needs the whole grid)")
    if shard is not None and plot:
        raise UsageError("--plot cannot be combined with --shard (a plot needs the whole grid)")


# --- size policy: what each output can hold ------------------------------------------------

#: most points of one (i, l) run (the whole grid, or this shard's part), by output; checked
#: from the axes' N before any array is built.  A table and a plot hold the whole grid as
#: arrays (~160 bytes per point); JSON holds every point as a Python object and its text
#: (~3 KB per point); CSV, on stdout or to a file (through a staged file renamed at the end),
#: is streamed in blocks (memory constant, ~2.5 us per point).
MAX_COLLECTED_POINTS = 2_000_000
MAX_JSON_POINTS = 100_000
MAX_CSV_STREAM_POINTS = 1_000_000_000
#: most points of one --param run with JSON output (~9 KB per point: 30 columns); every
#: --param grid is also limited to MAX_PARAM_POINTS points
MAX_PARAM_JSON_POINTS = 50_000


def ratio_distance_limits(fmt: str, plot: bool) -> list:
    """(limit, what it is for, what to do instead) for an (i, l) run writing ``fmt``
    ("table", "json" or "csv") and, with ``plot``, a plot."""
    if fmt == "table":
        out = [(MAX_COLLECTED_POINTS, "--format table (it holds the whole grid)",
                "use --format csv or fewer values")]
    elif fmt == "json":
        out = [(MAX_JSON_POINTS, "--format json (it holds every point as an object)",
                "use --format csv, fewer values or --shard K/N")]
    else:
        out = [(MAX_CSV_STREAM_POINTS, "--format csv (about 2.5 us per point)", "split it with --shard K/N")]
    if plot:
        out.append((MAX_COLLECTED_POINTS, "--plot (it holds the whole grid)", "plot a coarser grid"))
    return out


def check_ratio_distance_size(n_i: int, n_l: int, fmt: str, plot: bool,
                              shard: tuple[int, int] | None = None, figures: bool = False) -> None:
    """Refuse (UsageError) a run whose point count exceeds the limit of its output (see
    :func:`ratio_distance_limits`), from the axes' sizes alone: nothing is built.  With ``figures``
    every design is a full analysis, as a --param point: at most MAX_PARAM_POINTS points."""
    total = n_i * n_l
    start, stop = shard_bounds(total, *shard) if shard else (0, total)
    points = stop - start
    where = f"--i x --l-mm: {n_i} x {n_l} = {total} points" + (f" ({points} in this shard)" if shard else "")
    if figures and points > MAX_PARAM_POINTS:
        raise UsageError(f"{where} are more than the limit of {MAX_PARAM_POINTS} for --figures (each design is "
                         "a full analysis with its budget and acceptance test, about 50 ms); use fewer values or "
                         "--shard K/N")
    for limit, what, instead in ratio_distance_limits(fmt, plot):
        if points > limit:
            raise UsageError(f"{where} are more than the limit of {limit} for {what}; {instead}")
    if fmt == "json" and n_i + n_l > MAX_JSON_POINTS:
        raise UsageError(f"--i x --l-mm: {n_i} + {n_l} grid values are more than the limit of {MAX_JSON_POINTS} "
                         "for --format json (it lists the grid); use --format csv")


def check_param_size(axes: list, fmt: str, shard: tuple[int, int] | None = None) -> None:
    """Refuse (UsageError) a --param run too large for its output (JSON: MAX_PARAM_JSON_POINTS;
    every grid: :func:`check_param_axes`)."""
    check_param_axes(axes)
    total = param_size(axes)
    start, stop = shard_bounds(total, *shard) if shard else (0, total)
    if fmt == "json" and stop - start > MAX_PARAM_JSON_POINTS:
        counts = " x ".join(str(len(ax.values)) for ax in axes)
        raise UsageError(f"--param: {counts} = {total} points" + (f" ({stop - start} in this shard)" if shard else "")
                         + f" are more than the limit of {MAX_PARAM_JSON_POINTS} for --format json (it holds "
                         "every point as an object); use --format csv or --shard K/N")
