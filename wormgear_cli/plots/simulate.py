"""Plots of ``wormgear simulate`` and ``wormgear synth`` (matplotlib imported only when called)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wormgear_cli.plots import pyplot, save_figure


def plot_simulation(curves: dict, path: Path) -> None:
    """Dense scan: forward and reverse curves with the lost motion below.
    ``--at``: simulated (and measured, when present) error per direction."""
    plt = pyplot()
    unit = curves["unit"]
    if curves["kind"] == "dense":
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6), sharex=True,
                                          gridspec_kw={"height_ratios": [3, 1]})
        x = curves["angle_deg"]
        top.plot(x, curves["forward"], lw=0.8, label="forward (+1)")
        top.plot(x, curves["reverse"], lw=0.8, label="reverse (-1)")
        top.plot(x, 0.5 * (curves["forward"] + curves["reverse"]), lw=0.8, ls="--", color="0.4",
                 label="common mode")
        top.set_ylabel(f"error [{unit}]")
        top.legend(loc="upper right", fontsize=8)
        top.set_title(f"{curves['drive']}: simulated error at the output")
        bottom.plot(x, curves["reverse"] - curves["forward"], lw=0.8, color="C3")
        bottom.set_ylabel(f"lost motion [{unit}]")
        bottom.set_xlabel("output angle [deg]")
        for ax in (top, bottom):
            ax.grid(True, lw=0.3)
    else:
        fig, ax = plt.subplots(figsize=(9, 5))
        x, d = curves["angle_deg"], curves["direction"]
        for sign, name, colour in ((1.0, "forward", "C0"), (-1.0, "reverse", "C1")):
            sel = d == sign
            if not np.any(sel):
                continue
            order = np.argsort(x[sel], kind="stable")
            if curves["measured"] is not None:
                ax.plot(x[sel], curves["measured"][sel], ".", ms=3, color=colour, alpha=0.5,
                        label=f"measured {name}")
            ax.plot(x[sel][order], curves["simulated"][sel][order], "-", lw=0.8, color=colour,
                    label=f"simulated {name}")
        ax.set_xlabel("output angle [deg]")
        ax.set_ylabel(f"error [{unit}]")
        ax.set_title(f"{curves['drive']}: simulated at the rows of {Path(curves['source']).name}")
        ax.legend(loc="upper right", fontsize=8)
        ax.grid(True, lw=0.3)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def plot_synthesis(result, drive: str, path: Path) -> None:
    """Synthetic data: error per run and direction over the angle; temperature and load over time."""
    plt = pyplot()
    c = result.columns
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6), gridspec_kw={"height_ratios": [3, 1]})
    for r in np.unique(c["run"]):
        for sign, ls in ((1, "-"), (-1, "--")):
            sel = (c["run"] == r) & (c["direction"] == sign)
            top.plot(c["angle_deg"][sel], c["error_arcsec"][sel], ls, marker=".", ms=3, lw=0.6,
                     color=f"C{(int(r) - 1) % 10}", label=f"run {r} {'fwd' if sign > 0 else 'rev'}")
    top.set_xlabel("output angle [deg]")
    top.set_ylabel("error [arcsec]")
    top.set_title(f"{drive}: synthetic measurement")
    if len(np.unique(c["run"])) <= 5:
        top.legend(fontsize=7, ncol=2, loc="upper right")
    top.grid(True, lw=0.3)
    bottom.plot(c["time_s"], c["temperature_C"], color="C3", lw=0.8)
    bottom.set_xlabel("time [s]")
    bottom.set_ylabel("temperature [degC]", color="C3")
    twin = bottom.twinx()
    twin.plot(c["time_s"], c["load_Nm"], color="C2", lw=0.8)
    twin.set_ylabel("load [N m]", color="C2")
    bottom.grid(True, lw=0.3)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
