"""The gyro drift/noise compensation stage as a gymnasium environment (seed 001 §3.4-§4).

Two oven runs of one gyro, one to train and one to test (§4.1). ``reset`` decomposes the
training record with the task's pipeline (VMD with ``[k, alpha]``, sample-entropy classes, see
:mod:`tcbench.compensation.gyro.pipeline`) and builds the learner's training set: block means of
``[T, dT/dt]`` (or ``[T]``) against the drift part. The action is a candidate vector of the
learner's initial weights and thresholds (or a batch ``(n, d)``); the observation its training
error (eq. 3 in normalised units; eq. 36's MSE up to the factor 2), which BAS, PSO, FA ...
minimise to initialise the learner (BAS-Elman, §3.4.4). :meth:`GyroDriftNoiseEnv.score` trains
the learner from the best vector and runs the whole pipeline on the test record, scoring it
before and after with the bandwidth it keeps (:mod:`tcbench.compensation.gyro.scoring`).

By default VMD runs with seed 001's tuned ``[k, alpha] = [8, 9755]`` (§4.2), so
``gymnasium.make("tcbench/Gyro-DriftNoise-v0")`` is a complete task. With ``k=None`` or
``alpha=None`` they are to be tuned first and come from
``reset(options={"k": .., "alpha": ..})``: ``tcbench run`` (whose task config sets them null)
tunes them on ``tcbench/Gyro-VMDTuning-v0`` (MOPSO by default, §3.2).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from importlib.metadata import entry_points
from typing import Any

import gymnasium as gym
import numpy as np

from tcbench.compensation.data import DEFAULT_TIER, TaskDataError, check_tier
from tcbench.compensation.gyro.cache import cached_front
from tcbench.compensation.gyro.data import GyroData, check_effects, check_settings
from tcbench.compensation.gyro.pipeline import TUNED, FrontEnd, ParallelPipeline, PipelineConfig
from tcbench.compensation.gyro.scoring import DPS_TO_DPH, Method, score_record
from tcbench.compensation.gyro.tuning import PAPER_BEST, tuning_window
from tcbench.compensation.methods import memorised
from tcbench.compensation.oracle import oracle_inverse
from tcbench.compensation.scoring import Score
from tcbench.errors import unknown_name
from tcbench.learners.base import FitHistory, Learner
from tcbench.tasks.gyro_vmd_env import load_gyro_data
from tcbench.tasks.ids import GYRO_DRIFTNOISE_ID
from tcbench.tasks.checks import is_integer, is_real
from tcbench.tasks.msra_env import make_learner
from tcbench.tasks.weight_search import WeightSearch

ENV_ID = GYRO_DRIFTNOISE_ID
PIPELINE_KEYS = tuple(f.name for f in dataclasses.fields(PipelineConfig))


def _check_tuner(name: object) -> None:
    """The VMD tuner: the name of a registered optimiser, read from the entry points so that tasks
    do not import the optimisers (whether it is multi-objective, and its parameters and budget, are
    checked by the job's config validation, which runs it)."""
    known = sorted(entry_points(group="tcbench.optimisers").names)
    if not isinstance(name, str) or name not in known:
        raise ValueError(f"tuner must be the name of a multi-objective optimiser ({', '.join(known)}), got {name!r}")


def _raw(env: GyroDriftNoiseEnv, bandwidth: bool) -> Score:
    assert env.pipeline is not None
    env.pipeline.learner = None
    return env._score_pipeline(float("nan"), bandwidth)


def _memoriser(env: GyroDriftNoiseEnv, bandwidth: bool) -> Score:
    assert env.data is not None
    memo = memorised(env.data.train, "output")
    recs = [score_record(tr, lambda y, tr=tr: y - memo(tr.recording.time_s), env.amplitude_dps, None,
                         bandwidth) for tr in env.data.test]
    return Score("gyro", recs)


def _model(env: GyroDriftNoiseEnv, bandwidth: bool) -> Score:
    from tcbench.tasks.diagnosed import diagnose_runs, gyro_method

    assert env.data is not None
    fitted = diagnose_runs(env.data.train)
    recs = [score_record(tr, gyro_method(fitted, tr.recording.time_s, tr.recording.temperature_c),
                         env.amplitude_dps, None, bandwidth) for tr in env.data.test]
    return Score("gyro", recs, extra={"diagnosed": fitted})


def _oracle(thermometer: bool) -> Callable[[GyroDriftNoiseEnv, bool], Score]:
    """The simulator's drift removed: of the package temperature, or (``thermometer``) of the
    thermometer reading."""

    def score(env: GyroDriftNoiseEnv, bandwidth: bool) -> Score:
        assert env.data is not None
        if not env.data.has_truth:
            raise TaskDataError("the oracle needs the simulator's truth; recordings read from files have none")
        recs = [score_record(tr, lambda y, tr=tr: oracle_inverse(y, tr.truth, thermometer), env.amplitude_dps,
                             None, bandwidth) for tr in env.data.test]
        return Score("gyro", recs)

    return score


# How each baseline scores the env's test records: ``(env, bandwidth) -> Score``.
BASELINE_SCORES: dict[str, Callable[[GyroDriftNoiseEnv, bool], Score]] = {
    "raw": _raw,
    "memoriser": _memoriser,
    "oracle": _oracle(False),
    "oracle_thermometer": _oracle(True),
    "model": _model,
}
BASELINES = tuple(BASELINE_SCORES)


class GyroDriftNoiseEnv(WeightSearch, gym.Env[np.ndarray, np.ndarray]):
    """Search a drift learner's initial parameters on a gyro oven task.

    learner, learner_params: the registered learner (default Elman) and its parameters; None for
        an env that only scores the baselines (``raw``: the pipeline without a drift learner;
        ``oracle``: the simulator's true drift removed, noise untouched).
    budget: candidate evaluations per episode.
    device_seed, recordings_seed, n_train, n_test, sample_rate_hz, hold_s: the simulated oven
        runs (seed 001: one to train, one to test, 10 Hz, 1 h soaks); ``recordings_seed`` None draws
        them from the reset seed (a row over draws, e.g. the limits).
    split: the tier the simulated test runs are drawn on (:data:`~tcbench.compensation.data.SPLITS`;
        default ``next_run``, new power-ons).
    train_files, test_files: schema-v1 gyro recordings instead.
    decomposition, k, alpha, denoise, tfpf_window, wavelet_level, noise_above, drift_below, inputs,
        rate_window_s, learner_block_s: the pipeline (:class:`~tcbench.compensation.gyro.pipeline.PipelineConfig`);
        ``k``/``alpha`` default to seed 001's tuned ``[8, 9755]``; None: to be tuned, then set by
        ``reset(options=...)``.
    bandwidth_amplitude_dps: amplitude of each injected sine of the bandwidth test (deg/s).
    effects: changes of the simulated device's effects, ``{id: {param: value}}`` in deg/s units
        (e.g. ``{"bias_instability": {"b": 8.3e-4}}`` for 3 deg/h of flicker).
    tuner, tuner_params, tuning_budget, tuning_samples: the multi-objective search of
        ``[k, alpha]`` that the runner does before ``reset`` when they are unset
        (:func:`tcbench.runner.loop.tune_vmd`); ``tuner_params`` None takes the tuner's defaults.
    """

    metadata = {"render_modes": []}
    baselines = BASELINES  # no lagpoly: the drift pipeline has its own learners

    def __init__(self, learner: str | None = "elman", learner_params: dict[str, Any] | None = None,
                 budget: int = 1000, device_seed: int = 0, recordings_seed: int | None = 0, n_train: int = 1,
                 n_test: int = 1, train_files: list[str] | None = None, test_files: list[str] | None = None,
                 sample_rate_hz: float = 10.0, hold_s: float = 3600.0, decomposition: str = "vmd",
                 k: int | None = PAPER_BEST[0], alpha: float | None = PAPER_BEST[1], denoise: str = "tfpf",
                 tfpf_window: int = 31, wavelet_level: int | None = None,
                 noise_above: float = 0.5, drift_below: float = 0.15, inputs: str = "t_rate",
                 rate_window_s: float = 120.0, learner_block_s: float = 10.0,
                 bandwidth_amplitude_dps: float = 0.005, effects: dict[str, dict[str, float]] | None = None,
                 tuner: str = "mopso", tuning_budget: int = 440, tuning_samples: int = 2048,
                 tuner_params: dict[str, Any] | None = None, split: str = DEFAULT_TIER) -> None:
        if not is_integer(budget) or budget < 1:
            raise ValueError(f"budget must be a positive integer, got {budget}")
        drawn = recordings_seed is None  # the runs drawn from the reset seed
        for name, value in (("device_seed", device_seed), ("recordings_seed", 0 if drawn else recordings_seed)):
            if not is_integer(value) or value < 0:
                raise ValueError(f"{name} must be a non-negative integer, got {value}")
        if (train_files is None) != (test_files is None):
            raise ValueError("give both train_files and test_files, or neither")
        if not is_integer(tuning_budget) or tuning_budget < 1:
            raise ValueError(f"tuning_budget must be a positive integer, got {tuning_budget}")
        tuning_window(np.zeros(1), tuning_samples)  # validates the window length
        _check_tuner(tuner)
        self.tuning = {"tuner": str(tuner), "params": dict(tuner_params or {}), "budget": int(tuning_budget),
                       "samples": int(tuning_samples)}
        if not (is_real(bandwidth_amplitude_dps) and bandwidth_amplitude_dps > 0):
            raise ValueError(f"bandwidth_amplitude_dps must be > 0, got {bandwidth_amplitude_dps}")
        try:
            check_tier(split)
            check_settings(sample_rate_hz, hold_s, n_train, n_test)
            self.effects = check_effects(effects)
        except TaskDataError as exc:
            raise ValueError(str(exc)) from None
        pipeline = {"decomposition": decomposition, "denoise": denoise, "tfpf_window": tfpf_window,
                    "wavelet_level": wavelet_level,
                    "noise_above": noise_above, "drift_below": drift_below, "inputs": inputs,
                    "rate_window_s": rate_window_s, "learner_block_s": learner_block_s}
        self.config = PipelineConfig(**pipeline, **({"k": k} if k is not None else {}),
                                     **({"alpha": alpha} if alpha is not None else {}))
        self.needs_tuning = decomposition in TUNED and (k is None or alpha is None)
        if recordings_seed is None and self.needs_tuning:
            raise ValueError("recordings_seed null draws the runs from the run seed; give task.k and task.alpha (or "
                             "decomposition none or emd), since VMD is tuned on fixed recordings")
        self.budget, self.device_seed = int(budget), int(device_seed)
        self.recordings_seed = None if recordings_seed is None else int(recordings_seed)
        self.n_train, self.n_test = int(n_train), int(n_test)
        self.split = split
        self.train_files, self.test_files = train_files, test_files
        self.sample_rate_hz, self.hold_s = float(sample_rate_hz), float(hold_s)
        self.amplitude_dps = float(bandwidth_amplitude_dps)
        self.learner_name, self.learner_params = learner, dict(learner_params or {})
        self.learner: Learner | None = None
        if learner is not None:
            self.learner = self._make_learner(np.random.default_rng(0))
        searchable = self.learner is not None and self.learner.searchable
        self.dim = self.learner.n_params if searchable else 1
        low, high = self.learner.init_bounds() if searchable else (-1.0, 1.0)
        self.lower, self.upper = np.full(self.dim, float(low)), np.full(self.dim, float(high))
        self.action_space = gym.spaces.Box(self.lower, self.upper, dtype=np.float64)
        self.observation_space = gym.spaces.Box(0.0, np.inf, shape=(1,), dtype=np.float64)
        self.f_opt, self.target_precision = 0.0, 0.0
        self.data: GyroData | None = None
        self.pipeline: ParallelPipeline | None = None
        self._x = self._y = None
        self._reset_counters()

    def check_files(self) -> None:
        """Read the user's recordings (``train_files``/``test_files``) as the task will; a
        :class:`~tcbench.compensation.data.TaskDataError` naming what is wrong. No-op when simulated."""
        if self.train_files:
            load_gyro_data(self.device_seed, 0, self.train_files, self.test_files,
                           self.sample_rate_hz, self.hold_s, self.n_train, self.n_test, self.effects)

    def _make_learner(self, rng: np.random.Generator) -> Learner:
        form = "bias_rate" if self.config.inputs == "t_rate" else "bias"
        return make_learner(str(self.learner_name), self.learner_params, form, rng, self.config.n_inputs)

    def tuning_kwargs(self) -> dict[str, Any]:
        """Arguments of the ``tcbench/Gyro-VMDTuning-v0`` env that tunes this task's VMD."""
        return {"device_seed": self.device_seed, "recordings_seed": self.recordings_seed,
                "train_files": self.train_files, "sample_rate_hz": self.sample_rate_hz, "hold_s": self.hold_s,
                "effects": self.effects}

    # -- episode ---------------------------------------------------------------------------
    def _front(self, y: np.ndarray) -> FrontEnd:
        assert self.data is not None
        return cached_front(y, self.data.sample_rate_hz, self.config)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        opts = dict(options or {})
        if "k" in opts or "alpha" in opts:
            self.config = dataclasses.replace(self.config, k=int(opts.get("k", self.config.k)),
                                              alpha=float(opts.get("alpha", self.config.alpha)))
            self.needs_tuning = False
        if self.needs_tuning:
            raise ValueError("VMD k and alpha are unset: give task.k and task.alpha, or tune them first "
                             "(tcbench run does, on tcbench/Gyro-VMDTuning-v0)")
        rseed = self.recordings_seed
        if rseed is None:
            rseed = int(self.np_random.integers(0, 2**31 - 1))
        self.data = load_gyro_data(self.device_seed, rseed, self.train_files, self.test_files,
                                   self.sample_rate_hz, self.hold_s, self.n_train, self.n_test, self.effects,
                                   self.split)
        self.pipeline = ParallelPipeline(self.config)
        learner_rng = np.random.default_rng(int(self.np_random.integers(0, 2**63 - 1)))
        if self.learner_name is not None:
            self.learner = self._make_learner(learner_rng)
            sets = [self.pipeline.training_set(r.time_s, r.temperature_c, self._front(r.output))
                    for r in (tr.recording for tr in self.data.train)]
            self._x = np.concatenate([s[0] for s in sets])
            self._y = np.concatenate([s[1] for s in sets])
            if self.learner.searchable:
                self.learner.scale_to(self._x, self._y)
        self._reset_counters()
        return np.array([np.inf]), self._info()

    # -- final scorer ----------------------------------------------------------------------
    def _pipeline_method(self, t: np.ndarray, temp: np.ndarray) -> Method:
        pipe = self.pipeline
        assert pipe is not None
        return lambda y: pipe.apply(t, temp, y, front=self._front(y)).output

    def _score_pipeline(self, train_rmse: float, bandwidth: bool = True) -> Score:
        assert self.data is not None and self.pipeline is not None
        recs = []
        for tr in self.data.test:
            r = tr.recording
            parts = self.pipeline.apply(r.time_s, r.temperature_c, r.output, front=self._front(r.output))
            recs.append(score_record(tr, self._pipeline_method(r.time_s, r.temperature_c), self.amplitude_dps,
                                     parts, bandwidth))
        return Score("gyro", recs, train_rmse, extra={"k": self.config.k, "alpha": self.config.alpha,
                                                       "classes": [p.parts.classes for p in recs]})

    def score(self, init: np.ndarray | None = None, bandwidth: bool = True) -> tuple[Score, FitHistory]:
        """Train the learner on the training record from ``init`` (None: its own random start)
        and score the whole pipeline on the test record(s), before and after."""
        if self.data is None or self.learner is None or self.pipeline is None or self._x is None:
            raise RuntimeError("call reset() on an env with a learner before score()")
        history = self.learner.fit(self._x, self._y, init=init)
        self.pipeline.learner = self.learner
        train_rmse = float(np.sqrt(np.mean((self.learner.predict(self._x) - self._y) ** 2)) * DPS_TO_DPH)
        return self._score_pipeline(train_rmse, bandwidth), history

    def score_baseline(self, which: str, bandwidth: bool = True) -> Score:
        """``raw`` (the pipeline without drift compensation: the recorded output itself for the
        serial pipeline without a denoiser), ``memoriser`` (the training runs' mean output at the
        same time since the start subtracted: no physics), ``oracle`` (the simulator's truth),
        ``oracle_thermometer`` (the simulator's model fed the thermometer reading) or ``model`` (the
        models ``tcbench diagnose`` fits to the training runs, their mean bias subtracted:
        :mod:`tcbench.tasks.diagnosed`)."""
        if self.data is None or self.pipeline is None:
            raise RuntimeError("call reset() before score_baseline()")
        score = BASELINE_SCORES.get(which)
        if score is None:
            raise ValueError(unknown_name("baseline", which, BASELINES))
        return score(self, bandwidth)
