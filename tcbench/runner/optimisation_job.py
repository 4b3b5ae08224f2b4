"""An optimisation job prepared once from its config (:func:`prepare_job`): the checked task, its
env's arguments, the optimiser, the job's names, its IOHprofiler folder and the env it runs on.

The env is built once per job in a process, as a compensation job's
(:mod:`~tcbench.runner.compensation_job`): the plan check keeps the env it built and checked
(:func:`~tcbench.runner.prepared_job.keep`, :mod:`~tcbench.runner.kept_env`) for the job that
runs next in the same process with the same env arguments, which takes it instead of building
another; a job on a worker process is prepared there, on an env of its own.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tcbench.runner import kept_env
from tcbench.runner.optimiser_config import optimiser_of
from tcbench.runner.config import checked_config, validate_optimisation
from tcbench.runner.kinds import JobNames
from tcbench.runner.prepared_job import PreparedJob, run_settings
from tcbench.tasks import TaskSpec, task_kwargs


@dataclass(frozen=True, kw_only=True)
class OptimisationJob(PreparedJob):
    """One optimisation job, checked (:class:`~tcbench.runner.prepared_job.PreparedJob`).

    ioh_folder: where its IOHprofiler log goes (``tracking.ioh_dir``), or None."""

    ioh_folder: Path | None

    @property
    def env_key(self) -> str:
        """What the env is built from, as one string (:func:`env_key`)."""
        return env_key(self.spec, self.budget, self.task_kwargs)

    @property
    def optimiser_config(self) -> dict[str, Any]:
        """The optimiser as :func:`~tcbench.runner.loop.run_optimisation` takes it: its name and
        parameters (the leaderboard label aside)."""
        return {"name": self.optimiser.name, **self.optimiser.params}


def env_key(spec: TaskSpec, budget: int, kwargs: dict[str, Any]) -> str:
    """The arguments of an optimisation env (``gym.make`` of ``spec.gym_id``) as one string: two
    jobs with the same key start from the same env."""
    return json.dumps([spec.gym_id, budget, kwargs], sort_keys=True, default=str)


def prepare_job(c: dict[str, Any], names: Callable[[dict[str, Any]], JobNames],
                ioh_folder: Callable[[dict[str, Any]], Path | None]) -> OptimisationJob:
    """The optimisation job of config ``c``, checked as :func:`validate
    <tcbench.runner.config.validate>` checks it (one-line ConfigErrors naming the key), then named
    (``names(c)``) and given its IOHprofiler folder (``ioh_folder(c)``), with its env: the one a
    plan check kept for these arguments (:func:`~tcbench.runner.prepared_job.keep`), else built now."""
    spec, task = checked_config(c)
    kwargs = task_kwargs(task)
    kept = kept_env.take(env_key(spec, c["budget"], kwargs))
    env = validate_optimisation(c, spec, task, kept)
    return OptimisationJob(spec=spec, task=task, task_kwargs=kwargs, optimiser=optimiser_of(c), **run_settings(c),
                           names=names(c), ioh_folder=ioh_folder(c), env=env)
