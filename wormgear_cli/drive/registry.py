"""THE registry of a drive's error sources, built once from its train; every command reads it.

:func:`build` evaluates each stage by its kind's model (:mod:`~wormgear_cli.drive.worm`,
:mod:`~wormgear_cli.drive.spur`, :mod:`~wormgear_cli.drive.belt`) and collects, at the output:

* ``results``: each stage's TE and backlash at its own output shaft (:class:`StageResult`), whose
  sum divided by the ratios after each stage is the drive's total (the paper's
  Delta phi = sum_h Delta phi_h / i_h);
* ``sources``: every periodic error source (:class:`Source`: stage, part, kind, order, amplitude,
  phase, origin, size keys and the vectorised size function), in the budget's order;
* ``statics``: the static TE terms (tooth deflection, belt stretch) and ``clearances``: the
  constant lost-motion terms not tied to a source;
* ``compliance``: the process-load lag and the wind-up per N m at the output, summed over the
  stages referred to the output (1/k_out = sum_h 1/(k_h O_h^2)).

Order of the lines (the budget's and simulate's): the model's own sources and each stage's static
term stage by stage from the output back to the motor, then the full budget's once-per-turn
additions, then its mesh-order ones.  A name used by two stages is prefixed ``stageN_``.
"""

import math
from typing import Any, NamedTuple

from wormgear_cli.drive import spur
from wormgear_cli.drive import train as train_mod
from wormgear_cli.drive.models import MODELS
from wormgear_cli.drive.records import Clearance, Compliance, Source, StageResult, Static


class Registry(NamedTuple):
    """Everything the commands read about a drive's errors (module docstring).  Angles [rad]."""

    train: Any  # a drive.train.Train
    results: tuple
    sources: tuple
    statics: tuple
    clearances: tuple
    compliance: Compliance
    deflections: tuple
    lines: tuple

    def periodic(self, all_budget_sources: bool = False) -> list[Source]:
        """The periodic sources: the model's own always (zero-size ones included), the full budget's
        additions only when they have a size, or always with ``all_budget_sources``."""
        return [s for s in self.sources if all_budget_sources or s.tier == 0 or s.amplitude != 0.0]

    def totals(self) -> tuple[float, float]:
        """(TE, backlash) at the output [rad]: sum_h value_h / O_h, added from the output back, and the
        drive-level lost motion (:meth:`backlash_additions`)."""
        te = bl = 0.0
        for r in reversed(self.results):
            te = te + r.transmission_error / r.after
            bl = bl + r.backlash / r.after
        return te, bl + sum(self.backlash_additions().values())

    def backlash_additions(self) -> dict:
        """name -> lost motion at the output [rad] that belongs to no stage (the wind-up of a friction
        torque through the whole train's compliance)."""
        return {c.name: c.amount for c in self.clearances if not c.in_stage}

    def result(self, kind: str) -> StageResult | None:
        """The last stage of kind ``kind`` (the legacy form's gear or worm stage), or None."""
        found = [r for r in self.results if r.kind == kind]
        return found[-1] if found else None


def origin_of(stage, keys) -> str:
    """The origin of a size read from stage ``keys``: "grade" if any is graded, else "spec" if any is
    written, else "default"."""
    found = {stage.origins.get(k, "default") for k in keys}
    for o in ("grade", "spec"):
        if o in found:
            return o
    return "default"


def deflections(spec, stages=None) -> tuple:
    """Each stage's tooth deflection under its load [mm] (its model's; 0 for a belt stage)."""
    stages = spec.stages if stages is None else stages
    return tuple(MODELS[s.kind].tooth_deflection(spec, s, stages) for s in stages)


def build(spec) -> Registry:
    """The registry of ``spec`` (module docstring)."""
    t = train_mod.of(spec)
    defl = deflections(spec)
    results, keyed, statics, clears = [], [], [], []
    lag = per_nm = 0.0
    n = len(t.stages)
    for s, d in zip(t.stages, defl):
        model = MODELS[s.kind]
        res = model.evaluate(spec, s, t, d)
        src, st, cl = model.sources(spec, s, t, d, res, origin_of)
        c_lag, c_per = model.compliance(spec, s, t, d)
        lag, per_nm = lag + c_lag, per_nm + c_per
        results.append(res)
        statics += st
        clears += cl
        keyed += [((x.tier, n - s.index, k), x) for k, x in enumerate(src)]
        keyed += [((0, n - s.index, 100 + k), x) for k, x in enumerate(st)]
    friction = getattr(spec.drive, "friction_torque", None)
    if friction:  # reverses with the motion: the train winds up by T_f C_out each way
        clears.append(Clearance("friction_windup", 2.0 * friction * per_nm, "drive", 0, "drive", origin="spec",
                                 in_stage=False))
    keyed.sort(key=lambda item: item[0])
    lines = _unique_names([x for _, x in keyed])
    sources = tuple(x for x in lines if isinstance(x, Source))
    statics_out = tuple(x for x in lines if isinstance(x, Static))
    return Registry(t, tuple(results), sources, statics_out, tuple(clears), Compliance(lag, per_nm), defl,
                    tuple(lines))


def _unique_names(lines: list) -> list:
    """The lines with every name used more than once prefixed by its stage: ``stage3_pinion_...``."""
    count: dict[str, int] = {}
    for x in lines:
        count[x.name] = count.get(x.name, 0) + 1
    return [x._replace(name=f"stage{x.stage_index}_{x.name}") if count[x.name] > 1 else x for x in lines]


def aligned_phases(spec, quantity: str = "error", registry: Registry | None = None) -> dict[str, float]:
    """Source phases [rad] that make the sources peak together at theta = 0.

    ``quantity="error"``: every sinusoidal source at phase 90 deg and each paper-kinematics spur
    stage's eccentricity at the pinion angle of its kinematic maximum, so the common mode reaches
    the linear sum of the peaks at theta = 0.  ``quantity="reversal"``: every source at 90 deg, so
    the sources with lost motion (a spur stage's eccentricity, a worm stage's radial composite
    error) peak together and the reversal reaches analyze's total backlash at theta = 0.
    """
    if quantity not in ("error", "reversal"):
        raise ValueError(f"quantity must be 'error' or 'reversal', got {quantity!r}")
    reg = registry or build(spec)
    out = {src.name: 0.5 * math.pi for src in reg.periodic()}
    if quantity == "error":

        for src in reg.sources:
            stage = reg.train.stages[src.stage_index - 1]
            if src.stage_kind == "spur" and src.part == "pinion" and src.kind == "shaft" and src.size_keys[0] == \
                    "eccentricity_mm" and stage.kinematics == "paper":
                r1, r2 = spur.radii(stage)
                _, phi = spur.paper_te_max(r1, r2, stage.model_eccentricity, stage.pressure_angle, 0.0)
                out[src.name] = float(phi)
    return out


__all__ = ["MODELS", "Registry", "Source", "Static", "Clearance", "Compliance", "StageResult", "build",
           "aligned_phases", "deflections", "origin_of"]
