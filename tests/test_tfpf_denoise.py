"""Time-frequency peak filtering (tcbench.signal.tfpf) and the wavelet / EMD baselines
(tcbench.signal.denoise)."""

from __future__ import annotations

import numpy as np
import pytest

import tcbench.signal.tfpf as tfpf_module
from tcbench.signal.denoise import (
    emd_imfs,
    emd_wavelet_denoise,
    universal_threshold,
    wavelet_denoise,
)
from tcbench.signal.tfpf import tfpf

N = 4000
T = np.arange(N)


def _rms(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(e * e)))


def _amplitude(y: np.ndarray, period: float) -> float:
    """Least-squares amplitude of the sinusoid of ``period`` samples in ``y``."""
    basis = np.c_[np.sin(2 * np.pi * T / period), np.cos(2 * np.pi * T / period)]
    coef = np.linalg.lstsq(basis, y, rcond=None)[0]
    return float(np.hypot(*coef))


def _blocks_and_sine() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(5)
    t = np.linspace(0.0, 1.0, 2049)
    clean = 4.0 * np.sin(4 * np.pi * t) - np.sign(t - 0.3) - np.sign(0.72 - t)
    return clean, clean + 0.3 * rng.standard_normal(t.size)


def test_tfpf_denoises_slow_sine():
    rng = np.random.default_rng(1)
    clean = np.sin(2 * np.pi * T / 1000)
    noisy = clean + 0.3 * rng.standard_normal(N)
    out = tfpf(noisy, 31, fs_hz=100.0)
    assert out.shape == noisy.shape
    assert _rms(noisy - clean) / _rms(out - clean) > 2.0


def test_tfpf_recovers_ramp_and_does_not_depend_on_fs():
    ramp = 3.0 + 0.01 * T
    np.testing.assert_allclose(tfpf(ramp, 31), ramp, rtol=0, atol=1e-8)
    slow = ramp + 0.5 * np.sin(2 * np.pi * T / 1000)
    out = tfpf(slow, 31)
    assert np.max(np.abs(out - slow)[50:-50]) < 1e-3
    np.testing.assert_allclose(tfpf(slow, 31, fs_hz=250.0), out, rtol=0, atol=1e-9)


def test_tfpf_window_trades_noise_for_bandwidth():
    rng = np.random.default_rng(3)
    noise = 0.3 * rng.standard_normal(N)
    fast = np.sin(2 * np.pi * T / 80)
    inner = slice(200, -200)
    short, long = 11, 41
    # longer window: less output noise ...
    assert np.std(tfpf(noise, long)[inner]) < 0.7 * np.std(tfpf(noise, short)[inner])
    # ... but more attenuation and error on a faster component
    out_short, out_long = tfpf(fast, short), tfpf(fast, long)
    assert _amplitude(out_long, 80) < _amplitude(out_short, 80) - 0.03
    assert _rms((out_long - fast)[inner]) > 2.0 * _rms((out_short - fast)[inner])


def test_tfpf_mu_and_chunking(monkeypatch):
    rng = np.random.default_rng(2)
    clean = np.sin(2 * np.pi * T / 1000)
    noisy = clean + 0.3 * rng.standard_normal(N)
    ref = tfpf(noisy, 21, fs_hz=10.0)
    span = np.ptp(noisy) * 1.5  # generous bound on the padded range
    small_mu = tfpf(noisy, 21, fs_hz=10.0, mu=0.1 * 10.0 / span)
    assert _rms(noisy - clean) / _rms(small_mu - clean) > 2.0
    monkeypatch.setattr(tfpf_module, "_CHUNK_VALUES", 1000)  # chunks of a few rows
    np.testing.assert_allclose(tfpf(noisy, 21, fs_hz=10.0), ref, rtol=0, atol=1e-10)


def test_tfpf_constant_and_minimal_window():
    np.testing.assert_array_equal(tfpf(np.full(50, 2.5), 5), np.full(50, 2.5))
    x = np.linspace(-1.0, 1.0, 3)
    np.testing.assert_allclose(tfpf(x, 3), x, atol=1e-10)


@pytest.mark.parametrize(
    ("x", "kwargs"),
    [
        (np.r_[np.zeros(10), np.nan, np.zeros(10)], {"window": 5}),
        (np.zeros((10, 2)), {"window": 5}),
        (np.zeros(20), {"window": 1}),
        (np.zeros(20), {"window": 4}),
        (np.zeros(20), {"window": 21}),
        (np.zeros(20), {"window": 5.0}),
        (np.arange(20.0), {"window": 5, "fs_hz": 0.0}),
        (np.arange(20.0), {"window": 5, "mu": -1.0}),
        (np.arange(20.0), {"window": 5, "mu": 1.0}),  # range 28 * 1 Hz > 0.4 fs
    ],
)
def test_tfpf_bad_input(x, kwargs):
    with pytest.raises(ValueError) as info:
        tfpf(x, **kwargs)
    assert "\n" not in str(info.value)


def test_wavelet_denoise_lowers_error_and_keeps_length():
    clean, noisy = _blocks_and_sine()
    for mode in ("soft", "hard"):
        out = wavelet_denoise(noisy, mode=mode)
        assert out.shape == noisy.shape
        assert _rms(out - clean) < 0.6 * _rms(noisy - clean)
    odd = noisy[:2047]
    assert wavelet_denoise(odd, "sym8", level=4).shape == odd.shape
    np.testing.assert_allclose(wavelet_denoise(noisy, threshold=0.0), noisy, atol=1e-10)
    sigma = universal_threshold(noisy) / np.sqrt(2 * np.log(noisy.size))
    assert 0.25 < sigma < 0.35


def test_emd_imfs_sum_to_signal_and_emd_wavelet_denoises():
    clean, noisy = _blocks_and_sine()
    imfs = emd_imfs(noisy)
    assert imfs.ndim == 2 and imfs.shape[1] == noisy.size and imfs.shape[0] >= 3
    assert np.max(np.abs(imfs.sum(axis=0) - noisy)) <= 1e-8 * np.max(np.abs(noisy))
    two = emd_imfs(noisy, max_imf=2)
    assert two.shape[0] == 3
    np.testing.assert_allclose(two.sum(axis=0), noisy, rtol=0, atol=1e-8 * np.max(np.abs(noisy)))
    out = emd_wavelet_denoise(noisy, noise_imfs=1, mixed_imfs=2)
    assert out.shape == noisy.shape
    assert _rms(out - clean) < 0.7 * _rms(noisy - clean)
    np.testing.assert_allclose(emd_wavelet_denoise(noisy, 0, 0), noisy, atol=1e-8)
    np.testing.assert_allclose(emd_wavelet_denoise(noisy, 99, 0), imfs[-1], atol=1e-12)


@pytest.mark.parametrize(
    ("func", "args", "kwargs"),
    [
        (wavelet_denoise, (np.r_[1.0, np.inf, 2.0, 3.0],), {}),
        (wavelet_denoise, (np.zeros((8, 8)),), {}),
        (wavelet_denoise, (np.zeros(64),), {"mode": "garrote-ish"}),
        (wavelet_denoise, (np.zeros(64),), {"wavelet": "nope"}),
        (wavelet_denoise, (np.zeros(64),), {"level": 20}),
        (wavelet_denoise, (np.zeros(64),), {"threshold": "sure"}),
        (wavelet_denoise, (np.zeros(64),), {"threshold": -1.0}),
        (emd_imfs, (np.r_[1.0, np.nan, 2.0, 3.0],), {}),
        (emd_imfs, (np.zeros((8, 8)),), {}),
        (emd_imfs, (np.arange(64.0),), {"max_imf": 0}),
        (emd_wavelet_denoise, (np.arange(64.0),), {"noise_imfs": -1}),
    ],
)
def test_denoise_bad_input(func, args, kwargs):
    with pytest.raises(ValueError) as info:
        func(*args, **kwargs)
    assert "\n" not in str(info.value)


def test_read_only_input_as_pandas_gives_it() -> None:
    """A read-only array (pandas 3's ``.values``) failed in PyWavelets with "buffer source array
    is read-only"; every signal function now takes one and leaves it untouched."""
    from tcbench.signal.denoise import emd_wavelet_denoise, universal_threshold, wavelet_denoise
    from tcbench.signal.entropy import fuzzy_entropy, permutation_entropy, sample_entropy
    from tcbench.signal.tfpf import tfpf
    from tcbench.signal.vmd import vmd

    rng = np.random.default_rng(4)
    x = np.sin(np.linspace(0.0, 20.0, 1024)) + 0.3 * rng.normal(size=1024)
    frozen = x.copy()
    frozen.flags.writeable = False
    np.testing.assert_array_equal(wavelet_denoise(frozen), wavelet_denoise(x))
    assert universal_threshold(frozen) == universal_threshold(x)
    np.testing.assert_array_equal(emd_wavelet_denoise(frozen), emd_wavelet_denoise(x))
    np.testing.assert_array_equal(tfpf(frozen), tfpf(x))
    np.testing.assert_array_equal(vmd(frozen, 3, 2000.0).modes, vmd(x, 3, 2000.0).modes)
    for fn in (sample_entropy, permutation_entropy, fuzzy_entropy):
        assert fn(frozen[:300]) == fn(x[:300])
    np.testing.assert_array_equal(frozen, x)
