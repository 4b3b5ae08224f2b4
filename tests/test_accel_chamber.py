"""The accelerometer chamber task: an ordinary IMU's accelerometer at rest through chamber cycles,
compensated by the baselines, the learners and the diagnosed model, on simulated and on files
(the commands in this process: :mod:`cli_here`)."""

from __future__ import annotations

import os
from pathlib import Path

import gymnasium as gym
import numpy as np
import pandas as pd
import pytest
from cli_here import tcbench as here
from gymnasium.utils.env_checker import check_env

import tcbench  # noqa: F401 - registers the envs
from tcbench.compensation.data import TaskDataError, file_data
from tcbench.sensors.recording import write_recording
from tcbench.sensors.simulate import simulate_recording

ENV = "tcbench/Accel-Chamber-v0"


@pytest.fixture(scope="module")
def baselines() -> dict[str, dict[str, float]]:
    env = gym.make(ENV, learner=None).unwrapped
    env.reset(seed=0)
    out = {name: env.score_baseline(name).summary() for name in env.baselines}
    poly = gym.make(ENV, learner="poly").unwrapped
    poly.reset(seed=0)
    out["poly3"] = poly.score(None)[0].summary()
    return out


def test_the_env_checks_and_splits_three_cycles_to_two() -> None:
    env = gym.make(ENV, learner="bp", learner_params={"training": "gd", "epochs": 20}, budget=20).unwrapped
    check_env(env, skip_render_check=True)
    env.reset(seed=0)
    assert (len(env.data.train), len(env.data.test)) == (3, 2) and env.data.form == "bias"
    x, y = env.data.training_set()
    assert x.shape == (y.size, 2) and y.size == sum(len(t.recording.data) for t in env.data.train)
    assert env.data.train[0].recording.meta.sensor == "accel" and env.data.scale_factor_hz_per_g == 1.0


def test_the_limits_bound_every_baseline(baselines) -> None:
    oracle, thermo, raw = baselines["oracle"]["drift_ug"], baselines["oracle_thermometer"]["drift_ug"], \
        baselines["raw"]["drift_ug"]
    # the thermometer sits apart from the element and moves at each power-on: a real floor (measured 158
    # against 74 µg on device 0)
    assert thermo > 1.3 * oracle
    for name in ("model", "lagpoly", "poly3"):
        assert thermo < baselines[name]["drift_ug"] < raw / 10, name
    assert baselines["raw"]["gain_drift_ug"] == 1.0 and raw > 1000.0


def test_a_temperature_polynomial_cannot_close_the_loop_and_the_rate_term_can(baselines) -> None:
    """The cooling-minus-heating difference at one thermometer reading is untouched by any function of
    that reading (poly3 leaves the raw loop but for the spread of readings inside a 1 degC bin); the
    cubic with a rate term tells heating from cooling and closes part of it (measured 698 against 1 213 µg)."""
    raw, poly, oracle = (baselines[k]["hysteresis_ug"] for k in ("raw", "poly3", "oracle"))
    assert poly == pytest.approx(raw, rel=0.01)
    env = gym.make(ENV, learner="poly", learner_params={"form": "bias_rate"}).unwrapped
    env.reset(seed=0)
    rate = env.score(None)[0].summary()
    assert oracle < rate["hysteresis_ug"] < 0.7 * raw
    assert rate["drift_ug"] < baselines["poly3"]["drift_ug"]


def test_an_unknown_baseline_is_named() -> None:
    env = gym.make("tcbench/MSRA-FullTemp-v0", learner=None).unwrapped
    assert "model" in env.baselines and "model" in gym.make(ENV, learner=None).unwrapped.baselines
    env.reset(seed=0)
    with pytest.raises(ValueError, match="unknown baseline 'diagnosed' of task msra_fulltemp"):
        env.score_baseline("diagnosed")


def _write(tmp: Path, name: str, rec) -> str:  # type: ignore[no-untyped-def]
    path = tmp / f"{name}.csv"
    write_recording(rec, path)
    return str(path)


def test_recordings_from_files_are_compensated_and_checked(tmp_path: Path) -> None:
    cycles = [_write(tmp_path, f"c{i}", simulate_recording("accel", "chamber", 1, i)) for i in range(3)]
    env = gym.make(ENV, learner="poly", train_files=cycles[:2], test_files=cycles[2:]).unwrapped
    env.reset(seed=0)
    s = env.score(None)[0].summary()
    assert env.data.source == "files" and s["drift_ug"] < s["raw_drift_ug"] / 2
    model = env.score_baseline("model").summary()  # the diagnosis needs no truth
    assert model["drift_ug"] < s["drift_ug"] / 3  # device 1's 7 mg loop: the hysteresis is the drift
    with pytest.raises(TaskDataError, match="oracle needs the simulator's truth"):
        env.score_baseline("oracle")
    msra = _write(tmp_path, "msra", simulate_recording("msra", "roomtemp", 0, 0))
    with pytest.raises(TaskDataError, match=r"msra.csv: test recording is from a msra sensor; this task needs accel"):
        file_data("chamber", cycles[:1], [msra])
    moving = _write(tmp_path, "moving", simulate_recording("accel", "multipos", 0, 0))
    with pytest.raises(TaskDataError, match=r"moving.csv: training recording's applied input varies"):
        file_data("chamber", [moving], cycles[:1])


def test_a_sweep_and_its_board_from_the_command_line(tmp_path: Path) -> None:
    """Baselines and the two polynomials (named apart) in one sweep, then the board with both limits.
    The sweep's runs draw no figures (the board reads none); the single run draws the task's."""
    run = here("run", "-m", "task=accel_chamber", "learner=raw,oracle,oracle_thermometer,poly", "seed=0",
               "tracking.plots=false", cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    rate = here("run", "task=accel_chamber", "learner=poly", "learner.form=bias_rate", cwd=tmp_path)
    assert rate.returncode == 0 and "poly3_rate-accel_chamber-dev0-s0" in rate.stdout + rate.stderr
    store = Path(os.environ["MLFLOW_TRACKING_URI"].removeprefix("sqlite:///")).parent
    assert len(list(store.glob("mlartifacts/*/*/artifacts/fig7_test*.png"))) == 2  # the single run's figures only
    board = here("leaderboard", cwd=tmp_path)
    assert board.returncode == 0, board.stdout + board.stderr
    table = pd.read_csv(tmp_path / "leaderboards" / "accel_chamber-dev0.csv").set_index("method")
    assert list(table.index[:2]) == ["oracle", "oracle_thermometer"] and table.index[-1] == "raw"
    assert set(table.index) == {"oracle", "oracle_thermometer", "poly3", "poly3_rate", "raw"}
    np.testing.assert_allclose(table["x_oracle"], table["median_drift_ug"] / table.loc["oracle", "median_drift_ug"])
    assert "hyst_ug" in (tmp_path / "leaderboards" / "accel_chamber-dev0.md").read_text()


def test_a_record_the_diagnosis_refuses_is_one_line(tmp_path: Path) -> None:
    """The diagnosed row on runs too short to diagnose: the job fails with one line naming the run."""
    short = [_write(tmp_path, f"s{i}", simulate_recording("accel", "chamber", 0, i, soak_s=60.0, room_s=60.0,
                                                          ramp_c_per_min=20.0)) for i in range(2)]
    run = here("run", "task=accel_chamber", "learner=model", f"task.train_files=[{short[0]}]",
                  f"task.test_files=[{short[1]}]", cwd=tmp_path)
    assert run.returncode == 1 and "Traceback" not in run.stdout + run.stderr, run.stdout + run.stderr
    assert "training recording s0 cannot be diagnosed (recording too short" in run.stdout + run.stderr
