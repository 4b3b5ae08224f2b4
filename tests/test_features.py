"""The causal temperature rate: loop reference, exact ramps, causality."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.compensation.features import bin_means, running_mean, temperature_rate_c_per_s


def _loop_reference(t_s: np.ndarray, temp_c: np.ndarray, window_s: float) -> np.ndarray:
    out = np.zeros(t_s.size)
    for i in range(t_s.size):
        keep = (t_s > t_s[i] - window_s) & (t_s <= t_s[i])
        if keep.sum() >= 2:
            out[i] = np.polyfit(t_s[keep], temp_c[keep], 1)[0]
    return out


def test_matches_a_loop_reference_on_irregular_times() -> None:
    rng = np.random.default_rng(0)
    t_s = 1000.0 + np.cumsum(rng.uniform(0.5, 1.5, 600))
    temp_c = 25.0 + 2.0 * np.sin(t_s / 200.0) + rng.normal(0.0, 0.01, t_s.size)
    got = temperature_rate_c_per_s(t_s, temp_c, window_s=60.0)
    np.testing.assert_allclose(got, _loop_reference(t_s, temp_c, 60.0), rtol=0.0, atol=1e-9)
    assert got[0] == 0.0


def _centred_slope(t_s: np.ndarray, temp_c: np.ndarray) -> float:
    """The least-squares slope with both variables centred on their own means first (two passes)."""
    u, v = t_s - t_s.mean(), temp_c - temp_c.mean()
    return float(np.sum(u * v) / np.sum(u * u))


def test_keeps_its_digits_in_a_burst_far_from_the_start() -> None:
    """Bursts of five 20-ms samples every 300 s over 15 hours, a thermometer in 0.01-degC steps:
    a window holds one burst's first samples, 0.02 s apart, tens of thousands of seconds after
    the record's first sample. Its rate is the centred two-pass slope to 1e-12 (moments summed
    about the first sample and centred afterwards were 0.2 % off on such a record)."""
    rng = np.random.default_rng(3)
    t_s = (np.arange(180)[:, None] * 300.0 + np.arange(5)[None, :] * 0.02).reshape(-1) + rng.uniform(0, 1e-3, 900)
    temp_c = np.round((20.0 - 40.0 * (1.0 - np.exp(-t_s / 2e4)) + rng.normal(0.0, 0.02, t_s.size)) * 100.0) / 100.0
    got = temperature_rate_c_per_s(t_s, temp_c, window_s=120.0)
    want = np.array([_centred_slope(t_s[i - i % 5:i + 1], temp_c[i - i % 5:i + 1]) if i % 5 else 0.0
                     for i in range(t_s.size)])
    assert np.count_nonzero(want) > 500
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.max(np.abs(want)))


def test_recovers_an_exact_ramp() -> None:
    t_s = np.arange(0.0, 40000.0, 1.0)
    slope_c_per_s = 1.0 / 60.0
    rate = temperature_rate_c_per_s(t_s, -40.0 + slope_c_per_s * t_s, window_s=120.0)
    assert rate[0] == 0.0
    np.testing.assert_allclose(rate[1:], slope_c_per_s, rtol=0.0, atol=1e-9)


def test_is_causal() -> None:
    rng = np.random.default_rng(1)
    t_s = np.arange(500.0)
    temp_c = 20.0 + np.cumsum(rng.normal(0.0, 0.01, t_s.size))
    base = temperature_rate_c_per_s(t_s, temp_c)
    changed = temp_c.copy()
    changed[300] += 5.0
    after = temperature_rate_c_per_s(t_s, changed)
    np.testing.assert_array_equal(after[:300], base[:300])
    assert after[300] != base[300]


def test_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="strictly increasing"):
        temperature_rate_c_per_s(np.array([0.0, 1.0, 1.0]), np.zeros(3))
    with pytest.raises(ValueError, match="window_s"):
        temperature_rate_c_per_s(np.arange(3.0), np.zeros(3), window_s=0.0)
    with pytest.raises(ValueError, match="samples"):
        temperature_rate_c_per_s(np.arange(3.0), np.zeros(4))


def test_running_mean_is_the_valid_convolution() -> None:
    rng = np.random.default_rng(2)
    x = 1e3 + rng.normal(0.0, 1.0, 5000)  # a large mean: the prefix sums grow to 5e6
    for width in (1, 7, 60, 5000):
        np.testing.assert_allclose(running_mean(x, width), np.convolve(x, np.ones(width) / width, "valid"),
                                   rtol=0.0, atol=1e-10)
    with pytest.raises(ValueError, match="width must be 1..5000"):
        running_mean(x, 0)


def test_bin_means_keep_the_mean_and_skip_gaps() -> None:
    rng = np.random.default_rng(3)
    t_s = np.r_[np.arange(0.0, 95.0, 1.0), np.arange(300.0, 312.0, 1.0)]  # a gap of 205 s
    cols = rng.normal(0.0, 1.0, (t_s.size, 2))
    t_bin, means = bin_means(t_s, cols, 10.0)
    assert means.shape == (12, 2)  # 0-9 .. 90-94 (10 bins), then 300-309 and 310-311: none in the gap
    counts = np.r_[[10] * 9, 5, 10, 2]
    np.testing.assert_allclose(counts @ means / counts.sum(), cols.mean(axis=0), rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(means[0], cols[:10].mean(axis=0), rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(t_bin[[0, 9, 10, 11]], [4.5, 92.0, 304.5, 310.5])
    same_t, same = bin_means(t_s, cols, 0.5)  # a bin per sample: the samples themselves
    np.testing.assert_array_equal(same_t, t_s)
    np.testing.assert_array_equal(same, cols)
    with pytest.raises(ValueError, match="bin_s must be > 0"):
        bin_means(t_s, cols, 0.0)
