"""Tests of the seed 001 parallel gyro pipeline on synthetic 1 Hz gyro-like records."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from tcbench.compensation.gyro import (
    ParallelPipeline,
    PipelineConfig,
    PipelineOutput,
    classify_modes,
)
from tcbench.learners.polynomial import PolynomialModel


def _record(seed: int, steps: tuple[float, ...], hours: float = 4.0) -> tuple[np.ndarray, ...]:
    """Times (s), temperature (degC, steps through a 600 s first-order lag), gyro output (deg/s;
    true rate 0: drift = cubic in T + 2 s * dT/dt, plus white noise of 0.02 deg/s)."""
    gen = np.random.default_rng(seed)
    n = int(hours * 3600)
    t = np.arange(n, dtype=np.float64)
    target = np.repeat(np.asarray(steps, dtype=np.float64), -(-n // len(steps)))[:n]
    a = np.exp(-1.0 / 600.0)
    # first-order lag temp[i] = a temp[i-1] + (1 - a) target[i], starting settled at target[0]
    temp = lfilter([1.0 - a], [1.0, -a], target, zi=[a * target[0]])[0]
    x = (temp - 25.0) / 20.0
    drift = 0.3 + 0.4 * x + 0.25 * x**2 - 0.1 * x**3 + 2.0 * np.gradient(temp, t)
    return t, temp, drift + gen.normal(0.0, 0.02, n)


@pytest.fixture(scope="module")
def fitted() -> tuple[ParallelPipeline, tuple[np.ndarray, ...], PipelineOutput]:
    pipe = ParallelPipeline(PipelineConfig())
    pipe.fit(*_record(1, (25.0, 45.0, 10.0, 35.0, 20.0)), learner=PolynomialModel(2, {"degree": 3, "form": "bias"}))
    test = _record(2, (22.0, 40.0, 12.0, 33.0, 27.0))
    return pipe, test, pipe.apply(*test)


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def test_classify_modes_separates_slow_and_white() -> None:
    gen = np.random.default_rng(0)
    t = np.arange(12000, dtype=np.float64)
    modes = np.vstack((np.sin(2 * np.pi * t / 6000.0), gen.normal(size=t.size)))
    classes = classify_modes(modes)
    assert classes.label == ("drift", "noise")
    assert classes.entropy[0] < classes.drift_below
    assert classes.entropy[1] > classes.noise_above


def test_lowest_mode_is_always_drift() -> None:
    gen = np.random.default_rng(1)
    classes = classify_modes(gen.normal(size=(2, 3000)))
    assert classes.label == ("drift", "noise")


def test_training_classes(fitted: tuple[ParallelPipeline, tuple[np.ndarray, ...], PipelineOutput]) -> None:
    pipe = fitted[0]
    classes = pipe.train_classes
    assert classes is not None
    assert classes.label[0] == "drift" and classes.entropy[0] < classes.entropy[1:].min()
    assert "noise" in classes.label[len(classes.label) // 2:]


def test_apply_reduces_rms_and_keeps_length(
        fitted: tuple[ParallelPipeline, tuple[np.ndarray, ...], PipelineOutput]) -> None:
    _, (t, _, raw), out = fitted
    n = t.size
    assert out.modes.shape == (8, n)
    for part in (out.noise_part, out.mixed_part, out.drift_part, out.denoised_mixed,
                 out.predicted_drift, out.compensated_drift, out.output):
        assert part.shape == (n,)
    assert out.classes.label[0] == "drift" and "noise" in out.classes.label
    np.testing.assert_allclose(out.output, out.denoised_mixed + out.drift_part - out.predicted_drift)
    assert _rms(out.output) * 5.0 <= _rms(raw)


def test_bad_input_raises(fitted: tuple[ParallelPipeline, tuple[np.ndarray, ...], PipelineOutput]) -> None:
    pipe, (t, temp, raw), _ = fitted
    with pytest.raises(ValueError, match="lengths differ") as err:
        pipe.apply(t, temp[:-1], raw)
    assert "\n" not in str(err.value)
    bad = raw.copy()
    bad[10] = np.nan
    with pytest.raises(ValueError, match="finite") as err:
        pipe.apply(t, temp, bad)
    assert "\n" not in str(err.value)
    with pytest.raises(ValueError):
        ParallelPipeline().fit(t, temp, bad, PolynomialModel(2, {"degree": 3, "form": "bias"}))
    with pytest.raises(ValueError):
        classify_modes(np.full((2, 100), np.nan))
