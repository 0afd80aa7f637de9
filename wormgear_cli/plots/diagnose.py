"""Plot of ``wormgear diagnose``: measured vs simulated and the residual, before and after
(matplotlib imported only when called)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np

from wormgear_cli.plots import pyplot, save_figure
from wormgear_cli.plots.arc import arc_degrees
from wormgear_cli.units import ARCSEC, RAD_PER_UNIT


def draw(diag, doc: dict, unit: str):
    """A 2 x 2 figure: top, measured and simulated error per direction before
    (phases and offset fitted) and after (effects added); bottom, the residual.
    Every angle is converted from arcsec to ``unit``.  Returns the figure."""
    plt = pyplot()
    factor = ARCSEC / RAD_PER_UNIT[unit]
    meas = diag.meas

    x, moved = arc_degrees(meas.angle)  # an arc through 0 deg drawn as one arc
    d = meas.direction
    y = meas.error_arcsec * factor
    fitted = {"before": diag.before.fitted * factor, "after": diag.augmented_fitted * factor}
    gaps = {"before": doc["gap_before"], "after": doc["gap_after"]}
    dense = len(meas) > 5000
    fig, axes = plt.subplots(2, 2, figsize=(12, 7), sharex=True, sharey="row")
    for col, stage in enumerate(("before", "after")):
        top, bottom = axes[0, col], axes[1, col]
        sim = fitted[stage]
        resid = y - sim
        for sign, name, colour in ((1.0, "forward", "C0"), (-1.0, "reverse", "C1")):
            sel = d == sign
            if not np.any(sel):
                continue
            marker = "," if dense else "."
            top.plot(x[sel], y[sel], marker, ms=3, color=colour, alpha=0.45, label=f"measured {name}",
                     rasterized=dense)
            top.plot(x[sel], sim[sel], marker, ms=2, color="0.15" if sign > 0 else "0.45",
                     label=f"simulated {name}", rasterized=dense)
            bottom.plot(x[sel], resid[sel], marker, ms=3, color=colour, alpha=0.6, label=name, rasterized=dense)
        rms = gaps[stage]["rms_arcsec"] * factor
        if stage == "before":
            title = "before: spec with fitted phases and offset"
        else:
            names = ", ".join(e["name"] for e in doc["effects_found"]) or "no effect added"
            title = f"after: {names}"
        top.set_title(title, fontsize=10)
        bottom.set_title(f"residual, RMS {rms:.3g} {unit}", fontsize=10)
        bottom.axhline(0.0, color="0.5", lw=0.5)
        bottom.set_xlabel("output angle [deg]" + (" (along the arc, through 0)" if moved else ""))
        for ax in (top, bottom):
            ax.grid(True, lw=0.3)
    axes[0, 0].set_ylabel(f"error [{unit}]")
    axes[1, 0].set_ylabel(f"measured - simulated [{unit}]")
    axes[0, 0].legend(loc="upper right", fontsize=7, markerscale=3)

    # the verdict's first clause (the rest is in the report), wrapped to the figure's width
    headline = doc["verdict"].split("; ")[0]
    fig.suptitle(textwrap.fill(f"{doc['drive']} vs {Path(doc['data']).name}: {headline}", 130), fontsize=11)
    fig.tight_layout()
    return fig


def save(fig, path: Path) -> None:
    """Write the figure atomically and release it."""
    plt = pyplot()
    try:
        save_figure(fig, path)
    finally:
        plt.close(fig)
