"""Sample, permutation and fuzzy entropy against antropy and EntropyHub, properties, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.signal.entropy import fuzzy_entropy, permutation_entropy, sample_entropy

# The peer libraries are imported inside the tests that compare with them, each in one test (on one
# worker), and EntropyHub takes about 3 s. antropy compiles its numba functions on import (8 s), so it
# is imported with numba's JIT off (1.8 s): the same functions run as Python, on records short enough
# for it (400 samples: 0.1 s a call).


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


def _antropy_as_python():  # type: ignore[no-untyped-def]
    """antropy imported with numba's JIT off (its numba functions stay Python functions)."""
    numba = pytest.importorskip("numba")
    jit_off = numba.config.DISABLE_JIT
    numba.config.DISABLE_JIT = True
    try:
        return pytest.importorskip("antropy")
    finally:
        numba.config.DISABLE_JIT = jit_off


def test_sample_and_permutation_entropy_match_antropy() -> None:
    """Every signal at orders 1-3 (sample, on its first 400 samples) and five (order, delay) pairs
    (permutation), the KD-tree path antropy takes from 5000 samples, ties broken as a stable argsort, and
    nats unnormalised."""
    antropy = _antropy_as_python()
    wrong = []
    for name, x in sorted(SIGNALS.items()):
        short = x[:400]  # antropy's sample entropy runs as Python here (_antropy_as_python)
        for m in (1, 2, 3):
            if abs(sample_entropy(short, m=m) - antropy.sample_entropy(short, order=m, metric="chebyshev")) > TOL:
                wrong.append(f"sample {name} m={m}")
        for m, delay in ((3, 1), (4, 1), (5, 2), (6, 3), (3, 4)):
            expected = antropy.perm_entropy(x, order=m, delay=delay, normalize=True)
            if abs(permutation_entropy(x, m=m, delay=delay) - expected) > TOL:
                wrong.append(f"permutation {name} m={m} delay={delay}")
    x = np.random.default_rng(5).standard_normal(5200)  # antropy's KD-tree path
    if abs(sample_entropy(x) - antropy.sample_entropy(x, order=2)) > TOL:
        wrong.append("sample, KD-tree path")
    ties = np.random.default_rng(3).integers(0, 3, 800).astype(float)
    wrong += [f"permutation ties m={m}" for m in (3, 4, 5)
              if abs(permutation_entropy(ties, m=m) - antropy.perm_entropy(ties, order=m, normalize=True)) > TOL]
    bits = antropy.perm_entropy(SIGNALS["white"], order=4, normalize=False)
    if abs(permutation_entropy(SIGNALS["white"], m=4, normalize=False) - bits * np.log(2)) > TOL:
        wrong.append("permutation unnormalised (nats)")
    assert wrong == []


def test_fuzzy_entropy_matches_entropyhub() -> None:
    """Every signal at orders 1-3 with r = 0.2 sigma, n = 2; then other r and exponents."""
    EntropyHub = pytest.importorskip("EntropyHub")  # noqa: N806 - the library's own name
    wrong = []
    for name, signal in sorted(SIGNALS.items()):
        x = signal[:700]  # EntropyHub holds an N x N matrix
        for m in (1, 2, 3):
            fuzz, _, _ = EntropyHub.FuzzEn(x, m=m, tau=1, r=(0.2 * np.std(x), 2), Fx="default")
            if abs(fuzzy_entropy(x, m=m) - fuzz[m - 1]) > TOL:
                wrong.append(f"{name} m={m}")
    x = SIGNALS["walk"][:600]
    for r, n in ((0.15, 3), (0.3, 1)):
        fuzz, _, _ = EntropyHub.FuzzEn(x, m=2, tau=1, r=(r * np.std(x), n), Fx="default")
        if abs(fuzzy_entropy(x, m=2, r=r, n=n) - fuzz[1]) > TOL:
            wrong.append(f"walk r={r} n={n}")
    assert wrong == []


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
