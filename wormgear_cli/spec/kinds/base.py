"""What a stage kind is on the spec side (:class:`StageKind`), and the keys several kinds share.

A kind's module (:mod:`~wormgear_cli.spec.kinds.worm`, ``spur``, ``belt``) holds everything the
spec layer and the tolerance analysis know about that kind: its keys as data, its record types, its
members, how its derived values and its load are found, the example values of its template and its
toleranced keys.  :mod:`wormgear_cli.spec.stages` builds the ``[[stage]]`` checks and records from
these; the drive layer's model of the kind is :mod:`wormgear_cli.drive` ``/<kind>.py``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

from wormgear_cli.spec.fields import FORCE, MISSING, Field, field_


class Toleranced(NamedTuple):
    """A toleranced key of a kind, as the tolerance analysis varies it: ``key`` (stage key),
    ``kind`` (``radial``, ``signed``, ``unknown`` or ``allowance``: the interval and default
    distribution, :class:`wormgear_cli.tolerance.distributions.Kind`), ``grade_driven`` (an ISO
    1328 grade sets it), ``length`` (elements of an array key), ``kinematics`` (the spur kinematics
    under which the model reads it; None: always), ``since`` (the release generation that added it:
    its random-stream rows come after every earlier one)."""

    key: str
    kind: str
    grade_driven: bool = False
    length: int = 1
    kinematics: str | None = None
    since: int = 1


class Plausible(NamedTuple):
    """A tolerance key held against the drive's own scale (:mod:`wormgear_cli.spec.plausibility`):
    implausible (a warning) above ``factor`` x the scale ``scale``, impossible (an error) above the
    scale ``limit`` (None: never).  Scales: ISO 1328 grade 12's ``F_pT``, ``f_pT``, ``F_alphaT``,
    ``F_rT``, ``F_i2T`` at the part's size, ``tooth`` (pi m / 2), ``depth`` (2 m), ``radius`` (the
    part's pitch radius), ``pitch`` (the stage's pitch)."""

    key: str
    scale: str
    factor: float
    limit: str | None


class StageKind(NamedTuple):
    """One stage kind on the spec side (module docstring).

    ``name``: the ``kind = ...`` value; ``fields``: its keys after ``kind`` and ``name`` (paths
    relative to the stage table, order = template and reference order); ``record``: the stage's
    record type; ``members``: member table -> its record type (input shaft's member first);
    ``default_name``: the stage's name in reports; ``anti_backlash``: the arrangements it may have;
    ``ratio_keys``: (teeth of the output member, teeth or starts of the input member);
    ``load_key``: the key of its load; ``load_radius(values)``: the radius [mm] turning the torque on
    its output shaft into that load (None while a key it needs is missing); ``derive(values, label,
    problems)``: fills its derived defaults in place; ``examples``: the template's values (key units)
    with their sources; ``toleranced``: the keys tolerance varies, in a fixed order (append only);
    ``listed``: (parts' tolerance keys, assembly keys) that ``analyze`` lists as values used;
    ``plausible``: its tolerance keys held against the drive's scale; ``part_size(stage, key)``: the
    (reference diameter, pitch radius) [mm] of the part a stage key belongs to (its scales')."""

    name: str
    fields: tuple[Field, ...]
    record: type
    members: dict[str, type]
    default_name: str
    anti_backlash: tuple[str, ...]
    ratio_keys: tuple[str, str]
    load_key: str
    load_radius: Callable[[dict], float | None]
    derive: Callable[[dict, str, list[str]], None]
    examples: dict[str, tuple]
    toleranced: tuple[Toleranced, ...]
    listed: tuple[tuple[str, ...], tuple[str, ...]]
    plausible: tuple[Plausible, ...]
    part_size: Callable[[Any, str], tuple[float, float]]


def _limit(key: str, attr: str, what: str) -> Field:
    return field_(key, attr, "arcsec", "", f"limit on this stage's {what} at its own output shaft", lo=0.0,
                  hi=1e9, lo_open=True)


def limit_fields() -> tuple[Field, Field]:
    """The limits every stage may have, on its TE and backlash at its own output shaft."""
    return (_limit("max_transmission_error_arcsec", "max_transmission_error", "transmission error"),
            _limit("max_backlash_arcsec", "max_backlash", "backlash"))


def mesh_fields(anti_backlash: tuple[str, ...], arrangement: str) -> tuple[Field, ...]:
    """The keys of a gear mesh's stage: its load, stiffness model, anti-backlash arrangement (one of
    ``anti_backlash``, ``arrangement`` describing the one besides none), residual lost motion and
    output-shaft stiffness."""
    return (
        field_("normal_force_N", "normal_force", "N", "derived",
               "normal force F_N on the teeth (default: from [drive] output_torque_Nm through the ratios "
               "after this stage and its pitch radius, else 0)", **FORCE),
        Field("stiffness_model", "stiffness_model", "str", "", "derived",
              "deflection model of this mesh (default: [stiffness] model)", choices=("iso6336", "empirical")),
        Field("anti_backlash", "anti_backlash", "str", "", "none",
              "anti-backlash arrangement: " + arrangement + " sets the clearance to residual_lost_motion_arcsec",
              choices=anti_backlash),
        field_("residual_lost_motion_arcsec", "residual_lost_motion", "arcsec", 0.0,
               "lost motion left by the anti-backlash arrangement, at this stage's output shaft (replaces "
               "the clearance terms; the tooth deflection stays)", lo=0.0, hi=36000.0),
        field_("shaft_stiffness_Nm_per_arcmin", "shaft_stiffness", "N m/arcmin", "",
               "torsional stiffness of the stage's output shaft from its gear (wheel) to the next stage or the "
               "load, bearings and couplings included: a wind-up under load, 1 / (k O^2) at the output "
               "(default: none, rigid)", lo=1e-6, hi=1e12),
    )


def missing(values: dict, *keys: str) -> bool:
    """Whether any of ``keys`` has no value yet (MISSING)."""
    return any(values[k] is MISSING for k in keys)


__all__ = ["Plausible", "StageKind", "Toleranced", "limit_fields", "mesh_fields", "missing"]
