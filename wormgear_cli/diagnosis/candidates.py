"""Catalogue effects as candidate design columns, and whether the data can show them.

Observability (the signal an effect needs varies), replication (effects
that vary between runs need at least MIN_RUNS runs), physical range, and
the orders the target spacing aliases (:func:`order_aliases`,
:func:`unaliased_orders`, :func:`jointly_fittable_orders`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from wormgear_cli.diagnosis.design import residualise
from wormgear_cli.diagnosis.mixed import level_shares
from wormgear_cli.diagnosis.phases import probe_signals
from wormgear_cli.diagnosis.runs import DataInfo, Groups
from wormgear_cli.diagnosis.thresholds import JOINT_MIN_SINGULAR_VALUE, MIN_TEMPERATURE_RANGE, MONOTONIC
from wormgear_cli.measurement.harmonics import alias_groups, aliasing, physical_orders
from wormgear_cli.physics.effects import EFFECTS, params_to_keys, train_effects
from wormgear_cli.physics.signals import SIGNALS
from wormgear_cli.units import ARCSEC


class CandidateKind(str, Enum):
    """How a catalogue effect's error depends on its size parameter p."""

    LINEAR = "linear"  #: error = p * column
    RECIPROCAL = "reciprocal"  #: error = column / p (a stiffness)
    PERIODIC = "periodic"  #: error = A [cos(psi) col_sin + sin(psi) col_cos]


@dataclass(frozen=True)
class Candidate:
    """A catalogue effect as design columns.

    ``kind``: "linear" (error = p * column), "reciprocal" (error = column / p,
    a stiffness) or "periodic" (error = A [cos(psi) col_sin + sin(psi) col_cos],
    A the amplitude parameter, psi the phase).  ``columns`` (N, q)
    [arcsec per internal unit]; ``fixed``: the other parameters (internal
    units, e.g. the reference temperature at its catalogue default)."""

    name: str
    kind: CandidateKind
    columns: np.ndarray
    order: float | None
    needs: str | None
    fixed: dict

    @property
    def q(self) -> int:
        return self.columns.shape[1]


def candidate(name: str, signals, geometry) -> Candidate | None:
    """Design columns of catalogue effect ``name`` from its registry signature.

    The signature is evaluated with its amplitude parameter at 1 (and 2,
    to tell linear from reciprocal), the phase at 0 and 90 deg, every other
    parameter at its catalogue default.  Returns None for a signature that
    is none of the three forms (it cannot be fitted linearly)."""
    eff = EFFECTS[name]
    base = {}
    for p in eff.params:
        base[p.name] = (p.default if p.default is not None else 0.0) * p.scale
    amp = eff.amplitude
    fixed = {k: v for k, v in base.items() if k not in (amp, eff.phase)}

    def ev(a, ph=None, sig=signals):
        kw = {**base, amp: a}
        if eff.phase is not None:
            kw[eff.phase] = ph if ph is not None else 0.0
        return np.asarray(eff.function(sig, geometry, **kw), dtype=float) * np.ones(sig.theta.shape) / ARCSEC

    order = float(eff.order(geometry)) if eff.order is not None else None
    probe = probe_signals(signals)
    if eff.phase is not None:
        c_sin = ev(1.0, 0.0, probe)
        c_cos = ev(1.0, math.pi / 2, probe)
        test = ev(2.0, 1.0, probe)
        if not np.allclose(test, 2.0 * (math.cos(1.0) * c_sin + math.sin(1.0) * c_cos),
                           atol=1e-9 * max(1.0, float(np.max(np.abs(test))))):
            return None
        cols = np.column_stack([ev(1.0, 0.0), ev(1.0, math.pi / 2)])
        return Candidate(name, CandidateKind.PERIODIC, cols, order, eff.needs, fixed)
    one, two = ev(1.0, sig=probe), ev(2.0, sig=probe)
    scale = max(1e-300, float(np.max(np.abs(one))))
    if np.allclose(two, 2.0 * one, atol=1e-9 * scale):
        kind = CandidateKind.LINEAR
    elif np.allclose(two, 0.5 * one, atol=1e-9 * scale):
        kind = CandidateKind.RECIPROCAL
    else:
        return None
    return Candidate(name, kind, ev(1.0)[:, None], order, eff.needs, fixed)


def candidate_params(cand: Candidate, beta: np.ndarray) -> dict:
    """Internal parameters of an effect from its fitted column coefficients."""
    eff = EFFECTS[cand.name]
    out = dict(cand.fixed)
    if cand.kind is CandidateKind.PERIODIC:
        out[eff.amplitude] = float(math.hypot(beta[0], beta[1]))
        out[eff.phase] = float(math.atan2(beta[1], beta[0]))
    elif cand.kind is CandidateKind.RECIPROCAL:
        out[eff.amplitude] = float(1.0 / beta[0]) if beta[0] != 0 else math.inf
    else:
        out[eff.amplitude] = float(beta[0])
    return out


def needs_problem(name: str, needs: str | None, info: DataInfo) -> str | None:
    """Why the data cannot show an effect that needs a varying signal (None: they can)."""
    if needs == "temperature":
        if not info.temperature_present:
            return (f"no {SIGNALS['temperature'].column} column: record the drive temperature (a sensor on the "
                    "housing) during a warm-up, ideally heating and cooling")
        if info.temperature_range < MIN_TEMPERATURE_RANGE:
            return (f"the temperature varies by only {info.temperature_range:.3g} K: measure through a warm-up "
                    "(several kelvin), ideally heating and cooling")
    if needs == "load":
        if not info.load_present:
            return f"no {SIGNALS['load'].column} column: measure at two or more output torques (load steps)"
        if info.load_range <= 0:
            return "the load does not vary: measure at two or more output torques (load steps)"
    if needs is not None and name in EFFECTS and EFFECTS[name].mode == "differential":
        if len(info.directions) < 2:
            return "only one direction measured: lost motion shows only between forward and reverse runs"
    if needs == "direction" and len(info.directions) < 2:
        return "only one direction measured: measure forward and reverse runs"
    return None


REPLICATION_REMEDY = "measure at least 3 runs in each direction"


def replication_problem(cand: Candidate, basis, groups: Groups, info: DataInfo) -> tuple[str, str] | None:
    """Why, with fewer than MIN_RUNS runs, a candidate cannot be tested (None: it can), and the remedy.

    Its test needs replication between runs when its columns (after the
    model) vary mainly between passes or runs: with one or two runs, scatter
    between passes cannot be estimated and would be taken for the effect.  A
    thermal effect in a monotonic warm-up within so few runs is tied to time
    and angle as well (a drift over time or an angle pattern fits as well)."""
    runs = groups.runs
    plural = "s" if runs != 1 else ""
    res = residualise(basis, cand.columns)
    if float(np.sum(res * res)) > 1e-12 * float(np.sum(cand.columns**2)):
        run_s, pass_s = level_shares(res, groups)
        if max(float(np.max(run_s)), float(np.max(pass_s))) > 0.5:
            return (f"it changes mainly between passes, and with {runs} run{plural} the scatter between passes "
                    "cannot be estimated: it would be taken for the effect", REPLICATION_REMEDY)
    corr = info.temperature_time_corr
    if cand.needs == "temperature" and not math.isnan(corr) and abs(corr) > MONOTONIC:
        return (f"with {runs} run{plural}, a monotonic warm-up ties temperature to time and angle (correlation "
                f"{corr:.2f}): a drift over time or an angle pattern fits as well",
                REPLICATION_REMEDY + ", ideally heating and cooling")
    return None


def physical_problem(name: str, params: dict) -> str | None:
    """A fitted parameter outside the catalogue's physical range (None: inside)."""
    eff = EFFECTS[name]
    keys = params_to_keys(name, params)
    p = eff.param(next(pp.key for pp in eff.params if pp.name == eff.amplitude))
    v = keys[p.key]
    if not math.isfinite(v) or v < p.lo or v > p.hi:
        return f"{p.key} = {v:.4g} {p.unit}, outside its physical range [{p.lo:g}, {p.hi:g}] {p.unit}"
    return None


#: what a significant but unphysical fit of an effect says about the spec (each effect's ``unphysical_hint``)
UNPHYSICAL_HINT = {name: eff.unphysical_hint for name, eff in EFFECTS.items() if eff.unphysical_hint}


def order_aliases(theta, cands: dict, sources, geometry) -> dict:
    """Per periodic candidate: the orders it cannot be told from at these angles, as (order, label)."""
    labels = dict(physical_orders(geometry, 3))
    for s in sources:
        labels.setdefault(s.order, s.name)
    orders = sorted({*labels, *(c.order for c in cands.values() if c is not None and c.order is not None)})
    groups, folded_orders = aliasing(theta, orders)
    folded = set(folded_orders)
    out = {}
    for name, c in cands.items():
        if c is None or c.order is None:
            continue
        notes = []
        for grp in groups:
            if c.order in grp:
                notes += [(o, "a constant" if o == 0 else labels.get(o, f"order {o:g}")) for o in grp if o != c.order]
        if c.order in folded and not any(o == 0.0 for o, _ in notes):
            notes.append((c.order, "its own mirror (only one phase component is sampled)"))
        out[name] = notes
    return out


def unaliased_orders(theta, orders) -> tuple[list, dict]:
    """(orders the target spacing does not alias, {order: what it is aliased with}) among ``orders``.

    An order aliased onto a constant, or folded onto its own mirror, is left
    out; of orders aliased with each other only the lowest is kept.  Aliasing
    only: whether the kept orders can be fitted together is
    :func:`jointly_fittable_orders`.  (Not the same test as
    :func:`wormgear_cli.measurement.harmonics.resolvable_orders`, which judges the
    conditioning of the whole design for ``measure``.)"""
    orders = [float(o) for o in orders]
    aliased = {}
    groups, folded = aliasing(theta, orders)
    for grp in groups:
        members = [o for o in grp if o != 0.0]
        if 0.0 in grp:
            for o in members:
                aliased[o] = "a constant"
        else:
            for o in members[1:]:
                aliased[o] = f"order {members[0]:g}"
    for o in folded:
        aliased.setdefault(o, "its own mirror (one phase component)")
    return [o for o in orders if o not in aliased], aliased


def jointly_fittable_orders(theta, orders, priority=None,
                            tol: float = JOINT_MIN_SINGULAR_VALUE) -> tuple[list, dict]:
    """Like :func:`unaliased_orders`, then greedily (in ``priority`` order) keep
    only orders whose cos/sin columns stay independent of the intercept and the
    orders kept before them at the distinct sampled angles (smallest singular
    value of the column-normalised design >= ``tol``), while the columns use at
    most half the distinct angles.  The one joint-fit criterion of the
    diagnosis (used by its order table)."""
    keep, aliased = unaliased_orders(theta, orders)
    angles = np.unique(np.round(np.asarray(theta, dtype=float), 9))
    cols = [np.ones_like(angles) / math.sqrt(angles.shape[0])]
    chosen = []
    for o in (priority or keep):
        if o not in keep:
            continue
        trial = [np.cos(o * angles), np.sin(o * angles)]
        trial = [c / max(np.linalg.norm(c), 1e-300) for c in trial]
        design = np.column_stack(cols + trial)
        sv = np.linalg.svd(design, compute_uv=False)
        # keep at least half the distinct angles as residual degrees of freedom
        if 2 * design.shape[1] <= design.shape[0] and sv[-1] >= tol:
            cols += trial
            chosen.append(o)
        else:
            aliased[o] = "other orders at these targets (too few targets to resolve them all)"
    return [o for o in keep if o in chosen], aliased


def effect_order(name: str, geometry) -> float | None:
    """The order [cycles/rev] of catalogue effect ``name`` on this drive (None: not periodic)."""
    eff = EFFECTS[name]
    return float(eff.order(geometry)) if eff.order is not None else None


def catalogue_orders(geometry) -> list[float]:
    """The orders [cycles/rev] of the periodic catalogue effects of this drive's train (in catalogue order)."""
    return [o for n in train_effects(geometry) if (o := effect_order(n, geometry)) is not None]


def aliased_effects(theta, name: str, names, geometry) -> list[tuple[str, float]]:
    """Catalogue effects among ``names`` that the target spacing makes indistinguishable from ``name``.

    Two periodic effects at different orders k1, k2 are indistinguishable
    when the angles ``theta`` [rad] sample their columns alike
    (:func:`wormgear_cli.measurement.harmonics.alias_groups`: k1 - k2 or k1 + k2 a
    multiple of the number of equally spaced targets, e.g. the spur-mesh
    order 144 and the intermediate-shaft order 8 at 136 targets): either
    explains the data equally well.  Orders aliased onto a constant are left
    out (the offset takes them).  Returns [(name, order)] sorted by order;
    empty when ``name`` is not periodic or nothing folds onto it."""
    k = effect_order(name, geometry)
    if k is None:
        return []
    others = {}
    for other in names:
        o = effect_order(other, geometry) if other != name else None
        if o is not None and abs(o - k) > 1e-9 * max(1.0, k):
            others[other] = o
    if not others:
        return []
    for grp in alias_groups(np.asarray(theta, dtype=float), sorted({k, *others.values()})):
        if k in grp and 0.0 not in grp:
            return sorted(((n, o) for n, o in others.items() if o in grp), key=lambda t: t[1])
    return []
