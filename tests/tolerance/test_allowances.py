"""Issue 19, item 3: tooth-thickness allowances are one-sided (they thin the teeth), so no sampled drive
has a thicker-than-nominal tooth and no sampled backlash is negative.

Done when: no sampled backlash is negative, on every shipped drive and on an involute spur stage whose
centre-distance term alone could not close the clearance.  The drawn thickness columns are checked
against the interval [0, T] and against an independent oracle (scipy's truncated normal on [0, T],
mean T/2, sigma T/6: the default of an allowance), by a Kolmogorov-Smirnov test.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.paths import CONFIGS
from wormgear_cli.spec.loader import load_spec, with_values
from wormgear_cli.tolerance import engine

SHIPPED = sorted(p.name for p in CONFIGS.glob("*.toml"))


def _blocks(spec, n=20_000, seed=3, metrics="paper"):
    s = engine.setup(spec, engine.Options(samples=n, seed=seed, metrics=metrics, unit="arcsec"))
    cols, mets = {}, {}
    for b in engine.blocks(s):
        for k, v in b.columns.items():
            cols.setdefault(k, []).append(np.asarray(v))
        for k, v in b.metrics.items():
            mets.setdefault(k, []).append(np.asarray(v))
    return {k: np.concatenate(v) for k, v in cols.items()}, {k: np.concatenate(v) for k, v in mets.items()}


@pytest.mark.parametrize("name", SHIPPED)
def test_no_sampled_backlash_is_negative_and_no_tooth_is_thicker_than_nominal(name):
    spec = load_spec(CONFIGS / name)
    cols, mets = _blocks(spec)
    assert np.all(mets["total_backlash"] >= 0.0), name
    thick = [k for k in cols if k.endswith("thickness_deviation_mm")]
    for k in thick:
        assert cols[k].min() >= 0.0, (name, k)


def test_an_involute_stage_samples_its_allowances_in_zero_to_t_as_the_truncated_normal_oracle():
    from scipy import stats

    spec = with_values(load_spec(CONFIGS / "rotary-table-precision.toml"), {"gear_pair.kinematics": "involute"})
    cols, mets = _blocks(spec, n=40_000, seed=11)
    assert np.all(mets["total_backlash"] >= 0.0)
    key = next(k for k in cols if k.endswith("output_gear.thickness_deviation_mm"))
    t = float(spec.gear_pair.output_gear.thickness_deviation)
    assert t > 0
    x = cols[key]
    assert 0.0 <= x.min() and x.max() <= t
    oracle = stats.truncnorm(-3.0, 3.0, loc=t / 2.0, scale=t / 6.0)
    assert stats.kstest(x, oracle.cdf).pvalue > 1e-3
    # the old reading ([-T, T], mean 0) would put half the samples below zero
    assert abs(np.mean(x) - t / 2.0) < 0.01 * t
