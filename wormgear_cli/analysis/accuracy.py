"""Whole-drive analysis: each stage's model applied to a :class:`Spec`, totals at the output.

No I/O.  :func:`analyze` returns an :class:`Analysis` holding every angle in
radians; :meth:`Analysis.report` converts to a unit for output, and
:meth:`Analysis.metrics` flattens it to the CSV/sweep columns.  The stage
models and the aggregation live in :mod:`wormgear_cli.drive` (the registry):
each stage's TE and backlash at its own output shaft, divided by the product
of the ratios after it (the paper's Delta phi = sum_h Delta phi_h / i_h).

The legacy two-stage helpers (:func:`deflections`, :func:`worm_stage`,
:func:`gear_eccentricity`, :func:`line_loads`) read a [worm, spur] drive through
its legacy sections.  Deprecated: nothing in the tool uses them any more (the train serves
every drive: :mod:`wormgear_cli.drive`); they keep working, with a DeprecationWarning naming
their replacement, for callers that hold them.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from wormgear_cli.errors import SpecError
from wormgear_cli.spec.loader import legacy_stages
from wormgear_cli.units import to_unit

if TYPE_CHECKING:
    from wormgear_cli.drive.registry import Registry

#: flat metric columns of a [worm, spur] drive (CSV of analyze, columns of sweep --param); all angles
METRIC_COLUMNS = (
    "gear_transmission_error",
    "gear_backlash",
    "worm_transmission_error",
    "worm_backlash",
    "total_transmission_error",
    "total_backlash",
    "gear_te_eccentricity",
    "gear_te_deformation",
    "gear_backlash_eccentricity",
    "gear_backlash_deformation",
    "worm_te_deformation",
    "worm_te_envelope",
    "worm_backlash_deformation",
    "worm_backlash_profile",
    "worm_backlash_thickness",
    "worm_backlash_envelope",
)
#: flat non-angle columns that follow the angle columns (a [worm, spur] drive)
INFO_COLUMNS = ("gear_ratio", "gear_te_phi_deg", "gear_load_share_pct", "gear_deflection_um", "worm_deflection_um",
                "gear_te_share_pct", "gear_backlash_share_pct")


# an immutable named record built as a NamedTuple, not a frozen dataclass: it is created when
# ``analyze`` starts (0.1 ms against 0.6 ms; docs/development.md, "Start-up")
class Deflections(NamedTuple):
    """Tooth deflections [mm] and the model that produced them."""

    gear: float
    worm: float
    model: str


def geometry(spec):
    """Derived geometry used by the effect catalogue and simulation (a ``DriveGeometry``, any train:
    :func:`wormgear_cli.drive.train.drive_geometry`)."""
    from wormgear_cli.drive.train import drive_geometry  # lazy: keeps drive.train off `analyze`'s start-up

    return drive_geometry(spec)


def _superseded(name: str, new: str) -> None:
    warnings.warn(f"wormgear_cli.analysis.accuracy.{name} reads only a worm + spur drive and is superseded by "
                  f"{new}; it will be removed in wormgear-cli 0.3", DeprecationWarning, stacklevel=3)


def _legacy(spec) -> tuple:
    """(worm stage, spur stage) of a [worm, spur] drive, read from its legacy sections as they are."""
    if spec.gear_pair is None:
        kinds = ", ".join(s.kind for s in spec.stages)
        raise SpecError(f"{spec.source}: this calculation is available for a drive of one worm stage followed by "
                        f"one spur stage; this drive has the stages {kinds}")
    return legacy_stages(spec)


def deflections(spec, gear_force=None, worm_force=None, linear_at_spec_load=False) -> Deflections:
    """delta1 and delta2 [mm] of a [worm, spur] drive from its loads and stiffness model.

    ``gear_force``/``worm_force`` override the spec's normal forces [N]
    (arrays allowed; used by sweeps that hold torque instead of force).
    ``linear_at_spec_load``: evaluate ISO 6336-1's low-load reduction of c'
    at the spec's own loads and keep it fixed, so the deflection is linear in
    the given forces (the compliance about the operating point; a spec without
    load uses the unreduced c').  Otherwise c' follows the given forces.
    The one definition per stage: :func:`wormgear_cli.drive.stiffness.deflection` (deprecated
    wrapper of it; a drive's deflections at its loads: ``drive.registry.build(spec).deflections``).
    """
    from wormgear_cli.drive.stiffness import deflection  # lazy: keeps drive.stiffness off `analyze`'s start-up

    _superseded("deflections", "wormgear_cli.drive.stiffness.deflection(spec, stage, force)")
    stages = _legacy(spec)
    d1, d2 = (deflection(spec, s, f, linear_at_spec_load, stages) for s, f in ((stages[1], gear_force),
                                                                              (stages[0], worm_force)))
    return Deflections(float(d1) if np.ndim(d1) == 0 else d1, float(d2) if np.ndim(d2) == 0 else d2,
                       spec.stiffness.model)


def line_loads(spec) -> tuple[float, float]:
    """F_t K_A / b [N/mm] of the spur and the worm mesh of a [worm, spur] drive at its loads (ISO 6336-1).
    Deprecated: :func:`wormgear_cli.drive.stiffness.line_load` of each stage."""
    from wormgear_cli.drive.stiffness import line_load  # lazy: keeps drive.stiffness off `analyze`'s start-up

    _superseded("line_loads", "wormgear_cli.drive.stiffness.line_load(spec, stage)")
    worm, gear = _legacy(spec)
    return line_load(spec, gear), line_load(spec, worm)


def gear_eccentricity(spec) -> float:
    """The spur stage's eccentricity Delta e [mm] the chosen kinematics uses (a [worm, spur] drive):
    ``paper``, ``assembly.gear_eccentricity_mm`` (default the centre-distance error, as the paper
    reads Table 1); ``involute``, only an eccentricity written in the spec.  Deprecated: a spur
    stage's ``model_eccentricity``."""
    _superseded("gear_eccentricity", "the spur stage's model_eccentricity (spec.stages[k].model_eccentricity)")
    return _legacy(spec)[1].model_eccentricity


def worm_stage(spec, deflection):
    """The paper's worm stage of a [worm, spur] ``spec`` at tooth deflection ``deflection`` [mm] (delta2;
    scalar or array): :func:`wormgear_cli.drive.worm.paper`, the one definition that ``analyze`` and
    the torque-held ``sweep`` use.  Deprecated: :func:`wormgear_cli.drive.worm.paper` of the stage."""
    from wormgear_cli.drive.worm import paper  # lazy: keeps drive.worm off `analyze`'s start-up

    _superseded("worm_stage", "wormgear_cli.drive.worm.paper(stage, deflection)")
    return paper(_legacy(spec)[0], deflection)


def _pct(part, whole) -> float:
    return float(100.0 * part / whole) if whole > 0 else 0.0


def shares(results, te_total: float, bl_total: float) -> list[tuple[float, float]]:
    """Each stage's share [%] of the total TE and backlash (motor -> output): 100 c_h / total for
    every stage but the first, whose share is 100 less the others' (so they add up to 100)."""
    out = [(_pct(r.te_at_output, te_total), _pct(r.backlash_at_output, bl_total)) for r in results]
    if len(out) > 1:
        out[0] = (100.0 - sum(te for te, _ in out[1:]), 100.0 - sum(bl for _, bl in out[1:]))
    return out


@dataclass(frozen=True)
class Analysis:
    """Result of :func:`analyze`.  ``angles``: name -> value [rad];
    ``info``: name -> dimensionless or labelled values; ``stages``: each stage's
    :class:`~wormgear_cli.drive.records.StageResult` (motor -> output); ``registry``: the drive's
    :class:`~wormgear_cli.drive.registry.Registry`."""

    drive: str
    angles: dict
    info: dict
    stages: tuple = ()
    registry: Registry | None = field(default=None, repr=False, compare=False)

    @property
    def columns(self) -> tuple[tuple, tuple]:
        """(angle columns, other columns) of :meth:`metrics`: the legacy columns for a [worm, spur]
        drive, else each stage's (output -> motor) by its name."""
        if tuple(r.kind for r in self.stages) == ("worm", "spur"):
            return METRIC_COLUMNS, INFO_COLUMNS
        back = self.stages[::-1]
        angle = [f"{r.name}_{q}" for r in back for q in ("transmission_error", "backlash")]
        angle += ["total_transmission_error", "total_backlash"]
        angle += [f"{r.name}_te_{p}" for r in back for p in r.te_parts]
        angle += [f"{r.name}_backlash_{p}" for r in back for p in r.backlash_parts]
        info = [f"{r.name}_{k}" for r in back for k in _info_keys(r)]
        info += [f"{r.name}_{q}_share_pct" for r in back for q in ("te", "backlash")]
        return tuple(angle), tuple(info)

    def metrics(self, unit: str) -> dict:
        """Flat ``column -> value`` (angles in ``unit``) for CSV and sweeps."""
        angle_cols, info_cols = self.columns
        out = {c: float(to_unit(self.angles[c], unit)) for c in angle_cols}
        out.update({c: (None if self.info[c] is None else float(self.info[c])) for c in info_cols})
        return out

    def report(self, unit: str) -> dict:
        """The JSON document of ``wormgear analyze`` (angles in ``unit``): ``stages`` a list from the
        motor to the output, each at its own output shaft and its contribution at the output."""
        a = {k: float(to_unit(v, unit)) for k, v in self.angles.items()}
        i = self.info
        ratios = {"total": i["total_ratio"], "stages": [r.ratio for r in self.stages]}
        if tuple(r.kind for r in self.stages) == ("worm", "spur"):
            ratios = {"gear": i["gear_ratio"], "worm": i["worm_ratio"], **ratios}
        return {
            "drive": self.drive,
            "unit": unit,
            "ratios": ratios,
            "deflection_model": i["deflection_model"],
            "stages": [_stage_report(r, a, i) for r in self.stages],
            "total": {
                "transmission_error": a["total_transmission_error"],
                "backlash": a["total_backlash"],
                **({"backlash_additions": {k[len("drive_backlash_"):]: v for k, v in a.items()
                                           if k.startswith("drive_backlash_")}}
                   if any(k.startswith("drive_backlash_") for k in a) else {}),
            },
        }


def _info_keys(r) -> tuple[str, ...]:
    if r.kind == "spur":
        return ("ratio", "te_phi_deg", "load_share_pct", "deflection_um")
    if r.kind == "worm":
        return ("ratio", "deflection_um")
    if r.kind == "belt":
        return ("ratio", "stretch_um")
    return ("ratio",)  # another kind: its ratio (its model's info is in the JSON stage entry)


def _stage_report(r, a: dict, i: dict) -> dict:
    """One stage's entry of analyze's JSON ``stages`` list."""
    n = r.name
    te, bl = a[f"{n}_transmission_error"], a[f"{n}_backlash"]
    tp = {k: a[f"{n}_te_{k}"] for k in r.te_parts}
    bp = {k: a[f"{n}_backlash_{k}"] for k in r.backlash_parts}
    if r.kind == "worm":
        paper_te, paper_bl = ("deformation", "envelope"), ("deformation", "profile", "thickness", "envelope")
        tp = {"deformation": tp["deformation"], "envelope_halfwidth": tp["envelope"],
              "lower_bound": tp["deformation"] - tp["envelope"],
              **{k: v for k, v in tp.items() if k not in paper_te}}  # the parts beyond the paper, when given
        if "envelope" in bp:
            bp = {"deformation": bp["deformation"], "profile": bp["profile"], "thickness": bp["thickness"],
                  "envelope_halfwidth": bp["envelope"], "lower_bound": bl - 2.0 * bp["envelope"],
                  **{k: v for k, v in bp.items() if k not in paper_bl}}
    out: dict = {"stage": r.index, "name": n, "kind": r.kind, "ratio": r.ratio, "ratio_after": r.after}
    if r.symbols[0]:
        out["symbols"] = {"transmission_error": r.symbols[0], "backlash": r.symbols[1]}
    out.update({"transmission_error": te, "backlash": bl, "transmission_error_parts": tp, "backlash_parts": bp})
    if r.kind == "spur":
        out.update({"kinematics": r.info["kinematics"], "line_load_N_per_mm": r.info["line_load_N_per_mm"],
                    "phi_at_max_deg": r.info["phi_at_max_deg"], "load_share_pct": r.info["load_share_pct"],
                    "deflection_um": r.info["deflection_um"]})
    elif r.kind == "worm":
        out.update({"deflection_um": r.info["deflection_um"], "line_load_N_per_mm": r.info["line_load_N_per_mm"]})
    else:  # a belt stage (effective tension, stretch, span length, centre distance) or another kind: its model's
        out.update(r.info)
    if r.info.get("anti_backlash", "none") != "none":
        out["anti_backlash"] = r.info["anti_backlash"]
    out["contribution"] = {"transmission_error": te / r.after, "backlash": bl / r.after,
                           "transmission_error_pct": i[f"{n}_te_share_pct"],
                           "backlash_pct": i[f"{n}_backlash_share_pct"]}
    return out


def analyze(spec, registry: Registry | None = None) -> Analysis:
    """Each stage's model and the totals at the output for one drive.

    Stage values are at each stage's own output shaft (as the paper reports
    them); totals at the output: Delta phi = sum_h Delta phi_h / O_h, O_h the
    product of the ratios after stage h (for the paper's [worm, spur] drive
    Delta phi_c = Delta phi_cc + Delta phi_wc / i_c, Delta phi_h = Delta phi_ch +
    Delta phi_wh / i_c with i_c = z1/z2).  ``registry``: the spec's
    :func:`wormgear_cli.drive.registry.build`, built when omitted.
    """
    from wormgear_cli.drive.registry import build  # lazy: keeps drive.registry off `analyze`'s start-up

    reg = registry if registry is not None else build(spec)
    total_te, total_bl = reg.totals()
    extra = reg.backlash_additions()  # drive-level lost motion: in the total, in no stage's share
    angles: dict = {f"drive_backlash_{k}": v for k, v in extra.items()}
    train: Any = reg.train  # (the registry's train is typed object in drive.registry)
    info: dict = {"total_ratio": train.total_ratio, "deflection_model": spec.stiffness.model}
    for r, (te_pct, bl_pct) in zip(reg.results, shares(reg.results, total_te, total_bl - sum(extra.values()))):
        n = r.name
        angles[f"{n}_transmission_error"] = r.transmission_error
        angles[f"{n}_backlash"] = r.backlash
        angles.update({f"{n}_te_{k}": v for k, v in r.te_parts.items()})
        angles.update({f"{n}_backlash_{k}": v for k, v in r.backlash_parts.items()})
        info.update({f"{n}_ratio": r.ratio, f"{n}_te_share_pct": te_pct, f"{n}_backlash_share_pct": bl_pct})
        info.update({f"{n}_{k}": v for k, v in r.info.items() if k not in ("phi_at_max_deg",)})
        if r.kind == "spur":
            info[f"{n}_te_phi_deg"] = r.info["phi_at_max_deg"]
            info.setdefault("kinematics", r.info["kinematics"])
    angles["total_transmission_error"] = float(total_te)
    angles["total_backlash"] = float(total_bl)
    spurs = [r for r in reg.results if r.kind == "spur"]
    if spurs:
        info["kinematics"] = spurs[-1].info["kinematics"]
    return Analysis(spec.drive.name, angles, info, reg.results, reg)
