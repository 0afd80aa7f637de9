"""Plots of ``wormgear sweep`` (matplotlib imported only when called).

The (i, l) study is drawn like the paper's Figure 1: a filled contour map of the gear-stage
TE over centre distance and ratio, with line cuts at fixed i and at fixed l.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wormgear_cli.errors import UsageError
from wormgear_cli.output.sweep import grid2d, subsample
from wormgear_cli.plots import pyplot, save_figure
from wormgear_cli.units import to_unit

#: line cuts drawn per panel
_CUTS = 4


def _cut_indices(n: int, k: int = _CUTS) -> np.ndarray:
    return subsample(n, k)


def _grid(sweep, data, name, unit):
    return to_unit(grid2d(sweep, data, name), unit)


def check_ratio_distance_plot(n_i: int, n_l: int) -> None:
    """Refuse (UsageError) an (i, l) grid that cannot be drawn: it needs 2+ values of i or of l.
    Cheap: the CLI calls it before doing any work."""
    if n_i < 2 and n_l < 2:
        raise UsageError("--plot needs at least 2 values of i or of l (a single point has no curve to draw)")


def check_param_plot(counts: list) -> None:
    """Refuse (UsageError) a --param grid that cannot be drawn: one or two keys, and 2+ values of
    at least one of them (``counts``: the number of values of each key)."""
    if len(counts) > 2:
        raise UsageError(f"--plot draws one or two --param keys, got {len(counts)}")
    if max(counts, default=0) < 2:
        raise UsageError("--plot needs at least 2 values of a --param key (a single point has no curve to draw)")


def plot_ratio_distance(path: Path, sweep, data: dict, unit: str) -> None:
    """Contour map of the gear TE over (l, i) plus cuts: TE vs l at fixed i, TE vs i at fixed l.
    Gear TE solid, total TE at the output dashed.  Skipped (snapped) points are gaps."""
    iv, lv = sweep.i_values, sweep.l_values
    check_ratio_distance_plot(iv.size, lv.size)
    plt = pyplot()
    gear = _grid(sweep, data, "gear_transmission_error", unit)
    total = _grid(sweep, data, "total_transmission_error", unit)
    surface = iv.size >= 2 and lv.size >= 2
    with plt.rc_context({"svg.hashsalt": "wormgear-sweep"}):
        if surface:
            fig = plt.figure(figsize=(12, 4.6))
            ax_map = fig.add_subplot(1, 3, 1)
            ax_l = fig.add_subplot(1, 3, 2)
            ax_i = fig.add_subplot(1, 3, 3)
        else:
            fig = plt.figure(figsize=(7, 4.6))
            ax_map = None
            ax_l = fig.add_subplot(1, 1, 1) if lv.size >= 2 else None
            ax_i = fig.add_subplot(1, 1, 1) if iv.size >= 2 else None
        title = f"{sweep.spec.drive.name}: gear-stage TE over ratio and centre distance"
        if sweep.module is not None:
            title += f" (whole teeth, m = {sweep.module:g} mm)"
        fig.suptitle(title, fontsize=11)
        if ax_map is not None:
            masked = np.ma.masked_invalid(gear)
            cs = ax_map.contourf(lv, iv, masked, levels=14, cmap="viridis")
            lines = ax_map.contour(lv, iv, masked, levels=cs.levels[::2], colors="white", linewidths=0.5)
            ax_map.clabel(lines, fontsize=7, fmt="%.3g")
            fig.colorbar(cs, ax=ax_map, label=f"gear TE $\\Delta\\varphi_{{cc}}$ [{unit}]")
            ax_map.set_xlabel("centre distance l [mm]")
            ax_map.set_ylabel("gear ratio i [-]")
            ax_map.set_title("response surface", fontsize=9)
        if ax_l is not None:
            for n, r in enumerate(_cut_indices(iv.size)):
                colour = f"C{n}"
                ax_l.plot(lv, gear[r], color=colour, lw=1.2, label=f"i = {iv[r]:.3g}")
                ax_l.plot(lv, total[r], color=colour, lw=0.8, ls="--")
            ax_l.set_xlabel("centre distance l [mm]")
            ax_l.set_ylabel(f"TE [{unit}]  (solid: gear stage, dashed: total)")
            ax_l.set_title("cuts at fixed i", fontsize=9)
            ax_l.legend(fontsize=7)
            ax_l.grid(True, lw=0.3)
        if ax_i is not None:
            for n, c in enumerate(_cut_indices(lv.size)):
                colour = f"C{n}"
                ax_i.plot(iv, gear[:, c], color=colour, lw=1.2, label=f"l = {lv[c]:.4g} mm")
                ax_i.plot(iv, total[:, c], color=colour, lw=0.8, ls="--")
            ax_i.set_xlabel("gear ratio i [-]")
            ax_i.set_ylabel(f"TE [{unit}]  (solid: gear stage, dashed: total)")
            ax_i.set_title("cuts at fixed l", fontsize=9)
            ax_i.legend(fontsize=7)
            ax_i.grid(True, lw=0.3)
        fig.tight_layout()
        save_figure(fig, path)
    plt.close(fig)


def plot_params(path: Path, drive: str, axes: list, columns: list, rows: list, unit: str,
                stage_column: str = "gear_transmission_error") -> None:
    """One key: gear TE, total TE and total backlash against it.  Two keys: contour map of the
    total TE over both, with cuts of the total TE against the first key."""
    check_param_plot([len(ax.values) for ax in axes])
    if not rows:
        raise UsageError("--plot: no points to draw")
    plt = pyplot()
    data = np.array(rows, dtype=float)
    col = {c: n for n, c in enumerate(columns)}
    with plt.rc_context({"svg.hashsalt": "wormgear-sweep"}):
        if len(axes) == 1:
            key = axes[0].key
            fig, (ax_te, ax_bl) = plt.subplots(1, 2, figsize=(10, 4.2))
            x = data[:, 0]
            ax_te.plot(x, data[:, col[stage_column]], lw=1.2,
                       label="gear stage" if stage_column == "gear_transmission_error" else
                       stage_column.removesuffix("_transmission_error") + " stage")
            ax_te.plot(x, data[:, col["total_transmission_error"]], lw=1.2, label="total at the output")
            ax_te.set_ylabel(f"transmission error [{unit}]")
            ax_bl.plot(x, data[:, col["gear_backlash"]], lw=1.2, label="gear stage")
            ax_bl.plot(x, data[:, col["total_backlash"]], lw=1.2, label="total at the output")
            ax_bl.set_ylabel(f"backlash [{unit}]")
            for ax in (ax_te, ax_bl):
                ax.set_xlabel(key)
                ax.grid(True, lw=0.3)
                ax.legend(fontsize=8)
        else:
            k0, k1 = axes[0].key, axes[1].key
            v0, v1 = np.array(axes[0].values, float), np.array(axes[1].values, float)
            z = data[:, col["total_transmission_error"]].reshape(v0.size, v1.size)
            fig, (ax_map, ax_cut) = plt.subplots(1, 2, figsize=(11, 4.4))
            if v0.size >= 2 and v1.size >= 2:
                cs = ax_map.contourf(v1, v0, z, levels=14, cmap="viridis")
                fig.colorbar(cs, ax=ax_map, label=f"total TE [{unit}]")
            else:
                ax_map.text(0.5, 0.5, "a map needs 2+ values of each key", ha="center", transform=ax_map.transAxes)
            ax_map.set_xlabel(k1)
            ax_map.set_ylabel(k0)
            for n, c in enumerate(_cut_indices(v1.size)):
                ax_cut.plot(v0, z[:, c], color=f"C{n}", lw=1.2, label=f"{k1} = {v1[c]:g}")
            ax_cut.set_xlabel(k0)
            ax_cut.set_ylabel(f"total TE [{unit}]")
            ax_cut.legend(fontsize=7)
            ax_cut.grid(True, lw=0.3)
        fig.suptitle(f"{drive}: sweep of {', '.join(ax.key for ax in axes)}", fontsize=11)
        fig.tight_layout()
        save_figure(fig, path)
    plt.close(fig)
