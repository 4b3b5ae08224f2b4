"""VMD parameter tuning as a multi-objective gymnasium environment (seed 001 §3.2, §4.2).

The action is a candidate ``[k, alpha]`` in ``[4, 12] x [1000, 10000]`` (or a batch ``(n, 2)``;
``k`` is rounded to the nearest integer); the observation is its two objectives, the mean fuzzy
and mean permutation entropy of the VMD modes of a window of the training record
(:mod:`tcbench.compensation.gyro.tuning` states the reading of the seed). ``reset(seed=...)`` builds the
training record (simulated oven run of one gyro, or ``train_files``); ``info`` carries the
non-dominated set so far, its hypervolume against ``ref_point`` and ``chosen``, the compromise
point of that set. Registered as ``tcbench/Gyro-VMDTuning-v0``; MOPSO with the seed's settings
(40 particles, 10 moves: 440 evaluations) is its default optimiser.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from tcbench.compensation.data import DEFAULT_TIER, TaskDataError
from tcbench.compensation.gyro.data import (
    GyroData,
    check_effects,
    check_settings,
    file_gyro_data,
    simulated_gyro_data,
)
from tcbench.compensation.gyro.tuning import (
    ALPHA_RANGE,
    K_RANGE,
    REF_POINT,
    compromise,
    decode,
    tuning_window,
    vmd_objectives,
)
from tcbench.sensors.data_hash import shared_recordings
from tcbench.tasks.checks import is_integer
from tcbench.tasks.function_env import as_batch, check_budget
from tcbench.tasks.ids import GYRO_VMDTUNING_ID
from tcbench.tasks.mo_env import record_front

ENV_ID = GYRO_VMDTUNING_ID


def load_gyro_data(device_seed: int, recordings_seed: int, train_files: list[str] | None,
                   test_files: list[str] | None, sample_rate_hz: float, hold_s: float,
                   n_train: int = 1, n_test: int = 1, effects: dict[str, dict[str, float]] | None = None,
                   split: str = DEFAULT_TIER) -> GyroData:
    """Simulated oven runs (the device's ``effects`` changed, test runs on tier ``split``), or the
    files when ``train_files`` is given."""
    if train_files:
        data = file_gyro_data(list(train_files), list(test_files or train_files))  # no test files: tuning only
        if test_files and (shared := shared_recordings(train_files, test_files)):
            raise TaskDataError(f"{shared[0]} is both a training and a test recording (the same data); a task never "
                                "tests on its own training runs")
        return data
    return simulated_gyro_data(device_seed, recordings_seed, n_train, n_test, sample_rate_hz, hold_s, effects, split)


class GyroVMDTuningEnv(gym.Env[np.ndarray, np.ndarray]):
    """Minimise the mode entropies of VMD over ``[k, alpha]`` within ``budget`` evaluations.

    device_seed, recordings_seed: the simulated gyro and its runs (the first one is tuned on);
    train_files: schema-v1 gyro recordings instead (the first is tuned on);
    sample_rate_hz, hold_s: the simulated oven run's rate and soak length;
    tuning_samples: length of the window the entropies are computed on;
    effects: changes of the simulated device's effects, ``{id: {param: value}}`` (deg/s units).
    """

    metadata = {"render_modes": []}

    def __init__(self, budget: int = 440, device_seed: int = 0, recordings_seed: int = 0,
                 train_files: list[str] | None = None, sample_rate_hz: float = 10.0, hold_s: float = 3600.0,
                 tuning_samples: int = 2048, effects: dict[str, dict[str, float]] | None = None) -> None:
        if not is_integer(budget) or budget < 1:
            raise ValueError(f"budget must be a positive integer, got {budget}")
        for name, value in (("device_seed", device_seed), ("recordings_seed", recordings_seed)):
            if not is_integer(value) or value < 0:
                raise ValueError(f"{name} must be a non-negative integer, got {value}")
        tuning_window(np.zeros(1), tuning_samples)  # validates the window length
        self.budget, self.device_seed, self.recordings_seed = int(budget), int(device_seed), int(recordings_seed)
        self.train_files, self.sample_rate_hz, self.hold_s = train_files, float(sample_rate_hz), float(hold_s)
        self.tuning_samples = int(tuning_samples)
        try:
            check_settings(sample_rate_hz, hold_s, 1, 1)
            self.effects = check_effects(effects)
        except TaskDataError as exc:
            raise ValueError(str(exc)) from None
        self.dim, self.n_objectives = 2, 2
        self.lower = np.array([K_RANGE[0], ALPHA_RANGE[0]])
        self.upper = np.array([K_RANGE[1], ALPHA_RANGE[1]])
        self.ref_point = np.asarray(REF_POINT, dtype=np.float64)
        self.action_space = gym.spaces.Box(self.lower, self.upper, dtype=np.float64)
        self.observation_space = gym.spaces.Box(0.0, np.inf, shape=(2,), dtype=np.float64)
        self.signal: np.ndarray | None = None
        self._reset_counters()

    def _reset_counters(self) -> None:
        self.evaluations = 0
        self.nonfinite = 0
        self.front_f = np.empty((0, 2))
        self.front_x = np.empty((0, 2))
        self.hypervolume = 0.0
        self.evaluated_f: list[np.ndarray] = []  # every batch of objectives, in order (for plots)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        if self.signal is None:
            data = load_gyro_data(self.device_seed, self.recordings_seed, self.train_files, None,
                                  self.sample_rate_hz, self.hold_s, effects=self.effects)
            self.signal = tuning_window(data.train[0].recording.output, self.tuning_samples)
        self._reset_counters()
        return np.full(2, np.inf), self._info()

    def evaluate(self, x: np.ndarray) -> np.ndarray:
        """Objectives ``(n, 2)`` of candidates ``x`` ``(n, 2)``, without counting them."""
        if self.signal is None:
            raise RuntimeError("call reset() before step()")
        return np.array([vmd_objectives(self.signal, *decode(row)) for row in x]).reshape(-1, 2)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, np.ndarray | float, bool, bool, dict[str, Any]]:
        x2, single = as_batch(action, self.dim)
        if not np.all((x2 >= self.lower) & (x2 <= self.upper)):
            raise ValueError("action outside [4, 12] x [1000, 10000] (k, alpha) or not finite")
        check_budget(self.evaluations, x2.shape[0], self.budget)
        f = self.evaluate(x2)
        self.evaluated_f.append(f)
        record_front(self, x2, f)
        sums = -f.sum(axis=1)
        reward: np.ndarray | float = float(sums[0]) if single else sums
        return (f[0] if single else f), reward, False, self.evaluations >= self.budget, self._info()

    def chosen(self) -> tuple[int, float]:
        """``(k, alpha)`` of the compromise point of the non-dominated set so far."""
        if not len(self.front_f):
            raise RuntimeError("no finite evaluation yet")
        return decode(self.front_x[compromise(self.front_x, self.front_f)])

    def _info(self) -> dict[str, Any]:
        return {
            "evaluations": self.evaluations, "budget": self.budget, "lower": self.lower.copy(),
            "upper": self.upper.copy(), "n_objectives": 2, "front_f": self.front_f.copy(),
            "front_x": self.front_x.copy(), "hypervolume": self.hypervolume,
            "ref_point": self.ref_point.copy(), "nonfinite": self.nonfinite,
            "chosen": self.chosen() if len(self.front_f) else None,
        }
