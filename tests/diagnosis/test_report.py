"""The verdict and the data warnings of the report."""

from __future__ import annotations

import pytest

from tests.support.diagnosis_data import (
    REMEDY,
    TB,
    WARM_SLOW,
    Plan,
    diagnose_doc,
    drop_column,
    gap_never_grows,
    make_csv,
)


def test_data_without_a_direction_column_name_nothing_and_say_why(mch50_spec):
    text, _ = make_csv(mch50_spec, Plan(runs=6, warmup=WARM_SLOW), hidden=TB, seed=1)
    doc = diagnose_doc(mch50_spec, drop_column(text, "direction"))
    assert doc["effects_found"] == []
    gap_never_grows(doc)
    assert "add a direction column" in doc["signals"]["data_warning"]


def test_one_run_with_more_lost_motion_is_not_called_fine(mch50_spec):
    # bearing clearance of 4 arcsec in a single run: +-2 arcsec between the two passes, against 0.3 arcsec noise
    text, _ = make_csv(mch50_spec, Plan(runs=1, targets=48), seed=3, run_sd=0.0,
                       hidden={"bearing_clearance": {"clearance_arcsec": 4.0}})
    doc = diagnose_doc(mch50_spec, text)
    assert doc["effects_found"] == []
    assert doc["verdict"] != "no missing effect found"
    status = {c["name"]: c for c in doc["candidates"]}["bearing_clearance"]
    assert status["status"] == "untestable" and REMEDY in status["remedy"]
    reversal = [u for u in doc["unexplained"] if u["kind"] == "reversal"]
    assert reversal and reversal[0]["mean_reversal_change_arcsec"] == pytest.approx(4.0, rel=0.15)
    excess = [u for u in doc["unexplained"] if u["kind"] == "excess"]
    assert excess and excess[0]["rms_arcsec"] > 4 * excess[0]["noise_floor_arcsec"]
    assert excess[0]["noise_floor_arcsec"] == pytest.approx(0.3, rel=0.3)
