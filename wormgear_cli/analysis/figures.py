"""The sign-off figures of a drive as flat columns (``analyze --format csv``, ``sweep --param``): the full
budget's totals, amplitudes (zero to peak) and the phased curve's range (peak to peak), and the ISO
230-2 figures of the acceptance test (ranges) predicted on the spec's ``[test_plan]``
(:func:`wormgear_cli.analysis.acceptance.predict`), so that a sweep over an accuracy grade or a
tolerance shows its effect on what a designer signs off (issue 19)."""

from __future__ import annotations

#: column -> what it is (docs/budget.md); the budget's amplitudes, its range, the ISO 230-2 ranges
FIGURE_COLUMNS = {
    "budget_amplitude_linear": "the full budget, every line at its peak at once (amplitude)",
    "budget_amplitude_statistical": "the full budget, rss within an order summed across orders (amplitude)",
    "budget_amplitude_peak": "the full budget's phased curve, its largest value (amplitude)",
    "budget_range_peak": "the full budget's phased curve, max - min over a turn (range)",
    "iso230_A": "ISO 230-2 bidirectional accuracy A on the [test_plan] (range)",
    "iso230_E": "ISO 230-2 bidirectional systematic deviation E on the [test_plan] (range)",
    "iso230_B": "ISO 230-2 reversal value B on the [test_plan] (lost motion)",
    "iso230_M": "ISO 230-2 mean bidirectional positional deviation M on the [test_plan] (range)",
}


def figures(spec, result=None) -> dict[str, float]:
    """``column -> value`` [rad] of :data:`FIGURE_COLUMNS` for ``spec`` (``result``: its
    :func:`~wormgear_cli.analysis.accuracy.analyze`, computed when omitted)."""
    # lazy: analysis.acceptance, analysis.budget pull in numpy, ctypes; this module loads without them
    from wormgear_cli.analysis.acceptance import predict
    from wormgear_cli.analysis.budget import budget

    b = budget(spec, result)
    p = predict(spec)
    return {"budget_amplitude_linear": float(b.linear), "budget_amplitude_statistical": float(b.statistical),
            "budget_amplitude_peak": float(b.peak), "budget_range_peak": float(b.range_peak),
            **{f"iso230_{k}": p.figure(k) for k in ("A", "E", "B", "M")}}
