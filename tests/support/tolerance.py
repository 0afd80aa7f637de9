"""Specs built for the tolerance tests (from the MCH50 example, changed key by key)."""

from __future__ import annotations

from pathlib import Path

import tomli_w

from tests.support.paths import MCH50
from wormgear_cli.spec.loader import load_spec, raw_copy, spec_from_dict
from wormgear_cli.tolerance.quantities import QUANTITIES

ZERO_ERRORS = [0.0] * 6


def mch50_doc() -> dict:
    return raw_copy(load_spec(MCH50))


def only(doc: dict, keep: dict) -> dict:
    """``doc`` with every toleranced key of the registry at 0 except ``keep`` (path -> value)."""
    for q in QUANTITIES:
        value = keep.get(q.path, ZERO_ERRORS if q.length > 1 else 0.0)
        set_path(doc, q.path, value)
    # gear_eccentricity_mm is derived from the centre-distance error when absent: set it explicitly
    return doc


def set_path(doc: dict, path: str, value) -> None:
    parts = path.split(".")
    node = doc
    for p in parts[:-1]:
        node = node.setdefault(p, {})
    node[parts[-1]] = value


def spec_of(doc: dict, name: str = "t.toml"):
    return spec_from_dict(doc, name, "t")


def write(tmp_path: Path, doc: dict, name: str = "drive.toml") -> Path:
    path = tmp_path / name
    path.write_bytes(tomli_w.dumps(doc).encode())
    return path
