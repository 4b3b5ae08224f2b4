"""Job kinds: what differs between the jobs one runner (:func:`tcbench.runner.job.run_job`) runs.

A kind says how a job is named (:meth:`JobKind.names`), what it is made of once checked
(:meth:`JobKind.job`), runs it (:meth:`JobKind.execute`) and what of its outcome goes to MLflow
(:meth:`JobKind.record`); the runner does the rest the same
way for every kind: the memory limit, resume, the run's tags and params, the config artifact,
the FAILED path. A job's kind is its config's ``kind`` key (``simulate``, ``metrics``,
``import``, ``diagnose``, ``leaderboard``: the primary configs ``conf/<command>.yaml``) or, for ``tcbench run``,
the job kind of its task's spec (:mod:`tcbench.tasks.specs`). A new kind is one module here
and one entry in the ``kinds`` of its command's spec (:mod:`tcbench.commands.registry`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tcbench.commands.registry import job_kinds, load
from tcbench.errors import ConfigError, unknown_name


@dataclass(frozen=True)
class JobNames:
    """How a job is filed: its MLflow run name and the tags the leaderboards group by."""

    run: str
    task: str
    method: str
    seed: int | None = None
    tags: dict[str, str] = field(default_factory=dict)


class JobKind:
    """One kind of job, named by its command's spec; subclasses override what differs."""

    tag = ""  # ``tcbench.kind`` of its MLflow runs (the leaderboards select by it); default: name
    plots_in_sweeps = True  # ``tracking.plots: null`` in a sweep draws the figures
    # True: the MLflow run opens when the work is done (a user error, such as a malformed input
    # found while working, leaves no run; a crash still leaves a FAILED one); False: it opens
    # first and shows RUNNING while the job works (the long jobs of ``tcbench run``)
    opens_run_after_work = False

    def __init__(self, name: str) -> None:
        self.name = name
        self.tag = self.tag or name

    def prepare(self, c: dict[str, Any]) -> dict[str, Any]:
        """The config as it will run and be logged (defaults made explicit); nothing is run."""
        return c

    def check(self, c: dict[str, Any]) -> None:
        """The checks of the job's arguments and inputs that need no work (:meth:`execute` makes
        them again when it runs)."""

    def plan_check(self, c: dict[str, Any]) -> None:
        """What a command checks of every job of a sweep before the first one starts."""
        self.check(planned(c))

    def outputs(self, c: dict[str, Any]) -> list[Path]:
        """The files or folders the job writes outside MLflow: no two jobs of a sweep may share one."""
        return []

    def names(self, c: dict[str, Any]) -> JobNames:
        raise NotImplementedError

    def job(self, c: dict[str, Any]) -> Any:
        """The job that :meth:`execute`, :meth:`record` and :meth:`summary` take, made once from the
        prepared config ``c`` as the job starts (inside its MLflow run: a ConfigError it raises is
        recorded FAILED). Default: ``c`` itself; a kind may check it here and build what the work
        needs (a typed job)."""
        return c

    def execute(self, job: Any) -> Any:
        """Check the config and run the job (:meth:`job`'s); its outcome. User errors raise one line."""
        raise NotImplementedError

    def record(self, run: Any, outcome: Any, job: Any, where: Path) -> list[Path]:
        """Log the outcome's metrics and series on ``run`` (:class:`tcbench.tracking.store.JobRun`);
        the artifact files, written into ``where``."""
        return []

    def summary(self, outcome: Any, job: Any) -> str:
        """One line for the log when the job ends."""
        return f"{self.names(job).run} done"


def planned(c: dict[str, Any]) -> dict[str, Any]:
    """``c`` as a sweep's plan checks it before the first job starts. With ``tracking.resume`` a
    job that already finished is skipped and writes nothing, so its files being there is no reason
    to refuse the sweep: a job that does run still refuses them when it moves its files into place
    (:func:`tcbench.staging.staged_dir`), unless ``overwrite``."""
    track = c.get("tracking") or {}
    if "overwrite" in c and track.get("enabled") and track.get("resume"):
        return {**c, "overwrite": True}
    return c


def announce(run: Any, c: dict[str, Any]) -> None:
    """Say where a command's run is logged (the recording commands, whose output is the user's):
    printed once the run is recorded FINISHED (:meth:`tcbench.tracking.store.JobRun.announce`)."""
    from tcbench.tracking import store as tracking

    track = c["tracking"]
    run.announce(f"logged to MLflow run {run.run_id} in {tracking.tracking_uri(track.get('uri'))} "
                 f"(experiment {track['experiment']!r})")


def kind_name(c: dict[str, Any]) -> str:
    """The kind of a composed job config: its ``kind`` key, else its task's job kind."""
    if c.get("kind"):
        return str(c["kind"])
    from tcbench.tasks import UnknownTaskError, task_spec

    try:
        return task_spec(str((c.get("task") or {}).get("name"))).job_kind
    except UnknownTaskError as exc:
        raise ConfigError(f"task: {exc}") from None


@functools.cache
def _kind(name: str, path: str) -> JobKind:
    """The one instance of the JobKind class at ``path`` (imported now) running kind ``name``."""
    return load(path)(name)  # type: ignore[no-any-return]


def kind_of(c: dict[str, Any]) -> JobKind:
    """The :class:`JobKind` that runs config ``c``; ConfigError for an unknown kind."""
    name = kind_name(c)
    paths = job_kinds()
    if name not in paths:
        raise ConfigError("kind: " + unknown_name("job kind", name, paths))
    return _kind(name, paths[name])
