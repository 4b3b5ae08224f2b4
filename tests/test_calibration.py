"""Calibration on the user's own record: offset models fitted on the first cooling branch of the
real tofupilot chamber cycle and scored on its heating and second cooling branches."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.compensation.calibration import METHODS, Record, fit, from_model, record, residual, scores
from tcbench.compensation.fitted_model import deterministic_output, dropped_terms
from tcbench.sensors import effects as fx
from tcbench.sensors.fitted import PolynomialModel
from tcbench.sensors.simulate import simulate_recording
from tcbench.datasets.real import tofupilot_gyro
from tcbench.signal.branches import temperature_branches


@pytest.fixture(scope="module")
def axes() -> dict[str, tuple[Record, list[slice]]]:
    out = {}
    for a in "xyz":
        r = tofupilot_gyro(a)
        rec = record(r.time_s, r.temperature_c, r.output, r.input)
        out[a] = (rec, [slice(b.start, b.stop) for b in temperature_branches(r.time_s, r.temperature_c)])
    return out


def test_the_cubic_from_one_branch_cuts_the_drift_of_the_others(axes: dict[str, tuple[Record, list[slice]]]) -> None:
    for a, (rec, branches) in axes.items():
        train = [rec.part(branches[0].start, branches[0].stop)]
        models = {m: fit(m, train) for m in METHODS if m != "model"}
        res = {m: residual(model, rec) for m, model in models.items()}
        np.testing.assert_array_equal(res["raw"], rec.output - rec.truth)
        for held_out in branches[1:]:
            raw = scores(res["raw"][held_out], rec.t_s[held_out])["drift_rms"]
            cubic = scores(res["poly3"][held_out], rec.t_s[held_out])["drift_rms"]
            assert cubic < 0.8 * raw, (a, held_out)
        fitted = branches[0]
        # nested least squares: the rate term cannot fit the training branch worse
        assert scores(res["poly3_rate"][fitted], rec.t_s[fitted])["rms"] <= \
            scores(res["poly3"][fitted], rec.t_s[fitted])["rms"] + 1e-12


def test_scores_and_bad_methods() -> None:
    t = np.arange(600.0)
    noise = np.random.default_rng(0).normal(0.0, 1.0, t.size)
    s = scores(noise + 0.5, t, drift_window_s=60.0)
    assert s["rms"] == pytest.approx(np.sqrt(1.0 + 0.25), rel=0.1)
    assert s["drift_rms"] == pytest.approx(0.5, abs=0.15)  # the noise averaged out, the offset kept
    rec = record(t, 20.0 + 0.01 * t, noise, np.zeros_like(t))
    with pytest.raises(ValueError, match="unknown calibration method 'elm'"):
        fit("elm", [rec])


def test_a_diagnosed_model_compensates_its_temperature_terms_not_its_clock() -> None:
    """A fitted model with a lag, a hysteresis and a step, run through a chamber cycle without
    noise: all of it reproduces the record up to what the thermometer's own noise (5 mK) and
    resolution (10 mK) make of it through the model (the simulator saw the true temperature).
    As the compensator (``from_model``) it leaves the step out — keyed to the calibration run's
    clock, which no shipped compensator reads —, so with noise the residual is the noise plus
    the step from 7200 s on, and nothing else."""
    step = 3e-4
    model = PolynomialModel(sensor="accel", centre_c=20.0, half_range_c=40.0, bias=(0.01, 0.004, 0.001),
                            scale_factor=(1.0, 1e-4), effects=(fx.ThermalLag(200.0), fx.Hysteresis(5e-4, 4.0),
                                                               fx.BiasStep(7200.0, step), fx.WhiteNoise(1e-4)))
    quiet = simulate_recording("accel", "chamber", 0, 0, model=model, without=("white_noise",), gravity_g=1.0)
    offset = deterministic_output(model, quiet.time_s, quiet.temperature_c, quiet.input)
    np.testing.assert_allclose(offset, quiet.output, rtol=0, atol=2e-6)  # 1e-4 g/K x 10 mK, with margin
    assert np.std(offset - quiet.output) < 5e-7
    shipped = deterministic_output(model, quiet.time_s, quiet.temperature_c, quiet.input, clock_terms=False)
    np.testing.assert_allclose(offset - shipped, np.where(quiet.time_s >= 7200.0, step, 0.0), rtol=0, atol=1e-12)
    assert dropped_terms(model) == ["bias_step (time_s=7200, size=0.0003)"]
    noisy = simulate_recording("accel", "chamber", 0, 0, model=model, gravity_g=1.0)
    rec = record(noisy.time_s, noisy.temperature_c, noisy.output, noisy.input)
    res = residual(from_model(model), rec) - np.where(rec.t_s >= 7200.0, step, 0.0)
    white = 1e-4 * np.sqrt(noisy.meta.sample_rate_hz)
    assert np.std(res) == pytest.approx(white, rel=0.05) and abs(np.mean(res)) < 3 * white / np.sqrt(res.size)
    with pytest.raises(ValueError, match="fitted by tcbench diagnose"):
        fit("model", [rec])


def _smooth_record(seconds: float, noise: float, seed: int) -> Record:
    """A 1 Hz record of a cubic offset in a chamber cycle's temperature plus white noise."""
    t = np.arange(0.0, seconds, 1.0)
    temp = 20.0 + 30.0 * np.sin(2.0 * np.pi * t / seconds)
    offset = 0.02 + 1e-3 * (temp - 20.0) - 2e-5 * (temp - 20.0) ** 2
    out = offset + np.random.default_rng(seed).normal(0.0, noise, t.size)
    return record(t, temp, out, np.zeros_like(t))


def test_binned_training_gives_the_per_sample_fit_of_a_smooth_offset() -> None:
    """bp (the paper's gradient descent) trained on 5-s bin means and on every sample, from the
    same seed and normalisation, ends at the same network up to a small part of the offset's
    span; both take out the offset."""
    rec = _smooth_record(7200.0, 2e-3, 0)
    truth = rec.output - np.random.default_rng(0).normal(0.0, 2e-3, rec.t_s.size)
    span = np.ptp(truth)
    binned, every = fit("bp_gd", [rec], seed=3), fit("bp_gd", [rec], seed=3, bin_s=None)
    assert binned.bin_s == 5.0 and every.bin_s is None
    a, b = binned.offset(rec), every.offset(rec)
    assert np.max(np.abs(a - b)) < 0.03 * span
    for off in (a, b):
        assert np.sqrt(np.mean((off - truth) ** 2)) < 0.03 * span


def test_binned_elman_steps_once_per_bin() -> None:
    """elman trained on bins runs on the record's bins, its output interpolated between the bins'
    mean times, and takes out most of a smooth offset on a cycle it did not see."""
    train, test = _smooth_record(7200.0, 2e-3, 1), _smooth_record(7200.0, 2e-3, 2)
    model = fit("elman", [train], seed=0)
    coarse = test.binned(5.0)
    assert coarse.t_s.size == 1440 and coarse.t_s[0] == 2.0
    on_bins = model.learner.predict(np.column_stack([coarse.temp_c, coarse.rate_c_per_s]))
    np.testing.assert_allclose(model.offset(test), np.interp(test.t_s, coarse.t_s, on_bins), rtol=0.0, atol=1e-15)
    res = residual(model, test)
    assert scores(res, test.t_s)["drift_rms"] < 0.2 * scores(test.output - test.truth, test.t_s)["drift_rms"]
    with pytest.raises(ValueError, match="bin_s must be > 0 or None"):
        fit("bp", [train], bin_s=0.0)


def _two_parts(drift: str) -> tuple[Record, np.ndarray]:
    """Two 30-min parts at 1 Hz: the first cools 50 -> 0 degC, the second heats 0 -> 50 degC (its
    temperature runs the other way at the same elapsed time); the offset a function of the time
    since each part's start (``elapsed``) or of the temperature alone (``temperature``), plus
    white noise. Returns the record and the parts' first times."""
    part_s = 1800
    elapsed = np.tile(np.arange(part_s, dtype=float), 2)
    t = np.arange(2 * part_s, dtype=float)
    tau = elapsed / part_s
    temp = np.where(t < part_s, 50.0 - 50.0 * tau, 50.0 * tau)
    if drift == "elapsed":
        offset = 0.5 * np.exp(-elapsed / 300.0) + 0.1 * np.sin(2 * np.pi * elapsed / 900.0)
    else:
        offset = 0.01 * temp + 2e-4 * (temp - 10.0) ** 2
    noise = np.random.default_rng(4).normal(0.0, 0.01, t.size)
    return record(t, temp, offset + noise, np.zeros_like(t)), np.array([0.0, float(part_s)])


def test_the_memoriser_removes_a_drift_keyed_to_the_part_s_clock_and_nothing_of_a_temperature_one() -> None:
    held = slice(1800, 3600)
    for drift in ("elapsed", "temperature"):
        rec, starts_s = _two_parts(drift)
        train = [rec.part(0, 1800)]
        memoriser = fit("memoriser", train, part_starts_s=starts_s[:1])
        res = {"raw": rec.output - rec.truth, "memoriser": residual(memoriser, rec, starts_s),
               "poly3": residual(fit("poly3", train), rec)}
        ratio = {m: scores(r[held], rec.t_s[held])["drift_rms"] / scores(res["raw"][held], rec.t_s[held])["drift_rms"]
                 for m, r in res.items()}
        if drift == "elapsed":
            # the same time since each part's start: the memoriser takes it all, the cubic in the
            # temperature (which runs the other way here) cannot
            assert ratio["memoriser"] < 0.05 and ratio["poly3"] > 0.5, ratio
        else:
            # a function of the temperature alone, which the held-out part runs the other way:
            # the memoriser removes nothing of it, the cubic nearly all
            assert ratio["memoriser"] > 0.9 and ratio["poly3"] < 0.05, ratio
    # without the parts' starts the memoriser reads the time since the record's: the second part
    # then lies beyond the fitted one and gets the last bin's offset
    rec, starts_s = _two_parts("elapsed")
    memoriser = fit("memoriser", [rec.part(0, 1800)], part_starts_s=starts_s[:1])
    np.testing.assert_allclose(memoriser.offset(rec)[held], memoriser.memory[1][-1])


def test_the_memoriser_counts_from_each_part_s_start_not_each_screened_piece_s() -> None:
    rec, starts_s = _two_parts("elapsed")
    pieces = [rec.part(0, 700), rec.part(760, 1800)]  # the first part cut by screening
    from_part = fit("memoriser", pieces, part_starts_s=starts_s[:1])
    from_piece = fit("memoriser", pieces)
    held = slice(1800, 3600)
    raw = scores((rec.output - rec.truth)[held], rec.t_s[held])["drift_rms"]
    assert scores(residual(from_part, rec, starts_s)[held], rec.t_s[held])["drift_rms"] < 0.05 * raw
    assert scores(residual(from_piece, rec, starts_s)[held], rec.t_s[held])["drift_rms"] > 0.1 * raw
    with pytest.raises(ValueError, match="part_starts_s is empty"):
        fit("memoriser", pieces, part_starts_s=np.array([]))
