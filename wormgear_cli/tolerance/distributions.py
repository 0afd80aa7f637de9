"""The distributions a toleranced quantity is sampled from, as data.

Each :class:`Distribution` has a name, the quantity kinds (:class:`Kind`) it fits, whether the
process capability indices cp/cpk apply, and its inverse CDF truncated to the tolerance
interval.  ``[statistics]`` tables are validated against :data:`DISTRIBUTIONS`; the sampler
(:mod:`wormgear_cli.tolerance.sampling`) draws through them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum

import numpy as np


class Kind(str, Enum):
    """Nature of a toleranced quantity (sets the default distribution and the interval)."""

    radial = "radial"
    signed = "signed"
    unknown = "unknown"
    allowance = "allowance"


def _normal_params(low: float, high: float, cp: float | None, cpk: float | None) -> tuple[float, float]:
    cp_e = cp if cp is not None else (cpk if cpk is not None else 1.0)
    cpk_e = cpk if cpk is not None else cp_e
    width = high - low
    sigma = width / (6.0 * cp_e)
    mu = 0.5 * (low + high) + 0.5 * width * (1.0 - cpk_e / cp_e)
    return mu, sigma


def _normal_ppf(u, low, high, cp, cpk):
    # lazy: scipy.special is slow to import (a large part of a second); only this path needs it
    from scipy.special import ndtr, ndtri

    mu, sigma = _normal_params(low, high, cp, cpk)
    a, b = ndtr((low - mu) / sigma), ndtr((high - mu) / sigma)
    return mu + sigma * ndtri(a + u * (b - a))


def _rayleigh_sigma(high: float, cp: float | None, cpk: float | None) -> float:
    c = cpk if cpk is not None else (cp if cp is not None else 1.0)
    return high / (3.0 * c)


def _rayleigh_ppf(u, low, high, cp, cpk):
    sigma = _rayleigh_sigma(high, cp, cpk)
    f_high = -math.expm1(-high * high / (2.0 * sigma * sigma))
    return sigma * np.sqrt(-2.0 * np.log1p(-u * f_high))


def _uniform_ppf(u, low, high, cp, cpk):
    return low + u * (high - low)


def _normal_whole(u, low, high, cp, cpk):
    # lazy: scipy.special is slow to import (a large part of a second); only this path needs it
    from scipy.special import ndtri

    mu, sigma = _normal_params(low, high, cp, cpk)
    return mu + sigma * ndtri(u)


def _rayleigh_whole(u, low, high, cp, cpk):
    return _rayleigh_sigma(high, cp, cpk) * np.sqrt(-2.0 * np.log1p(-u))


@dataclass(frozen=True)
class Distribution:
    """A distribution of the catalogue: ``name``; ``kinds``: the quantity kinds it
    fits; ``capability``: whether cp/cpk apply; ``ppf(u, low, high, cp, cpk)``: the
    truncated inverse CDF on [low, high] ([mm] arrays in, [mm] out); ``doc``; ``whole``: the
    inverse CDF of the untruncated law, the same parameters (an uninspected key; None: ``ppf``, a law
    bounded by itself)."""

    name: str
    kinds: tuple[str, ...]
    capability: bool
    ppf: Callable
    doc: str
    whole: Callable | None = None


DISTRIBUTIONS: dict[str, Distribution] = {
    d.name: d for d in (
        Distribution("normal", (Kind.signed.value, Kind.radial.value, Kind.unknown.value, Kind.allowance.value), True,
                     _normal_ppf,
                     "normal, T at 3 sigma (cp = 1), mean shifted towards the upper limit by cpk < cp", _normal_whole),
        Distribution("rayleigh", (Kind.radial.value, Kind.unknown.value), True, _rayleigh_ppf,
                     "magnitude of a 2-D normal offset, sigma per axis = T / (3 c)", _rayleigh_whole),
        Distribution("uniform", (Kind.signed.value, Kind.radial.value, Kind.unknown.value, Kind.allowance.value),
                     False, _uniform_ppf,
                     "every value in the interval equally likely"),
    )
}
