"""The augmented spec: the input spec with fitted phases and the named effects (its TOML text
is written by :func:`wormgear_cli.diagnosis.report.augmented_toml`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from wormgear_cli.diagnosis.inference import augmented_params, wrap_deg
from wormgear_cli.spec.loader import raw_copy, set_path, spec_from_dict
from wormgear_cli.units import ARCSEC

if TYPE_CHECKING:
    from wormgear_cli.diagnosis.phases import ModelFit


def augment(spec, sig, after: ModelFit, sources, found, fit_phases, y, base: int = 1):
    """The spec as a TOML dict with fitted phases and the named effects, and its
    simulation (plus the fitted zero offset, and each run's offset and drift: the first ``base``
    linear columns of ``after``) at the measured rows [arcsec]."""
    from wormgear_cli.analysis.simulate import simulate  # lazy: keeps analysis.simulate off `measure`'s start-up

    raw = raw_copy(spec)
    if fit_phases:
        for s, psi in zip(sources, after.psi):
            set_path(raw, s.key, round(wrap_deg(float(psi)), 4))  # stage.N reaches a [[stage]] table
    for f in found:
        raw.setdefault("effects", {})[f.name] = augmented_params(f)
    aug = spec_from_dict(raw, str(spec.source), spec.drive.name)
    held = after.offset if base == 1 else after.lin[:, :base] @ after.beta[:base]
    return raw, simulate(aug, sig) / ARCSEC + held
