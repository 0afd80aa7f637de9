"""Plots of ``wormgear tolerance``: histograms with limits and percentiles, and the variance shares."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wormgear_cli.plots import pyplot, save_figure
from wormgear_cli.tolerance.report import short_key, variance_rows

#: height of the variance-share panel per key shown [in], and of its axis labels and title
_SHARE_ROW_IN, _SHARE_EXTRA_IN = 0.3, 1.3
#: shares written into their cell at or above this (smaller ones stay blank, as zeros do)
_SHARE_WRITTEN = 0.01


def figure(doc: dict, values: dict, limits: dict, labels: dict):
    """The figure: one histogram per metric (limit as a red line, p50/p99/p99.73 dashed, corner
    dotted), two per row, then across the full width the variance shares as a matrix (a row per
    key, a column per metric, each cell shaded and written with its share): no legend, every key
    its own row, readable however many keys vary."""
    plt = pyplot()
    names = list(doc["metrics"])
    metrics, shares = variance_rows(doc["sensitivity"])
    cols = 2 if len(names) > 1 else 1
    rows = (len(names) + cols - 1) // cols
    share_h = _SHARE_ROW_IN * len(shares) + _SHARE_EXTRA_IN if shares else 0.0
    heights = [3.4] * rows + ([share_h] if shares else [])
    fig = plt.figure(figsize=(5.5 * cols, sum(heights)))
    grid = fig.add_gridspec(len(heights), cols, height_ratios=heights)
    unit = doc["unit"]
    limit_of = dict(limits.values())
    for k, m in enumerate(names):
        ax = fig.add_subplot(grid[k // cols, k % cols])
        ax.hist(np.asarray(values[m]), bins=80, color="0.6")
        r = doc["metrics"][m]
        for key, style in (("50", "--"), ("99", "--"), ("99.73", "-.")):
            ax.axvline(r["percentiles"][key], color="tab:blue", linestyle=style, label=f"p{key}")
        ax.axvline(r["corner"], color="black", linestyle=":", label="corner")
        if m in limit_of:
            ax.axvline(limit_of[m], color="tab:red", label="limit")
        ax.set_title(labels.get(m, m))
        ax.set_xlabel(unit)
        ax.legend(fontsize=7)
    if shares:
        _shares(fig.add_subplot(grid[rows, :]), metrics, shares, labels)
    fig.tight_layout()
    return fig


def _shares(ax, metrics: list, shares: list, labels: dict) -> None:
    matrix = np.array([v for _, v in shares])
    ax.imshow(matrix, cmap="Blues", vmin=0.0, vmax=1.0, aspect="auto", interpolation="nearest")
    ax.set_xticks(range(len(metrics)), [labels.get(m, m) for m in metrics], fontsize=8)
    ax.set_yticks(range(len(shares)), [("remainder (rest, interactions)" if k == "remainder" else short_key(k))
                                       for k, _ in shares], fontsize=8)
    ax.xaxis.tick_top()
    for (r, c), v in np.ndenumerate(matrix):
        if v >= _SHARE_WRITTEN:
            ax.text(c, r, f"{v:.2f}", ha="center", va="center", fontsize=7, color="white" if v > 0.55 else "black")
    ax.set_title("share of variance (first-order index; each column sums to 1 with the remainder)", fontsize=9)
    ax.tick_params(length=0)


def draw(doc: dict, values: dict, limits: dict, path: Path, labels: dict) -> None:
    """Draw :func:`figure` to ``path`` (.png, .svg or .pdf)."""
    plt = pyplot()
    fig = figure(doc, values, limits, labels)
    save_figure(fig, path)
    plt.close(fig)
