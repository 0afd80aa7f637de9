"""The full error budget of a drive: every source as a line at the output, and three totals.

No I/O.  The lines are the drive's registry (:mod:`wormgear_cli.drive.registry`): its
periodic sources (the same names, orders, sizes and phases that ``simulate``, ``synth``
and ``diagnose`` use) and its static terms (each gear stage's tooth deflection, the
paper's deformation parts of Delta phi_cc and Delta phi_wc, and a belt's stretch, each
divided by the ratios after its stage).

Each line: ``source``, ``stage`` (the stage's name: gear / worm / belt ...), ``kind``
(shaft: once per turn of a shaft; mesh: a tooth-mesh order; belt: once per belt
revolution; static: load, no order), ``order`` (cycles per output revolution: 1, i_c,
z1, n_w ...; 0 for static), ``amplitude`` [rad at the output: the largest value of the
line's curve over a turn, the amplitude for a sinusoid], ``origin`` (spec / grade /
default), ``phase`` [rad], ``stage_index`` (1-based from the motor), ``stage_kind``,
``part``.

Combination rules (:class:`Rule`), all for the transmission error at the output:

* ``linear``: the paper's rule, the sum of every line's maximum, sum_k a_k (a
  bound: every source at its peak at once);
* ``rss``: the static lines added, the periodic ones root-sum-squared,
  sum_static a_k + sqrt(sum_periodic a_k^2) (the statistical size when the
  phases are independent and uniformly random);
* ``peak``: the static lines plus the exact largest value, over one output
  revolution, of the phased periodic curve that ``simulate`` draws,
  sum_static a_k + max_theta sum_periodic c_k(theta, psi_k).

rss <= linear and peak <= linear always; peak = linear when every periodic
line peaks at the same output angle (``simulate --phases aligned-error``).
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass
from enum import Enum
from typing import NamedTuple

import numpy as np


class Rule(str, Enum):
    """How the budget's lines combine into a total (see the module docstring)."""

    LINEAR = "linear"
    RSS = "rss"
    PEAK = "peak"


# an immutable named record built as a NamedTuple, not a frozen dataclass: it is created when
# ``analyze`` starts (0.1 ms against 0.6 ms; docs/development.md, "Start-up")
class BudgetLine(NamedTuple):
    """One error source at the output (see the module docstring for the fields)."""

    source: str
    stage: str
    kind: str
    order: float
    amplitude: float
    origin: str
    phase: float = 0.0
    stage_index: int = 0
    stage_kind: str = ""
    part: str = ""


#: samples per cycle of the highest order when searching the phased curve's peak; the
#: search is then refined by a parabola through the three samples around the best one
PEAK_SAMPLES_PER_CYCLE = 64
_MIN_PEAK_SAMPLES = 4096


@dataclass(frozen=True)
class Budget:
    """The lines and their totals [rad] under each :class:`Rule`."""

    drive: str
    lines: tuple
    linear: float
    rss: float
    peak: float

    def total(self, rule) -> float:
        """The total [rad] under ``rule`` (a :class:`Rule` or its value)."""
        return {Rule.LINEAR: self.linear, Rule.RSS: self.rss, Rule.PEAK: self.peak}[Rule(rule)]

    def report(self, unit: str) -> dict:
        """``{"budget": [...], "total_with_budget": {...}}`` for analyze's JSON (angles in ``unit``)."""
        from wormgear_cli.units import to_unit

        lin = self.linear
        lines = [{"source": ln.source, "stage": ln.stage, "kind": ln.kind, "order": float(ln.order),
                  "amplitude": float(to_unit(ln.amplitude, unit)), "origin": ln.origin,
                  "phase_deg": math.degrees(ln.phase),
                  "share_pct": float(100.0 * ln.amplitude / lin) if lin > 0 else 0.0,
                  "stage_index": ln.stage_index, "stage_kind": ln.stage_kind, "part": ln.part}
                 for ln in self.lines]
        return {"budget": lines,
                "total_with_budget": {"transmission_error_" + r.value: float(to_unit(self.total(r), unit))
                                      for r in Rule}}


def budget(spec, analysis=None) -> Budget:
    """Every error source of ``spec`` as a :class:`BudgetLine` and the three totals.

    ``analysis``: the spec's :func:`wormgear_cli.analysis.accuracy.analyze` result (computed when
    omitted); its registry gives the lines.
    """
    from wormgear_cli.analysis.accuracy import analyze
    from wormgear_cli.drive.records import Static

    a = analysis if analysis is not None else analyze(spec)
    reg = a.registry
    sources = reg.periodic(all_budget_sources=True)
    all_lines = tuple(
        BudgetLine(x.name, x.stage, "static", 0.0, float(x.amplitude), x.origin, 0.0, x.stage_index, x.stage_kind,
                   "") if isinstance(x, Static) else
        BudgetLine(x.name, x.stage, x.kind, float(x.order), float(x.peak if x.peak is not None else x.amplitude),
                   x.origin, float(x.phase), x.stage_index, x.stage_kind, x.part)
        for x in reg.lines)
    static = [ln for ln in all_lines if ln.kind == "static"]
    periodic = [ln for ln in all_lines if ln.kind != "static"]
    s_static = sum(ln.amplitude for ln in static)
    linear = sum(ln.amplitude for ln in all_lines)
    rss = s_static + math.sqrt(sum(ln.amplitude ** 2 for ln in periodic))
    peak = s_static + phased_peak(sources)
    return Budget(a.drive, all_lines, float(linear), float(rss), float(peak))


def phased_peak(sources, phases: dict | None = None) -> float:
    """max over one output revolution of sum_k curve_k(theta, psi_k)  [rad].

    Dense samples (:data:`PEAK_SAMPLES_PER_CYCLE` per cycle of the highest order),
    then a parabola through the best sample and its neighbours.  ``phases``
    overrides source phases by name [rad].  0 when there are no sources.
    """
    phases = phases or {}
    live = [s for s in sources if s.amplitude != 0.0 or (s.peak or 0.0) != 0.0]
    if not live:
        return 0.0
    top = max(max(abs(s.order) for s in live), 1.0)
    n = max(_MIN_PEAK_SAMPLES, int(math.ceil(PEAK_SAMPLES_PER_CYCLE * top)))
    step = 2.0 * math.pi / n
    theta = np.arange(n) * step
    # sinusoids of one order add exactly as phasors, sum_k a_k sin(o t + psi_k) = |P| sin(o t + arg P)
    # with P = sum_k a_k exp(i psi_k): one sine per order instead of one per source
    phasors: dict[float, complex] = {}
    others = []
    for s in live:
        sine = getattr(s.curve, "sine", None)
        psi = phases.get(s.name, s.phase)
        if sine is None:
            others.append((s.curve, psi))
        else:
            phasors[sine[1]] = phasors.get(sine[1], 0j) + sine[0] * cmath.exp(1j * psi)

    def curve(t):
        total = sum(c(t, psi) for c, psi in others) if others else np.zeros_like(t)
        for order, p in phasors.items():
            total = total + abs(p) * np.sin(order * t + cmath.phase(p))
        return total

    y = curve(theta)
    k = int(np.argmax(y))
    y0, y1, y2 = y[k - 1], y[k], y[(k + 1) % n]
    den = y0 - 2.0 * y1 + y2
    best = float(y1)
    if den < 0.0:
        t = theta[k] + 0.5 * step * (y0 - y2) / den
        best = max(best, float(curve(np.array([t]))[0]))
    return best
