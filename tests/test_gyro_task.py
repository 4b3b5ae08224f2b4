"""The gyro drift/noise track as tasks: VMD tuning, the compensation env, baselines, bandwidth."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tcbench  # noqa: F401  (registers the envs)
from tcbench.compensation.data import TaskDataError
from tcbench.compensation.gyro.tuning import compromise, decode, tuning_window, vmd_objectives
from tcbench.learners.polynomial import PolynomialModel
from tcbench.runner import loop, remembered
from tcbench.runner.loop import _tune, run_compensation, tune_vmd
from tcbench.sensors.recording import make_recording, write_recording
from tcbench.sensors.simulate import simulate_recording
from tcbench.tasks import GyroDriftNoiseEnv, GyroVMDTuningEnv

# Short oven runs: 1 Hz, 30 min soaks (12 soaks, ~7.5 h, ~27 000 samples).
SMALL = {"sample_rate_hz": 1.0, "hold_s": 1800.0}
# The pipeline's mechanics (drift removed to the flicker floor, bandwidth kept, ARW) are tested on a
# replay of the training power-on: on one 1 Hz oven run the soak means scatter by the flicker alone
# (33 deg/h), and a new power-on's drift can sit inside that scatter (device 0's next run: raw 35.8
# against the oracle's 36.6 deg/h), which says nothing about the pipeline.
FIXED = {"k": 6, "alpha": 2000.0, "split": "replay"}


def _env(learner: str | None = "poly", **kw: object) -> GyroDriftNoiseEnv:
    params = {"degree": 3} if learner == "poly" else {"hidden": 4, "epochs": 30} if learner == "elman" else {}
    env = GyroDriftNoiseEnv(learner, params, budget=40, **(SMALL | FIXED | kw))
    env.reset(seed=0)
    return env


@pytest.fixture(scope="module")
def scores() -> dict[str, dict[str, float]]:
    """Summaries of the methods on the small task, computed once."""
    out = {"poly": _env("poly").score()[0].summary()}
    out["raw"] = _env(None).score_baseline("raw").summary()
    out["oracle"] = _env(None).score_baseline("oracle").summary()
    out["serial_poly"] = _env("poly", decomposition="none", denoise="none").score()[0].summary()
    out["wtd"] = _env(None, decomposition="none", denoise="wavelet").score_baseline("raw").summary()
    out["plain"] = _env(None, decomposition="none", denoise="none").score_baseline("raw").summary()
    return out


# -- VMD tuning --------------------------------------------------------------------------------
def test_objectives_and_window() -> None:
    gen = np.random.default_rng(0)
    y = np.sin(np.arange(3000) / 40.0) + 0.3 * gen.normal(size=3000)
    w = tuning_window(y, 1024)
    np.testing.assert_array_equal(w, y[988:2012])
    f = vmd_objectives(w, 4, 2000.0)
    assert f.shape == (2,) and np.all(np.isfinite(f)) and 0 < f[1] <= 1
    assert decode(np.array([7.6, 1234.5])) == (8, 1234.5)
    with pytest.raises(ValueError, match="tuning_samples"):
        tuning_window(y, 10)


def test_compromise_is_the_knee() -> None:
    front_f = np.array([[0.0, 1.0], [0.1, 0.2], [0.5, 0.1], [1.0, 0.0]])
    front_x = np.array([[4, 1e3], [6, 2e3], [8, 3e3], [12, 4e3]])
    assert compromise(front_x, front_f) == 1


def test_tuning_env_passes_check_env_and_keeps_a_front() -> None:
    env = GyroVMDTuningEnv(budget=30, tuning_samples=512, **SMALL)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(env, skip_render_check=True)
    env.reset(seed=0)
    f, *_, info = env.step(np.array([[4.2, 1000.0], [11.8, 10000.0]]))
    assert f.shape == (2, 2) and info["evaluations"] == 2 and len(info["front_f"]) >= 1
    assert info["chosen"][0] in (4, 12) and info["hypervolume"] > 0
    with pytest.raises(ValueError, match="outside"):
        env.step(np.array([3.0, 5000.0]))


def test_tuning_by_mopso_is_deterministic_and_in_range(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "cache").write_text("a file: nothing kept, both tunings computed")
    monkeypatch.setenv("TCBENCH_CACHE_DIR", str(tmp_path / "cache"))
    kwargs = {"device_seed": 0, "recordings_seed": 0, "train_files": None} | SMALL
    a = tune_vmd(kwargs, "mopso", 80, 256)
    assert 4 <= a.k <= 12 and 1000 <= a.alpha <= 10000 and a.evaluations == 80
    assert a.evaluated_f.shape == (80, 2) and len(a.front_f) >= 1
    _tune.cache_clear()
    b = tune_vmd(kwargs, "mopso", 80, 256)
    assert (a.k, a.alpha) == (b.k, b.alpha)
    np.testing.assert_array_equal(a.front_f, b.front_f)


def test_a_tuning_is_kept_between_processes_and_keyed_by_record_settings_and_code(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TCBENCH_CACHE_DIR", str(tmp_path / "cache"))
    kwargs = {"device_seed": 0, "recordings_seed": 1, "train_files": None} | SMALL
    a = tune_vmd(kwargs, "mopso", 40, 256)
    _tune.cache_clear()  # as a new process: only the user cache has it

    def untuned(*args: object) -> None:
        raise AssertionError("tuned again")

    monkeypatch.setattr(loop, "_tune", untuned)
    b = tune_vmd(kwargs, "mopso", 40, 256)
    assert (a.k, a.alpha, a.seconds) == (b.k, b.alpha, b.seconds)
    np.testing.assert_array_equal(a.evaluated_f, b.evaluated_f)
    with pytest.raises(AssertionError, match="tuned again"):  # another draw
        tune_vmd({**kwargs, "recordings_seed": 2}, "mopso", 40, 256)
    with pytest.raises(AssertionError, match="tuned again"):  # another budget
        tune_vmd(kwargs, "mopso", 41, 256)
    monkeypatch.setattr(remembered, "source_digest", lambda: "other code")
    with pytest.raises(AssertionError, match="tuned again"):  # the same with other code
        tune_vmd(kwargs, "mopso", 40, 256)
    monkeypatch.setattr(loop, "_tune", _tune)
    kept = tmp_path / "cache" / "vmd-tuning"
    assert len(list(kept.glob("*.pkl"))) == 1
    # a plugin's tuner (nsga2 from tcbench-peers): its code is not in the key, so nothing is kept
    tune_vmd(kwargs, "nsga2", 40, 256, tuner_params={"population": 20})
    assert len(list(kept.glob("*.pkl"))) == 1


def test_a_recording_file_s_bytes_are_in_the_key(tmp_path: Path) -> None:
    f = tmp_path / "train.csv"
    f.write_text("t,y\n0,1\n")
    first = remembered.key_of({"budget": 1}, [str(f)])
    assert remembered.key_of({"budget": 1}, [str(f)]) == first != remembered.key_of({"budget": 2}, [str(f)])
    f.write_text("t,y\n0,2\n")
    assert remembered.key_of({"budget": 1}, [str(f)]) != first


def test_an_unusable_cache_computes_and_keeps_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "cache").write_text("not a folder")
    monkeypatch.setenv("TCBENCH_CACHE_DIR", str(tmp_path / "cache"))
    calls = []
    assert remembered.remembered("kind", "k", lambda: calls.append(1) or 7) == 7
    assert remembered.remembered("kind", "k", lambda: calls.append(1) or 7) == 7
    assert calls == [1, 1] and (tmp_path / "cache").read_text() == "not a folder"


def test_a_full_disk_keeps_no_half_written_result(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TCBENCH_CACHE_DIR", str(tmp_path / "cache"))

    def full(value: object, f: Any, protocol: int) -> None:
        f.write(b"half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(remembered.pickle, "dump", full)
    assert remembered.remembered("kind", "k", lambda: 7) == 7
    assert list((tmp_path / "cache" / "kind").iterdir()) == []


# -- the compensation env ------------------------------------------------------------------------
def test_driftnoise_env_passes_check_env() -> None:
    env = GyroDriftNoiseEnv("elman", {"hidden": 3, "epochs": 5}, budget=50, **(SMALL | FIXED))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(env, skip_render_check=True)
    assert env.dim == 3 * 2 + 3 * 3 + 3 + 3 + 1


def test_env_made_by_id_runs_the_papers_vmd_parameters_by_default() -> None:
    env = gym.make("tcbench/Gyro-DriftNoise-v0", learner="poly", **SMALL).unwrapped
    assert (env.config.k, env.config.alpha) == (8, 9755.0) and not env.needs_tuning


def test_env_with_null_vmd_parameters_needs_them_tuned() -> None:
    env = gym.make("tcbench/Gyro-DriftNoise-v0", learner="poly", k=None, alpha=None, **SMALL).unwrapped
    assert env.needs_tuning
    with pytest.raises(ValueError, match="k and alpha are unset"):
        env.reset(seed=0)
    env.reset(seed=0, options={"k": 5, "alpha": 1500.0})
    assert (env.config.k, env.config.alpha) == (5, 1500.0) and not env.needs_tuning


def test_search_steps_and_budget() -> None:
    env = _env("elman")
    x = np.random.default_rng(1).uniform(env.lower, env.upper, (4, env.dim))
    f, reward, _, truncated, info = env.step(x)
    assert f.shape == (4,) and np.all(f > 0) and np.allclose(reward, -f) and not truncated
    assert info["best_f"] == f.min() and info["evaluations"] == 4
    with pytest.raises(RuntimeError, match="only 36 of the budget"):
        env.step(np.zeros((37, env.dim)))


def test_compensation_removes_the_drift_and_keeps_the_bandwidth(scores: dict[str, dict[str, float]]) -> None:
    raw, poly, serial, oracle = scores["plain"], scores["poly"], scores["serial_poly"], scores["oracle"]
    # the soak means scatter by the flicker noise (B = 33 deg/h) even for the oracle: a polynomial
    # in T, dT/dt removes the temperature drift down to that floor
    assert raw["drift_dph"] > 1.4 * oracle["drift_dph"]
    assert serial["drift_dph"] < 1.15 * oracle["drift_dph"]
    assert serial["bandwidth_hz"] == pytest.approx(0.5)  # no filter: the whole band (Nyquist) kept
    assert oracle["bandwidth_hz"] == pytest.approx(0.5)
    assert serial["arw_1s_deg_per_sqrt_h"] == pytest.approx(raw["arw_1s_deg_per_sqrt_h"], rel=0.05)
    # the parallel pipeline lowers the ARW far below the oracle's by dropping bandwidth
    assert poly["arw_1s_deg_per_sqrt_h"] < 0.5 * oracle["arw_1s_deg_per_sqrt_h"]
    assert poly["bandwidth_hz"] < 0.1 and poly["drift_dph"] < 1.15 * oracle["drift_dph"]
    assert poly["bias_instability_dph"] < 0.2 * oracle["bias_instability_dph"]
    # ... and that "bias instability" is no floor: the filtered output's Allan minimum is an end of
    # its curve, where the raw record has its flicker floor inside it
    assert poly["allan_min_interior"] == 0.0 and poly["raw_allan_min_interior"] == 1.0


def test_denoising_alone_smooths_but_does_not_compensate(scores: dict[str, dict[str, float]]) -> None:
    raw, wtd = scores["plain"], scores["wtd"]
    assert wtd["arw_1s_deg_per_sqrt_h"] < 0.5 * raw["arw_1s_deg_per_sqrt_h"]
    assert wtd["bandwidth_hz"] < 0.5
    assert 0.85 * raw["drift_dph"] < wtd["drift_dph"] < 1.05 * raw["drift_dph"]  # the drift is below its band
    assert scores["raw"]["drift_dph"] == pytest.approx(raw["drift_dph"], rel=0.3)  # VMD-TFPF alone


def test_compensated_output_follows_a_rate_step() -> None:
    env = _env("poly", decomposition="none", denoise="none")
    env.score()
    rec = env.data.test[0].recording
    step = np.where(rec.time_s > rec.time_s[-1] / 2, 0.05, 0.0)
    method = env._pipeline_method(rec.time_s, rec.temperature_c)
    moved = method(rec.output + step) - method(rec.output)
    np.testing.assert_allclose(moved, step, atol=1e-9)


def test_baseline_and_learner_runs_agree_with_the_runner() -> None:
    task = {"name": "gyro_driftnoise", **SMALL, **FIXED, "decomposition": "none", "denoise": "none"}
    a = run_compensation(task, {"name": "poly", "degree": 3}, {"name": "none"}, 10, 0)
    b = run_compensation(task, {"name": "poly", "degree": 3}, {"name": "none"}, 10, 0)
    assert a.score.summary() == b.score.summary() and a.tuning is None
    assert a.score.summary()["train_rmse_dph"] > 0


# -- recordings from files -----------------------------------------------------------------------
def _gyro_file(tmp_path, seed: int) -> str:
    rec = simulate_recording("gyro", "oven", 0, seed, **SMALL)
    return str(write_recording(rec, tmp_path / f"oven{seed}.csv"))


def test_files_train_and_test_without_an_oracle(tmp_path) -> None:
    train, test = _gyro_file(tmp_path, 0), _gyro_file(tmp_path, 1)
    env = GyroDriftNoiseEnv("poly", {"degree": 3}, train_files=[train], test_files=[test],
                            decomposition="none", denoise="none")
    env.reset(seed=0)
    score = env.score(bandwidth=False)[0].summary()
    assert score["drift_dph"] * 1.2 < score["raw_drift_dph"]
    with pytest.raises(TaskDataError, match="truth"):
        env.score_baseline("oracle")


def test_bursty_or_foreign_files_are_refused(tmp_path) -> None:
    t = np.r_[np.arange(0, 400, 0.5), np.arange(1000, 1400, 0.5)]
    temp = np.linspace(20, 30, t.size)
    burst = make_recording(t, temp, np.zeros_like(t), np.zeros_like(t), sensor="gyro", sample_rate_hz=2.0,
                           device_id="burst")
    path = str(write_recording(burst, tmp_path / "burst.csv"))
    env = GyroDriftNoiseEnv("poly", train_files=[path], test_files=[path], **FIXED)
    with pytest.raises(TaskDataError, match="not uniformly sampled") as err:
        env.reset(seed=0)
    assert "\n" not in str(err.value)
    msra = str(write_recording(simulate_recording("msra", "roomtemp", 0, 0), tmp_path / "msra.csv"))
    with pytest.raises(TaskDataError, match="msra sensor"):
        GyroDriftNoiseEnv("poly", train_files=[msra], test_files=[msra], **FIXED).reset(seed=0)


def test_invalid_settings_raise_one_line() -> None:
    for kw, match in (({"decomposition": "fft"}, "decomposition"), ({"denoise": "kalman"}, "denoise"),
                      ({"inputs": "x"}, "inputs"), ({"sample_rate_hz": 0.0}, "sample_rate_hz"),
                      ({"tfpf_window": 30}, "odd"), ({"bandwidth_amplitude_dps": -1.0}, "amplitude")):
        with pytest.raises(ValueError, match=match) as err:
            GyroDriftNoiseEnv("poly", **kw)
        assert "\n" not in str(err.value)


def test_poly_bias_rate_recovers_a_lagged_bias() -> None:
    gen = np.random.default_rng(0)
    temp = gen.uniform(-40, 60, 400)
    rate = gen.uniform(-0.02, 0.02, 400)
    bias = 0.01 * temp + 2e-4 * temp**2 - 3e-6 * temp**3 + (5.0 + 0.02 * temp) * rate
    model = PolynomialModel(2, {"degree": 3, "form": "bias_rate"})
    model.fit(np.column_stack([temp, rate]), bias)
    np.testing.assert_allclose(model.predict(np.column_stack([temp, rate])), bias, atol=1e-9)
    assert model.n_params == 3 + 1 + 3
    bias_only = PolynomialModel(2, {"degree": 3, "form": "bias"})
    bias_only.fit(np.column_stack([temp, rate]), bias)
    assert np.abs(bias_only.predict(np.column_stack([temp, rate])) - bias).max() > 0.01


def test_device_effects_change_the_simulated_gyro() -> None:
    low = {"bias_instability": {"b": 3.0 / 3600.0}}  # 3 deg/h of flicker instead of ~33
    env = _env("poly", decomposition="none", denoise="none", effects=low)
    s = env.score(bandwidth=False)[0].summary()
    assert s["drift_dph"] * 5 < s["raw_drift_dph"]  # with little flicker the drift is what is left
    assert env.data.train[0].recording.meta.extra["effect_changes"] == low
    with pytest.raises(ValueError, match="unknown effect 'nosuch'"):
        GyroDriftNoiseEnv("poly", effects={"nosuch": {"b": 1.0}})
    with pytest.raises(ValueError, match="has no parameter q"):
        GyroVMDTuningEnv(effects={"bias_instability": {"q": 1.0}})


def test_the_wavelet_level_sets_what_the_threshold_removes(scores: dict[str, dict[str, float]]) -> None:
    """WTD's ARW and bandwidth are functions of its level (the boards' WTD is the deepest): a
    shallow threshold keeps more band and more noise; the level is named in the method."""
    from tcbench.runner.kinds.compensation import compensation_label

    shallow = _env(None, decomposition="none", denoise="wavelet", wavelet_level=2).score_baseline("raw").summary()
    deepest = scores["wtd"]
    assert shallow["bandwidth_hz"] > 4 * deepest["bandwidth_hz"]
    assert shallow["arw_1s_deg_per_sqrt_h"] > 2 * deepest["arw_1s_deg_per_sqrt_h"]
    task = {"name": "gyro_driftnoise", "decomposition": "none", "denoise": "wavelet", "wavelet_level": 2}
    assert compensation_label({"name": "raw"}, {"name": "none"}, task) == "WTD-L2"
    assert compensation_label({"name": "raw"}, {"name": "none"}, task | {"wavelet_level": None}) == "WTD"
    with pytest.raises(ValueError, match="wavelet_level must be an integer >= 1"):
        _env(None, decomposition="none", denoise="wavelet", wavelet_level=0)
