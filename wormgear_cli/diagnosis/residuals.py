"""Views of the residual: the gap in common and differential mode, amplitudes at the
physical orders, trends against the signals, the noise floor and ISO 230-2 figures."""

from __future__ import annotations

import math

import numpy as np

from wormgear_cli.diagnosis.candidates import jointly_fittable_orders
from wormgear_cli.diagnosis.mixed import VarFit
from wormgear_cli.diagnosis.phases import ModelFit
from wormgear_cli.diagnosis.runs import DataInfo, Groups
from wormgear_cli.diagnosis.thresholds import MIN_RUNS
from wormgear_cli.measurement.harmonics import fit_modes_each, physical_orders
from wormgear_cli.measurement.iso230 import group_targets, iso230_figures
from wormgear_cli.measurement.serial import point_noise
from wormgear_cli.physics.signals import SIGNALS
from wormgear_cli.units import ARCSEC


def short_term_noise(resid: np.ndarray, groups: Groups, time: np.ndarray | None = None) -> float:
    """Point-to-point noise [arcsec]: robust standard deviation (1.4826 x median absolute value) of the
    differences of consecutive rows within a pass (in time order), over sqrt(2).  Offsets per pass or
    run cancel; structure that changes slowly along a pass adds little.  NaN without such pairs."""
    return point_noise(resid, groups.pass_id, time)


def noise_floor_rms(state: ModelFit, groups: Groups, time=None) -> float:
    """The noise the data establish [arcsec]: point-to-point noise within passes, plus the fitted scatter
    between passes and runs where it can be estimated (at least MIN_RUNS runs)."""
    short = short_term_noise(state.residual, groups, time)
    if not math.isfinite(short):
        short = state.var.s_white
    between = state.var.sigma2 * (state.var.gp + state.var.gr) if groups.runs >= MIN_RUNS else 0.0
    return math.sqrt(short**2 + between)


def _target_pairs(meas):
    """(key of each row's target/run cell, common and differential per cell with both directions)."""
    tgt, _ = group_targets(meas.angle)
    run = meas.run if "run" in meas.present else np.zeros(len(meas), dtype=int)
    return tgt, run


def target_run_cells(meas) -> tuple[np.ndarray, int]:
    """(cell of each row (N,), number of cells): the (target, run) cells :func:`gap_summary` pairs
    the directions in (they depend on the angles and runs only: make them once per measurement)."""
    tgt, run = _target_pairs(meas)
    _, run_idx = np.unique(run, return_inverse=True)
    pair = tgt.astype(np.int64) * (int(run_idx.max()) + 1) + run_idx.reshape(-1)
    uniq, inv = np.unique(pair, return_inverse=True)
    return inv.reshape(-1), int(uniq.shape[0])


def gap_summary(meas, resid: np.ndarray, cells: tuple[np.ndarray, int] | None = None) -> dict:
    """RMS and max |residual| [arcsec] of all rows, and of the common mode (mean of
    the directions) and differential mode (half forward - reverse) per target and run.
    ``cells``: :func:`target_run_cells` of ``meas`` when already made."""
    inv, size = cells if cells is not None else target_run_cells(meas)
    out: dict[str, float | int | None] = {"rms_arcsec": float(np.sqrt(np.mean(resid**2))),
                                          "max_arcsec": float(np.max(np.abs(resid)))}
    sums = {}
    for dv in (1, -1):
        sel = meas.direction == dv
        cnt = np.bincount(inv[sel], minlength=size)
        tot = np.bincount(inv[sel], weights=resid[sel], minlength=size)
        sums[dv] = (tot, cnt)
    ok = (sums[1][1] > 0) & (sums[-1][1] > 0)
    if np.any(ok):
        fwd = sums[1][0][ok] / sums[1][1][ok]
        rev = sums[-1][0][ok] / sums[-1][1][ok]
        common, diff = 0.5 * (fwd + rev), 0.5 * (fwd - rev)
        out.update(common_rms_arcsec=float(np.sqrt(np.mean(common**2))),
                   common_max_arcsec=float(np.max(np.abs(common))),
                   differential_rms_arcsec=float(np.sqrt(np.mean(diff**2))),
                   differential_max_arcsec=float(np.max(np.abs(diff))), pairs=int(common.shape[0]))
    else:
        out.update(common_rms_arcsec=None, common_max_arcsec=None, differential_rms_arcsec=None,
                   differential_max_arcsec=None, pairs=0)
    return out


def order_table(meas, resid, geometry) -> list[dict]:
    """Amplitude of the residual at each physical order (common and differential
    mode, joint least squares at the exact orders the targets resolve; standard
    errors assume white noise).  Orders the targets cannot resolve are listed
    with what they are aliased with."""
    return order_tables(meas, [resid], geometry)[0]


def order_tables(meas, resids, geometry) -> list[list[dict]]:
    """:func:`order_table` of each residual in ``resids`` (each (N,) [arcsec]) of one measurement.

    Which orders are fitted depends on the angles only, and the joint fit's
    design is built once for all residuals
    (:func:`wormgear_cli.measurement.harmonics.fit_modes_each`): the same tables as one
    call per residual, for little more than the cost of one."""
    phys = physical_orders(geometry, 3)
    bases = geometry.base_orders

    def harmonic(o):
        return min((h for h in (1, 2, 3) for b in bases if abs(o - h * b) < 1e-9 * max(o, 1.0)), default=4)

    priority = sorted((o for o, _ in phys), key=lambda o: (harmonic(o), o))
    keep, aliased = jointly_fittable_orders(meas.angle, [o for o, _ in phys], priority)
    fits: list = [None] * len(resids)  # (one ModeFit per residual where orders are kept, else None)
    if keep:
        with np.errstate(invalid="ignore", divide="ignore"):
            fits = fit_modes_each(meas.angle, resids, meas.direction, keep)
    return [_order_rows(fit, phys, keep, aliased) for fit in fits]


def _order_rows(fit, phys, keep, aliased) -> list[dict]:
    out = []
    if fit is not None:
        row = {"order": 0.0, "label": "constant (common: offset; differential: half the mean reversal change)",
               "identifiable": True, "common_arcsec": float(fit.common.offset)}
        if np.isfinite(fit.differential.offset):
            row["differential_arcsec"] = float(fit.differential.offset)
        out.append(row)
    for o, label in phys:
        row = {"order": o, "label": label}
        if o in aliased or fit is None:
            row.update(identifiable=False, aliased_with=aliased.get(o, "a constant"))
            out.append(row)
            continue
        i = keep.index(o)
        ident = bool(fit.common.identifiable[i])
        row.update(identifiable=ident, common_arcsec=float(fit.common.amplitude[i]),
                   common_stderr_arcsec=float(fit.common.amplitude_stderr[i]))
        if np.isfinite(fit.differential.amplitude[i]):
            row["differential_arcsec"] = float(fit.differential.amplitude[i])
            row["differential_stderr_arcsec"] = float(fit.differential.amplitude_stderr[i])
        out.append(row)
    return out


def versus(meas, resid, info: DataInfo, bins: int = 5) -> dict:
    """The residual against temperature, load and time (each that varies):
    least-squares slopes of the common and differential mode and binned means per direction."""
    out = {}
    both = len(info.directions) == 2
    for name, values in ((SIGNALS[s].column, getattr(meas, s)) for s in ("temperature", "load", "time")):
        if np.ptp(values) <= 0:
            continue
        x = values - np.mean(values)
        cols = [np.ones_like(x), x] + ([meas.direction, meas.direction * x] if both else [])
        coef, *_ = np.linalg.lstsq(np.column_stack(cols), resid, rcond=None)
        entry = {"range": [float(np.min(values)), float(np.max(values))], "slope_common": float(coef[1])}
        if both:
            entry["slope_differential"] = float(coef[3])
        edges = np.quantile(values, np.linspace(0, 1, bins + 1))
        idx = np.clip(np.searchsorted(edges, values, side="right") - 1, 0, bins - 1)
        rows = []
        for b in range(bins):
            sel = idx == b
            if not np.any(sel):
                continue
            row: dict[str, float | int | None] = {"from": float(edges[b]), "to": float(edges[b + 1]),
                                                  "rows": int(np.count_nonzero(sel))}
            for dname, dv in (("forward", 1), ("reverse", -1)):
                s2 = sel & (meas.direction == dv)
                row[f"mean_{dname}_arcsec"] = float(np.mean(resid[s2])) if np.any(s2) else None
            rows.append(row)
        entry["bins"] = rows
        out[name] = entry
    return out


def noise_floor(meas, resid, var: VarFit, groups: Groups) -> dict:
    """Scatter over repeated runs [arcsec]: pooled standard deviation of the residual
    per target and direction, and the fitted white, pass and run components."""
    t = iso230_figures(meas.angle, resid * ARCSEC, meas.direction).targets
    num = 0.0
    den = 0.0
    for s, nn in ((t.s_up, t.n_up), (t.s_down, t.n_down)):
        ok = np.isfinite(s) & (nn >= 2)
        num += float(np.sum((nn[ok] - 1) * (s[ok] / ARCSEC) ** 2))
        den += float(np.sum(nn[ok] - 1))
    between = groups.runs >= MIN_RUNS  # scatter between passes and runs is estimated only from enough runs
    return {"repeat_std_arcsec": math.sqrt(num / den) if den > 0 else None, "white_arcsec": var.s_white,
            "pass_arcsec": var.s_pass if between else None, "run_arcsec": var.s_run if between else None,
            "total_arcsec": math.sqrt(var.sigma2 * (1.0 + var.gp + var.gr)), "passes": groups.passes,
            "runs": groups.runs, "structure": groups.describe}


def iso_figures(meas, error_arcsec) -> dict:
    """ISO 230-2 axis figures A, B, E, M, R [arcsec] of an error array at the measured rows."""
    f = iso230_figures(meas.angle, np.asarray(error_arcsec) * ARCSEC, meas.direction)
    out = {}
    for key in ("A", "B", "E", "M", "R"):
        v = getattr(f, key)
        out[key] = float(v / ARCSEC) if math.isfinite(v) else None
    return out
