"""The full error budget of a drive: every source as a line at the output, and its totals.

No I/O.  The lines are the drive's registry (:mod:`wormgear_cli.drive.registry`): its
periodic sources (the same names, orders, sizes and phases that ``simulate``, ``synth``
and ``diagnose`` use), its static terms (each gear stage's tooth deflection, the
paper's deformation parts of Delta phi_cc and Delta phi_wc, and a belt's stretch, each
divided by the ratios after its stage) and its thermal drifts at the stated operating
temperatures.

Each line: ``source``, ``stage`` (the stage's name: gear / worm / belt ...), ``kind``
(shaft: once per turn of a shaft; mesh: a tooth-mesh order; belt: once per belt
revolution; static: load, no order; thermal: a drift at the operating temperatures),
``order`` (cycles per output revolution: 1, i_c, z1, n_w ...; 0 for static and thermal),
``amplitude`` [rad at the output: the largest value of the line's periodic part over a
turn, the amplitude for a sinusoid; a curve's constant mean is no positioning error and
is reported apart, :attr:`Budget.offsets`], ``origin`` (spec / grade / default), ``phase``
[rad], ``stage_index`` (1-based from the motor), ``stage_kind``, ``part``.

Every total is of the transmission error at the output and is an **amplitude**
(zero-to-peak: the largest departure from the mean position over a turn), the quantity
the paper's Delta phi_c is; a **range** (peak-to-peak, max - min) is what ISO 230-2's
E, M, A and B are, and is named so (docs/budget.md, "Amplitudes and ranges").

Combination rules (:class:`Rule`), amplitudes:

* ``linear``: the paper's rule, the sum of every line's maximum, sum_k a_k (a
  bound: every source at its peak at once);
* ``statistical``: the static lines added; the periodic lines root-sum-squared within
  an order and the orders added: sum_static a_k + sum_o sqrt(sum_{k in o} a_k^2).
  Sources of one order add as vectors (the rss is the rms of their sum under
  independent uniform phases, and the median for two); sources of different orders
  reach their peaks within one turn nearly together, so across orders the peaks add
  (docs/budget.md gives the derivation and the check against the random-phase peak);
* ``peak``: the static lines plus the exact largest value, over one output
  revolution, of the phased periodic curve that ``simulate`` draws,
  sum_static a_k + max_theta sum_periodic (c_k(theta, psi_k) - offset_k);
* ``rss`` (kept for compatibility, deprecated): the static lines plus the
  root-sum-square of every periodic line, which under-states the peak of sources of
  different orders.

And one range: ``range_peak``, max - min over one output revolution of that phased
periodic curve (the common mode's peak-to-peak, what ISO 230-2's M sees on a dense test).

statistical <= linear, rss <= statistical, peak <= linear always; peak = linear when every
periodic line peaks at the same output angle (``simulate --phases aligned-error``).
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass
from enum import Enum
from typing import NamedTuple

import numpy as np

from wormgear_cli.analysis.accuracy import analyze
from wormgear_cli.drive.records import Static
from wormgear_cli.units import to_unit


class Rule(str, Enum):
    """How the budget's lines combine into a total amplitude (see the module docstring)."""

    LINEAR = "linear"
    STATISTICAL = "statistical"
    PEAK = "peak"
    RSS = "rss"  # deprecated: everything in quadrature


#: the budget's line kinds that have no order: added in every rule
STATIC_KINDS = ("static", "thermal")


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
#: most samples of the phased curve over a turn (orders up to 2**23 / 64 = 131072 are sampled;
#: faster ones are bounded by their amplitudes, see :func:`phased_extremes`)
MAX_PEAK_SAMPLES = 2**23
#: samples evaluated at a time (memory: a few arrays of this length)
_PEAK_BLOCK = 2**16
#: samples of one row of :class:`_SampledSines` (its factors: a row per order)
_SINE_ROW = 512


@dataclass(frozen=True)
class Budget:
    """The lines and their totals [rad] under each :class:`Rule` (amplitudes), the phased
    curve's range ``range_peak`` and the constant ``offsets`` ((source, stage, offset [rad]) of
    curves whose mean is not zero: reported apart, in no total)."""

    drive: str
    lines: tuple
    linear: float
    rss: float
    peak: float
    statistical: float = 0.0
    range_peak: float = 0.0
    offsets: tuple = ()

    def total(self, rule) -> float:
        """The total amplitude [rad] under ``rule`` (a :class:`Rule` or its value)."""
        return {Rule.LINEAR: self.linear, Rule.RSS: self.rss, Rule.PEAK: self.peak,
                Rule.STATISTICAL: self.statistical}[Rule(rule)]

    def report(self, unit: str) -> dict:
        """``{"budget": [...], "total_with_budget": {...}}`` for analyze's JSON (angles in ``unit``;
        ``budget_offsets`` when a curve has a constant mean)."""
        lin = self.linear
        lines = [{"source": ln.source, "stage": ln.stage, "kind": ln.kind, "order": float(ln.order),
                  "amplitude": float(to_unit(ln.amplitude, unit)), "origin": ln.origin,
                  "phase_deg": math.degrees(ln.phase),
                  "share_pct": float(100.0 * ln.amplitude / lin) if lin > 0 else 0.0,
                  "stage_index": ln.stage_index, "stage_kind": ln.stage_kind, "part": ln.part}
                 for ln in self.lines]
        u = lambda x: float(to_unit(x, unit))  # noqa: E731
        totals = {
            # the names of schema 2, kept (deprecated): amplitudes; "rss" is the old quadrature rule
            "transmission_error_linear": u(self.linear), "transmission_error_rss": u(self.rss),
            "transmission_error_peak": u(self.peak),
            "transmission_error_amplitude_linear": u(self.linear),
            "transmission_error_amplitude_statistical": u(self.statistical),
            "transmission_error_amplitude_peak": u(self.peak),
            "transmission_error_range_peak": u(self.range_peak),
        }
        out = {"budget": lines, "total_with_budget": totals}
        if self.offsets:
            out["budget_offsets"] = [{"source": s, "stage": st, "offset": u(v)} for s, st, v in self.offsets]
        return out


def statistical_total(amplitudes, orders, static=0.0):
    """static + sum over distinct orders of sqrt(sum of the squared amplitudes at that order)  [rad].

    ``amplitudes``: sequence of the periodic lines' amplitudes (numbers, or arrays of sampled
    drives, all one shape); ``orders``: their orders [cycles per output revolution] (orders equal
    to 1e-9 relative are one order); ``static``: the static lines' sum.  Vectorised over the
    amplitudes' shape, so a sampler can call it on arrays (docs/budget.md, "How the lines
    combine")."""
    groups: dict[float, float | np.ndarray] = {}
    keys: list[float] = []
    for a, o in zip(amplitudes, orders):
        key = next((k for k in keys if abs(k - o) <= 1e-9 * max(abs(k), abs(o), 1.0)), None)
        if key is None:
            keys.append(float(o))
            key = float(o)
        groups[key] = groups.get(key, 0.0) + np.square(a)
    total = static
    for sq in groups.values():
        total = total + np.sqrt(sq)
    return total


def budget(spec, analysis=None) -> Budget:
    """Every error source of ``spec`` as a :class:`BudgetLine` and the totals.

    ``analysis``: the spec's :func:`wormgear_cli.analysis.accuracy.analyze` result (computed when
    omitted); its registry gives the lines.
    """
    a = analysis if analysis is not None else analyze(spec)
    reg = a.registry
    assert reg is not None  # (analyze keeps the registry it built)
    sources = reg.periodic(all_budget_sources=True)
    all_lines = tuple(
        BudgetLine(x.name, x.stage, x.kind, 0.0, float(x.amplitude), x.origin, 0.0, x.stage_index, x.stage_kind,
                   "") if isinstance(x, Static) else
        BudgetLine(x.name, x.stage, x.kind, float(x.order), float(x.peak if x.peak is not None else x.amplitude),
                   x.origin, float(x.phase), x.stage_index, x.stage_kind, x.part)
        for x in reg.lines)
    static = [ln for ln in all_lines if ln.kind in STATIC_KINDS]
    periodic = [ln for ln in all_lines if ln.kind not in STATIC_KINDS]
    s_static = sum(ln.amplitude for ln in static)
    linear = sum(ln.amplitude for ln in all_lines)
    rss = s_static + math.sqrt(sum(ln.amplitude ** 2 for ln in periodic))
    statistical = statistical_total([ln.amplitude for ln in periodic], [ln.order for ln in periodic], s_static)
    high, low = phased_extremes(sources)
    offsets = tuple((x.name, x.stage, float(x.offset)) for x in reg.sources if x.offset != 0.0)
    return Budget(a.drive, all_lines, float(linear), float(rss), float(s_static + high), float(statistical),
                  float(high - low), offsets)


def phased_peak(sources, phases: dict | None = None) -> float:
    """max over one output revolution of sum_k (curve_k(theta, psi_k) - offset_k)  [rad]
    (:func:`phased_extremes`)."""
    return phased_extremes(sources, phases)[0]


def phased_extremes(sources, phases: dict | None = None) -> tuple[float, float]:
    """(max, min) over one output revolution of the periodic curve sum_k (curve_k(theta, psi_k)
    - offset_k)  [rad]; max - min is its range (peak-to-peak).

    Dense samples (:data:`PEAK_SAMPLES_PER_CYCLE` per cycle of the highest order), evaluated a
    block at a time (memory bounded whatever the orders), then a parabola through the best
    sample and its neighbours.  A train of many stages puts orders at the product of its ratios:
    past :data:`MAX_PEAK_SAMPLES` samples the orders above ``MAX_PEAK_SAMPLES /
    PEAK_SAMPLES_PER_CYCLE`` are not sampled; their amplitudes are added to the slower curve's
    extremes (a bound: a fast term reaches its own peak within half its period of any angle, so
    the true extremes lie within the slower curve's change over that span of it).  ``phases``
    overrides source phases by name [rad].  (0, 0) when there are no sources.
    """
    phases = phases or {}
    live = [s for s in sources if s.amplitude != 0.0 or (s.peak or 0.0) != 0.0]
    if not live:
        return 0.0, 0.0
    fastest = MAX_PEAK_SAMPLES / PEAK_SAMPLES_PER_CYCLE
    fast = [s for s in live if abs(s.order) > fastest]
    slow = [s for s in live if abs(s.order) <= fastest]
    bound = sum(abs(s.amplitude) for s in fast)
    top = max([abs(s.order) for s in slow] + [1.0])
    n = max(_MIN_PEAK_SAMPLES, int(math.ceil(PEAK_SAMPLES_PER_CYCLE * top)))
    step = 2.0 * math.pi / n
    # sinusoids of one order add exactly as phasors, sum_k a_k sin(o t + psi_k) = |P| sin(o t + arg P)
    # with P = sum_k a_k exp(i psi_k): one sine per order instead of one per source
    phasors: dict[float, complex] = {}
    others = []
    for s in slow:
        sine = getattr(s.curve, "sine", None)
        psi = phases.get(s.name, s.phase)
        if sine is None:
            others.append((s.curve, psi, s.offset))
        else:
            phasors[sine[1]] = phasors.get(sine[1], 0j) + sine[0] * cmath.exp(1j * psi)

    def curve(t):
        total = sum(c(t, psi) - off for c, psi, off in others) if others else np.zeros_like(t)
        for order, p in phasors.items():
            total = total + abs(p) * np.sin(order * t + cmath.phase(p))
        return total

    sines = _SampledSines(phasors, step)
    high, low = -math.inf, math.inf
    for a in range(0, n, _PEAK_BLOCK):  # each block with one sample either side, for the parabola
        theta = (np.arange(a - 1, min(n, a + _PEAK_BLOCK) + 1)) * step
        y = sines(a - 1, theta.shape[0])
        for c, psi, off in others:
            y += c(theta, psi) - off
        high = max(high, _refined(curve, theta, y, step))
        low = min(low, -_refined(lambda t: -curve(t), theta, -y, step))
    return high + bound, low - bound


class _SampledSines:
    """sum_o |P_o| sin(o theta_k + arg P_o) at the samples theta_k = k ``step`` [rad] of a turn, for the
    phasors ``{order: P}``: by rows of :data:`_SINE_ROW` samples, each row one complex matrix product,
    sum_o (P_o e^(i o s step)) e^(i o j step) for the row's first sample s and j < _SINE_ROW
    (the angle-addition formula: one product sum a sample and order instead of a sine; the factors
    e^(i o j step) computed once).  Within a few units in the last place of the sum of sines taken
    directly."""

    def __init__(self, phasors: dict, step: float) -> None:
        self.orders = np.array(list(phasors), dtype=float)
        self.phasors = np.array(list(phasors.values()), dtype=complex)
        self.step = step
        self.turn = np.exp(1j * np.multiply.outer(self.orders, np.arange(_SINE_ROW) * step))  # (orders, row)

    def __call__(self, first: int, count: int) -> np.ndarray:
        """The sum at samples first .. first + count - 1, shape (count,)."""
        if self.orders.shape[0] == 0:
            return np.zeros(count)
        rows = -(-count // _SINE_ROW)
        starts = (first + _SINE_ROW * np.arange(rows)) * self.step
        at = self.phasors * np.exp(1j * np.multiply.outer(starts, self.orders))  # (rows, orders)
        return (at @ self.turn).imag.reshape(-1)[:count]


def _refined(curve, theta, y, step) -> float:
    """The largest inner sample of ``y`` (the first and last are its neighbours only) refined by
    a parabola through it and its neighbours."""
    k = 1 + int(np.argmax(y[1:-1]))
    y0, y1, y2 = y[k - 1], y[k], y[k + 1]
    den = y0 - 2.0 * y1 + y2
    best = float(y1)
    if den < 0.0:
        t = theta[k] + 0.5 * step * (y0 - y2) / den
        best = max(best, float(curve(np.array([t]))[0]))
    return best
