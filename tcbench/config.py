"""Structured config of a tcbench job and its validation.

The dataclasses are registered with Hydra's ConfigStore as ``base_config`` so OmegaConf checks
types at composition; :func:`validate` then checks the task's keys against its schema
(:class:`TaskConfig` for function tasks, :class:`MSRATaskConfig` for compensation tasks), ranges
and names (task, dimension, optimiser and learner names and parameters, budget against one
generation) and raises :class:`ConfigError` with one line that names the offending key.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from hydra.core.config_store import ConfigStore
from omegaconf import MISSING, DictConfig, OmegaConf

from tcbench.compensation_config import validate_compensation
from tcbench.errors import ConfigError
from tcbench.optimisers import registry
from tcbench.outputs import folder_problem
from tcbench.params import coerce_param, make_params
from tcbench.tasks import is_bbob, is_compensation, is_gyro, task_class
from tcbench.tracking_config import TrackingConfig


@dataclass
class TaskConfig:
    """Which function task to solve and how (see :class:`tcbench.tasks.FunctionEnv`)."""

    name: str = MISSING
    dim: int = 2
    shift: bool = False
    target_precision: float = 1e-8
    lower: float | None = None
    upper: float | None = None


@dataclass
class BBOBTaskConfig:
    """A BBOB function from ioh (see :class:`tcbench.tasks.bbob_env.BBOBEnv`)."""

    name: str = MISSING
    function: int = 1
    dim: int = 5
    instance: int = 1
    target_precision: float = 1e-8
    stop_at_target: bool = True


@dataclass
class MSRATaskConfig:
    """An MSRA compensation task (see :class:`tcbench.tasks.MSRACompensationEnv`)."""

    name: str = MISSING
    device_seed: int = 0
    recordings_seed: int | None = 0
    n_train: int | None = None
    n_test: int | None = None
    train_files: list | None = None
    test_files: list | None = None
    train_on: str = "positions"
    rate_window_s: float = 120.0
    bias_form: str = "plus"


@dataclass
class GyroTuningTaskConfig:
    """VMD tuning on a gyro oven record (see :class:`tcbench.tasks.GyroVMDTuningEnv`)."""

    name: str = MISSING
    device_seed: int = 0
    recordings_seed: int = 0
    train_files: list | None = None
    sample_rate_hz: float = 10.0
    hold_s: float = 3600.0
    tuning_samples: int = 2048
    effects: dict | None = None


@dataclass
class GyroTaskConfig(GyroTuningTaskConfig):
    """The gyro drift/noise task (see :class:`tcbench.tasks.GyroDriftNoiseEnv`); ``tuner``,
    ``tuner_params`` and ``tuning_budget`` set the multi-objective search of VMD's ``[k, alpha]``
    when they are null."""

    n_train: int = 1
    n_test: int = 1
    test_files: list | None = None
    decomposition: str = "vmd"
    k: int | None = None
    alpha: float | None = None
    tuner: str = "mopso"
    tuner_params: dict | None = None
    tuning_budget: int = 440
    denoise: str = "tfpf"
    tfpf_window: int = 31
    noise_above: float = 0.5
    drift_below: float = 0.15
    inputs: str = "t_rate"
    rate_window_s: float = 120.0
    learner_block_s: float = 10.0
    bandwidth_amplitude_dps: float = 0.005


@dataclass
class JobConfig:
    """One optimisation job: task, optimiser, seed and evaluation budget."""

    task: dict[str, Any] = field(default_factory=lambda: {"name": MISSING})
    optimiser: dict[str, Any] = field(default_factory=lambda: {"name": MISSING})
    learner: dict[str, Any] | None = None
    seed: int = 0
    budget: int = 1000
    progress: bool = False
    tracking: TrackingConfig = field(default_factory=TrackingConfig)


def register_schema() -> None:
    """Make the structured schema available to Hydra as ``base_config``."""
    ConfigStore.instance().store(name="base_config", node=JobConfig)


def as_dict(cfg: DictConfig | dict[str, Any]) -> dict[str, Any]:
    """Plain, resolved dict of a (sub)config."""
    if isinstance(cfg, DictConfig):
        return OmegaConf.to_container(cfg, resolve=True)  # type: ignore[return-value]
    return dict(cfg)


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


def validate(cfg: DictConfig | dict[str, Any]) -> None:
    """Check ranges and names of a composed job config; raise :class:`ConfigError` if wrong."""
    c = as_dict(cfg)
    if c["seed"] < 0:
        raise ConfigError(f"seed must be >= 0, got {c['seed']}")
    if c["budget"] < 1:
        raise ConfigError(f"budget must be a positive number of evaluations, got {c['budget']}")
    track = c.get("tracking") or {}
    if track.get("enabled", True) and not str(track.get("experiment") or "").strip():
        raise ConfigError("tracking.experiment: give the MLflow experiment a name (default: tcbench)")
    name = str(c["task"].get("name"))
    ioh_dir = c.get("tracking", {}).get("ioh_dir")
    if ioh_dir is not None and not str(ioh_dir).strip():
        raise ConfigError("tracking.ioh_dir: give a folder, or null for no IOHprofiler log")
    if ioh_dir and is_compensation(name):
        raise ConfigError(f"tracking.ioh_dir: IOHprofiler logs are written for optimisation tasks, "
                          f"not for task {name}")
    if ioh_dir and (problem := folder_problem(ioh_dir)):
        raise ConfigError(f"tracking.ioh_dir={ioh_dir}: {problem}")
    if is_compensation(name):
        validate_compensation(c, checked_task(c["task"], GyroTaskConfig if is_gyro(name) else MSRATaskConfig))
        return
    if c.get("learner"):
        raise ConfigError(f"learner={c['learner'].get('name')}: learners apply to compensation tasks "
                          f"(msra_fulltemp, msra_zerobias, gyro_driftnoise), not to task {c['task'].get('name')}")
    try:
        if is_gyro(name):
            task = {k: v for k, v in checked_task(c["task"], GyroTuningTaskConfig).items() if k != "name"}
            from tcbench.tasks.gyro_vmd_env import GyroVMDTuningEnv

            env = GyroVMDTuningEnv(budget=c["budget"], **task)
        elif is_bbob(name):
            from tcbench.tasks.bbob_env import BBOBEnv

            task = {k: v for k, v in checked_task(c["task"], BBOBTaskConfig).items() if k != "name"}
            check_job_memory(c, task["dim"])
            env = BBOBEnv(budget=c["budget"], **task)
        else:
            task = {k: v for k, v in checked_task(c["task"], TaskConfig).items() if k != "name"}
            check_job_memory(c, task["dim"])
            env = task_class(name)(function=name, budget=c["budget"], **task)
    except ConfigError:
        raise
    except (KeyError, ValueError) as exc:
        raise ConfigError(f"task: {exc}") from None
    if ioh_dir and getattr(env, "n_objectives", 1) > 1:
        raise ConfigError(f"tracking.ioh_dir: IOHprofiler logs are for one objective; task {name} has "
                          f"{env.n_objectives}")
    check_optimiser(c, env, name)


def check_job_memory(c: dict[str, Any], dim: Any) -> None:
    """Refuse a job whose optimiser's own estimate (:meth:`Optimiser.memory_bytes`) in ``dim``
    dimensions exceeds what one job may use here (:func:`tcbench.memory.job_budget_bytes`),
    before the task or the optimiser allocates anything."""
    from tcbench.memory import ENV, human, job_budget_bytes

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
