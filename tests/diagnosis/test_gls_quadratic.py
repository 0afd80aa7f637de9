"""mixed.gls_quadratic (the phase fits' cost at every trial step) is the c of Cross.weighted bit for bit,
and r' V~^-1 r of the covariance written out densely (an independent path)."""

from __future__ import annotations

import numpy as np
import pytest

from wormgear_cli.diagnosis.mixed import Cross, gls_quadratic
from wormgear_cli.diagnosis.runs import make_groups, pass_sums


def _groups(runs: int, per_pass: int, seed: int):
    rng = np.random.default_rng(seed)
    run = np.repeat(np.arange(1, runs + 1), 2 * per_pass)
    direction = np.tile(np.repeat([1.0, -1.0], per_pass), runs)
    return make_groups(direction, run), rng.normal(size=run.shape[0])


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize(("gp", "gr"), [(0.0, 0.0), (0.3, 0.0), (0.0, 0.7), (0.25, 1.5)])
def test_equals_cross_weighted_bitwise(seed, gp, gr):
    groups, r = _groups(5, 7, seed)
    assert groups.nested
    cr = Cross(np.zeros((1, 1)), np.zeros(1), float(r @ r), np.zeros((groups.passes, 1)), pass_sums(r, groups),
               groups)
    assert gls_quadratic(r, groups, gp, gr) == float(cr.weighted([gp], [gr])[2][0])


@pytest.mark.parametrize(("gp", "gr"), [(0.0, 0.0), (0.4, 0.0), (0.2, 0.9)])
def test_equals_the_dense_quadratic_form(gp, gr):
    groups, r = _groups(4, 6, 11)
    zp = np.equal.outer(groups.pass_id, np.arange(groups.passes)).astype(float)
    zr = zp @ groups.run_indicator.T
    v = np.eye(r.shape[0]) + gp * zp @ zp.T + gr * zr @ zr.T
    assert gls_quadratic(r, groups, gp, gr) == pytest.approx(float(r @ np.linalg.solve(v, r)), rel=1e-12)
