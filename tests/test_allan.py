"""Overlapping Allan deviation and its IEEE Std 952 read-offs (tcbench.signal.allan)."""

from __future__ import annotations

import allantools
import numpy as np
import pytest
from scipy.signal import lfilter

from tcbench.signal.allan import (
    AllanDeviation,
    allan_deviation,
    arw_to_deg_per_sqrt_hour,
    noise_parameters,
    to_deg_per_hour,
)


def _signals() -> dict[str, tuple[np.ndarray, float]]:
    rng = np.random.default_rng(7)
    n = 5003  # not a power of two
    t = np.arange(n) / 50.0
    return {
        "white": (rng.standard_normal(n), 50.0),
        "random walk": (np.cumsum(rng.standard_normal(n)) + 100.0, 200.0),
        "sine": (np.sin(2 * np.pi * 0.7 * t) + 0.01 * rng.standard_normal(n), 50.0),
        "short": (rng.standard_normal(7), 1.0),
    }


@pytest.mark.parametrize("name", ["white", "random walk", "sine", "short"])
@pytest.mark.parametrize("taus", ["octave", "decade", "seconds"])
def test_matches_allantools_oadev(name, taus):
    rate, fs_hz = _signals()[name]
    if taus == "seconds":
        m_max = (rate.size - 1) // 2
        taus = np.unique(np.r_[1, 3, m_max // 3, m_max]) / fs_hz
    ad = allan_deviation(rate, fs_hz, taus)
    tau_ref, adev_ref, _, n_ref = allantools.oadev(rate, rate=fs_hz, data_type="freq", taus=ad.tau_s)
    np.testing.assert_allclose(ad.tau_s, tau_ref, rtol=1e-12)
    np.testing.assert_array_equal(ad.n_terms, n_ref)
    np.testing.assert_allclose(ad.adev, adev_ref, rtol=1e-9)
    if isinstance(taus, np.ndarray):
        np.testing.assert_allclose(ad.tau_s, taus, rtol=1e-12)


def test_tau_sets():
    rate = np.random.default_rng(0).standard_normal(1001)  # m_max = 500
    octave = allan_deviation(rate, 10.0, "octave")
    np.testing.assert_allclose(octave.tau_s * 10.0, [1, 2, 4, 8, 16, 32, 64, 128, 256])
    np.testing.assert_array_equal(octave.n_terms, 1002 - 2 * np.rint(octave.tau_s * 10.0))
    m = np.rint(allan_deviation(rate, 10.0, "decade").tau_s * 10.0)
    assert m[0] == 1 and m[-1] == 500 and np.all(np.diff(m) > 0)
    assert 22 <= m.size <= 28  # about 10 per decade over 2.7 decades, duplicates merged
    # Seconds are rounded to samples, sorted, and coinciding m merged.
    ad = allan_deviation(rate, 10.0, np.array([0.52, 0.1, 0.5, 0.24]))
    np.testing.assert_allclose(ad.tau_s, [0.1, 0.2, 0.5])


def test_hand_worked_five_samples():
    # rate [1, -1, 2, 0, 3] at 2 Hz: theta = 0.5 * [0, 1, 0, 2, 2, 5] (mean removal changes no
    # second difference). m = 1: second differences -1, 1.5, -1, 1.5 -> 6.5 / (2 * 0.25 * 4).
    # m = 2: theta[k+4] - 2 theta[k+2] + theta[k] = 1, 1 -> 2 / (2 * 1 * 2).
    ad = allan_deviation(np.array([1.0, -1.0, 2.0, 0.0, 3.0]), 2.0)
    np.testing.assert_allclose(ad.tau_s, [0.5, 1.0])
    np.testing.assert_array_equal(ad.n_terms, [4, 2])
    np.testing.assert_allclose(ad.adev, np.sqrt([3.25, 0.5]), rtol=1e-14)
    assert ad.adev.dtype == np.float64 and not ad.adev.flags.writeable
    assert ad.fs_hz == 2.0 and ad.n_samples == 5


def test_ramp_adev_and_no_random_walk_regions():
    # A rate ramp R t has sigma(tau) = R tau / sqrt(2) exactly, slope +1: no -1/2 or +1/2 region.
    fs_hz, r = 10.0, 0.3
    ad = allan_deviation(r * np.arange(20_000) / fs_hz, fs_hz)
    np.testing.assert_allclose(ad.adev, r * ad.tau_s / np.sqrt(2), rtol=1e-6)
    p = noise_parameters(ad)
    assert np.isnan(p.angle_random_walk) and np.isnan(p.arw_tau_range_s).all()
    assert np.isnan(p.rate_random_walk) and np.isnan(p.rrw_tau_range_s).all()
    assert p.tau_min_s == ad.tau_s[0] and not p.min_is_interior


def test_white_noise_adev_and_arw():
    s, fs_hz, n = 0.2, 100.0, 200_000
    rate = s * np.random.default_rng(1).standard_normal(n)
    for taus in ("octave", "decade"):
        ad = allan_deviation(rate, fs_hz, taus)
        short = ad.tau_s <= 1.0  # m <= 100: thousands of independent intervals
        np.testing.assert_allclose(ad.adev[short], s / np.sqrt(ad.tau_s[short] * fs_hz), rtol=0.05)
        p = noise_parameters(ad)
        assert p.angle_random_walk == pytest.approx(s / np.sqrt(fs_hz), rel=0.06)
        assert p.arw_tau_range_s[0] == ad.tau_s[0]
        assert 50.0 <= p.arw_tau_range_s[1] <= p.tau_max_s == n / fs_hz / 10
        assert np.isnan(p.rate_random_walk)


def test_rate_random_walk_adev_and_k():
    k, fs_hz, n = 0.01, 100.0, 200_000
    rate = np.cumsum(k * np.sqrt(1 / fs_hz) * np.random.default_rng(2).standard_normal(n))
    for taus in ("octave", "decade"):
        ad = allan_deviation(rate, fs_hz, taus)
        long = (ad.tau_s >= 1.0) & (ad.tau_s <= 20.0)
        np.testing.assert_allclose(ad.adev[long], k * np.sqrt(ad.tau_s[long] / 3), rtol=0.25)
        p = noise_parameters(ad)
        assert p.rate_random_walk == pytest.approx(k, rel=0.15)
        assert p.rrw_tau_range_s[1] / p.rrw_tau_range_s[0] >= 3.0
        assert np.isnan(p.angle_random_walk)


def _gauss_markov_bank(rng: np.random.Generator, n: int, fs_hz: float, b: float) -> np.ndarray:
    """docs/concepts/physics.md, metrics: first-order Gauss-Markov processes, two per decade, sigma 0.605 B each."""
    out = np.zeros(n)
    sigma = 0.605 * b
    for tc_s in 10 ** np.arange(0.0, 4.01, 0.5):
        a = np.exp(-1.0 / (fs_hz * tc_s))
        drive = sigma * np.sqrt(1 - a * a) * rng.standard_normal(n)
        out += lfilter([1.0], [1.0, -a], drive, zi=[a * sigma * rng.standard_normal()])[0]
    return out


def test_flicker_floor_bias_instability():
    b, fs_hz, n = 0.01, 10.0, 200_000
    rng = np.random.default_rng(3)
    rate = _gauss_markov_bank(rng, n, fs_hz, b) + 0.664 * b * np.sqrt(fs_hz) * rng.standard_normal(n)
    ad = allan_deviation(rate, fs_hz, "decade")
    p = noise_parameters(ad)
    used = ad.tau_s <= p.tau_max_s
    i = int(np.argmin(ad.adev[used]))
    assert p.adev_min == ad.adev[used][i] and p.tau_min_s == ad.tau_s[used][i]
    assert p.bias_instability == pytest.approx(p.adev_min / 0.664, rel=1e-12)
    assert p.min_is_interior and 3.0 < p.tau_min_s < p.tau_max_s
    # The bank's floor is 0.664 B within the ripple and the estimate's scatter (0.65-0.98 B
    # over 20 seeds with this recipe; the minimum of a noisy floor reads low).
    assert 0.6 * b < p.bias_instability < 1.1 * b
    # White noise chosen to cross the floor at 1 s: N = 0.664 B in rate-unit·sqrt(s).
    assert p.angle_random_walk == pytest.approx(0.664 * b, rel=0.15)


def _curve(tau_s: np.ndarray, adev: np.ndarray) -> AllanDeviation:
    """A given curve, from a record long enough (T/10 = 10^5 s) for every tau to be used."""
    return AllanDeviation(tau_s, adev, np.full(tau_s.size, 10**6), fs_hz=1.0, n_samples=10**6)


def test_read_offs_of_exact_piecewise_curve():
    # max(N / sqrt(tau), F, K sqrt(tau / 3)) with the corners on grid points (tau = 16, 1024).
    n, f = 0.04, 0.01
    k = f * np.sqrt(3 / 1024)
    tau_s = 2.0 ** np.arange(-4, 14)
    adev = np.maximum.reduce([n / np.sqrt(tau_s), np.full(tau_s.size, f), k * np.sqrt(tau_s / 3)])
    p = noise_parameters(_curve(tau_s, adev))
    assert p.angle_random_walk == pytest.approx(n, rel=1e-12)  # the line's value at 1 s
    assert p.arw_tau_range_s == (1 / 16, 16.0)
    assert p.rate_random_walk == pytest.approx(k, rel=1e-12)  # the line's value at 3 s
    assert p.rrw_tau_range_s == (1024.0, 8192.0)
    assert p.adev_min == pytest.approx(f) and p.bias_instability == pytest.approx(f / 0.664)
    assert 16.0 <= p.tau_min_s <= 1024.0 and p.min_is_interior


def test_slope_region_must_span_a_factor_of_three():
    tau_s = np.array([1.0, 2.0, 4.0, 8.0])
    one_octave = _curve(tau_s, np.array([1.0, 1.0, 2**-0.5, 2**-0.5]))  # one -1/2 segment
    assert np.isnan(noise_parameters(one_octave).angle_random_walk)
    two_octaves = _curve(tau_s, np.array([1.0, 2**-0.5, 0.5, 0.5]))
    p = noise_parameters(two_octaves)
    assert p.angle_random_walk == pytest.approx(1.0) and p.arw_tau_range_s == (1.0, 4.0)
    # Two -1/2 runs: the wider one (16..128 s, on the line 2 / sqrt(tau)) is used.
    tau_s = 2.0 ** np.arange(8)
    two_runs = _curve(tau_s, np.array([1.0, 2**-0.5, 0.5, 0.5, 0.5, 2**-1.5, 0.25, 2**-2.5]))
    p = noise_parameters(two_runs)
    assert p.angle_random_walk == pytest.approx(2.0) and p.arw_tau_range_s == (16.0, 128.0)


def test_noise_parameters_tau_max_and_empty():
    ad = allan_deviation(np.random.default_rng(4).standard_normal(4000), 100.0)
    full = noise_parameters(ad, tau_max_s=np.inf)
    assert full.tau_min_s == ad.tau_s[np.argmin(ad.adev)] and full.tau_max_s == np.inf
    tiny = noise_parameters(ad, tau_max_s=1e-3)  # below the first tau: nothing to read
    assert np.isnan([tiny.angle_random_walk, tiny.bias_instability, tiny.rate_random_walk]).all()
    assert np.isnan(tiny.tau_min_s) and not tiny.min_is_interior


def test_constant_signal_gives_zero_adev_and_nan_slopes():
    ad = allan_deviation(np.full(1000, 3.5), 1.0)
    np.testing.assert_array_equal(ad.adev, 0.0)
    p = noise_parameters(ad)
    assert p.bias_instability == 0.0 and np.isnan(p.angle_random_walk)


def test_unit_conversions():
    assert to_deg_per_hour(1.0) == 3600.0
    np.testing.assert_allclose(to_deg_per_hour(np.array([1e-3, 2.0])), [3.6, 7200.0])
    assert arw_to_deg_per_sqrt_hour(1.0) == 60.0
    # docs/concepts/physics.md, metrics: N[deg/sqrt(h)] = sigma(1 s)[deg/h] / 60 for white noise.
    sigma_1s_dps = 0.01
    assert arw_to_deg_per_sqrt_hour(sigma_1s_dps) == pytest.approx(
        to_deg_per_hour(sigma_1s_dps) / 60
    )


@pytest.mark.parametrize(
    ("rate", "fs_hz", "taus", "match"),
    [
        (np.r_[1.0, 2.0, np.nan, 4.0, np.inf], 1.0, "octave", r"rate\[2\] = nan"),
        (np.r_[1.0, 2.0, 3.0, -np.inf], 1.0, "octave", r"rate\[3\] = -inf"),
        (np.ones(2), 1.0, "octave", "at least 3 samples, got 2"),
        (np.ones((10, 2)), 1.0, "octave", "1-D"),
        (np.ones(10), 0.0, "octave", "fs_hz must be .* > 0"),
        (np.ones(10), -5.0, "octave", "fs_hz must be .* > 0"),
        (np.ones(10), np.nan, "octave", "fs_hz must be .* > 0"),
        (np.ones(10), 1.0, "weekly", "'octave', 'decade'"),
        (np.ones(10), 10.0, np.array([0.1, 0.04]), r"tau 0\.04 s \(taus\[1\]\)"),
        (np.ones(10), 10.0, np.array([0.5, 0.1]), r"tau 0\.5 s \(taus\[0\]\).*\[1, 4\]"),
        (np.ones(10), 10.0, np.array([-0.2]), r"tau -0\.2 s"),
        (np.ones(10), 10.0, np.array([]), "non-empty"),
    ],
)
def test_validation_errors(rate, fs_hz, taus, match):
    with pytest.raises(ValueError, match=match):
        allan_deviation(rate, fs_hz, taus)


def test_result_is_frozen():
    ad = allan_deviation(np.arange(10.0), 1.0)
    assert isinstance(ad, AllanDeviation)
    with pytest.raises(AttributeError):
        ad.adev = None  # type: ignore[misc]
    with pytest.raises(ValueError):
        ad.tau_s[0] = 1.0
