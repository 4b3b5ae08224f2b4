"""A compensation job prepared once from its config (:func:`prepare_job`): the checked task, its
env's arguments, the learner and the optimiser, the job's names and the env it runs on.

The env is built once per job in a process: the plan check of a command line
(:meth:`~tcbench.runner.kinds.JobKind.plan_check`, before any job starts) keeps the env it built
and checked for the job that runs next in the same process with the same env arguments
(:func:`~tcbench.runner.prepared_job.keep`, :mod:`~tcbench.runner.kept_env`), which takes it
instead of building another (an env is fresh until its first ``reset``: a check reads it, never
steps it). A job on a worker process is prepared there. What it shares with an optimisation job
is :class:`~tcbench.runner.prepared_job.PreparedJob`.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from tcbench.runner import kept_env
from tcbench.runner.compensation_config import LearnerConfig, learner_of, validate_compensation
from tcbench.runner.optimiser_config import optimiser_of
from tcbench.runner.config import checked_config
from tcbench.runner.kinds import JobNames
from tcbench.runner.prepared_job import PreparedJob, run_settings
from tcbench.sensors.data_hash import shared_recordings
from tcbench.tasks import TaskSpec, task_kwargs


@dataclass(frozen=True, kw_only=True)
class CompensationJob(PreparedJob):
    """One compensation job, checked (:class:`~tcbench.runner.prepared_job.PreparedJob`): its
    learner too, and ``in_sample``, the test files that are also training files."""

    learner: LearnerConfig
    in_sample: tuple[str, ...]

    @property
    def env_key(self) -> str:
        """What the env is built from, as one string (:func:`env_key`)."""
        return env_key(self.spec, self.learner, self.budget, self.task_kwargs)


def env_key(spec: TaskSpec, learner: LearnerConfig, budget: int, kwargs: dict[str, Any]) -> str:
    """The arguments of a compensation env (``gym.make`` of ``spec.gym_id``) as one string: two
    jobs with the same key start from the same env."""
    return json.dumps([spec.gym_id, learner.env_learner, learner.params, budget, kwargs], sort_keys=True,
                      default=str)


def in_sample(task: dict[str, Any]) -> list[str]:
    """The test files of ``task`` that are also training files (the same path or the same bytes)."""
    if not task.get("train_files") or not task.get("test_files"):
        return []
    return shared_recordings(task["train_files"], task["test_files"])


def draw_of(c: dict[str, Any]) -> int | None:
    """The draw of power-ons a simulated compensation job trains and tests on: ``task.recordings_seed``,
    or the run seed where it is null (restart *i* on draw *i*: a method and its limits meet the same
    draws, :mod:`tcbench.leaderboard.paired`); None on the user's recordings or a task without draws."""
    task = c["task"]
    if task.get("train_files") or "recordings_seed" not in task:
        return None
    return int(c["seed"]) if task["recordings_seed"] is None else int(task["recordings_seed"])


def prepare_job(c: dict[str, Any], names: Callable[[dict[str, Any]], JobNames]) -> CompensationJob:
    """The compensation job of config ``c``, checked as :func:`validate
    <tcbench.runner.config.validate>` checks it (one-line ConfigErrors naming the key), then named
    (``names(c)``), with its env: the one a plan check kept for these arguments
    (:func:`~tcbench.runner.prepared_job.keep`), else built now."""
    spec, task = checked_config(c)
    learner, optimiser = learner_of(c), optimiser_of(c)
    if (draw := draw_of(c)) is not None:
        task = {**task, "recordings_seed": draw}
    kwargs = task_kwargs(task)
    kept = kept_env.take(env_key(spec, learner, c["budget"], kwargs))
    env = validate_compensation(c, task, kept)
    return CompensationJob(spec=spec, task=task, task_kwargs=kwargs, learner=learner, optimiser=optimiser,
                           **run_settings(c), names=names(c), in_sample=tuple(in_sample(c["task"])), env=env)
