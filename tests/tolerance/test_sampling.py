"""Sampling: distributions against their formulas, truncation, counter-based streams."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.tolerance import mch50_doc, spec_of
from wormgear_cli.tolerance import sampling
from wormgear_cli.tolerance.quantities import QUANTITY_BY_PATH, Varied, varied_quantities

T = 0.03  # tolerance [mm] used throughout


def _phi(x):  # standard normal pdf
    return math.exp(-0.5 * x * x) / math.sqrt(2.0 * math.pi)


def _cdf(x):  # standard normal cdf
    return 0.5 * (1.0 + math.erf(x / math.sqrt(2.0)))


def _varied(path, distribution, cp=None, cpk=None, tol=T):
    return Varied(QUANTITY_BY_PATH[path], (tol,), distribution, cp, cpk)


def _draw(v: Varied, n: int, seed: int) -> np.ndarray:
    """Values drawn through the uniforms of the counter-based streams (the path the runs take)."""
    u = np.concatenate([sampling.block_uniforms(seed, b, rows=1)[0] for b in range(-(-n // sampling.BLOCK))])[:n]
    return sampling.sample_values(v, u)


N = 400_000
SEEDS = (1, 2, 3)


@pytest.mark.parametrize("seed", SEEDS)
def test_uniform_mean_and_spread(seed):
    # U(L, U): mean (L + U)/2, variance (U - L)^2 / 12; signed quantity: L = -T, U = T
    x = _draw(_varied("worm_pair.lead_error_mm", "uniform"), N, seed)
    sd = 2 * T / math.sqrt(12)
    assert abs(x.mean()) < 5 * sd / math.sqrt(N)  # 5 standard errors
    assert x.std() == pytest.approx(sd, rel=0.01)


@pytest.mark.parametrize("seed", SEEDS)
def test_normal_default_is_tolerance_at_three_sigma(seed):
    # symmetric truncation at +/- 3 sigma: mean 0, var = sigma^2 (1 - 2 b phi(b) / (2 Phi(b) - 1)), b = 3
    x = _draw(_varied("worm_pair.lead_error_mm", "normal"), N, seed)
    sigma, b = T / 3, 3.0
    var = sigma**2 * (1 - 2 * b * _phi(b) / (2 * _cdf(b) - 1))
    assert abs(x.mean()) < 5 * math.sqrt(var / N)
    assert x.var() == pytest.approx(var, rel=0.01)


@pytest.mark.parametrize("seed", SEEDS)
def test_normal_with_cp_and_cpk_matches_scipy_truncnorm(seed):
    # cp = 1.33, cpk = 1.0 on [-T, T]: sigma = 2T/(6 cp), mean shifted up so that (T - mu) / (3 sigma) = cpk
    from scipy.stats import truncnorm

    cp, cpk = 1.33, 1.0
    sigma = 2 * T / (6 * cp)
    mu = T - 3 * sigma * cpk
    ref = truncnorm((-T - mu) / sigma, (T - mu) / sigma, loc=mu, scale=sigma)
    x = _draw(_varied("worm_pair.lead_error_mm", "normal", cp, cpk), N, seed)
    mean, var = (float(v) for v in ref.stats("mv"))
    assert abs(x.mean() - mean) < 5 * math.sqrt(var / N)
    assert x.var() == pytest.approx(var, rel=0.01)


@pytest.mark.parametrize("seed", SEEDS)
def test_rayleigh_truncated_at_tolerance(seed):
    # Rayleigh sigma = T/3 truncated to [0, T]: moments of the truncated law by quadrature
    from scipy.integrate import quad

    s = T / 3
    pdf = lambda r: r / s**2 * math.exp(-r * r / (2 * s * s))  # noqa: E731
    mass = 1 - math.exp(-T * T / (2 * s * s))
    m1 = quad(lambda r: r * pdf(r), 0, T)[0] / mass
    m2 = quad(lambda r: r * r * pdf(r), 0, T)[0] / mass
    x = _draw(_varied("assembly.wheel_eccentricity_mm", "rayleigh"), N, seed)
    assert abs(x.mean() - m1) < 5 * math.sqrt((m2 - m1 * m1) / N)
    assert x.var() == pytest.approx(m2 - m1 * m1, rel=0.01)
    # untruncated Rayleigh mean s sqrt(pi/2) lies above: truncation removed the tail
    assert x.mean() < s * math.sqrt(math.pi / 2)


def test_normal_law_passes_kolmogorov_smirnov_against_scipy():
    from scipy.stats import kstest, truncnorm

    x = _draw(_varied("worm_pair.lead_error_mm", "normal"), 20_000, 7)
    assert kstest(x, truncnorm(-3, 3, scale=T / 3).cdf).pvalue > 1e-3
    # a thickness allowance is one-sided (issue 19): [0, T], centred on T/2 with its ends at 3 sigma
    y = _draw(_varied("worm_pair.worm.thickness_deviation_mm", "normal"), 20_000, 7)
    assert y.min() >= 0.0 and y.max() <= T
    assert kstest(y, truncnorm(-3, 3, loc=T / 2, scale=T / 6).cdf).pvalue > 1e-3


@pytest.mark.parametrize("distribution,cp,cpk", [("normal", None, None), ("normal", 0.5, 0.2), ("normal", 2, 2),
                                                 ("rayleigh", None, None), ("rayleigh", None, 0.3),
                                                 ("uniform", None, None)])
@pytest.mark.parametrize("path", ["assembly.worm_eccentricity_mm", "worm_pair.wheel.thickness_deviation_mm"])
def test_truncation_holds(distribution, cp, cpk, path):
    v = _varied(path, distribution, cp, cpk)
    if v.quantity.kind.value not in sampling.DISTRIBUTIONS[distribution].kinds:
        pytest.skip("law does not fit this kind")
    x = _draw(v, 200_000, 11)
    lo, hi = v.bounds()
    assert x.min() >= lo and x.max() <= hi
    assert np.all(np.isfinite(x))


def test_zero_tolerance_gives_zero():
    x = _draw(_varied("assembly.worm_eccentricity_mm", "rayleigh", tol=0.0), 1000, 1)
    assert np.all(x == 0.0)


def test_sample_j_is_the_same_whatever_the_pieces():
    varied = varied_quantities(spec_of(mch50_doc()))
    n = sampling.BLOCK + 5000
    whole = sampling.draw(varied, 42, 0, n)
    cuts = [0, 17, 1000, sampling.BLOCK - 1, sampling.BLOCK + 1, n]
    for a, b in zip(cuts[:-1], cuts[1:]):
        part = sampling.draw(varied, 42, a, b)
        for k in whole.values:
            assert np.array_equal(part.values[k], whole.values[k][a:b])
        for k in whole.phases:
            assert np.array_equal(part.phases[k], whole.phases[k][a:b])


def test_other_seed_other_samples_and_phases_uniform():
    varied = varied_quantities(spec_of(mch50_doc()))
    a = sampling.draw(varied, 1, 0, 50_000)
    b = sampling.draw(varied, 2, 0, 50_000)
    assert not np.array_equal(a.values["assembly.wheel_eccentricity_mm"], b.values["assembly.wheel_eccentricity_mm"])
    for p in a.phases.values():  # uniform on [0, 2 pi): mean pi, variance (2 pi)^2 / 12
        assert p.min() >= 0 and p.max() < 2 * math.pi
        assert abs(p.mean() - math.pi) < 5 * (2 * math.pi / math.sqrt(12)) / math.sqrt(p.size)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(10, 20))
def test_distribution_moments_replicated(seed):
    # the moment checks above, replicated over ten more seeds at a larger N (tolerances 5 SE / 0.5 %)
    n = 2_000_000
    x = _draw(_varied("worm_pair.lead_error_mm", "normal"), n, seed)
    sigma, b = T / 3, 3.0
    var = sigma**2 * (1 - 2 * b * _phi(b) / (2 * _cdf(b) - 1))
    assert abs(x.mean()) < 5 * math.sqrt(var / n)
    assert x.var() == pytest.approx(var, rel=0.005)
    y = _draw(_varied("assembly.wheel_eccentricity_mm", "uniform"), n, seed)
    assert y.var() == pytest.approx(T * T / 12, rel=0.005)


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=60)
@given(cp=st.floats(0.05, 5.0), ratio=st.floats(0.01, 1.0), tol=st.floats(1e-6, 10.0),
       signed=st.booleans(), seed=st.integers(0, 2**32))
def test_truncation_holds_for_any_capability(cp, ratio, tol, signed, seed):
    # whatever cp, cpk <= cp and tolerance, every normal draw stays inside its interval
    path = "worm_pair.lead_error_mm" if signed else "assembly.wheel_eccentricity_mm"
    v = _varied(path, "normal", cp, cp * ratio, tol)
    x = sampling.sample_values(v, np.random.default_rng(seed).random(2000))
    lo, hi = v.bounds()
    assert np.all((x >= lo) & (x <= hi))


def test_appending_a_quantity_to_the_registry_keeps_every_sample(monkeypatch):
    # growing the registry (as the budget's quantities and phases did) must not move existing samples
    from wormgear_cli.tolerance import quantities
    from wormgear_cli.tolerance.quantities import Kind, Quantity

    varied = varied_quantities(spec_of(mch50_doc()))
    before = sampling.draw(varied, 3, 100, 300)
    extra = Varied(Quantity("x.new_mm", Kind.radial), (0.01,), "rayleigh")
    monkeypatch.setattr(sampling, "STREAM_COLUMNS", sampling.STREAM_COLUMNS + 1)
    monkeypatch.setattr(quantities, "QUANTITIES", quantities.QUANTITIES + (extra.quantity,))
    monkeypatch.setattr(quantities, "STREAM_ROWS", quantities.STREAM_ROWS + ("x.new_mm",))
    after = sampling.draw(varied + (extra,), 3, 100, 300)
    for k in before.values:
        assert np.array_equal(before.values[k], after.values[k])
    for k in before.phases:
        assert np.array_equal(before.phases[k], after.phases[k])
    assert after.values["x.new_mm"].max() <= 0.01


# --- mutation-testing round 2 (issue 13): the inverse CDFs against scipy.stats, the streams' rows --

U = np.array([0.0, 0.01, 0.2, 0.5, 0.77, 0.999])


def test_normal_with_only_cpk_is_centred_with_cp_equal_to_cpk():
    # module doc: only cpk given -> cp = cpk, centred: sigma = 2T / (6 * 1.33), mean 0, truncated at +-3.99 sigma
    from scipy.stats import truncnorm

    sigma = 2 * T / (6 * 1.33)
    ref = truncnorm(-T / sigma, T / sigma, loc=0.0, scale=sigma).ppf(U)
    x = sampling.sample_values(_varied("worm_pair.lead_error_mm", "normal", None, 1.33), U)
    np.testing.assert_allclose(x, ref, rtol=1e-9, atol=1e-12)


def test_normal_on_a_radial_interval_is_centred_on_its_middle():
    # radial quantity: [L, U] = [0, T]; cp = cpk = 1: mean T/2, sigma = T/6 (scipy.stats.truncnorm as the oracle)
    from scipy.stats import truncnorm

    ref = truncnorm(-3.0, 3.0, loc=T / 2, scale=T / 6).ppf(U)
    x = sampling.sample_values(_varied("assembly.wheel_eccentricity_mm", "normal"), U)
    np.testing.assert_allclose(x, ref, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("cp, cpk, c", [(None, 1.33, 1.33), (1.5, None, 1.5), (2.0, 0.8, 0.8), (None, None, 1.0)])
def test_rayleigh_capability_sets_sigma(cp, cpk, c):
    # module doc: sigma = T / (3 c), c = cpk, else cp, else 1; truncated at T: x = F^-1(u F(T)) (scipy.stats.rayleigh)
    from scipy.stats import rayleigh

    law = rayleigh(scale=T / (3 * c))
    ref = law.ppf(U * law.cdf(T))
    x = sampling.sample_values(_varied("assembly.wheel_eccentricity_mm", "rayleigh", cp, cpk), U)
    np.testing.assert_allclose(x, ref, rtol=1e-9, atol=1e-15)


def test_zero_tolerance_keeps_the_shape_of_the_uniforms():
    x = sampling.sample_values(_varied("assembly.worm_eccentricity_mm", "uniform", tol=0.0), np.full((3, 4), 0.5))
    assert x.shape == (3, 4) and np.all(x == 0.0)


def test_columns_of_a_block_are_the_slice_of_its_whole_matrix():
    """A draw of a few samples skips the rest of the stream (PCG64's advance): the same numbers as
    the whole (rows, BLOCK) matrix cut, in every row, at both ends of the block and inside it."""
    whole = sampling.block_uniforms(7, 3, rows=5)
    assert whole.shape == (5, sampling.BLOCK)
    for lo, hi in ((0, 1), (0, 1000), (17, 4000), (sampling.BLOCK - 3, sampling.BLOCK), (1, sampling.BLOCK)):
        assert np.array_equal(sampling.block_uniforms(7, 3, rows=5, lo=lo, hi=hi), whole[:, lo:hi])
    assert np.array_equal(sampling.block_uniforms(7, 3, rows=1)[0], whole[0])


def test_a_draw_starting_past_the_first_block():
    varied = (_varied("worm_pair.lead_error_mm", "uniform"),)
    b = sampling.BLOCK
    whole = sampling.draw(varied, 8, 0, b + 10)
    part = sampling.draw(varied, 8, b + 5, b + 10)
    assert (part.start, part.stop) == (b + 5, b + 10)
    assert whole.values["worm_pair.lead_error_mm"].shape == (b + 10,)
    assert part.values["worm_pair.lead_error_mm"].shape == (5,)
    assert np.array_equal(part.values["worm_pair.lead_error_mm"], whole.values["worm_pair.lead_error_mm"][b + 5:])


def test_each_element_of_an_array_key_has_its_own_interval_and_stream():
    # element k of worm_pair_errors_mm (kind unknown: [0, T_k]) with T_k = 0.01 (k + 1), uniform:
    # each lies in its own interval, reaches near its top, and the six columns are uncorrelated
    from wormgear_cli.tolerance.quantities import QUANTITY_BY_PATH

    tol = tuple(0.01 * (k + 1) for k in range(6))
    v = Varied(QUANTITY_BY_PATH["assembly.worm_pair_errors_mm"], tol, "uniform")
    d = sampling.draw((v,), 4, 0, 20_000)
    cols = [d.values[f"assembly.worm_pair_errors_mm[{k}]"] for k in range(6)]
    for k, x in enumerate(cols):
        assert x.min() >= 0.0 and x.max() <= tol[k] and x.max() > 0.99 * tol[k]
    r = np.corrcoef(np.array(cols))
    assert np.max(np.abs(r - np.eye(6))) < 0.05  # 20 000 samples: standard error 0.007
