"""The one job runner: every kind of job (optimisation, compensation, simulate, metrics, import,
diagnose) runs through :func:`run_job`, with one MLflow run shape, one failure path, one resume.

What differs between kinds (naming, running, what is logged) is the :class:`~tcbench.runner.kinds.JobKind`
of the job's config; here is what is the same for all: the memory limit, resume (skip a job whose
config and seed already FINISHED), the run's tags (sweep, task, method, seed, kind) and params
(the flattened config), ``config.yaml`` as an artifact, and the failure path: a job that raises
or calls ``sys.exit`` is recorded FAILED with its error (tracked) and listed in :data:`FAILURES`,
and the sweep goes on.
"""

from __future__ import annotations

import logging
import tempfile
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from tcbench.runner.schema import as_dict
from tcbench.errors import ConfigError, disk_full, error_line
from tcbench.runner.kinds import JobKind, kind_of

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class JobFailure:
    """A job that raised (or called ``sys.exit``): its name and the error, one line; ``user``
    when the error is the user's (a bad argument, a malformed file: exit code 2 for one job)."""

    name: str
    error: str
    user: bool = False


# The failures of the jobs run in this process (and, in a sweep's parent, those its workers
# reported): the commands list them when no tracking store records them.
FAILURES: list[JobFailure] = []


def failed(name: str, exc: BaseException) -> JobFailure:
    """Log and remember a job's failure; the sweep goes on."""
    user = isinstance(exc, ConfigError)
    error = f"sys.exit({exc.code})" if isinstance(exc, SystemExit) else str(exc) if user else \
        disk_full(exc) or f"{type(exc).__name__}: {exc}"
    if isinstance(exc, MemoryError):
        from tcbench.runner.memory import ENV

        error = f"{error.rstrip(': ')} (more than one job may use here: the memory free when it started, or ${ENV})"
    failure = JobFailure(name, error_line(error), user)
    log.error("job %s failed: %s", name, failure.error)
    log.debug("%s", traceback.format_exc())
    FAILURES.append(failure)
    return failure


def job_name(c: dict[str, Any]) -> str:
    """The name a job's MLflow run gets (``<method>-<task key>-s<seed>`` for run jobs)."""
    try:
        return kind_of(c).names(c).run
    except Exception:  # noqa: BLE001 - a config too broken to name: its failure still needs a name
        return f"job-s{c.get('seed')}"


def plots_default(c: dict[str, Any]) -> bool:
    """What ``tracking.plots: null`` means for a job of a sweep: its kind's choice."""
    try:
        return kind_of(c).plots_in_sweeps
    except Exception:  # noqa: BLE001 - a broken config fails when it runs, with its own error
        return True


def run_job(cfg: Any, *, record_user_errors: bool = True) -> Any:
    """Run one configured job of any kind: its outcome, None when resume skipped it, or a
    :class:`JobFailure` when it raised or called ``sys.exit`` (recorded FAILED when tracked);
    never raises but for ``KeyboardInterrupt``. ``record_user_errors=False`` (one job of a
    recording command): a bad input the work finds leaves no MLflow run, as it leaves no file."""
    from tcbench.runner import memory

    c = as_dict(cfg)
    try:
        kind = kind_of(c)
        c = kind.prepare(c)
        with memory.limited(memory.job_budget_bytes()):
            return _run(kind, c, record_user_errors)
    except (Exception, SystemExit) as exc:  # recorded as FAILED by job_run when tracked
        return failed(job_name(c), exc)


def _run(kind: JobKind, c: dict[str, Any], record_user_errors: bool = True) -> Any:
    track = c.get("tracking") or {}
    if not track.get("enabled"):
        job = kind.job(c)
        outcome = kind.execute(job)
        log.info("%s", kind.summary(outcome, job))
        return outcome

    from tcbench.tracking import store as tracking

    names = kind.names(c)
    if track.get("resume"):
        done = tracking.finished_run(c)
        if done is not None:
            log.info("%s already FINISHED in run %s; skipped", names.run, done)
            return None
    tags = {
        "tcbench.sweep_id": str(track.get("sweep_id") or tracking.sweep_id_from_hydra()),
        "tcbench.task": names.task,
        "tcbench.method": names.method,
        "tcbench.seed": str(names.seed if names.seed is not None else c.get("seed", 0)),
        "tcbench.kind": kind.tag,
        **names.tags,
    }
    if kind.opens_run_after_work:
        try:
            job = kind.job(c)
            outcome = kind.execute(job)
        except BaseException as exc:
            if isinstance(exc, ConfigError) and not record_user_errors:
                raise  # the user's mistake in a single command: one line, no run
            with tracking.job_run(c, names.run, tags):
                raise  # recorded FAILED with its error (a sweep's record, or a crash)
        try:  # the store made now, after the work: a store that cannot be made is not left half-made
            tracking.prepare_store(track.get("uri"), str(track["experiment"]))
        except tracking.StoreError as exc:
            raise ConfigError(f"the files are written, but MLflow could not record them: {exc}") from None
    with tracking.job_run(c, names.run, tags) as run:
        if not kind.opens_run_after_work:
            job = kind.job(c)
            outcome = kind.execute(job)
        with tempfile.TemporaryDirectory() as tmp:
            where = Path(tmp)
            (where / "config.yaml").write_text(yaml.safe_dump(c, sort_keys=False))
            for f in [where / "config.yaml", *kind.record(run, outcome, job, where)]:
                run.log_artifact(f)
    log.info("%s", kind.summary(outcome, job))
    return outcome
