"""The augmented spec: the input spec with fitted phases and the named effects, as TOML."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from wormgear_cli.units import ARCSEC

if TYPE_CHECKING:
    from wormgear_cli.diagnosis.inference import Found
    from wormgear_cli.diagnosis.phases import ModelFit
    from wormgear_cli.diagnosis.selection import Diagnosis


def wrap_deg(x: float) -> float:
    v = (math.degrees(x) + 180.0) % 360.0 - 180.0
    return 180.0 if v == -180.0 else v


def _sig6(x: float) -> float:
    return float(f"{x:.6g}")


def _set_path(doc: dict, dotted: str, value) -> None:
    parts = dotted.split(".")
    node = doc
    for part in parts[:-1]:
        node = node.setdefault(part, {})
    node[parts[-1]] = value


def augmented_params(found: Found) -> dict:
    """A named effect's parameters keyed as in the catalogue (rounded as written)."""
    from wormgear_cli.physics.effects import EFFECTS, params_to_keys

    eff = EFFECTS[found.name]
    keys = params_to_keys(found.name, found.params)
    out = {}
    for p in eff.params:
        v = keys[p.key]
        if p.name == eff.phase:
            v = wrap_deg(v * p.scale)
            v = round(v, 4)
        else:
            v = _sig6(v)
        out[p.key] = v
    return out


def augment(spec, sig, after: ModelFit, sources, found, fit_phases, y):
    """The spec as a TOML dict with fitted phases and the named effects, and its
    simulation (plus the fitted zero offset) at the measured rows [arcsec]."""
    from wormgear_cli.analysis.simulate import simulate
    from wormgear_cli.spec.loader import raw_copy, spec_from_dict

    raw = raw_copy(spec)
    if fit_phases:
        for s, psi in zip(sources, after.psi):
            _set_path(raw, s.key, round(wrap_deg(float(psi)), 4))
    for f in found:
        raw.setdefault("effects", {})[f.name] = augmented_params(f)
    aug = spec_from_dict(raw, str(spec.source), spec.drive.name)
    return raw, simulate(aug, sig) / ARCSEC + after.offset


def augmented_toml(diag: Diagnosis, data_name: str = "") -> str:
    """The augmented spec as TOML text, with a comment header saying what changed."""
    import tomli_w

    lines = [f"# {diag.spec.drive.name}: written by wormgear diagnose from {diag.spec.source}"
             + (f" and {data_name}" if data_name else "")]
    if diag.fit_phases and diag.sources:
        lines.append("# fitted phases: " + ", ".join(s.key for s in diag.sources))
    if diag.found:
        lines.append("# effects added: " + ", ".join(f.name for f in diag.found))
        for f in diag.found:
            if not f.separable and f.intervals:
                key, (lo, hi) = next(iter(f.intervals.items()))
                lines.append(f"# {f.name}: its size is not separable from the fitted phases of "
                             f"{', '.join(f.indistinguishable_from)} ({key} from {lo:.3g} to {hi:.3g} fits as well)")
    else:
        lines.append("# no effect added (no missing effect found)")
    lines.append(f"# the fitted zero offset ({diag.after.offset:.4f} arcsec) is not part of a drive spec")
    return "\n".join(lines) + "\n\n" + tomli_w.dumps(diag.augmented)
