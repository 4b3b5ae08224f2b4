"""The lag-aware polynomial: it finds the lag of a record's bias behind its thermometer, and on the
simulated MSRA tasks it comes within 1.3x of the thermometer-limited oracle."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import tcbench.tasks  # noqa: F401 - registers the envs
from tcbench.compensation.lagpoly import fit_lag_poly, lagged
from tcbench.sensors.recording import make_recording


def _record(seed: int, tau_s: float, k_per_c: float, scale: float = 0.0) -> object:
    """A 2 h record at 1 Hz whose output is a line in the thermometer lagged by ``tau_s``."""
    rng = np.random.default_rng(seed)
    t = np.arange(7200.0)
    temp = 25.0 + 8.0 * np.sin(2 * np.pi * t / (3000.0 + 500.0 * seed)) + rng.normal(0.0, 0.005, t.size)
    applied = np.where((t // 600) % 2 == 0, 0.0, 1.0) if scale else np.zeros_like(t)
    out = 0.3 + k_per_c * (lagged(t, temp, tau_s) - 25.0) + applied * (1.0 + scale * (temp - 25.0))
    return make_recording(t, temp, applied, out + rng.normal(0.0, 0.002, t.size), sensor="accel",
                          sample_rate_hz=1.0, device_id=f"r{seed}")


def test_it_finds_the_lag_and_leaves_the_noise() -> None:
    recs = [_record(s, 400.0, 0.01) for s in range(3)]
    model = fit_lag_poly(recs)
    assert model.scale is None and 300.0 < model.tau_s < 550.0  # the grid is 21 points per two decades
    test = _record(7, 400.0, 0.01)
    assert np.std(test.output - model.bias_of(test)) < 1.5 * 0.002
    plain = fit_lag_poly(recs, taus_s=[0.0])  # the same polynomial without the lag
    assert np.std(test.output - plain.bias_of(test)) > 5 * 0.002


def test_with_an_input_it_solves_for_it() -> None:
    recs = [_record(s, 200.0, 0.004, scale=1e-3) for s in range(3)]
    model = fit_lag_poly(recs)
    assert model.scale is not None
    test = _record(5, 200.0, 0.004, scale=1e-3)
    assert np.max(np.abs(model.inverse(test, test.output) - test.input)) < 0.02


@pytest.mark.parametrize(("env_id", "metric", "split"), [("tcbench/MSRA-FullTemp-v0", "bias_variation_ug", "next_run"),
                                                          ("tcbench/MSRA-ZeroBias-v0", "zb_zero_start_ug", "replay")])
def test_within_the_target_of_the_thermometer_limited_oracle(env_id: str, metric: str, split: str) -> None:
    """Full temperature, new power-ons: within 1.3x of the limit of a compensator that knows the device
    but not this power-on (measured 46.6 against 39.1 µg), which is far above the die-temperature oracle.
    Zero bias: only where the test runs replay the training power-on (on new power-ons the runs' turn-on
    biases and ambients confound a fit across them: tests/test_msra_env.py)."""
    env = gym.make(env_id, split=split).unwrapped
    env.reset(seed=0)
    scores = {b: env.score_baseline(b).summary()[metric] for b in ("oracle", "oracle_thermometer", "lagpoly", "raw")}
    assert scores["oracle"] < scores["oracle_thermometer"] * 1.05  # the thermometer is a floor (one draw each)
    assert 0.9 * scores["oracle_thermometer"] <= scores["lagpoly"] < 1.3 * scores["oracle_thermometer"], scores
    assert scores["lagpoly"] < 0.05 * scores["raw"]
