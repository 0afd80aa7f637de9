"""``wormgear compare``: two or more drives side by side, and their differences to the first.

For each drive: the paper's totals (TE, backlash), the full budget's three TE totals (amplitudes), each
budget line's amplitude at the output, and, when asked (``samples``), the yield of built drives
against each drive's own ``[requirements]`` limits.  Every difference is a drive's value minus
the first drive's (the baseline).  Core code: no typer, no rich; angles in the output unit.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from wormgear_cli.errors import UsageError

#: the compared totals: key -> (label, where in analyze's document, under "total" / "total_with_budget")
TOTALS = {
    "total_transmission_error": ("total TE (paper)", "total", "transmission_error"),
    "total_backlash": ("total backlash (paper)", "total", "backlash"),
    "budget_linear": ("budget TE, linear", "total_with_budget", "transmission_error_amplitude_linear"),
    "budget_statistical": ("budget TE, statistical", "total_with_budget", "transmission_error_amplitude_statistical"),
    "budget_peak": ("budget TE, peak", "total_with_budget", "transmission_error_amplitude_peak"),
}
#: fewest drives compared
MIN_DRIVES = 2


@dataclass(frozen=True)
class Options:
    """What to compare beyond the analysis: ``samples`` built drives per drive for the yield (None:
    no yield), drawn with ``seed``; angles in ``unit``."""

    unit: str = "arcsec"
    samples: int | None = None
    seed: int = 0


def _row(values: list) -> dict:
    """``{"values", "differences"}``: each value minus the first (None where either is None)."""
    base = values[0]
    return {"values": values,
            "differences": [None if v is None or base is None else v - base for v in values]}


def _yields(specs: Sequence, samples: int, options: Options, progress: Callable[[int], None] | None) -> dict:
    """The ``yield`` section: per sampled requirement and ``all``, each drive against its own limits
    (``samples`` built drives each)."""
    # lazy: tolerance.engine pulls in numpy, ctypes; this module loads without it
    from wormgear_cli.tolerance import engine

    per_drive: list[dict] = []
    for spec in specs:
        metrics = engine.metrics_for_limits(spec)
        if metrics is None:
            per_drive.append({})
            continue
        s = engine.setup(spec, engine.Options(samples=samples, seed=options.seed, metrics=metrics,
                                              unit=options.unit))
        per_drive.append(engine.limit_yields(s, progress))
    keys = list(dict.fromkeys(k for y in per_drive for k in y if k != "all")) + ["all"]
    rows = {}
    for key in keys:
        got = [y.get(key) for y in per_drive]
        rows[key] = {**_row([None if y is None else y.value for y in got]),
                     "low": [None if y is None else y.low for y in got],
                     "high": [None if y is None else y.high for y in got]}
    return {"samples": options.samples, "seed": options.seed, "requirements": rows}


def compare(specs: Sequence, files: Sequence[str], options: Options,
            progress: Callable[[int], None] | None = None) -> dict:
    """The JSON document of ``wormgear compare`` for the loaded ``specs`` (named ``files``).

    Keys: ``unit``; ``drives`` [{``file``, ``drive``}] (the first is the baseline); ``totals``
    {key: {``label``, ``values``, ``differences``}} for :data:`TOTALS`; ``budget`` {source:
    {``values``, ``differences``}} (each line's amplitude at the output, None where a drive has no
    such line); ``yield`` (None without ``samples``): {``samples``, ``seed``, ``requirements``
    {key or ``all``: {``values``, ``low``, ``high``, ``differences``}}, fractions}.

    Raises
    ------
    UsageError
        Fewer than :data:`MIN_DRIVES` drives.
    """
    # lazy: analysis.accuracy, analysis.budget pull in numpy, ctypes; this module loads without them
    from wormgear_cli.analysis.accuracy import analyze
    from wormgear_cli.analysis.budget import budget

    if len(specs) < MIN_DRIVES:
        raise UsageError(f"compare needs at least {MIN_DRIVES} drives, got {len(specs)}")
    reports = []
    for spec in specs:
        result = analyze(spec)
        reports.append({**result.report(options.unit), **budget(spec, result).report(options.unit)})
    totals = {key: {"label": label, **_row([r[section][name] for r in reports])}
              for key, (label, section, name) in TOTALS.items()}
    lines = [{ln["source"]: ln["amplitude"] for ln in r["budget"]} for r in reports]
    sources = list(dict.fromkeys(src for by in lines for src in by))
    return {
        "unit": options.unit,
        "drives": [{"file": str(f), "drive": r["drive"]} for f, r in zip(files, reports)],
        "totals": totals,
        "budget": {src: _row([by.get(src) for by in lines]) for src in sources},
        "yield": None if options.samples is None else _yields(specs, options.samples, options, progress),
    }


def csv_rows(doc: dict) -> tuple[list[str], list[list]]:
    """(columns, rows) of ``compare --format csv``: one row per quantity and drive (a long table:
    pivot it by ``file``), ``section`` totals / budget / yield; yields as fractions."""
    columns = ["section", "quantity", "file", "drive", "value", "difference", "unit"]
    rows = []
    sections = [("totals", doc["totals"], doc["unit"]), ("budget", doc["budget"], doc["unit"])]
    if doc["yield"] is not None:
        sections.append(("yield", doc["yield"]["requirements"], "fraction"))
    for section, quantities, unit in sections:
        for key, q in quantities.items():
            for d, value, diff in zip(doc["drives"], q["values"], q["differences"]):
                rows.append([section, key, d["file"], d["drive"], value, diff, unit])
    return columns, rows
