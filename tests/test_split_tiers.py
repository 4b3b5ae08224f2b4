"""Split tiers of the simulated compensation tasks, and the memoriser that checks they hold out."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tcbench.compensation.data import SPLITS, TaskDataError, file_data, split_runs
from tcbench.compensation.scoring import PRIMARY
from tcbench.sensors.recording import write_recording
from tcbench.sensors.simulate import simulate_recording
from tcbench.tasks.msra_env import MSRACompensationEnv


def test_tiers_draw_the_runs_they_name() -> None:
    train, test = split_runs("chamber", "replay", 0, 0, 3, 2)
    assert {r.power_on for r in train + test} == {train[0].seed}  # one power-on, new noise
    assert len({r.seed for r in train + test}) == 5
    train, test = split_runs("chamber", "next_run", 0, 0, 3, 2)
    assert all(r.power_on is None and r.device_seed == 0 and not r.changes for r in train + test)
    train, test = split_runs("chamber", "new_profile", 0, 0, 3, 2)
    assert all(not r.changes for r in train) and all(dict(r.changes)["reverse"] for r in test)
    train, test = split_runs("chamber", "new_device", 4, 0, 3, 2)
    assert {r.device_seed for r in train}.isdisjoint({r.device_seed for r in test})


def test_unknown_tier_is_refused() -> None:
    with pytest.raises(TaskDataError, match="unknown split 'nextrun'"):
        split_runs("chamber", "nextrun", 0, 0, 3, 2)
    with pytest.raises(ValueError, match="unknown split"):
        MSRACompensationEnv(task="accel_chamber", learner=None, split="held_out")
    assert SPLITS[1] == "next_run"


def test_a_task_never_tests_on_its_training_files(tmp_path: Path) -> None:
    rec = simulate_recording("accel", "chamber", 0, 0, levels_c=(45.0, 5.0), soak_s=900.0, room_s=600.0)
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    write_recording(rec, a)
    write_recording(rec, b)  # the same data under another name
    with pytest.raises(TaskDataError, match="both a training and a test recording"):
        file_data("chamber", [str(a)], [str(a)])
    with pytest.raises(TaskDataError, match="both a training and a test recording"):
        file_data("chamber", [str(a)], [str(b)])


def _primary(task: str, split: str, learner: str | None, baseline: str | None = None, clamp: bool = True,
             **params: object) -> float:
    env = MSRACompensationEnv(task=task, learner=learner, learner_params=params or None, split=split,
                              clamp_inputs=clamp)
    env.reset(seed=0)
    score = env.score_baseline(baseline) if baseline else env.score()[0]
    return score.summary()[PRIMARY[score.protocol]]


@pytest.mark.parametrize(("task", "form"), [("accel_chamber", "bias"), ("msra_fulltemp", "inverse")])
def test_the_memoriser_loses_to_a_cubic_on_the_default_split(task: str, form: str) -> None:
    """docs/concepts/split-tiers.md: with no physics, the training runs' mean output at the same time since the
    start wins on a replay of their signal, and loses to a cubic in temperature on new power-ons
    (next_run, the default). Measured: accel chamber 1 593 against 318 µg drift (replay 91.5 against
    312); full temperature 3 380 against 39.2 µg bias variation (replay 4.9 against 3.4)."""
    cubic = _primary(task, "next_run", "poly", form=form, degree=3)
    memoriser = _primary(task, "next_run", None, "memoriser")
    assert memoriser > 2.0 * cubic
    replayed = _primary(task, "replay", None, "memoriser")
    assert replayed < memoriser / 5.0  # the same baseline on a replay: the tier is what it measures


def test_the_memoriser_loses_to_a_cubic_fitted_within_runs_on_zero_bias() -> None:
    """Zero bias (1.5 h from power-on at room temperature): the warm-up follows the time since
    power-on, so the memoriser keeps part of it (49.4 against raw 232 µg), and a cubic pooled over
    four power-ons at ambients 23-26.7 °C bends to their turn-on offsets and extrapolates them into
    a test run at 27.4-28.6 °C (165 µg). Fitted within runs (a constant per run) the cubic reaches
    32.0 µg and beats the memoriser; on a replay the memoriser reaches 21.4. Held to its training
    range (task.clamp_inputs, the default) the cubic cannot follow a test run above it: 153 µg, the
    memoriser's win."""
    within = _primary("msra_zerobias", "next_run", "poly", clamp=False, form="bias", degree=3, offsets="per_run")
    pooled = _primary("msra_zerobias", "next_run", "poly", clamp=False, form="bias", degree=3)
    memoriser = _primary("msra_zerobias", "next_run", None, "memoriser")
    assert memoriser > 1.3 * within
    assert pooled > 3.0 * within
    assert _primary("msra_zerobias", "replay", None, "memoriser") < memoriser / 2.0
    held = _primary("msra_zerobias", "next_run", "poly", form="bias", degree=3, offsets="per_run")
    assert held > 2.0 * memoriser


def test_the_memorised_output_is_the_runs_mean_at_the_same_time() -> None:
    """Mean of the runs at the same time since their start; past a shorter run's end the runs still
    going; past the longest its last value."""
    from tcbench.compensation.data import TaskRecording
    from tcbench.compensation.methods import memorised
    from tcbench.sensors.recording import make_recording

    def rec(n: int, level: float, start_s: float) -> TaskRecording:
        t = start_s + np.arange(n, dtype=float)
        return TaskRecording("r", make_recording(t, np.full(n, 20.0), np.zeros(n), np.full(n, level) + t - start_s,
                                                 sensor="accel", sample_rate_hz=1.0, device_id="x"))

    memo = memorised([rec(10, 0.0, 100.0), rec(20, 2.0, 5.0)])
    got = memo(50.0 + np.arange(25, dtype=float))  # a test run of its own clock
    np.testing.assert_allclose(got[:10], np.arange(10) + 1.0)   # both runs: (t + t + 2) / 2
    np.testing.assert_allclose(got[10:20], np.arange(10, 20) + 2.0)  # the longer run alone
    np.testing.assert_allclose(got[20:], 21.0)  # held at the longest run's last value


def _gyro_drift_dph(split: str, learner: str | None, baseline: str | None = None, **size: float) -> float:
    """The drift (deg/h) a learner or a baseline leaves on the gyro oven task (the serial pipeline,
    so the learner is the only compensation) at ``size`` (the task's own by default)."""
    from tcbench.tasks.gyro_env import GyroDriftNoiseEnv

    env = GyroDriftNoiseEnv(learner, {"form": "bias"} if learner else None, split=split,
                            decomposition="none", denoise="none", **size)
    env.reset(seed=0)
    score = env.score_baseline(baseline, bandwidth=False) if baseline else env.score(bandwidth=False)[0]
    return score.summary()["drift_dph"]


@pytest.mark.slow  # two 14 h records at 10 Hz per tier; the small oven below stays in CI
def test_the_memoriser_loses_to_a_cubic_on_the_gyro_oven() -> None:
    """The gyro drift task (seed 001's oven runs, 10 Hz): on new power-ons the memoriser loses to the
    cubic, on a replay it is at the oracle. Measured (drift, deg/h): next_run memoriser 60.6, cubic
    35.0, oracle 34.4, raw 45.0; replay 39.1, 39.2, 38.4, 62.8."""
    assert _gyro_drift_dph("next_run", None, "memoriser") > 1.3 * _gyro_drift_dph("next_run", "poly")
    assert _gyro_drift_dph("replay", None, "memoriser") < 1.1 * _gyro_drift_dph("replay", None, "oracle")


def test_the_memoriser_loses_to_a_cubic_on_a_small_gyro_oven() -> None:
    """The same oven at 1 Hz with 30 min soaks: on a new power-on the memoriser leaves 1.7 times the
    cubic's drift (68.2 against 40.0 deg/h; the oracle 36.6)."""
    small = {"sample_rate_hz": 1.0, "hold_s": 1800.0}
    assert _gyro_drift_dph("next_run", None, "memoriser", **small) > 1.3 * _gyro_drift_dph("next_run", "poly", **small)


def test_a_task_that_cannot_pass_runs_refuses_per_run_offsets_up_front() -> None:
    """The gyro task trains on one record through its pipeline: poly's per-run offsets are refused
    before any work, naming the key; the static-input tasks accept them."""
    from tcbench.errors import ConfigError
    from tcbench.runner.compensation_config import validate_compensation

    job = {"learner": {"name": "poly", "offsets": "per_run"}, "optimiser": {"name": "none"}, "budget": 10}
    with pytest.raises(ConfigError, match="learner.offsets=per_run: task gyro_driftnoise"):
        validate_compensation(job, {"name": "gyro_driftnoise", "decomposition": "none", "denoise": "none"})
    validate_compensation(job, {"name": "msra_zerobias"})
