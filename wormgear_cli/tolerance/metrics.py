"""Metrics of each sampled drive, vectorised over samples.

* ``total_transmission_error``, ``total_backlash``: the paper's totals
  exactly as :func:`wormgear_cli.analysis.analyze` computes them (same model
  functions, here on arrays of sampled values); phases do not enter them.
* ``iso230_E``, ``iso230_B``, ``iso230_M``, ``iso230_A``: the ISO 230-2:2014
  (clause 2) figures of an acceptance test without measurement noise, on the
  curve :func:`wormgear_cli.simulation.simulate` gives for the sample's values
  and phases, at the test's targets (one run; with no noise every run is the
  same, s = 0, so A = E):
  E = max_i,dir x_i - min_i,dir x_i;  B = max_i |x_i(up) - x_i(down)|;
  M = max_i x_i(bi) - min_i x_i(bi) with x_i(bi) = (x_i(up) + x_i(down)) / 2;
  A = max(x + 2 s) - min(x - 2 s) with s = 0.

The simulated error (simulation module doc) written per sample with the
sinusoidal sources of one shaft combined into one term
(a sin(o theta + psi) = a cos(psi) sin(o theta) + a sin(psi) cos(o theta)):

    e(theta, d) = gear_kinematic_te(i_c theta + psi_e) + sum_k a_k sin(o_k theta + psi_k)
                  - d/2 [Delta e tan(alpha)(1 + sin(i_c theta + psi_e)) / R2
                         + max(central + h_j sin(i_c theta + psi_Fi), 0) / (r_w i_c)]
                  + fixed(theta, d)

where fixed = tooth-deflection lag and the spec's effects (not varied).
All angles [rad], lengths [mm].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wormgear_cli.models import gear as gear_model
from wormgear_cli.models import worm as worm_model

PAPER_METRICS = ("total_transmission_error", "total_backlash")
ISO_METRICS = ("iso230_E", "iso230_B", "iso230_M", "iso230_A")
#: metric sets of ``--metrics``
METRIC_SETS = {"paper": PAPER_METRICS, "iso": ISO_METRICS, "all": PAPER_METRICS + ISO_METRICS}

#: Chebyshev-Lobatto nodes of the gear-TE interpolant in Delta e, and its accepted relative error
_CHEB_DEGREE = 48
_CHEB_RTOL = 1e-11
#: samples x targets evaluated at once for the ISO figures (bounds the memory of a block)
_ISO_CELLS = 2_097_152


class GearTeMax:
    """max over phi of the paper's Delta phi_cc as a function of Delta e alone (the other
    inputs are fixed by the spec).  Evaluated with a Chebyshev interpolant on [0, T]
    of :func:`wormgear_cli.models.gear.gear_te_max_fast` (degree 48, checked against
    the exact maximiser between the nodes to 1e-11 relative; the exact maximiser
    is used when the check fails).  Capped at the value at T (the maximum grows
    with Delta e), so no sample exceeds the corner case."""

    def __init__(self, spec, tolerance: float, deflection: float):
        gp = spec.gear_pair
        self.args = (gp.module * gp.pinion.teeth / 2.0, gp.module * gp.output_gear.teeth / 2.0)
        self.alpha, self.d1, self.t = gp.pressure_angle, deflection, float(tolerance)
        self.at_t = float(self.exact(np.array([self.t]))[0])
        self.coef = None
        if self.t > 0:
            from numpy.polynomial import chebyshev

            k = np.arange(_CHEB_DEGREE + 1)
            x = -np.cos(np.pi * k / _CHEB_DEGREE)
            coef = chebyshev.chebfit(x, self.exact(0.5 * self.t * (x + 1.0)), _CHEB_DEGREE)
            mid = -np.cos(np.pi * (k[:-1] + 0.5) / _CHEB_DEGREE)
            ref = self.exact(0.5 * self.t * (mid + 1.0))
            err = np.max(np.abs(chebyshev.chebval(mid, coef) - ref)) / max(self.at_t, 1e-300)
            if err <= _CHEB_RTOL:
                self.coef = coef

    def exact(self, de):
        return gear_model.gear_te_max_fast(*self.args, de, self.alpha, self.d1)[0]

    def __call__(self, de):
        de = np.asarray(de, dtype=float)
        if self.coef is None:
            value = self.exact(de)
        else:
            from numpy.polynomial import chebyshev

            value = chebyshev.chebval(2.0 * de / self.t - 1.0, self.coef)
        return np.minimum(np.where(de == self.t, self.at_t, value), self.at_t)


@dataclass(frozen=True)
class Context:
    """Everything the metrics need that the samples do not vary (built once per run)."""

    spec: object
    deflection_gear: float
    deflection_worm: float
    gear_te: GearTeMax
    theta: np.ndarray  # test targets [rad]
    fixed_up: np.ndarray  # deflection lag + effects, forward [rad]
    fixed_down: np.ndarray


def context(spec, gear_eccentricity_tolerance: float, targets_rad: np.ndarray, dwell_s: float = 10.0) -> Context:
    """Build the :class:`Context` of ``spec`` for test targets ``targets_rad`` [rad] (one
    run, forward pass then reverse pass, ``dwell_s`` [s] per point as ``synth``)."""
    from wormgear_cli.analysis import deflections
    from wormgear_cli.models.effects import Signals
    from wormgear_cli.simulation import components

    d = deflections(spec)
    theta = np.asarray(targets_rad, dtype=float)
    n = theta.size
    fixed = {}
    for sign, times in ((1.0, np.arange(n) * dwell_s), (-1.0, (2 * n - 1 - np.arange(n)) * dwell_s)):
        parts = components(spec, Signals.make(theta, sign, 0.0, 20.0, times))
        fixed[sign] = sum((v for k, v in parts.items() if k == "deformation" or k.startswith("effect:")),
                          np.zeros(n))
    return Context(spec, float(d.gear), float(d.worm), GearTeMax(spec, gear_eccentricity_tolerance, d.gear),
                   theta, np.broadcast_to(fixed[1.0], (n,)).copy(), np.broadcast_to(fixed[-1.0], (n,)).copy())


def paper_totals(ctx: Context, values: dict) -> dict[str, np.ndarray]:
    """Total TE and total backlash [rad] per sample, as :func:`analyze` computes them.

    ``values``: column -> values [mm] (see :func:`wormgear_cli.tolerance.sampling.draw`).
    Source: the paper's Delta phi_c = Delta phi_cc + Delta phi_wc / i_c and
    Delta phi_h = Delta phi_ch + Delta phi_wh / i_c (module doc of analysis).
    """
    spec = ctx.spec
    gp, wp = spec.gear_pair, spec.worm_pair
    z1, z2 = gp.output_gear.teeth, gp.pinion.teeth
    i_c = z1 / z2
    v = values
    de = v["assembly.gear_eccentricity_mm"]
    te_gear = ctx.gear_te(de)
    bl_gear = gear_model.gear_backlash_max(gp.module, z1, de, gp.pressure_angle, ctx.deflection_gear)
    lam, a2, m2, z3 = wp.lead_angle, wp.transverse_pressure_angle, wp.module, wp.wheel.teeth
    f_hl, fi = v["worm_pair.lead_error_mm"], v["worm_pair.wheel.radial_composite_error_mm"]
    h_te = worm_model.worm_te_halfwidth(f_hl, v["assembly.worm_eccentricity_mm"],
                                        v["assembly.worm_bearing_clearance_mm"], fi,
                                        v["assembly.wheel_eccentricity_mm"], v["assembly.wheel_bearing_clearance_mm"],
                                        lam, a2)
    wte = worm_model.worm_te(ctx.deflection_worm, h_te, m2, z3)
    ft1, ft2 = v["worm_pair.worm.profile_error_mm"], v["worm_pair.wheel.profile_error_mm"]
    ts1, ts2 = v["worm_pair.worm.thickness_deviation_mm"], v["worm_pair.wheel.thickness_deviation_mm"]
    j_def, j_prof, j_thk = worm_model.worm_backlash_central(ctx.deflection_worm, ft1, ft2, ts1, ts2, lam)
    e_sq = sum(v[f"assembly.worm_pair_errors_mm[{i}]"] ** 2 for i in range(6))
    h_j = worm_model.worm_backlash_halfwidth(ft1, ft2, ts1, ts2, e_sq, f_hl,
                                             v["assembly.worm_centre_distance_error_mm"], fi, lam, a2)
    wbl = worm_model.worm_backlash(j_def + j_prof + j_thk, h_j, m2, z3)
    return {"total_transmission_error": te_gear + wte / i_c, "total_backlash": bl_gear + wbl / i_c}


def iso_figures(ctx: Context, values: dict, phases: dict) -> dict[str, np.ndarray]:
    """ISO 230-2 E, B, M, A [rad] per sample on the simulated curve at the targets (module doc).

    ``values``: column -> values [mm]; ``phases``: phase path -> phases [rad].
    Worked in chunks of samples so that memory stays bounded.
    """
    n = len(next(iter(values.values())))
    per = max(1, _ISO_CELLS // max(ctx.theta.size, 1))
    out = {k: np.empty(n) for k in ISO_METRICS}
    for lo in range(0, n, per):
        hi = min(n, lo + per)
        part = _iso_chunk(ctx, {k: a[lo:hi] for k, a in values.items()}, {k: a[lo:hi] for k, a in phases.items()})
        for k in ISO_METRICS:
            out[k][lo:hi] = part[k]
    return out


def _iso_chunk(ctx: Context, v: dict, ph: dict) -> dict:
    from wormgear_cli.analysis import geometry

    spec = ctx.spec
    g = geometry(spec)
    gp, wp = spec.gear_pair, spec.worm_pair
    r1, r2 = gp.module * gp.pinion.teeth / 2.0, gp.module * gp.output_gear.teeth / 2.0
    alpha, i_c, n_w = gp.pressure_angle, g.gear_ratio, g.worm_order
    to_out = 1.0 / (g.wheel_pitch_radius * i_c)
    theta = ctx.theta[None, :]
    col = lambda a: np.asarray(a, dtype=float)[:, None]  # noqa: E731

    de, psi_e = col(v["assembly.gear_eccentricity_mm"]), col(ph["assembly.gear_eccentricity_phase_deg"])
    # sinusoidal sources [rad at the output]: (amplitude, phase path, order)
    worm_ecc = np.hypot(v["assembly.worm_eccentricity_mm"], v["assembly.worm_bearing_clearance_mm"]) / math.cos(
        wp.lead_angle)
    wheel_ecc = np.hypot(v["assembly.wheel_eccentricity_mm"], v["assembly.wheel_bearing_clearance_mm"]) / math.cos(
        wp.transverse_pressure_angle)
    sines = (
        (v["worm_pair.lead_error_mm"], "worm_pair.lead_error_phase_deg", n_w),
        (worm_ecc, "assembly.worm_eccentricity_phase_deg", n_w),
        (v["worm_pair.wheel.radial_composite_error_mm"], "worm_pair.wheel.radial_composite_phase_deg", i_c),
        (wheel_ecc, "assembly.wheel_eccentricity_phase_deg", i_c),
    )
    # every sinusoid of one order as p sin(o theta) + q cos(o theta): one matrix product per term
    th = ctx.theta
    basis = np.stack([np.sin(n_w * th), np.cos(n_w * th), np.sin(i_c * th), np.cos(i_c * th), np.ones_like(th)])
    coef = np.zeros((de.shape[0], 5))
    for a, k, o in sines:
        j = 0 if o == n_w else 2
        amp = np.asarray(a, dtype=float) * (0.5 * to_out)
        coef[:, j] += amp * np.cos(ph[k])
        coef[:, j + 1] += amp * np.sin(ph[k])
    common = gear_model.gear_kinematic_te(i_c * theta + psi_e, r1, r2, de, alpha) + coef @ basis
    # lost motion (never negative): the gear part and simulation._worm_lost_motion
    ft1, ft2 = v["worm_pair.worm.profile_error_mm"], v["worm_pair.wheel.profile_error_mm"]
    ts1, ts2 = v["worm_pair.worm.thickness_deviation_mm"], v["worm_pair.wheel.thickness_deviation_mm"]
    _, prof, thk = worm_model.worm_backlash_central(0.0, ft1, ft2, ts1, ts2, wp.lead_angle)
    e_sq = sum(v[f"assembly.worm_pair_errors_mm[{i}]"] ** 2 for i in range(6))
    h_j = worm_model.worm_backlash_halfwidth(ft1, ft2, ts1, ts2, e_sq, v["worm_pair.lead_error_mm"],
                                             v["assembly.worm_centre_distance_error_mm"],
                                             v["worm_pair.wheel.radial_composite_error_mm"], wp.lead_angle,
                                             wp.transverse_pressure_angle)
    psi_f = np.asarray(ph["worm_pair.wheel.radial_composite_phase_deg"], dtype=float)
    c_gear = de[:, 0] * (math.tan(alpha) / r2)
    gear_lost = np.stack([np.zeros_like(c_gear), np.zeros_like(c_gear), c_gear * np.cos(psi_e[:, 0]),
                          c_gear * np.sin(psi_e[:, 0]), c_gear], axis=1) @ basis
    worm_inner = np.stack([np.zeros_like(c_gear), np.zeros_like(c_gear), h_j * np.cos(psi_f), h_j * np.sin(psi_f),
                           np.broadcast_to(prof + thk, c_gear.shape)], axis=1) @ basis
    lost = gear_lost + np.maximum(worm_inner, 0.0) * to_out
    up = common - 0.5 * lost + ctx.fixed_up[None, :]
    down = common + 0.5 * lost + ctx.fixed_down[None, :]
    e = np.maximum(up.max(axis=1), down.max(axis=1)) - np.minimum(up.min(axis=1), down.min(axis=1))
    bi = common + 0.5 * (ctx.fixed_up + ctx.fixed_down)[None, :]  # (x(up) + x(down)) / 2
    # no noise: s = 0, so A = max(x + 2 s) - min(x - 2 s) over both directions is E
    return {"iso230_E": e, "iso230_B": np.abs(up - down).max(axis=1), "iso230_M": bi.max(axis=1) - bi.min(axis=1),
            "iso230_A": e.copy()}


def evaluate(ctx: Context, values: dict, phases: dict, metrics: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The chosen ``metrics`` [rad] per sample (see the module doc)."""
    out = {}
    if any(m in PAPER_METRICS for m in metrics):
        out.update(paper_totals(ctx, values))
    if any(m in ISO_METRICS for m in metrics):
        out.update(iso_figures(ctx, values, phases))
    return {m: out[m] for m in metrics}
