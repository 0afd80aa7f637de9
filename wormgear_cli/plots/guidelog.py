"""The periodic-error chart of ``wormgear measure`` on a PHD2 guide log."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wormgear_cli.plots import pyplot, save_figure
from wormgear_cli.units import to_unit

#: frames drawn as individual points at most in the folded panel (beyond that only the bin means)
MAX_POINTS = 20000


def periodic_error_chart(measurement, guide, unit: str, path: Path, title: str = "") -> None:
    """:func:`periodic_error_figure` saved to ``path``."""
    plt = pyplot()
    fig = periodic_error_figure(measurement, guide, unit, title)
    try:
        save_figure(fig, path)
    finally:
        plt.close(fig)


def periodic_error_figure(measurement, guide, unit: str, title: str = ""):
    """Three panels over the guide log ``measurement`` and its periodic error ``guide``
    (:class:`~wormgear_cli.workflows.guidelog.GuideResult`), angles in ``unit``:

    1. the reconstructed RA-axis error against time [min], each session in its own colour, and the
       fitted drift of each session (offset and cubic) over it;
    2. the drift alone (what guiding absorbs slowly: polar misalignment, refraction);
    3. the error with the drift (and the orders fitted alongside) removed, folded on the worm
       period, its means in bins of worm phase, and the smoothed periodic-error curve.

    Without a periodic error (``guide.periodic`` None) only the first panel is drawn."""
    plt = pyplot()
    m, pe = measurement, guide.periodic
    fig, axes = plt.subplots(3 if pe is not None else 1, 1, figsize=(9, 9 if pe is not None else 4), squeeze=False)
    axes = axes[:, 0]
    minutes = m.time / 60.0
    y = to_unit(m.error, unit)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    numbers, first = np.unique(m.run, return_index=True)
    for i, number in enumerate(numbers[np.argsort(first)]):
        rows = m.run == number
        c = colours[i % len(colours)]
        axes[0].plot(minutes[rows], y[rows], ".", ms=2, color=c, alpha=0.5)
        if pe is not None:
            axes[0].plot(minutes[rows], to_unit(pe.drift[rows], unit), "-", lw=1.0, color="black")
            axes[1].plot(minutes[rows], to_unit(pe.drift[rows] - pe.drift[rows].mean(), unit), "-", lw=1.2, color=c)
    axes[0].set_ylabel(f"RA-axis error [{unit}]")
    axes[0].set_title("reconstructed error (each session a colour) and each session's drift (black)", fontsize=9)
    if pe is not None:
        axes[1].set_ylabel(f"drift [{unit}]")
        axes[1].set_title("drift of each session (offset removed)", fontsize=9)
        _folded(axes[2], m, pe, unit)
    for ax in axes[:2]:
        ax.set_xlabel("time since the first session [min]")
    for ax in axes:
        ax.grid(True, lw=0.3)
        ax.axhline(0.0, color="grey", lw=0.6)
    head = title
    if pe is not None:
        figure = (f"PE {to_unit(pe.peak_to_peak, unit):.3g} {unit} peak to peak over the worm period "
                  f"{pe.period_s:.5g} s (order {pe.order:.6g}, {pe.cycles:.3g} cycles); RMS "
                  f"{to_unit(pe.rms_detrended, unit):.3g} -> {to_unit(pe.rms_without_worm, unit):.3g} {unit} "
                  "without the worm harmonics")
        head = f"{title}\n{figure}" if title else figure
    fig.suptitle(head, fontsize=10)
    fig.tight_layout()
    return fig


def _folded(ax, m, pe, unit: str) -> None:
    """The third panel: samples folded on the worm period, bin means, the smoothed curve."""
    period = pe.period_s
    phase = np.mod(pe.order * m.angle / (2.0 * np.pi), 1.0)
    rest = pe.worm + pe.residual  # the error with the drift and the orders fitted alongside removed
    if len(m) <= MAX_POINTS:
        ax.plot(phase * period, to_unit(rest, unit), ".", ms=2, color="tab:grey", alpha=0.35,
                label="frames, drift removed")
    good = pe.fold_count > 0
    ax.plot(pe.fold_phase[good] * period, to_unit(pe.fold_mean[good], unit), "o", ms=3, color="tab:blue",
            label="mean per bin")
    ax.plot(pe.curve_phase * period, to_unit(pe.curve, unit), "-", lw=1.6, color="tab:red",
            label=f"periodic error ({pe.harmonics} harmonics)")
    ax.set_xlim(0.0, period)
    ax.set_xlabel("time within the worm period [s]")
    ax.set_ylabel(f"error, drift removed [{unit}]")
    ax.set_title("folded on the worm period", fontsize=9)
    ax.legend(fontsize=8, loc="best")
