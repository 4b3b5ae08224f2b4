"""Checks of a compensation job's config before any job starts (one line per problem): above the
compensation, gyro and task layers it checks, below the config and job modules that call it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from tcbench.compensation.data import TaskDataError
from tcbench.compensation.methods import BASELINES
from tcbench.errors import ConfigError
from tcbench.learners import registry as learners
from tcbench.optimisers import registry as optimisers
from tcbench.params import make_params
from tcbench.runner.optimiser_config import OptimiserConfig, optimiser_of
from tcbench.tasks import task_kwargs, task_spec


def _error(message: str) -> Exception:
    return ConfigError(message)


@dataclass(frozen=True)
class LearnerConfig:
    """A compensation job's learner: its name (a registered learner or a baseline), its
    parameters (the config's ``learner`` but ``name`` and ``label``) and its leaderboard label."""

    name: str
    params: dict[str, Any]
    label: Any = None

    @property
    def baseline(self) -> bool:
        """Whether it is a baseline (``raw``, ``oracle`` ...): no learner to train."""
        return self.name in BASELINES

    @property
    def env_learner(self) -> str | None:
        """The ``learner`` argument of the task's env: its name, None for a baseline."""
        return None if self.baseline else self.name


def learner_of(c: dict[str, Any]) -> LearnerConfig:
    """The job's learner: its config's ``learner``, which the task's defaults list fills when
    the command line gives none (``bp``); a ConfigError when the config has none."""
    given = c.get("learner")
    if not given:
        known = ", ".join([*learners.REGISTRY.names(), *BASELINES])
        raise _error(f"learner: a compensation task needs one; known: {known}")
    params = dict(given)
    name = str(params.pop("name", None))
    label = params.pop("label", None)
    return LearnerConfig(name, params, label)


def build_env(task: dict[str, Any], learner: LearnerConfig, budget: int) -> Any:
    """The unwrapped env of a compensation job (``gym.make`` of its task's id); a ConfigError
    naming the task when the env refuses its arguments."""
    try:
        return gym.make(task_spec(str(task["name"])).gym_id, learner=learner.env_learner,
                        learner_params=learner.params, budget=budget, **task_kwargs(task)).unwrapped
    except ValueError as exc:
        raise _error(f"task {task['name']}: {exc}") from None


def validate_compensation(c: dict[str, Any], task: dict[str, Any], env: Any = None) -> Any:
    """Learner, optimiser and task of a compensation job; raise ConfigError naming the key. The
    env checked: ``env`` when given (built from the same arguments by an earlier check of this
    job), else built now."""
    learner = learner_of(c)
    name = learner.name
    if not learner.baseline:
        try:
            cls = learners.get(name)
        except learners.UnknownLearnerError as exc:
            raise _error(f"{exc}, {', '.join(BASELINES)}") from None
        try:
            make_params(cls, {k: v for k, v in learner.params.items() if k != "form" or v != "auto"})  # type: ignore[arg-type]
        except (TypeError, ValueError) as exc:
            text = str(exc)
            raise _error(f"learner {text}" if text.startswith(f"{name}") else f"learner {name}: {text}") from None
    if env is None:
        env = build_env(task, learner, c["budget"])
    try:
        env.check_files()
    except TaskDataError as exc:
        raise _error(str(exc)) from None
    if learner.params.get("offsets") == "per_run" and not getattr(env, "passes_runs", False):
        raise _error(f"learner.offsets=per_run: task {task['name']} does not pass the runs of its training rows "
                     "(msra_zerobias, msra_fulltemp and accel_chamber do)")
    known = getattr(env, "baselines", BASELINES)
    if learner.baseline and name not in known:
        raise _error(f"learner {name} is not a baseline of task {task['name']} (its baselines: {', '.join(known)})")
    if getattr(env, "needs_tuning", False):
        _check_tuner(task)
    _check_optimiser(optimiser_of(c), env, c["budget"])
    return env


def _check_optimiser(opt: OptimiserConfig, env: Any, budget: int) -> None:
    """The optimiser of the learner's initial weights: none, or a registered single-objective one
    with valid parameters and a budget of at least one generation (a learner that can be searched)."""
    if not opt.searches or env.learner is None or not env.learner.searchable:
        return
    try:
        ocls = optimisers.get(opt.name)
        params = make_params(ocls, opt.params)
    except optimisers.UnknownOptimiserError as exc:
        raise _error(f"{exc}, none") from None
    except (TypeError, ValueError) as exc:
        raise _error(f"optimiser {opt.name}: {exc}") from None
    if not ocls.single_objective:
        raise _error(f"optimiser {opt.name} is multi-objective only; initial weights have one objective")
    if budget < params.population:
        raise _error(f"budget of {budget} evaluations is smaller than one generation "
                     f"(optimiser {opt.name}: population {params.population})")
    try:
        ocls(env.lower, env.upper, budget, np.random.default_rng(0), params)
    except ValueError as exc:
        raise _error(f"optimiser {opt.name}: {exc}") from None


def _check_tuner(task: dict[str, Any]) -> None:
    """The gyro task's VMD tuner: a registered multi-objective optimiser with a budget of at
    least one generation."""
    name = str(task.get("tuner", "mopso"))
    try:
        cls = optimisers.get(name)
    except optimisers.UnknownOptimiserError as exc:
        raise _error(f"task.tuner: {exc}") from None
    if not cls.multi_objective:
        raise _error(f"task.tuner: optimiser {name} is single-objective; VMD tuning has 2 objectives")
    try:
        population = make_params(cls, dict(task.get("tuner_params") or {})).population
    except (TypeError, ValueError) as exc:
        hint = " (task.tuner_params=null takes its defaults)" if "has no parameter" in str(exc) else ""
        raise _error(f"task.tuner_params: {exc}{hint}") from None
    if int(task.get("tuning_budget", 440)) < population:
        raise _error(f"task.tuning_budget: {task.get('tuning_budget')} evaluations is smaller than one "
                     f"generation of {name} (population {population})")
