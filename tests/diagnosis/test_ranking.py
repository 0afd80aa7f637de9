"""The selection's ranking and stopping rules on a case built so that the right criterion and a wrong
one choose differently.

Forward selection takes, among the significant candidates, the one whose Wald chi^2 = F q is largest
(the drop in the GLS residual in units of the noise).  Here a two-column effect (a shaft runout:
cos and sin at order 8) and a one-column effect (a thermal drift) are hidden together, sized so that
the runout's chi^2 is the larger while its F (chi^2 / 2) is the smaller: ranking by F would take the
drift first.  ``max_effects`` 0, 1 and 2 then name nothing, the runout alone, and both.
"""

from __future__ import annotations

import pytest

from tests.support.diagnosis_data import NO_ORDER_8, WARM, Plan, make_measurement, spec_with
from wormgear_cli.diagnosis import diagnose, report

HIDDEN = {"intermediate_shaft_runout": {"eccentricity_um": 0.6, "phase_deg": 30.0},
          "thermal_drift": {"arcsec_per_K": 0.3}}
COLUMNS = {"intermediate_shaft_runout": 2, "thermal_drift": 1}


@pytest.fixture(scope="module")
def case():
    from tests.support.paths import MCH50
    from wormgear_cli.spec.loader import load_spec

    spec = spec_with(load_spec(MCH50), NO_ORDER_8)
    meas, _ = make_measurement(spec, Plan(warmup=WARM), hidden=HIDDEN, seed=4)
    return spec, meas


@pytest.fixture(scope="module")
def by_max_effects(case):
    spec, meas = case
    return {k: diagnose(spec, meas, resamples=0, max_effects=k) for k in (0, 1, 2)}


def test_the_case_separates_f_from_chi_square(by_max_effects):
    """Both significant; F ranks the drift first, F q ranks the runout first (the case is what it
    claims to be, else the next tests prove nothing)."""
    step = by_max_effects[1].steps[0]
    scores = {s["name"]: s for s in step["scores"]}
    runout, drift = scores["intermediate_shaft_runout"], scores["thermal_drift"]
    assert runout["p_adjusted"] < 0.01 and drift["p_adjusted"] < 0.01
    assert drift["F"] > runout["F"]
    assert runout["F"] * COLUMNS["intermediate_shaft_runout"] > drift["F"] * COLUMNS["thermal_drift"]


def test_the_first_step_takes_the_largest_chi_square(by_max_effects):
    assert by_max_effects[1].steps[0]["accepted"] == "intermediate_shaft_runout"
    assert [s["name"] for s in by_max_effects[1].steps[0]["scores"][:2]] == ["intermediate_shaft_runout",
                                                                              "thermal_drift"]


@pytest.mark.parametrize("k,names", [(0, []), (1, ["intermediate_shaft_runout"]),
                                     (2, ["intermediate_shaft_runout", "thermal_drift"])])
def test_max_effects_names_that_many_in_chi_square_order(by_max_effects, k, names):
    diag = by_max_effects[k]
    assert [f.name for f in diag.found] == names
    doc = report(diag)
    assert [e["name"] for e in doc["effects_found"]] == names
    if k < 2:   # stopped by the cap with a significant candidate left
        left = {c["name"]: c for c in doc["candidates"]}
        nxt = "intermediate_shaft_runout" if k == 0 else "thermal_drift"
        assert left[nxt]["status"] == "not_reached"


def test_chi_square_not_p_ranks_when_the_larger_chi_square_has_fewer_df():
    """A larger drift (0.6 arcsec/K): its chi^2 is now the larger, but its Satterthwaite df are few
    (a warm-up has few independent temperatures), so its p is the larger too: ranking by p would
    take the runout first, chi^2 takes the drift."""
    from tests.support.paths import MCH50
    from wormgear_cli.spec.loader import load_spec

    spec = spec_with(load_spec(MCH50), NO_ORDER_8)
    hidden = {**HIDDEN, "thermal_drift": {"arcsec_per_K": 0.6}}
    meas, _ = make_measurement(spec, Plan(warmup=WARM), hidden=hidden, seed=4)
    diag = diagnose(spec, meas, resamples=0, max_effects=1)
    scores = {s["name"]: s for s in diag.steps[0]["scores"]}
    runout, drift = scores["intermediate_shaft_runout"], scores["thermal_drift"]
    assert runout["p_adjusted"] < 0.01 and drift["p_adjusted"] < 0.01
    assert runout["p"] < drift["p"]
    assert drift["F"] * COLUMNS["thermal_drift"] > runout["F"] * COLUMNS["intermediate_shaft_runout"]
    assert [f.name for f in diag.found] == ["thermal_drift"]
