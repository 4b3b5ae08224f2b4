"""The simulator's truth (the recording minus it is noise alone) and the oracle built on it."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.compensation.oracle import oracle_bias, oracle_inverse
from tcbench.metrics import accelerometer as acc
from tcbench.sensors.kinds import unit
from tcbench.sensors.noise import FLICKER_SIGMA_PER_B
from tcbench.sensors.recording import Recording
from tcbench.sensors.simulate import simulate_recording
from tcbench.sensors.truth import Truth, simulate_truth

Run = tuple[Recording, Truth]


@pytest.fixture(scope="module")
def fulltemp() -> Run:
    return simulate_recording("msra", "fulltemp", 0, 0), simulate_truth("msra", "fulltemp", 0, 0)


@pytest.fixture(scope="module")
def roomtemp() -> Run:
    return simulate_recording("msra", "roomtemp", 0, 0), simulate_truth("msra", "roomtemp", 0, 0)


def _labels(rec: Recording) -> np.ndarray:
    return rec.data["position"].fillna("").astype(str).to_numpy()


def _configured_noise_std(n: int, dt_s: float, white: float, b: float, step: float) -> float:
    """Expected sample std of the configured noise over ``n`` samples: white per-sample std,
    quantisation ``step / sqrt(12)``, and the flicker bank of :func:`tcbench.sensors.noise.flicker`
    (Gauss-Markov processes with correlation times ``tc`` two per decade from 1 s to ten times
    the record, each of std ``0.605 b``), each process's variance reduced by the part the
    sample mean of a record of length ``T`` removes: ``1 - 2r (1 - r (1 - exp(-1/r)))``,
    ``r = tc / T``."""
    duration_s = n * dt_s
    low, high = max(1.0, 2.0 * dt_s), 10.0 * duration_s
    tcs = np.logspace(np.log10(low), np.log10(high), max(1, int(np.ceil(2 * np.log10(high / low))) + 1))
    r = tcs / duration_s
    kept = 1.0 - 2.0 * r * (1.0 - r * (1.0 - np.exp(-1.0 / r)))
    flicker_var = (FLICKER_SIGMA_PER_B * b) ** 2 * kept.sum()
    return float(np.sqrt(white**2 / dt_s + flicker_var + step**2 / 12.0))


def test_truth_matches_the_recording(fulltemp: Run) -> None:
    rec, truth = fulltemp
    np.testing.assert_array_equal(truth.t_s, rec.time_s)
    np.testing.assert_array_equal(truth.input, rec.input)
    assert truth.temp_die_c.shape == truth.output_det.shape == truth.sensitivity_per_input.shape
    # the die lags the package; the thermometer reads the package 1-3 degC apart (its placement)
    assert abs(truth.temp_die_c.min() - rec.temperature_c.min()) < 4.0
    sf = rec.meta.extra["scale_factor_hz_per_g"]
    assert np.all(np.abs(truth.sensitivity_per_input / sf - 1.0) < 0.05)


def test_residual_is_the_configured_noise(fulltemp: Run) -> None:
    rec, truth = fulltemp
    residual = rec.output - truth.output_det
    effects = {e.id: e.params() for e in unit("msra", 0).model.effects}
    dt_s = float(rec.time_s[1] - rec.time_s[0])
    expected = _configured_noise_std(residual.size, dt_s, effects["white_noise"]["density"],
                                     effects["bias_instability"]["b"], effects["quantisation"]["step"])
    assert abs(np.std(residual) / expected - 1.0) < 0.2


def test_residual_has_no_temperature_trend(fulltemp: Run) -> None:
    # Flicker drifts slowly, and over a monotonic -40..60 degC run any slow drift correlates with
    # temperature by chance (|corr| up to ~0.25 across run seeds), so the trend is checked on the
    # same run without it: white noise and quantisation only, the deterministic part unchanged.
    rec, truth = fulltemp
    quiet = simulate_recording("msra", "fulltemp", 0, 0, without=("bias_instability",))
    residual = quiet.output - truth.output_det
    assert abs(np.corrcoef(residual, rec.temperature_c)[0, 1]) < 0.1
    assert abs(np.corrcoef(residual, truth.temp_die_c)[0, 1]) < 0.1


def test_without_noise_the_recording_is_the_truth() -> None:
    without = ["white_noise", "bias_instability", "quantisation"]
    rec = simulate_recording("msra", "fulltemp", 0, 0, without=tuple(without))
    truth = simulate_truth("msra", "fulltemp", 0, 0, without=without)
    np.testing.assert_allclose(rec.output, truth.output_det, rtol=0.0, atol=1e-9)


def test_truth_follows_model_changes() -> None:
    plain = simulate_truth("msra", "roomtemp", 0, 0, duration_s=600.0)
    warm = simulate_truth("msra", "roomtemp", 0, 0, effects={"warmup": {"amplitude": 0.5}}, duration_s=600.0)
    np.testing.assert_allclose(warm.output_det - plain.output_det, 0.5 * np.exp(-plain.t_s / 1200.0))
    gyro = simulate_truth("gyro", "static", 0, 0, duration_s=60.0, sample_rate_hz=10.0)
    np.testing.assert_allclose(gyro.sensitivity_per_input, gyro.sensitivity_per_input[0])


def test_oracle_fulltemp_reaches_the_noise_floor(fulltemp: Run) -> None:
    rec, truth = fulltemp
    labels = _labels(rec)
    raw = acc.temperature_variation(acc.four_position(rec.temperature_c, rec.output, labels))
    accel_g = oracle_inverse(rec.output, truth)
    oracle = acc.temperature_variation(acc.four_position(rec.temperature_c, accel_g, labels))
    assert oracle.bias_ug < 10.0
    assert oracle.bias_ug < raw.bias_ug / 100.0
    assert oracle.scale_factor_ppm < raw.scale_factor_ppm / 100.0


def test_oracle_roomtemp_reaches_the_noise_floor(roomtemp: Run) -> None:
    rec, truth = roomtemp
    sf = rec.meta.extra["scale_factor_hz_per_g"]
    raw = acc.zero_bias_table(rec.time_s, rec.output, sf)
    oracle = acc.zero_bias_table(rec.time_s, oracle_bias(rec.output, truth), sf)
    for row, value in oracle.items():
        assert value < 15.0
        assert value < raw[row] / 5.0
    assert np.mean(oracle_bias(rec.output, truth)) == pytest.approx(np.mean(rec.output))


def test_oracle_rejects_mismatched_lengths(roomtemp: Run) -> None:
    rec, truth = roomtemp
    with pytest.raises(ValueError, match="samples"):
        oracle_bias(rec.output[:-1], truth)
    with pytest.raises(ValueError, match="samples"):
        oracle_inverse(rec.output[:-1], truth)


def test_the_thermometer_limited_oracle_reads_the_recorded_thermometer(roomtemp: Run) -> None:
    """``output_det_thermometer`` is the device's noise-free model (not this power-on's) fed the
    package temperature the device's thermometer placement implies from the recording's own
    thermometer column, smoothed over 61 samples; with a thermometer far coarser than the sensor's
    (1 degC steps, as a Bosch part reads) the two oracles part further, the thermometer-limited one
    the worse."""
    import dataclasses

    from scipy.ndimage import uniform_filter1d

    from tcbench.sensors.runs import placement
    from tcbench.sensors.simulate import prepare_run
    from tcbench.sensors.truth import STOCHASTIC_EFFECTS

    rec, truth = roomtemp
    det = unit("msra", 0).model.without(*STOCHASTIC_EFFECTS)
    profile = prepare_run("msra", "roomtemp", 0, 0).profile
    smoothed = uniform_filter1d(rec.temperature_c, 61, mode="nearest")
    profile = dataclasses.replace(profile, temp_c=placement("msra", 0).package_c(smoothed, profile.dt_s))
    np.testing.assert_allclose(truth.output_det_thermometer, det.simulate(profile, np.random.default_rng(0)),
                               rtol=0, atol=1e-9)
    assert np.std(truth.output_det_thermometer - truth.output_det) > 0

    coarse = {"thermometer_quantisation": {"step_c": 1.0}}
    rough, rough_truth = simulate_recording("msra", "roomtemp", 0, 0, coarse), simulate_truth("msra", "roomtemp", 0, 0, coarse)
    sf = float(rough.meta.extra["scale_factor_hz_per_g"])
    true_limit = acc.zero_bias_stability_ug(rough.time_s, oracle_bias(rough.output, rough_truth), sf)
    read_limit = acc.zero_bias_stability_ug(rough.time_s, oracle_bias(rough.output, rough_truth, thermometer=True), sf)
    assert read_limit > 1.5 * true_limit, (true_limit, read_limit)
