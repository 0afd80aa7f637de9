"""Issue 19, tolerance: inspected (the law truncated at the tolerance, the default) or uninspected (the
process's whole law) per key, said in the report.  The uninspected draws are checked against scipy's
untruncated laws (an independent oracle) and the truncated ones against the tolerance."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.support.paths import MCH50
from wormgear_cli.cli import app
from wormgear_cli.tolerance import sampling
from wormgear_cli.tolerance.quantities import QUANTITY_BY_PATH, Varied

T = 0.03


def _draw(v: Varied, n: int, seed: int) -> np.ndarray:
    u = np.concatenate([sampling.block_uniforms(seed, b, rows=1)[0] for b in range(-(-n // sampling.BLOCK))])[:n]
    return sampling.sample_values(v, u)


@pytest.mark.parametrize("seed", (1, 2))
def test_an_uninspected_normal_key_follows_the_whole_normal_law(seed):
    from scipy import stats

    v = Varied(QUANTITY_BY_PATH["worm_pair.lead_error_mm"], (T,), "normal", inspected=False)
    x = _draw(v, 100_000, seed)
    assert stats.kstest(x, stats.norm(0.0, T / 3).cdf).pvalue > 1e-3
    # about 0.27 % of the parts lie beyond the tolerance (|x| > 3 sigma), which inspection would reject
    beyond = np.mean(np.abs(x) > T)
    assert beyond == pytest.approx(2 * stats.norm.sf(3.0), abs=4 * math.sqrt(0.0027 / 100_000))
    inspected = _draw(Varied(QUANTITY_BY_PATH["worm_pair.lead_error_mm"], (T,), "normal"), 100_000, seed)
    assert np.abs(inspected).max() <= T


def test_an_uninspected_runout_follows_the_whole_rayleigh_law_and_an_allowance_stays_thin():
    from scipy import stats

    v = Varied(QUANTITY_BY_PATH["assembly.wheel_eccentricity_mm"], (T,), "rayleigh", inspected=False)
    x = _draw(v, 100_000, 5)
    assert stats.kstest(x, stats.rayleigh(scale=T / 3).cdf).pvalue > 1e-3
    assert x.max() > T
    a = Varied(QUANTITY_BY_PATH["worm_pair.wheel.thickness_deviation_mm"], (T,), "normal", inspected=False)
    assert _draw(a, 100_000, 5).min() >= 0.0


def test_the_report_says_which_keys_are_inspected(runner, tmp_path):
    text = MCH50.read_text(encoding="utf-8") + ('\n[statistics]\n"assembly.wheel_eccentricity_mm" = '
                                                "{ inspected = false }\n")
    path = tmp_path / "d.toml"
    path.write_text(text, encoding="utf-8")
    doc = json.loads(runner.invoke(app, ["tolerance", str(path), "-n", "500", "-f", "json"]).stdout)
    flags = {k: v["inspected"] for k, v in doc["varied"].items()}
    assert flags.pop("assembly.wheel_eccentricity_mm") is False and all(flags.values())
    table = runner.invoke(app, ["tolerance", str(path), "-n", "500"]).stdout
    assert "laws: inspected, truncated at the tolerance, except (uninspected, the whole law):" in " ".join(
        table.split())
    # a wrong value is one line naming the key
    path.write_text(text.replace("inspected = false", 'inspected = "no"'), encoding="utf-8")
    r = runner.invoke(app, ["tolerance", str(path), "-n", "10"])
    assert r.exit_code == 2
    assert r.stderr == (f'error: {path}: statistics."assembly.wheel_eccentricity_mm".inspected: expected true (parts '
                        "inspected: the law truncated at the tolerance) or false (the process's whole law), got 'no'\n")
