"""What an optimisation job and a compensation job share once prepared from their config
(:mod:`~tcbench.runner.optimisation_job`, :mod:`~tcbench.runner.compensation_job`): the checked
task and its env's arguments, the optimiser, the run's settings, the job's names and the env it
runs on, built once per job in a process (:func:`keep`, :mod:`~tcbench.runner.kept_env`)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any

from tcbench.runner import kept_env
from tcbench.runner.optimiser_config import OptimiserConfig
from tcbench.runner.kinds import JobNames
from tcbench.tasks import TaskSpec


@dataclass(frozen=True, kw_only=True)
class PreparedJob(ABC):
    """A job checked from its config: what its names, its run, its record and its summary need.

    task: the task's config as checked against its schema; task_kwargs: its env's keyword
    arguments. plots: ``tracking.plots`` (null: draw). env: the task's env (unwrapped), built once
    and not yet reset."""

    spec: TaskSpec
    task: dict[str, Any]
    task_kwargs: dict[str, Any]
    optimiser: OptimiserConfig
    budget: int
    seed: int
    progress: bool
    plots: bool | None
    names: JobNames
    env: Any = field(repr=False, compare=False)

    @property
    @abstractmethod
    def env_key(self) -> str:
        """What the env is built from, as one string: two jobs with the same key start from the
        same env."""


def run_settings(c: dict[str, Any]) -> dict[str, Any]:
    """The fields of a :class:`PreparedJob` read from config ``c`` as they are: the budget, the
    seed, the progress bar and ``tracking.plots``."""
    return {"budget": int(c["budget"]), "seed": int(c["seed"]), "progress": bool(c["progress"]),
            "plots": (c.get("tracking") or {}).get("plots")}


def keep(job: PreparedJob) -> None:
    """Keep ``job``'s env for the next job prepared in this process from the same env arguments
    (the plan check's job hands it to the job that runs; :mod:`~tcbench.runner.kept_env`)."""
    kept_env.keep(job.env_key, job.env)
