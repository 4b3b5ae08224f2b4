"""Sample, permutation and fuzzy entropy against antropy and EntropyHub, properties, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.signal.entropy import fuzzy_entropy, permutation_entropy, sample_entropy

# The peer libraries are imported by the tests that compare with them, on one worker: antropy compiles
# its numba functions on import (about 12 CPU-s), which every worker would pay at collection.
pytestmark = pytest.mark.xdist_group("entropy-peers")


@pytest.fixture(scope="module")
def antropy():  # type: ignore[no-untyped-def]
    return pytest.importorskip("antropy")


@pytest.fixture(scope="module")
def EntropyHub():  # type: ignore[no-untyped-def]  # noqa: N802 - the library's own name
    return pytest.importorskip("EntropyHub")

TOL = 1e-9


def _signals() -> dict[str, np.ndarray]:
    rng = np.random.default_rng(20240611)
    n = 1200
    t = np.arange(n)
    return {
        "white": rng.standard_normal(n),
        "sine": np.sin(2 * np.pi * t / 50) + 0.1 * rng.standard_normal(n),
        "walk": np.cumsum(rng.standard_normal(n)),
        "short-white": 3.0 + 0.01 * rng.standard_normal(500),  # offset and scale
    }


SIGNALS = _signals()


@pytest.mark.parametrize("name", sorted(SIGNALS))
@pytest.mark.parametrize("m", [1, 2, 3])
def test_sample_entropy_matches_antropy(name, m, antropy):
    x = SIGNALS[name]
    expected = antropy.sample_entropy(x, order=m, metric="chebyshev")
    assert abs(sample_entropy(x, m=m) - expected) <= TOL


def test_sample_entropy_matches_antropy_kdtree_path(antropy):
    # antropy switches from its numba loop to a KD-tree at 5000 samples.
    x = np.random.default_rng(5).standard_normal(5200)
    assert abs(sample_entropy(x) - antropy.sample_entropy(x, order=2)) <= TOL


@pytest.mark.parametrize("name", sorted(SIGNALS))
@pytest.mark.parametrize(("m", "delay"), [(3, 1), (4, 1), (5, 2), (6, 3), (3, 4)])
def test_permutation_entropy_matches_antropy(name, m, delay, antropy):
    x = SIGNALS[name]
    expected = antropy.perm_entropy(x, order=m, delay=delay, normalize=True)
    assert abs(permutation_entropy(x, m=m, delay=delay) - expected) <= TOL


def test_permutation_entropy_ties_match_stable_argsort(antropy):
    x = np.random.default_rng(3).integers(0, 3, 800).astype(float)  # many ties
    for m in (3, 4, 5):
        expected = antropy.perm_entropy(x, order=m, normalize=True)
        assert abs(permutation_entropy(x, m=m) - expected) <= TOL


def test_permutation_entropy_unnormalised_is_in_nats(antropy):
    x = SIGNALS["white"]
    bits = antropy.perm_entropy(x, order=4, normalize=False)
    assert abs(permutation_entropy(x, m=4, normalize=False) - bits * np.log(2)) <= TOL


@pytest.mark.parametrize("name", sorted(SIGNALS))
@pytest.mark.parametrize("m", [1, 2, 3])
def test_fuzzy_entropy_matches_entropyhub(name, m, EntropyHub):
    x = SIGNALS[name][:700]  # EntropyHub holds an N x N matrix
    fuzz, _, _ = EntropyHub.FuzzEn(x, m=m, tau=1, r=(0.2 * np.std(x), 2), Fx="default")
    assert abs(fuzzy_entropy(x, m=m) - fuzz[m - 1]) <= TOL


def test_fuzzy_entropy_r_and_exponent_match_entropyhub(EntropyHub):
    x = SIGNALS["walk"][:600]
    fuzz, _, _ = EntropyHub.FuzzEn(x, m=2, tau=1, r=(0.15 * np.std(x), 3), Fx="default")
    assert abs(fuzzy_entropy(x, m=2, r=0.15, n=3) - fuzz[1]) <= TOL
    fuzz, _, _ = EntropyHub.FuzzEn(x, m=2, tau=1, r=(0.3 * np.std(x), 1), Fx="default")
    assert abs(fuzzy_entropy(x, m=2, r=0.3, n=1) - fuzz[1]) <= TOL


def test_sine_is_more_regular_than_white_noise():
    rng = np.random.default_rng(1)
    white = rng.standard_normal(1500)
    sine = np.sin(2 * np.pi * np.arange(1500) / 60)
    assert sample_entropy(sine) < 0.5 * sample_entropy(white)
    assert permutation_entropy(sine) < 0.6 < permutation_entropy(white)
    assert fuzzy_entropy(sine[:800]) < 0.5 * fuzzy_entropy(white[:800])


def test_white_noise_permutation_entropy_is_near_one():
    x = np.random.default_rng(2).standard_normal(2000)
    assert 0.99 < permutation_entropy(x, m=3) <= 1.0
    assert 0.97 < permutation_entropy(x, m=4) <= 1.0


def test_monotone_signal_has_zero_permutation_entropy():
    assert permutation_entropy(np.arange(100.0)) == 0.0


@pytest.mark.parametrize("fn", [sample_entropy, permutation_entropy, fuzzy_entropy])
@pytest.mark.parametrize(
    ("x", "message"),
    [
        (np.array([1.0, np.nan, 2.0, 3.0, 4.0, 5.0]), "finite"),
        (np.array([1.0, np.inf, 2.0, 3.0, 4.0, 5.0]), "finite"),
        (np.ones((10, 10)), "1-D"),
        (np.array([1.0, 2.0]), "at least"),
        (np.array(["a", "b", "c", "d", "e"]), "numbers"),
    ],
)
def test_bad_input_raises(fn, x, message):
    with pytest.raises(ValueError, match=message):
        fn(x)


@pytest.mark.parametrize("fn", [sample_entropy, fuzzy_entropy])
def test_bad_tolerance_and_order_raise(fn):
    x = np.random.default_rng(4).standard_normal(100)
    for r in (0.0, -0.2, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="r must be"):
            fn(x, r=r)
    for m in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="m must be"):
            fn(x, m=m)
    with pytest.raises(ValueError, match="constant"):
        fn(np.full(50, 2.0))


def test_bad_permutation_parameters_raise():
    x = np.random.default_rng(4).standard_normal(100)
    with pytest.raises(ValueError, match="m must be"):
        permutation_entropy(x, m=1)
    with pytest.raises(ValueError, match="delay must be"):
        permutation_entropy(x, delay=0)
    with pytest.raises(ValueError, match="at least"):
        permutation_entropy(x[:9], m=5, delay=3)


def test_fuzzy_exponent_must_be_positive():
    x = np.random.default_rng(4).standard_normal(100)
    with pytest.raises(ValueError, match="n must be"):
        fuzzy_entropy(x, n=0)


def test_no_matches_give_nan_like_antropy():
    # With a tiny tolerance no two templates match: the entropy is undefined (nan).
    x = np.random.default_rng(6).standard_normal(200)
    assert np.isnan(sample_entropy(x, m=2, r=1e-9))
