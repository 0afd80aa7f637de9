"""The phase fit of the spec's periodic sources."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wormgear_cli import diagnosis as dg


def test_phase_fit_recovers_the_model_on_noise_free_data(mch50_spec):
    from wormgear_cli.analysis.accuracy import geometry
    from wormgear_cli.analysis.simulate import periodic_sources, simulate
    from wormgear_cli.physics.effects import Signals

    rng = np.random.default_rng(4)
    theta = np.radians(np.tile(np.sort(rng.uniform(0, 360, 40)), 4))
    d = np.repeat([1.0, -1.0, 1.0, -1.0], 40)
    sig = Signals.make(theta, d)
    truth = {s.name: float(rng.uniform(0, 2 * np.pi)) for s in periodic_sources(mch50_spec)}
    y = simulate(mch50_spec, sig, truth) / dg.ARCSEC + 2.0
    sources, _ = dg.phase_sources(mch50_spec, geometry(mch50_spec), sig)
    base = simulate(mch50_spec, sig) / dg.ARCSEC - dg.sources_total(sources, sig, [s.phase for s in sources])
    groups = dg.make_groups(d, np.repeat([1, 1, 2, 2], 40))
    ctx = dg.FitContext(y, sig, groups, base, tuple(sources), tuple(s.phase for s in sources))
    fit = dg.fit_model(ctx, np.ones((y.shape[0], 1)))
    assert np.max(np.abs(fit.residual)) < 1e-4
    assert fit.offset == pytest.approx(2.0, abs=1e-5)
    # single sources on their shaft come back exactly (mod 2 pi); shafts with several only as a sum
    by_name = dict(zip([s.name for s in sources], fit.psi))
    gear = by_name["gear_eccentricity"] - truth["gear_eccentricity"]
    assert math.isclose(math.cos(gear), 1.0, abs_tol=1e-6)
