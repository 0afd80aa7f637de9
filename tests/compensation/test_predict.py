"""What a table will leave: cross-validated over runs, then simulated repeat tests; judged against
repeat tests of the same drive (tests.support.compensation_data) corrected as LinuxCNC corrects."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support import compensation_data as data
from tests.support.controllers import LinuxCncJoint
from wormgear_cli.compensation.model import fit_plan, parameters, plan_model
from wormgear_cli.compensation.predict import predict_table
from wormgear_cli.compensation.table import TableGrid, build_table
from wormgear_cli.output.writers import WriteOptions, get
from wormgear_cli.units import ARCSEC


def _predict(seed, orders, **kw):
    a, e, d, r = data.iso_rows(seed, **kw)
    theta, y, d = np.radians(a), e * ARCSEC, d.astype(float)
    plan, _, _, model = plan_model(theta, y, d, orders, run=r)
    grid = TableGrid(256)

    def make(mask):
        return build_table(fit_plan(plan, theta[mask], y[mask], d[mask], r[mask]), grid)

    table = make(np.ones(theta.size, dtype=bool))
    prediction = predict_table(make, theta, y, d, r, plan.orders, parameters(plan, theta, d))
    return prediction, LinuxCncJoint(get("linuxcnc").write(table, WriteOptions()), file_type=1)


def _achieved(joint, seed):
    a, e, d, _ = data.iso_rows(seed)
    return data.e_and_b(a, e + joint.apply(a, d) * 3600.0, d)


def test_one_run_is_in_sample():
    p, _ = _predict(1, [1, 2, 9], runs=1)
    assert p.method == "in-sample" and p.folds == 0 and p.replicates == 0
    assert p.after["E"].low == p.after["E"].median == p.after["E"].high


def test_before_is_the_measurement_and_after_much_smaller():
    p, _ = _predict(1, [1, 2, 9])
    assert p.method == "cross-validated" and p.folds == 5
    assert p.before.E / ARCSEC > 60 and p.after["E"].median / ARCSEC < 2.0
    assert p.after["E"].low < p.after["E"].median < p.after["E"].high
    assert np.sqrt(p.noise.within) / ARCSEC == pytest.approx(0.5, rel=0.2)


@pytest.mark.slow
@pytest.mark.parametrize("orders", [[1, 2, 9], [1, 2]], ids=["model", "per-target means"])
def test_predictions_are_calibrated_over_seeds(orders):
    inside = {"E": 0, "B": 0}
    ratio = {"E": [], "B": []}
    pairs = 30
    for k in range(pairs):
        p, joint = _predict(100 + k, orders)
        e, b = _achieved(joint, 200 + k)
        for name, got in (("E", e), ("B", b)):
            f = p.after[name]
            inside[name] += f.low / ARCSEC <= got <= f.high / ARCSEC
            ratio[name].append(got / (f.median / ARCSEC))
    for name in ("E", "B"):
        assert inside[name] >= 0.75 * pairs, (name, inside, ratio)
        assert 0.85 <= np.median(ratio[name]) <= 1.2, (name, ratio)
