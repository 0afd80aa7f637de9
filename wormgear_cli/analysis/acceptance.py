"""The acceptance test, predicted: ISO 230-2 figures of the nominal drive on the spec's ``[test_plan]``.

No I/O.  ISO 230-2's A, E, M and B are ranges (max - min over the targets) and a reversal;
a drive file can hold them as requirements (``max_iso230_A_arcsec`` ...) and ``check`` judges
them on the figures this module predicts: the error curve of ``simulate`` (the spec's sources at
their phases, its clearances, the deflection lag under its loads, its ``[effects]`` at 20 degC)
read at the plan's targets, one pass up and one pass down per run, and put through
:func:`wormgear_cli.measurement.iso230.iso230_figures`, the same code that reads a measured test.

The plan (:func:`plan_targets`): ``targets`` positions over one output turn spaced irregularly,
P_i = i p + r_i (p = 360 deg / targets, r_0 = 0, r_i uniform in +/- ``jitter`` p: ``synth``'s iso
plan, the same targets for the same ``seed``), or the explicit ``targets_deg``; ``runs`` runs in
each direction (ISO 230-2's standard cycle: 5).  The model has no noise: every run reads the same
deviations, so the scatter between runs is the plan's ``reading_scatter_arcsec`` s: each cell is
given readings with exactly that sample standard deviation about the model's value, so A (which
takes x +/- 2 s) and R come out as the standard defines them for that s, and E, M, B are the
model's own.  Angles [rad] inside.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from wormgear_cli.analysis.simulate import components
from wormgear_cli.analysis.synth import Plan, plan_angles
from wormgear_cli.measurement.iso230 import iso230_figures
from wormgear_cli.physics.effects import Signals
from wormgear_cli.units import ARCSEC

#: the figures a requirement can limit, ``max_iso230_<NAME>_arcsec``
FIGURES = ("A", "E", "B", "M")
#: seconds per target, as synth's iso plan (the time only matters to time-dependent effects)
DWELL_S = 10.0


class Prediction(NamedTuple):
    """The predicted test: ``figures`` (an :class:`~wormgear_cli.measurement.iso230.Iso230Figures`,
    [rad]), ``targets`` [rad, ascending], ``runs``, ``reading_scatter`` [rad], ``spacing``: how the
    targets were placed (``{"jitter", "seed"}``, or None when the plan lists them)."""

    figures: object
    targets: np.ndarray
    runs: int
    reading_scatter: float
    spacing: dict | None = None

    def figure(self, name: str) -> float:
        """ISO 230-2 figure ``name`` (A, E, B, M, R ...) [rad]."""
        return float(getattr(self.figures, name))

    def describe(self) -> dict:
        """The plan as check's JSON states it next to each ISO 230-2 limit."""
        where = ({"targets_deg": "as listed in [test_plan]"} if self.spacing is None else
                 {"spacing": "irregular", **self.spacing})
        return {"targets": int(self.targets.size), **where, "runs": self.runs,
                "reading_scatter_arcsec": self.reading_scatter / ARCSEC}


def plan_targets(test_plan) -> np.ndarray:
    """The target angles [rad, ascending] of a spec's ``test_plan`` section (module docstring)."""
    if test_plan.targets_deg is not None:
        return np.sort(np.asarray(test_plan.targets_deg, dtype=float))

    rng = np.random.default_rng(np.random.SeedSequence(int(test_plan.seed)).spawn(4)[0])  # synth's target stream
    plan = Plan(kind="iso", targets=int(test_plan.targets), runs=int(test_plan.runs), jitter=float(test_plan.jitter))
    return np.radians(plan_angles(plan, rng))


def _spread(runs: int) -> np.ndarray:
    """``runs`` offsets of mean 0 and sample standard deviation 1 (n - 1), or zeros for one run."""
    if runs < 2:
        return np.zeros(runs)
    c = np.linspace(-1.0, 1.0, runs)
    return c / np.std(c, ddof=1)


def predict(spec, registry=None) -> Prediction:
    """The ISO 230-2 figures of ``spec``'s nominal drive on its own ``[test_plan]`` (module docstring).

    ``registry``: the spec's :func:`wormgear_cli.drive.registry.build` (built when omitted)."""
    tp = spec.test_plan
    theta = plan_targets(tp)
    n, runs = theta.size, int(tp.runs)
    one = np.concatenate([theta, theta[::-1]])
    direction = np.concatenate([np.ones(n), -np.ones(n)])
    time = np.arange(2 * n) * DWELL_S
    parts = components(spec, Signals.make(one, direction, 0.0, 20.0, time), registry=registry)
    model = sum(parts.values(), np.zeros(2 * n))
    scatter = float(tp.reading_scatter)
    angle = np.tile(one, runs)
    error = np.tile(model, runs) + scatter * np.repeat(_spread(runs), 2 * n)
    spacing = None if tp.targets_deg is not None else {"jitter": float(tp.jitter), "seed": int(tp.seed)}
    return Prediction(iso230_figures(angle, error, np.tile(direction, runs)), theta, runs, scatter, spacing)
