"""Noise processes: their Allan signatures (docs/concepts/physics.md, metrics)."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.sensors import noise
from tcbench.sensors.thermal import gauss_markov
from tcbench.signal.allan import allan_deviation, noise_parameters


def test_flicker_floor_is_0664_b() -> None:
    """Alone, the bank's Allan curve is flat at 0.664 b; under white noise the read-off gives b."""
    fs, b = 10.0, 2.0
    x = noise.flicker(int(6 * 3600 * fs), 1 / fs, b, np.random.default_rng(0))
    ad = allan_deviation(x, fs, "octave")
    plateau = ad.adev[(ad.tau_s >= 5) & (ad.tau_s <= 2000)]
    assert np.median(plateau) / b == pytest.approx(0.664, rel=0.1)
    assert plateau.max() / plateau.min() < 1.3
    floors = []
    for seed in range(3):
        rng = np.random.default_rng(seed)
        y = noise.flicker(x.size, 1 / fs, b, rng) + noise.white(x.size, 5.0 * b, rng)
        floors.append(noise_parameters(allan_deviation(y, fs, "octave")).bias_instability)
    assert np.median(floors) == pytest.approx(b, rel=0.2)


def test_white_noise_density() -> None:
    fs = 100.0
    x = noise.white(200_000, 0.5 * np.sqrt(fs), np.random.default_rng(1))
    p = noise_parameters(allan_deviation(x, fs, "octave"))
    assert p.angle_random_walk == pytest.approx(0.5, rel=0.05)


def test_random_walk() -> None:
    fs, k = 10.0, 0.01
    x = noise.random_walk(400_000, 1 / fs, k, np.random.default_rng(2))
    assert np.std(np.diff(x)) == pytest.approx(k / np.sqrt(fs), rel=0.01)


def test_gauss_markov_statistics() -> None:
    x = gauss_markov(200_000, 1.0, 50.0, 3.0, np.random.default_rng(3))
    assert np.std(x) == pytest.approx(3.0, rel=0.05)
    lag1 = np.corrcoef(x[:-1], x[1:])[0, 1]
    assert lag1 == pytest.approx(np.exp(-1 / 50.0), abs=0.01)


def test_quantise() -> None:
    np.testing.assert_allclose(noise.quantise(np.array([0.014, -0.026]), 0.01), [0.01, -0.03])
    x = np.array([1.23456])
    assert noise.quantise(x, 0.0) is x


def test_same_seed_same_noise() -> None:
    a = noise.flicker(1000, 0.1, 1.0, np.random.default_rng(5))
    b = noise.flicker(1000, 0.1, 1.0, np.random.default_rng(5))
    np.testing.assert_array_equal(a, b)
