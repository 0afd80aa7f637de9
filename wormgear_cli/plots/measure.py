"""Deviation chart of ``wormgear measure`` (ISO 230-2 style)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wormgear_cli.plots import pyplot, save_figure
from wormgear_cli.plots.arc import arc_degrees, gap_breaks
from wormgear_cli.units import to_unit

#: rows drawn as individual points at most (beyond that only the means)
MAX_POINTS = 5000


def deviation_chart(figures, measurement, unit: str, path: Path, title: str = "") -> None:
    """:func:`deviation_figure` saved to ``path``."""
    plt = pyplot()
    fig = deviation_figure(figures, measurement, unit, title)
    try:
        save_figure(fig, path)
    finally:
        plt.close(fig)


def deviation_figure(figures, measurement, unit: str, title: str = ""):
    """Mean deviation per target and direction with +/- 2 s bands, the mean
    bidirectional deviation, and (up to MAX_POINTS rows) the individual
    readings; the axis figures A, B, E, M, R in the title.  Angles in
    ``unit``, targets in degrees along the covered arc (an arc through 0 deg
    continuous, lines broken across unmeasured gaps).  Returns the figure."""
    plt = pyplot()
    t = figures.targets
    x, moved = arc_degrees(t.target)
    order = np.argsort(x, kind="stable")
    fig, ax = plt.subplots(figsize=(9, 5))
    if len(measurement) <= MAX_POINTS:
        row_x = arc_degrees(measurement.angle, of=t.target)[0]
        up = measurement.direction > 0
        ax.plot(row_x[up], to_unit(measurement.error[up], unit), ".", ms=3,
                color="tab:blue", alpha=0.35, label="readings forward")
        ax.plot(row_x[~up], to_unit(measurement.error[~up], unit), ".", ms=3,
                color="tab:red", alpha=0.35, label="readings reverse")
    for mean, s, n, colour, name in ((t.mean_up, t.s_up, t.n_up, "tab:blue", "forward"),
                                     (t.mean_down, t.s_down, t.n_down, "tab:red", "reverse")):
        sel = order[n[order] > 0]
        if not sel.size:
            continue
        xs, mu, sd = gap_breaks(x[sel], to_unit(mean[sel], unit), to_unit(s[sel], unit))
        ax.plot(xs, mu, "-o", ms=3, lw=1.2, color=colour, label=f"mean {name}")
        band = np.isfinite(sd)
        if len(t) == 1 and np.any(band):  # one target (one-position test): a band has no width, draw +/- 2 s bars
            ax.errorbar(xs, mu, yerr=2 * sd, fmt="none", capsize=6, color=colour, label=f"{name} +/- 2s")
        elif np.any(band):
            ax.fill_between(xs, np.where(band, mu - 2 * sd, np.nan), np.where(band, mu + 2 * sd, np.nan),
                            color=colour, alpha=0.15, lw=0, label=f"{name} +/- 2s")
    both = order[np.isfinite(t.mean_bi[order])]
    if both.size:
        ax.plot(*gap_breaks(x[both], to_unit(t.mean_bi[both], unit)), "--", lw=1.0, color="black",
                label="mean bidirectional")
    ax.axhline(0.0, color="grey", lw=0.6)

    def f(v):
        return "-" if not np.isfinite(v) else f"{to_unit(v, unit):.2f}"

    r = "below one step" if "R" in figures.below else f(figures.R)
    figs = (f"A {f(figures.A)}, B {f(figures.B)} (mean {f(figures.B_mean)}), E {f(figures.E)}, "
            f"M {f(figures.M)}, R {r} {unit}")
    ax.set_title(f"{title}\n{figs}" if title else figs, fontsize=10)
    ax.set_xlabel("target angle [deg]" + (" (along the arc, through 0)" if moved else ""))
    ax.set_ylabel(f"deviation (actual - target) [{unit}]")
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=8, ncol=2, loc="best")
    fig.tight_layout()
    return fig
