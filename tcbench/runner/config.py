"""Validation of a tcbench job's config.

Its schema (:mod:`.schema`, re-exported here) is registered with Hydra's ConfigStore as
``base_config`` so OmegaConf checks types at composition; :func:`validate` then checks the task's keys against its schema
(:class:`TaskConfig` for function tasks, :class:`MSRATaskConfig` for compensation tasks), ranges
and names (task, dimension, optimiser and learner names and parameters, budget against one
generation) and raises :class:`ConfigError` with one line that names the offending key.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import gymnasium as gym
import numpy as np
from omegaconf import DictConfig

from tcbench.errors import ConfigError
from tcbench.optimisers import registry
from tcbench.outputs import folder_problem
from tcbench.params import coerce_param, make_params
from tcbench.tasks import TASKS, TaskSpec, UnknownTaskError, task_kwargs, task_spec
from tcbench.tasks.schemas import (  # noqa: F401 - the schemas' home before tasks/schemas.py
    BBOBTaskConfig,
    GyroTaskConfig,
    GyroTuningTaskConfig,
    MSRATaskConfig,
    TaskConfig,
)
from tcbench.runner.schema import JobConfig, as_dict, register_schema  # noqa: F401 - their home before schema.py


def checked_task(task: dict[str, Any], schema: type) -> dict[str, Any]:
    """The task config with every key known to ``schema`` and values of its types."""
    fields = {f.name: f for f in dataclasses.fields(schema)}
    unknown = sorted(set(task) - set(fields))
    if unknown:
        raise ConfigError(f"task.{unknown[0]}: no such key for task {task.get('name')}; "
                          f"known: {', '.join(sorted(fields))}")
    out = {}
    for key, value in task.items():
        try:
            out[key] = coerce_param("task", key, fields[key].type, value)
        except ValueError as exc:
            raise ConfigError(str(exc)) from None
    return out


def checked_config(c: dict[str, Any]) -> tuple[TaskSpec, dict[str, Any]]:
    """What every run job's config must get right (seed, budget, the experiment's name, the task's
    name, ``tracking.ioh_dir``): the task's spec and its config checked against the spec's schema;
    :class:`ConfigError` naming the key otherwise."""
    if c["seed"] < 0:
        raise ConfigError(f"seed must be >= 0, got {c['seed']}")
    if c["budget"] < 1:
        raise ConfigError(f"budget must be a positive number of evaluations, got {c['budget']}")
    track = c.get("tracking") or {}
    if track.get("enabled", True) and not str(track.get("experiment") or "").strip():
        raise ConfigError("tracking.experiment: give the MLflow experiment a name (default: tcbench)")
    name = str(c["task"].get("name"))
    try:
        spec = task_spec(name)
    except UnknownTaskError as exc:
        raise ConfigError(f"task: {exc}") from None
    ioh_dir = c.get("tracking", {}).get("ioh_dir")
    if ioh_dir is not None and not str(ioh_dir).strip():
        raise ConfigError("tracking.ioh_dir: give a folder, or null for no IOHprofiler log")
    if ioh_dir and spec.is_compensation:
        raise ConfigError(f"tracking.ioh_dir: IOHprofiler logs are written for optimisation tasks, "
                          f"not for task {name}")
    if ioh_dir and (problem := folder_problem(ioh_dir)):
        raise ConfigError(f"tracking.ioh_dir={ioh_dir}: {problem}")
    return spec, checked_task(c["task"], spec.schema)


def validate(cfg: DictConfig | dict[str, Any]) -> None:
    """Check ranges and names of a composed job config; raise :class:`ConfigError` if wrong."""
    c = as_dict(cfg)
    spec, task = checked_config(c)
    if spec.is_compensation:
        # imported here: an optimisation job does not load the compensation stack
        from tcbench.runner.compensation_config import validate_compensation

        validate_compensation(c, task)
        return
    validate_optimisation(c, spec, task)


def validate_optimisation(c: dict[str, Any], spec: TaskSpec, task: dict[str, Any], env: Any = None) -> Any:
    """The optimiser and task of an optimisation job whose config :func:`checked_config` returned
    ``spec`` and ``task``; raise ConfigError naming the key. The env checked: ``env`` when given
    (built from the same arguments by an earlier check of this job), else built now (unwrapped,
    not yet reset)."""
    name = str(c["task"].get("name"))
    if c.get("learner"):
        raise ConfigError(f"learner={c['learner'].get('name')}: learners apply to compensation tasks "
                          f"({', '.join(n for n, s in TASKS.items() if s.is_compensation)}), not to task {name}")
    kwargs = task_kwargs(task)
    if spec.sized:
        check_job_memory(c, kwargs.get("dim", 2))
    if env is None:
        env = build_optimisation_env(spec, c["budget"], kwargs)
    ioh_dir = c.get("tracking", {}).get("ioh_dir")
    if ioh_dir and getattr(env, "n_objectives", 1) > 1:
        raise ConfigError(f"tracking.ioh_dir: IOHprofiler logs are for one objective; task {name} has "
                          f"{env.n_objectives}")
    check_optimiser(c, env, name)
    return env


def build_optimisation_env(spec: TaskSpec, budget: int, kwargs: dict[str, Any]) -> Any:
    """The unwrapped env of an optimisation job (``gym.make`` of ``spec.gym_id`` with ``budget``
    and the task's keyword arguments); a ConfigError naming the task when it refuses them."""
    try:
        return gym.make(spec.gym_id, budget=budget, **kwargs).unwrapped
    except ConfigError:
        raise
    except (KeyError, ValueError) as exc:
        raise ConfigError(f"task: {exc}") from None


def check_job_memory(c: dict[str, Any], dim: Any) -> None:
    """Refuse a job whose optimiser's own estimate (:meth:`Optimiser.memory_bytes`) in ``dim``
    dimensions exceeds what one job may use here (:func:`tcbench.runner.memory.job_budget_bytes`),
    before the task or the optimiser allocates anything."""
    from tcbench.runner.memory import ENV, human, job_budget_bytes

    opt = {k: v for k, v in c["optimiser"].items() if k not in {"name", "label"}}
    name = str(c["optimiser"].get("name"))
    try:
        cls = registry.get(name)
        need = cls.memory_bytes(make_params(cls, opt), int(dim))
    except (registry.UnknownOptimiserError, TypeError, ValueError):
        return  # check_optimiser and the task name what is wrong
    try:
        budget = job_budget_bytes()
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
    if budget is not None and need > budget:
        raise ConfigError(f"task.dim={dim}: a run of optimiser {name} would need about {human(need)}, more than "
                          f"the {human(budget)} one job may use here (free memory, or ${ENV}); lower task.dim "
                          "or the population")


def check_optimiser(c: dict[str, Any], env: Any, task_name: str) -> None:
    """The job's optimiser against ``env``: known, valid parameters, the right number of
    objectives, a budget of at least one generation; ConfigError naming the key otherwise."""
    opt = dict(c["optimiser"])
    name = opt.pop("name", None)
    opt.pop("label", None)  # leaderboard name, not a parameter
    try:
        cls = registry.get(str(name))
        params = make_params(cls, opt)
    except registry.UnknownOptimiserError as exc:
        raise ConfigError(str(exc)) from None
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"optimiser {name}: {exc}") from None
    m = getattr(env, "n_objectives", 1)
    if m > 1 and not cls.multi_objective:
        raise ConfigError(f"optimiser {name} is single-objective; task {task_name} has {m} objectives")
    if m == 1 and not cls.single_objective:
        raise ConfigError(f"optimiser {name} is multi-objective only; task {task_name} has one objective")
    if c["budget"] < params.population:
        raise ConfigError(
            f"budget of {c['budget']} evaluations is smaller than one generation "
            f"(optimiser {name}: population {params.population})"
        )
    try:  # the optimiser's own construction checks (e.g. BAS needs two evaluations per beetle)
        cls(env.lower, env.upper, c["budget"], np.random.default_rng(0), params, n_objectives=m)
    except ValueError as exc:
        raise ConfigError(f"optimiser {name}: {exc}") from None
