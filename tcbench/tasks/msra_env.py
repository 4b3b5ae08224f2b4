"""Static-input temperature compensation as gymnasium environments: the MSRA tasks of seed 000
§2.3 and §3, and ``accel_chamber``, a capacitive accelerometer at rest through a chamber cycle.

The action is a candidate vector of a learner's initial weights and thresholds (or a batch of
them, ``(n, d)``); the observation is its training error — seed 000 eq. 3 in normalised units,
the "brightness" IFA and FA rank fireflies by — and the reward its negation. An optimiser
searching these steps is steps 1-3 of seed 000 Fig. 5; :meth:`MSRACompensationEnv.score` is
steps 4-6: it trains the learner from the best vector and computes the paper's metrics on the
held-out test recordings, before and after.

``reset(seed=...)`` builds the task instance: with ``recordings_seed=None`` the recordings are
simulated from the reset seed; with an integer (default 0, the paper's setting of one fixed set
of datasets trained on 30 times) they are fixed, and the reset seed only draws the learner's own
random start. ``train_files``/``test_files`` replace the simulated recordings by schema-v1
files (for example real ones).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from tcbench.compensation import methods
from tcbench.compensation.data import (
    DEFAULT_SPLIT,
    DEFAULT_TIER,
    PROTOCOLS,
    MSRAData,
    TaskDataError,
    check_split,
    check_tier,
    file_data,
    simulated_data,
)
from tcbench.compensation.lagpoly import fit_lag_poly
from tcbench.compensation.scoring import Score, score_outputs
from tcbench.errors import unknown_name
from tcbench.learners import registry as learners
from tcbench.learners.base import FitHistory, Learner
from tcbench.tasks.checks import is_integer
from tcbench.tasks.weight_search import WeightSearch
from tcbench.tasks.ids import MSRA_ENV_IDS

TASKS = {"msra_zerobias": "roomtemp", "msra_fulltemp": "fulltemp", "accel_chamber": "chamber"}
ENV_IDS = MSRA_ENV_IDS
BIAS_FORMS = ("plus", "printed")


def make_learner(name: str, params: dict[str, Any] | None, form: str, rng: np.random.Generator,
                 n_inputs: int = 2) -> Learner:
    """A registered learner with ``n_inputs`` inputs; a ``form: auto`` parameter takes the task's form."""
    cls = learners.get(name)
    values = dict(params or {})
    fields = {f.name for f in dataclasses.fields(cls.Params)}
    if "form" in fields and values.get("form", "auto") == "auto":
        values["form"] = form
    return cls(n_inputs, values, rng)


def _raw(data: MSRAData, bias_form: str) -> Score:
    return score_outputs(data, methods.raw_compensator(data), bias_form, probe=False)


def _memoriser(data: MSRAData, bias_form: str) -> Score:
    return score_outputs(data, methods.memoriser_compensator(data), bias_form)


def _lagpoly(data: MSRAData, bias_form: str) -> Score:
    fitted = fit_lag_poly([tr.recording for tr in data.train])
    score = score_outputs(data, methods.lagpoly_compensator(data, fitted), bias_form)
    score.extra["lagpoly"] = fitted  # a run keeps it for the device (tcbench.compensation.run_device)
    return score


def _model(data: MSRAData, bias_form: str) -> Score:
    from tcbench.tasks.diagnosed import diagnosed_compensator

    fn, fitted = diagnosed_compensator(data)
    score = score_outputs(data, fn, bias_form)
    score.extra["diagnosed"] = fitted
    return score


def _oracle(thermometer: bool) -> Callable[[MSRAData, str], Score]:
    """The oracle fed the package temperature, or (``thermometer``) the thermometer reading."""

    def score(data: MSRAData, bias_form: str) -> Score:
        return score_outputs(data, methods.oracle_compensator(data, thermometer=thermometer), bias_form)

    return score


# How each baseline (:data:`tcbench.compensation.methods.BASELINES`) scores a task's test
# recordings: ``(data, bias_form) -> Score``.
BASELINE_SCORES: dict[str, Callable[[MSRAData, str], Score]] = {
    "raw": _raw,
    "memoriser": _memoriser,
    "oracle": _oracle(False),
    "oracle_thermometer": _oracle(True),
    "lagpoly": _lagpoly,
    "model": _model,
}


class MSRACompensationEnv(WeightSearch, gym.Env[np.ndarray, np.ndarray]):
    """Search a learner's initial parameters on a static-input compensation task.

    Parameters
    ----------
    task: ``msra_fulltemp``, ``msra_zerobias`` or ``accel_chamber``.
    learner, learner_params: the registered learner and its parameters (default: BP 2-10-1);
        ``None`` for an env that only scores the baselines (raw, oracle).
    budget: candidate evaluations per episode.
    device_seed: the simulated device; recordings_seed: fixes the recordings (None: from reset).
    n_train, n_test: recordings to train on and to test on (default 3/2 fulltemp and chamber,
        4/2 roomtemp).
    split: the tier the simulated test runs are drawn on (:data:`~tcbench.compensation.data.SPLITS`):
        ``replay``, ``next_run`` (default: new power-ons), ``new_profile`` or ``new_device``.
    train_files, test_files: schema-v1 recordings instead of simulated ones.
    train_on: ``positions`` (fulltemp: the labelled four-position samples) or ``all`` rows.
    rate_window_s: trailing window of the temperature-rate input (roomtemp, chamber), in s.
    bias_form: eq. 12 ``plus`` (default) or ``printed``.
    clamp_inputs: hold the learner's test inputs to the range of its training inputs (the
        temperature and its rate; fulltemp: the temperature, not the output U) as ``tcbench
        calibrate`` does; default True, the boards' setting.
    """

    metadata = {"render_modes": []}
    passes_runs = True  # a learner with uses_runs gets the run of each training row (poly offsets=per_run)

    def __init__(
        self,
        task: str = "msra_fulltemp",
        learner: str | None = "bp",
        learner_params: dict[str, Any] | None = None,
        budget: int = 1000,
        device_seed: int = 0,
        recordings_seed: int | None = 0,
        n_train: int | None = None,
        n_test: int | None = None,
        train_files: list[str] | None = None,
        test_files: list[str] | None = None,
        train_on: str = "positions",
        rate_window_s: float = 120.0,
        bias_form: str = "plus",
        split: str = DEFAULT_TIER,
        clamp_inputs: bool = True,
    ) -> None:
        if task not in TASKS:
            raise ValueError(unknown_name("static-input task", task, TASKS))
        self.task, self.protocol = task, TASKS[task]
        self.baselines = methods.BASELINES
        if not is_integer(budget) or budget < 1:
            raise ValueError(f"budget must be a positive integer, got {budget}")
        if not is_integer(device_seed) or device_seed < 0:
            raise ValueError(f"device_seed must be a non-negative integer, got {device_seed}")
        if recordings_seed is not None and (not is_integer(recordings_seed) or recordings_seed < 0):
            raise ValueError(f"recordings_seed must be a non-negative integer or null, got {recordings_seed}")
        if not isinstance(clamp_inputs, (bool, np.bool_)):
            raise ValueError(f"clamp_inputs must be true or false, got {clamp_inputs!r}")
        self.clamp_inputs = bool(clamp_inputs)
        if bias_form not in BIAS_FORMS:
            raise ValueError(f"bias_form must be one of {', '.join(BIAS_FORMS)}, got {bias_form!r}")
        if (train_files is None) != (test_files is None):
            raise ValueError("give both train_files and test_files, or neither")
        try:
            check_tier(split)
        except TaskDataError as exc:
            raise ValueError(str(exc)) from None
        self.split = split
        d_train, d_test = DEFAULT_SPLIT[self.protocol]
        self.n_train = len(train_files) if train_files else (d_train if n_train is None else n_train)
        self.n_test = len(test_files) if test_files else (d_test if n_test is None else n_test)
        try:
            check_split(self.protocol, self.n_train, self.n_test, train_on, rate_window_s)
        except TaskDataError as exc:
            raise ValueError(str(exc)) from None
        self.budget, self.device_seed, self.recordings_seed = int(budget), int(device_seed), recordings_seed
        self.train_files, self.test_files = train_files, test_files
        self.train_on, self.rate_window_s, self.bias_form = train_on, float(rate_window_s), bias_form
        self.learner_name, self.learner_params = learner, dict(learner_params or {})
        form = PROTOCOLS[self.protocol]
        self.learner: Learner | None = None
        if learner is not None:
            self.learner = make_learner(learner, self.learner_params, form, np.random.default_rng(0))
        searchable = self.learner is not None and self.learner.searchable
        dim = self.learner.n_params if searchable else 1
        low, high = self.learner.init_bounds() if searchable else (-1.0, 1.0)
        self.dim = dim
        self.lower, self.upper = np.full(dim, float(low)), np.full(dim, float(high))
        self.action_space = gym.spaces.Box(self.lower, self.upper, dtype=np.float64)
        self.observation_space = gym.spaces.Box(0.0, np.inf, shape=(1,), dtype=np.float64)
        self.f_opt = 0.0
        self.target_precision = 0.0
        self.data: MSRAData | None = None
        self._x = self._y = self._runs = None
        self._reset_counters()

    def check_files(self) -> None:
        """Read the user's recordings (``train_files``/``test_files``) as the task will; a
        :class:`~tcbench.compensation.data.TaskDataError` naming what is wrong. No-op when simulated."""
        if self.train_files is not None and self.test_files is not None:
            self._load()

    # -- episode ---------------------------------------------------------------------------
    def _load(self) -> MSRAData:
        if self.train_files is not None and self.test_files is not None:
            return file_data(self.protocol, list(self.train_files), list(self.test_files), self.train_on,
                             self.rate_window_s)
        rseed = self.recordings_seed
        if rseed is None:
            rseed = int(self.np_random.integers(0, 2**31 - 1))
        return simulated_data(self.protocol, self.device_seed, rseed, self.n_train, self.n_test,
                              self.train_on, self.rate_window_s, self.split)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self.data = self._load()
        learner_rng = np.random.default_rng(int(self.np_random.integers(0, 2**63 - 1)))
        if self.learner_name is not None:
            self.learner = make_learner(self.learner_name, self.learner_params, self.data.form, learner_rng)
            self._x, self._y = self.data.training_set(self.learner.sequential)
            self._runs = self.data.training_runs(self.learner.sequential)
            if self.learner.searchable:
                self.learner.scale_to(self._x, self._y)
        self._reset_counters()
        return np.array([np.inf]), self._info()

    # -- final scorer ----------------------------------------------------------------------
    def score(self, init: np.ndarray | None = None) -> tuple[Score, FitHistory]:
        """Train the learner from ``init`` (None: its own random start) and score the test
        recordings before and after (steps 4-6 of seed 000 Fig. 5)."""
        if self.data is None or self.learner is None:
            raise RuntimeError("call reset() on an env with a learner before score()")
        runs = {"runs": self._runs} if self.learner.uses_runs else {}
        history = self.learner.fit(self._x, self._y, init=init, **runs)  # the training set built by reset()
        final = self.learner.get_params()
        checkpoints = {}
        for epochs, params in sorted(history.snapshots.items()):  # shorter budgets of the same training
            self.learner.set_params(params)
            checkpoints[epochs] = self._score_learner().summary()
        self.learner.set_params(final)
        score = self._score_learner()
        score.extra["checkpoints"] = checkpoints
        return score, history

    def _score_learner(self) -> Score:
        """The test recordings compensated by the learner with its current parameters."""
        assert self.data is not None and self.learner is not None
        assert self._x is not None
        rmse = methods.training_rmse_ug(self.data, self.learner, self._x, self._y)
        box = self.data.input_range(self._x) if self.clamp_inputs else None
        return score_outputs(self.data, methods.learner_compensator(self.data, self.learner, box), self.bias_form,
                             rmse)

    def score_baseline(self, which: str) -> Score:
        """``raw`` (no compensation), ``memoriser`` (the training runs' mean output at the same time
        since the start: no physics), ``oracle`` (the simulator's truth: noise alone),
        ``oracle_thermometer`` (the simulator's model fed the thermometer reading), ``lagpoly``
        or ``model``, the mean of the models diagnosed on each training recording
        (:mod:`tcbench.tasks.diagnosed`)."""
        if self.data is None:
            raise RuntimeError("call reset() before score_baseline()")
        if which not in self.baselines:
            raise ValueError(unknown_name("baseline", which, self.baselines, f" of task {self.task}"))
        return BASELINE_SCORES[which](self.data, self.bias_form)
