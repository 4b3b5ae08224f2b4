"""Variational mode decomposition (tcbench.signal.vmd) against vmdpy.VMD and on its own."""

from __future__ import annotations

import numpy as np
import pytest
from vmdpy import VMD

from tcbench.signal.vmd import VMDResult, vmd

ALPHA = 2000.0
TONES = ((1.0, 0.01), (0.5, 0.08), (0.3, 0.25))  # (amplitude, cycles/sample)
VMDPY_INIT = {"zero": 0, "uniform": 1}


def _tones(n: int) -> list[np.ndarray]:
    t = np.arange(n)
    return [a * np.sin(2 * np.pi * f * t) for a, f in TONES]


def _noisy(n: int = 1200, seed: int = 0) -> np.ndarray:
    return sum(_tones(n)) + 0.1 * np.random.default_rng(seed).standard_normal(n)


def _vmdpy(x: np.ndarray, k: int, init: str, tau: float = 0.0, dc: bool = False
           ) -> tuple[np.ndarray, np.ndarray, int]:
    """vmdpy's modes and final centre frequencies sorted by frequency, and the index of the
    iterate it returns: its port returns iterate ``n - 1`` after ``n`` iterations, and
    ``omega`` has ``n`` rows."""
    u, _, omega = VMD(x, ALPHA, tau, k, dc, VMDPY_INIT[init], 1e-7)
    order = np.argsort(omega[-1], kind="stable")
    return u[order], omega[-1][order], omega.shape[0] - 1


def _assert_matches(ours: VMDResult, u_ref: np.ndarray, omega_ref: np.ndarray) -> None:
    assert ours.modes.shape == u_ref.shape
    rel = np.linalg.norm(ours.modes - u_ref, axis=1) / np.linalg.norm(u_ref, axis=1)
    assert rel.max() <= 1e-6, rel
    np.testing.assert_allclose(ours.centre_freqs, omega_ref, rtol=0, atol=1e-9)


@pytest.mark.parametrize("k", [3, 5])
@pytest.mark.parametrize("init", ["uniform", "zero"])
def test_matches_vmdpy_at_equal_iterations(k, init):
    x = _noisy()
    u_ref, omega_ref, iterate = _vmdpy(x, k, init)
    ours = vmd(x, k, ALPHA, init=init, tol=0.0, max_iter=iterate)
    assert ours.iterations == iterate and not ours.converged
    _assert_matches(ours, u_ref, omega_ref)


@pytest.mark.parametrize(("tau", "dc"), [(0.1, False), (0.0, True)])
def test_matches_vmdpy_dual_ascent_and_dc(tau, dc):
    x = _noisy(1000, seed=1) + 0.2  # an offset for the DC mode
    u_ref, omega_ref, iterate = _vmdpy(x, 3, "uniform", tau=tau, dc=dc)
    ours = vmd(x, 3, ALPHA, tau=tau, dc=dc, tol=0.0, max_iter=iterate)
    _assert_matches(ours, u_ref, omega_ref)
    if dc:
        assert ours.centre_freqs[0] == 0.0


def test_converged_result_close_to_vmdpy():
    # Different stopping rules (eq. 7 relative vs vmdpy's absolute) stop at different
    # iterations, but both near the same fixed point.
    x = _noisy()
    u_ref, omega_ref, _ = _vmdpy(x, 3, "uniform")
    ours = vmd(x, 3, ALPHA)
    assert ours.converged and ours.iterations < 500
    rel = np.linalg.norm(ours.modes - u_ref, axis=1) / np.linalg.norm(u_ref, axis=1)
    assert rel.max() < 1e-2
    np.testing.assert_allclose(ours.centre_freqs, omega_ref, atol=1e-4)


def test_clean_tones_separate_and_sum_back():
    n = 1500
    tones = _tones(n)
    x = sum(tones)
    for tau in (0.0, 1.0):
        res = vmd(x, 3, ALPHA, tau=tau)
        assert res.converged
        np.testing.assert_allclose(res.centre_freqs, [f for _, f in TONES], atol=5e-4)
        assert np.all(np.diff(res.centre_freqs) > 0)
        for mode, tone in zip(res.modes, tones, strict=True):
            assert np.linalg.norm(mode - tone) / np.linalg.norm(tone) < 0.1
        err = np.linalg.norm(res.modes.sum(axis=0) - x) / np.linalg.norm(x)
        assert err < (0.03 if tau == 0.0 else 0.003)  # tau > 0 enforces the constraint


def test_result_shape_types_and_read_only():
    x = _noisy(1001)  # odd length: every sample kept
    res = vmd(x, 4, ALPHA, max_iter=20)
    assert res.modes.shape == (4, 1001) and res.modes.dtype == np.float64
    assert res.centre_freqs.shape == (4,) and np.all(np.diff(res.centre_freqs) >= 0)
    assert np.all((res.centre_freqs >= 0) & (res.centre_freqs <= 0.5))
    assert isinstance(res.iterations, int) and 1 <= res.iterations <= 20
    with pytest.raises(ValueError):
        res.modes[0, 0] = 1.0
    with pytest.raises(ValueError):
        res.centre_freqs[0] = 1.0


def test_random_init_uses_the_generator():
    x = _noisy(800)
    a = vmd(x, 3, ALPHA, init="random", rng=np.random.default_rng(5), max_iter=30)
    b = vmd(x, 3, ALPHA, init="random", rng=5, max_iter=30)
    c = vmd(x, 3, ALPHA, init="random", rng=np.random.default_rng(6), max_iter=30)
    np.testing.assert_array_equal(a.modes, b.modes)
    assert not np.array_equal(a.modes, c.modes)


def test_zero_signal():
    res = vmd(np.zeros(64), 2, ALPHA)
    assert res.converged and res.iterations == 1
    assert not res.modes.any()


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"k": 0}, "k must be"),
        ({"k": 2.5}, "k must be"),
        ({"alpha": 0.0}, "alpha must be"),
        ({"alpha": -1.0}, "alpha must be"),
        ({"alpha": float("nan")}, "alpha must be"),
        ({"signal": np.r_[np.ones(10), np.nan, np.ones(10)]}, r"signal\[10\] = nan"),
        ({"signal": np.ones((2, 50))}, "must be 1-D"),
        ({"signal": np.ones(3)}, "at least"),
        ({"signal": np.ones(9), "k": 5}, "at least"),
        ({"signal": np.ones(50, dtype=complex)}, "real numbers"),
        ({"tau": -0.1}, "tau must be"),
        ({"init": "uniformly"}, "init must be"),
        ({"tol": -1.0}, "tol must be"),
        ({"max_iter": 0}, "max_iter must be"),
    ],
)
def test_bad_input(kwargs, match):
    args = {"signal": np.ones(50), "k": 2, "alpha": ALPHA, **kwargs}
    with pytest.raises(ValueError, match=match) as err:
        vmd(args.pop("signal"), args.pop("k"), args.pop("alpha"), **args)
    assert "\n" not in str(err.value)
