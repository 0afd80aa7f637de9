"""The records of the drive model: a stage's result and the registry's error sources.

Typed named tuples (immutable, fields by name), not frozen dataclasses: they are created when
``analyze`` starts (0.1 ms against 0.6 ms each; docs/development.md, "Start-up").  Angles [rad].
"""

from collections.abc import Callable
from typing import NamedTuple

import numpy as np


class StageResult(NamedTuple):
    """One stage's transmission error and backlash at its own output shaft [rad] (the paper's
    Delta phi_cc / Delta phi_ch for a spur stage, Delta phi_wc / Delta phi_wh for a worm stage).

    ``ratio`` i_k; ``after``: the product of the ratios after the stage (its contribution at the
    output is its value / ``after``); ``te_parts``, ``backlash_parts``: name -> [rad] at its shaft;
    ``info``: name -> number (deflection_um, line_load_N_per_mm, ...); ``symbols``: the paper's
    names of its TE and backlash, or ("", "")."""

    index: int  # type: ignore[assignment]  # a field named as tuple.index, by design
    name: str
    kind: str
    ratio: float
    after: float
    transmission_error: float
    backlash: float
    te_parts: dict
    backlash_parts: dict
    info: dict
    symbols: tuple = ("", "")

    @property
    def te_at_output(self) -> float:
        return self.transmission_error / self.after

    @property
    def backlash_at_output(self) -> float:
        return self.backlash / self.after


class Source(NamedTuple):
    """A periodic error source at the output (one line of the registry).

    ``name``: unique in the drive (``worm_lead_error``; ``stage3_pinion_single_pitch`` when a name
    repeats); ``phase_path``: TOML path of its phase key; ``order``: cycles per output revolution;
    ``amplitude`` [rad at the output] (for the non-sinusoidal paper gear curve: its first-harmonic
    size); ``phase`` [rad] as specified; ``curve(theta, phase)`` -> [rad], its common-mode
    contribution; ``lost_motion(theta, phase)`` -> [rad] at the output, or None; ``stage``: the
    stage's name (``gear``, ``worm``, ``belt``...); ``kind``: ``shaft`` (once per turn of a shaft),
    ``mesh`` (a tooth-mesh order) or ``belt`` (once per belt revolution); ``size_paths``: the TOML
    paths its size comes from; ``peak``: the largest value of ``curve`` over a turn [rad];
    ``stage_index`` (1-based, motor -> output), ``stage_kind``, ``part`` (worm, wheel, pinion,
    gear, driver, driven, belt); ``origin`` of its size (spec / grade / default); ``size_keys``: the
    stage keys its size comes from; ``size(value)`` -> amplitude [rad at the output] from
    ``value(stage_key)`` (numbers or arrays: the same function gives the spec's amplitude and,
    vectorised, a sampled drive's); ``tier``: 0 the model's sources (always listed), 1 the full
    budget's once-per-turn additions and 2 its mesh-order ones (listed when they have a size);
    ``lost_size(value)`` -> (c, a, s, clipped): the source's lost motion of a sampled drive (arrays)
    is max(c + a sin(order theta + phase), 0) s [rad at the output] (``clipped`` False: c >= |a|,
    never negative, taken as it is) (None: no lost motion);
    ``curve_at(value, theta, phase)`` -> [rad]: the curve of a sampled drive for a source that is
    not a sinusoid (None: ``size(value) sin(order theta + phase)``);
    ``offset``: the mean of ``curve`` over a turn [rad] (0 for a sinusoid; the paper's spur curve
    has one: a constant shift of every position, no positioning error), so ``peak`` is the
    largest value of ``curve - offset``, the periodic part the budget counts."""

    name: str
    phase_path: str
    order: float
    amplitude: float
    phase: float
    curve: Callable
    lost_motion: Callable | None = None
    stage: str = "gear"
    kind: str = "shaft"
    size_paths: tuple = ()
    peak: float | None = None
    stage_index: int = 0
    stage_kind: str = ""
    part: str = ""
    origin: str = "default"
    size_keys: tuple = ()
    size: Callable | None = None
    tier: int = 0
    lost_size: Callable | None = None
    curve_at: Callable | None = None
    offset: float = 0.0


class Static(NamedTuple):
    """A static transmission-error term at the output (tooth deflection, belt stretch under the
    process load; ``kind`` "static") or a thermal drift at the operating temperatures (``kind``
    "thermal") [rad], with the same identifying fields as :class:`Source`."""

    name: str
    amplitude: float
    stage: str
    stage_index: int
    stage_kind: str
    origin: str
    size_paths: tuple = ()
    kind: str = "static"


class Clearance(NamedTuple):
    """A constant lost motion at the output [rad] not tied to a periodic source (a belt's tooth
    clearance, the residual of an anti-backlash arrangement, a worm's thrust-bearing play, a
    thermal change of a clearance (negative: it closes), the wind-up of a friction torque;
    ``stage_index`` 0 and ``stage`` "drive" for a drive-level term); ``size(value)`` -> [rad] the
    amount of a sampled drive from ``value(stage_key)`` (None: not toleranced).  ``origin``: spec /
    default; ``in_stage``: already part of the stage's backlash (its :class:`StageResult`), else an
    addition to the drive's total."""

    name: str
    amount: float
    stage: str
    stage_index: int
    stage_kind: str
    size_keys: tuple = ()
    size: Callable | None = None
    origin: str = "spec"
    in_stage: bool = True


class Compliance(NamedTuple):
    """Tooth-stiffness terms [rad]: ``process_lag`` per direction under the spec's loads,
    ``per_Nm`` output wind-up per N m of external torque on the output; summed over the stages
    referred to the output (1/k_out = sum_h 1/(k_h O_h^2))."""

    process_lag: float
    per_Nm: float


def sine(amplitude, order):
    """``curve(theta, phase) = amplitude sin(order theta + phase)``, marked as a pure sinusoid."""
    def curve(theta, phase):
        return amplitude * np.sin(order * theta + phase)

    curve.sine = (amplitude, order)  # type: ignore[attr-defined]  # a pure sinusoid: the budget's peak adds these as phasors
    return curve


def sine_source(name, phase_path, order, amplitude, phase, stage, kind, paths, lost=None, **extra) -> Source:
    """A sinusoidal :class:`Source` (its peak is its amplitude)."""
    return Source(name, phase_path, order, amplitude, phase, sine(amplitude, order), lost, stage, kind, paths,
                  amplitude, **extra)
