"""The effect catalogue: physical terms the paper's model lacks.

Each effect is data: a name, its parameters (TOML key, internal name, unit,
conversion to internal units, physical range) and a signature function.
``simulate``, the spec loader and ``diagnose`` all read :data:`EFFECTS`.

Signature functions take the operating signals (output angle theta [rad],
direction d = +1/-1, external load on the output [N*m], temperature
[degC], time [s]), the drive geometry (:class:`DriveGeometry`) and the
effect's parameters in internal units, and return the error at the output
[rad] (actual - target).  All broadcast over numpy arrays.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import cast

import numpy as np

UM = 1e-3  # mm per um
from wormgear_cli.physics.geometry import DriveGeometry  # noqa: E402  (re-exported: its old home)
from wormgear_cli.units import ARCSEC, DEG  # noqa: E402  (rad per arcsec, per degree: one definition)


@dataclass(frozen=True)
class Param:
    """One effect parameter: TOML ``key``, internal ``name``, ``unit`` of the
    key, ``scale`` (internal = value * scale), physical range [lo, hi] in
    the key's unit, ``default`` in the key's unit (None: required)."""

    key: str
    name: str
    unit: str
    scale: float
    lo: float
    hi: float
    default: float | None = None
    doc: str = ""


@dataclass(frozen=True)
class Signals:
    """Operating conditions at each sample (arrays of one length)."""

    theta: np.ndarray
    direction: np.ndarray
    load: np.ndarray
    temperature: np.ndarray
    time: np.ndarray

    @classmethod
    def make(cls, theta, direction=1.0, load=0.0, temperature=20.0, time=0.0) -> Signals:
        theta = np.asarray(theta, dtype=float)
        full = lambda v: np.broadcast_to(np.asarray(v, dtype=float), theta.shape)  # noqa: E731
        return cls(theta, full(direction), full(load), full(temperature), full(time))


@dataclass(frozen=True)
class Effect:
    """A catalogue entry.

    ``order``: the harmonic order (cycles per output revolution) of a
    periodic effect as a function of the geometry, or None.  ``needs``:
    the signal that must vary for the effect to be observable
    ("temperature", "load", "direction") or None.  ``amplitude``: the
    parameter the signature is linear in (diagnosis fits it linearly);
    when ``extra.get("inverse")`` is True the signature is linear in the
    reciprocal of that parameter instead (``torsional_compliance``: load / k).
    ``phase``: the internal name of the phase parameter of a periodic
    effect, or None.

    What ``diagnose`` reads (the effect's diagnosis metadata): ``mode``,
    "common" (both directions alike) or "differential" (the reversal: lost
    motion); ``pattern``, what the residual scan sees of a non-periodic
    effect: "trend" (against its ``needs`` signal, in its ``mode``) or
    "reversal" (a change of the mean reversal), None for a periodic effect
    (its ``order``); ``signature``, those words for a report (see
    :meth:`signature_text`); ``separate_hint``, how to measure so the effect
    can be told from one its columns resemble; ``unphysical_hint``, what a
    significant fit outside the physical range says about the spec.
    """

    name: str
    function: Callable
    params: tuple[Param, ...]
    amplitude: str
    doc: str
    order: Callable[[DriveGeometry], float] | None = None
    needs: str | None = None
    phase: str | None = None
    extra: dict = field(default_factory=dict)
    mode: str = "common"
    pattern: str | None = None
    signature: str = ""
    separate_hint: str | None = None
    unphysical_hint: str | None = None

    def param(self, key: str) -> Param:
        return next(p for p in self.params if p.key == key)

    def signature_text(self, g: DriveGeometry) -> str:
        """The effect's signature in words: its ``signature``, or for a periodic effect its order in
        the drive ``g``, else its ``doc``."""
        if self.signature:
            return self.signature
        if self.order is not None:
            return f"order {float(self.order(g)):g} content in common mode"
        return self.doc


def output_gear_runout(s: Signals, g: DriveGeometry, eccentricity, phase):
    """(e / r_b1) sin(theta + psi)  [rad]: eccentricity e [mm] of the output gear,
    r_b1 its base radius [mm]; once per output revolution.

    The involute rule (docs/budget.md, ``gear_pair.kinematics = "involute"``): an
    eccentric gear moves its base circle by e sin(theta) along the line of action,
    a TE of e / r_b at its own shaft.  In any train the output member: the output stage's
    spur gear, worm wheel (e / r_b,wheel, the same size as the worm stage's wheel runout
    S2 = 2 e: S2 / (2 cos(alpha_2)) on its pitch circle) or driven pulley (e / R)."""
    return eccentricity / g.output_base_radius * np.sin(s.theta + phase)


def intermediate_shaft_runout(s: Signals, g: DriveGeometry, eccentricity, phase):
    """(e / r_b1) sin(i_c theta + psi)  [rad]: eccentricity e [mm] of the pinion, order i_c.

    In any train: the output stage's input member (its pinion or driving pulley), at its shaft's
    order; a train whose output stage is a worm has no such shaft apart from the worm shaft
    (:func:`worm_runout`).

    By the involute rule the pinion's eccentricity gives e / r_b2 at the pinion,
    i.e. e / (r_b2 i_c) = e / r_b1 at the output (r_b2 i_c = r_b1).  The worm wheel
    sits on the same shaft (same order) but converts through its own radius: a
    wheel eccentricity e_w gives e_w / (r_b,wheel i_c) at the output, not e_w / r_b1;
    enter it here as the equivalent e = e_w r_b1 / (r_b,wheel i_c).  The spec's wheel
    runout S2 (``wheel.runout_mm``, legacy ``assembly.wheel_eccentricity_mm``) is a total
    indicator reading, S2 = 2 e_w: the paper's S2 / (2 cos(alpha_2)) on the wheel's pitch
    circle is this same e_w / r_b,wheel (docs/models.md, "Runout and eccentricity")."""
    return eccentricity / g.output_base_radius * np.sin(g.intermediate_order * s.theta + phase)


def worm_runout(s: Signals, g: DriveGeometry, amplitude, phase):
    """(a / r_wheel) / i_c sin(n_w theta + psi)  [rad]: worm once-per-turn error
    a [mm] at the wheel pitch circle, reduced by the spur stage (in any train: by the
    product of the ratios after the worm stage)."""
    return amplitude / g.wheel_pitch_radius / g.worm_reduction * np.sin(g.worm_order * s.theta + phase)


def gear_mesh_error(s: Signals, g: DriveGeometry, amplitude, phase):
    """(a / r_1) sin(z1 theta + psi)  [rad]: tooth-mesh error a [mm] of the output
    gear at its pitch radius r_1 (in any train: the output stage's mesh, z1 the teeth of its
    output member)."""
    return amplitude / g.output_pitch_radius * np.sin(g.output_teeth * s.theta + phase)


def thermal_backlash(s: Signals, g: DriveGeometry, coefficient, reference_temperature):
    """-d Delta B / 2, Delta B = 2 k (T - T_ref) tan(alpha_x) / r_wheel / i_c  [rad].

    k [mm/K] is the growth of the worm centre distance per kelvin; a growing
    centre distance opens the backlash (lost motion grows)."""
    db = 2.0 * coefficient * (s.temperature - reference_temperature) * np.tan(g.axial_pressure_angle)
    db = db / g.wheel_pitch_radius / g.worm_reduction
    return -s.direction * db / 2.0


def thermal_drift(s: Signals, g: DriveGeometry, coefficient, reference_temperature):
    """k (T - T_ref)  [rad], both directions; k [rad/K]."""
    return coefficient * (s.temperature - reference_temperature)


def torsional_compliance(s: Signals, g: DriveGeometry, stiffness):
    """load / k  [rad], both directions; load [N m], k [N m / rad]."""
    return s.load / stiffness


def bearing_clearance(s: Signals, g: DriveGeometry, clearance):
    """-d c / 2  [rad]: extra lost motion c [rad]."""
    return -s.direction * clearance / 2.0


def _phase(doc="phase of the error at theta = 0"):
    return Param("phase_deg", "phase", "deg", DEG, -360.0, 360.0, 0.0, doc)


def _tref():
    return Param("reference_temperature_C", "reference_temperature", "degC", 1.0, -50.0, 150.0, 20.0,
                 "temperature at which the effect is zero")


_VARY_TEMPERATURE = "vary temperature independently of the other signals (heat and cool, or hold it during load steps)"

EFFECTS: dict[str, Effect] = {
    e.name: e
    for e in (
        Effect("output_gear_runout", output_gear_runout,
               (Param("eccentricity_um", "eccentricity", "um", UM, 0.0, 500.0, None, "output gear eccentricity"),
                _phase()),
               "eccentricity", "once-per-revolution runout of the output gear",
               order=lambda g: 1.0, phase="phase"),
        Effect("intermediate_shaft_runout", intermediate_shaft_runout,
               (Param("eccentricity_um", "eccentricity", "um", UM, 0.0, 500.0, None,
                      "pinion/wheel shaft eccentricity"), _phase()),
               "eccentricity", "runout of the intermediate (pinion + wheel) shaft, order i_c",
               order=lambda g: g.intermediate_order, phase="phase"),
        Effect("worm_runout", worm_runout,
               (Param("amplitude_um", "amplitude", "um", UM, 0.0, 500.0, None,
                      "once-per-worm-turn error at the wheel pitch circle"), _phase()),
               "amplitude", "worm shaft runout / lead error, order n_w",
               order=lambda g: g.worm_order, phase="phase"),
        Effect("gear_mesh_error", gear_mesh_error,
               (Param("amplitude_um", "amplitude", "um", UM, 0.0, 100.0, None,
                      "tooth-mesh error at the output gear pitch radius"), _phase()),
               "amplitude", "tooth-mesh frequency error of the spur stage, order z1",
               order=lambda g: float(g.output_teeth), phase="phase"),
        Effect("thermal_backlash", thermal_backlash,
               (Param("centre_distance_um_per_K", "coefficient", "um/K", UM, -20.0, 20.0, None,
                      "growth of the worm centre distance per kelvin"), _tref()),
               "coefficient", "worm-mesh backlash changing with temperature (differential mode)",
               needs="temperature", mode="differential", pattern="trend",
               signature="a differential-mode trend with temperature (the reversal changing as it warms)",
               separate_hint=_VARY_TEMPERATURE),
        Effect("thermal_drift", thermal_drift,
               (Param("arcsec_per_K", "coefficient", "arcsec/K", ARCSEC, -100.0, 100.0, None,
                      "output angle drift per kelvin"), _tref()),
               "coefficient", "zero drift with temperature (common mode)", needs="temperature", pattern="trend",
               signature="a common-mode trend with temperature", separate_hint=_VARY_TEMPERATURE),
        Effect("torsional_compliance", torsional_compliance,
               (Param("stiffness_Nm_per_arcsec", "stiffness", "N m/arcsec", 1.0 / ARCSEC, 1e-3, 1e9, None,
                      "torsional stiffness of the drive at the output"),),
               "stiffness", "wind-up under external torque (common mode)", needs="load",
               extra={"inverse": True}, pattern="trend", signature="a common-mode trend with load",
               separate_hint="apply load steps at constant temperature and in both signs",
               unphysical_hint="the table winds up less under load than the spec's tooth stiffness predicts"),
        Effect("bearing_clearance", bearing_clearance,
               (Param("clearance_arcsec", "clearance", "arcsec", ARCSEC, 0.0, 3600.0, None,
                      "extra lost motion"),),
               "clearance", "extra lost motion (differential mode)", needs="direction", mode="differential",
               pattern="reversal", signature="a change of the mean reversal",
               unphysical_hint="the table shows less lost motion than the spec predicts: the spec's backlash terms "
                               "(thickness deviations, clearances) are larger than the table's"),
    )
}


def absent_reason(name: str, kinds: tuple, single_start_worm_last: bool = False) -> str | None:
    """Why catalogue effect ``name`` does not exist in a train of stage ``kinds`` (motor -> output;
    empty: the legacy [worm, spur]), or None when it does: the worm's effects need a worm stage; the
    intermediate shaft is the output stage's input shaft, which in a train ending in a worm stage is
    the worm shaft (``worm_runout``); a single-start worm as the output stage puts its wheel's mesh
    order on the worm shaft's (``worm_runout`` stands for both).  The one rule that the spec loader,
    ``synth --effect`` and ``diagnose``'s candidates follow."""
    kinds = tuple(kinds) or ("worm", "spur")
    shown = " + ".join(kinds)
    if name in ("worm_runout", "thermal_backlash") and "worm" not in kinds:
        return f"this drive ({shown}) has no worm stage"
    if name == "intermediate_shaft_runout" and kinds[-1] == "worm":
        return (f"the output stage of this drive ({shown}) is a worm stage: its input shaft is the worm shaft, whose "
                "runout is worm_runout")
    if name == "gear_mesh_error" and kinds[-1] == "worm" and single_start_worm_last:
        return ("the output stage is a single-start worm: its wheel's mesh order is the worm shaft's, whose "
                "error is worm_runout")
    return None


def geometry_absent_reason(name: str, g: DriveGeometry) -> str | None:
    """:func:`absent_reason` for a drive's geometry (its ``kinds`` and worm starts)."""
    return absent_reason(name, g.kinds, g.worm_starts == 1)


def train_effects(g: DriveGeometry) -> list[str]:
    """The catalogue effects that exist in the train of ``g``, in catalogue order."""
    return [name for name in EFFECTS if geometry_absent_reason(name, g) is None]


def effect_error(name: str, signals: Signals, geometry: DriveGeometry, params: dict) -> np.ndarray:
    """Contribution [rad] of catalogue effect ``name`` with internal-unit ``params``."""
    return EFFECTS[name].function(signals, geometry, **params)


def params_from_keys(name: str, values: dict) -> dict:
    """TOML-keyed values (catalogue units) -> internal parameters, defaults filled."""
    out = {}
    for p in EFFECTS[name].params:
        v = values.get(p.key, p.default)  # a required key (default None) is there: the spec loader checked
        out[p.name] = float(cast(float, v)) * p.scale
    return out


def params_to_keys(name: str, params: dict) -> dict:
    """Internal parameters -> TOML-keyed values in catalogue units."""
    return {p.key: float(params[p.name]) / p.scale for p in EFFECTS[name].params if p.name in params}
