"""Checks of a compensation job's config before any job starts (one line per problem): above the
compensation, gyro and task layers it checks, below the config and job modules that call it."""

from __future__ import annotations

import copy
import functools
from typing import Any

import gymnasium as gym
import numpy as np
import yaml

from tcbench.compensation.data import TaskDataError
from tcbench.compensation.methods import BASELINES
from tcbench.config_dir import conf_dir
from tcbench.errors import ConfigError
from tcbench.learners import registry as learners
from tcbench.optimisers import registry as optimisers
from tcbench.params import make_params
from tcbench.tasks import task_kwargs, task_spec


def _error(message: str) -> Exception:
    return ConfigError(message)


# a compensation job's learner when its config gives none (config.yaml's defaults list has
# ``learner: null``: optimisation jobs take no learner)
DEFAULT_LEARNER = "bp"


@functools.cache
def _default_learner() -> dict[str, Any]:
    """The option :data:`DEFAULT_LEARNER` of the config group ``learner``, read once."""
    return dict(yaml.safe_load((conf_dir() / "learner" / f"{DEFAULT_LEARNER}.yaml").read_text(encoding="utf-8")))


def learner_of(c: dict[str, Any]) -> dict[str, Any]:
    """The job's learner config, a copy; the default learner's when none is given."""
    if c.get("learner"):
        return dict(c["learner"])
    return copy.deepcopy(_default_learner())


def validate_compensation(c: dict[str, Any], task: dict[str, Any]) -> None:
    """Learner, optimiser and task of a compensation job; raise ConfigError naming the key."""
    spec = task_spec(str(task["name"]))
    learner = learner_of(c)
    name = str(learner.pop("name", None))
    learner.pop("label", None)
    if name not in BASELINES:
        try:
            cls = learners.get(name)
        except learners.UnknownLearnerError as exc:
            raise _error(f"{exc}, {', '.join(BASELINES)}") from None
        try:
            make_params(cls, {k: v for k, v in learner.items() if k != "form" or v != "auto"})  # type: ignore[arg-type]
        except (TypeError, ValueError) as exc:
            text = str(exc)
            raise _error(f"learner {text}" if text.startswith(f"{name}") else f"learner {name}: {text}") from None
    kwargs = task_kwargs(task)
    try:
        env: Any = gym.make(spec.gym_id, learner=None if name in BASELINES else name, learner_params=learner,
                            budget=c["budget"], **kwargs).unwrapped
    except ValueError as exc:
        raise _error(f"task {task['name']}: {exc}") from None
    try:
        env.check_files()
    except TaskDataError as exc:
        raise _error(str(exc)) from None
    if learner.get("offsets") == "per_run" and not getattr(env, "passes_runs", False):
        raise _error(f"learner.offsets=per_run: task {task['name']} does not pass the runs of its training rows "
                     "(msra_zerobias, msra_fulltemp and accel_chamber do)")
    known = getattr(env, "baselines", BASELINES)
    if name in BASELINES and name not in known:
        raise _error(f"learner {name} is not a baseline of task {task['name']} (its baselines: {', '.join(known)})")
    if getattr(env, "needs_tuning", False):
        _check_tuner(task)
    opt = dict(c["optimiser"])
    oname = str(opt.pop("name", None))
    opt.pop("label", None)
    if oname == "none" or env.learner is None or not env.learner.searchable:
        return
    try:
        ocls = optimisers.get(oname)
        params = make_params(ocls, opt)
    except optimisers.UnknownOptimiserError as exc:
        raise _error(f"{exc}, none") from None
    except (TypeError, ValueError) as exc:
        raise _error(f"optimiser {oname}: {exc}") from None
    if not ocls.single_objective:
        raise _error(f"optimiser {oname} is multi-objective only; initial weights have one objective")
    if c["budget"] < params.population:
        raise _error(f"budget of {c['budget']} evaluations is smaller than one generation "
                     f"(optimiser {oname}: population {params.population})")
    try:
        ocls(env.lower, env.upper, c["budget"], np.random.default_rng(0), params)
    except ValueError as exc:
        raise _error(f"optimiser {oname}: {exc}") from None


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
