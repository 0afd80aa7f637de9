"""Plots of ``wormgear tolerance``: histograms with limits and percentiles, sensitivity bars."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wormgear_cli.plots import pyplot, save_figure


def draw(doc: dict, values: dict, limits: dict, path: Path, labels: dict) -> None:
    """One histogram per metric (limit as a red line, p50/p99/p99.73 dashed, corner dotted),
    then one panel of stacked sensitivity bars (share of each metric's variance per key)."""
    plt = pyplot()
    names = list(doc["metrics"])
    n = len(names) + 1
    cols = 2 if n > 2 else n
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5.5 * cols, 3.4 * rows), squeeze=False)
    flat = axes.ravel()
    unit = doc["unit"]
    limit_of = dict(limits.values())
    for ax, m in zip(flat, names):
        v = np.asarray(values[m])
        ax.hist(v, bins=80, color="0.6")
        r = doc["metrics"][m]
        for key, style in (("50", "--"), ("99", "--"), ("99.73", "-.")):
            ax.axvline(r["percentiles"][key], color="tab:blue", linestyle=style, label=f"p{key}")
        ax.axvline(r["corner"], color="black", linestyle=":", label="corner")
        if m in limit_of:
            ax.axvline(limit_of[m], color="tab:red", label="limit")
        ax.set_title(labels.get(m, m))
        ax.set_xlabel(unit)
        ax.legend(fontsize=7)
    ax = flat[len(names)]
    sens = {m: s for m, s in doc["sensitivity"].items() if s is not None}
    if sens:
        keys = [k for k in next(iter(sens.values())) if k != "remainder"]
        keys = [k for k in keys if any(sens[m][k] >= 0.005 for m in sens)] + ["remainder"]
        bottom = np.zeros(len(sens))
        for k in keys:
            h = np.array([sens[m][k] if k != "remainder" else 1.0 - sum(sens[m][j] for j in keys[:-1])
                          for m in sens])
            ax.bar([labels.get(m, m) for m in sens], h, bottom=bottom, label=k.split(".")[-1])
            bottom += h
        ax.set_ylim(0, 1)
        ax.set_title("share of variance")
        ax.legend(fontsize=6)
    for extra in flat[len(names) + 1:]:
        extra.set_visible(False)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
