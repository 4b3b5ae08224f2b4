"""MLflow tracking of tcbench jobs: one run per job, embedded store by default.

The store is ``sqlite:///mlflow.db`` in the working directory unless ``MLFLOW_TRACKING_URI`` (or
the ``tracking.uri`` config key) says otherwise; artifacts go to ``./mlartifacts/<experiment>``
(set explicitly when the experiment is created, so they never land relative to another
directory). MLflow's telemetry is off unless ``MLFLOW_DISABLE_TELEMETRY`` is set by the user.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import subprocess
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

os.environ.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")

import mlflow  # noqa: E402
from mlflow.entities import Metric, Param, RunStatus, RunTag  # noqa: E402
from mlflow.tracking import MlflowClient  # noqa: E402

import tcbench  # noqa: E402

TAG_PREFIX = "tcbench."
_BATCH = 1000


def tracking_uri(uri: str | None = None) -> str:
    """The store to use: explicit ``uri``, else ``$MLFLOW_TRACKING_URI``, else ./mlflow.db."""
    if uri:
        return uri
    env = os.environ.get("MLFLOW_TRACKING_URI")
    if env:
        return env
    return f"sqlite:///{Path.cwd() / 'mlflow.db'}"


def client(uri: str | None = None) -> MlflowClient:
    """An MLflow client on the resolved store."""
    return MlflowClient(tracking_uri=tracking_uri(uri))


def experiment_id(c: MlflowClient, name: str) -> str:
    """Id of experiment ``name``, creating it with an explicit artifact location if needed."""
    found = c.get_experiment_by_name(name)
    if found is not None:
        return found.experiment_id
    # A local store gets an explicit artifact folder; a tracking server keeps its own default
    # (proxied artifacts), which every machine of a shared sweep can reach.
    remote = str(c.tracking_uri).startswith(("http://", "https://"))
    location = None if remote else (Path.cwd() / "mlartifacts" / name).resolve().as_uri()
    try:
        return c.create_experiment(name, artifact_location=location)
    except mlflow.exceptions.MlflowException:  # created meanwhile by a concurrent job
        found = c.get_experiment_by_name(name)
        if found is None:
            raise
        return found.experiment_id


def sqlite_path(uri: str | None = None) -> Path | None:
    """The database file of a local SQLite store; None for any other store."""
    resolved = tracking_uri(uri)
    return Path(resolved[len("sqlite:///"):]) if resolved.startswith("sqlite:///") else None


@contextmanager
def store_lock(uri: str | None = None) -> Iterator[None]:
    """Exclusive lock on a local SQLite store (a ``<db>.lock`` file beside it) while held; a no-op
    for other stores. MLflow creates or upgrades a SQLite store's tables the first time a client
    touches it, and two processes doing so at once collide (``table ... already exists``)."""
    db = sqlite_path(uri)
    if db is None:
        yield
        return
    from tcbench.filelock import locked

    with locked(db):
        yield


def prepare_store(uri: str | None, experiment: str) -> str:
    """Create or upgrade the store and the experiment once, under :func:`store_lock`, before any
    job of a sweep starts; the experiment's id."""
    db = sqlite_path(uri)
    with store_lock(uri):
        if db is not None and (not db.exists() or db.stat().st_size == 0):
            from tcbench.store_template import create_store

            create_store(db)  # a copy of a migrated empty store; MLflow builds it if this fails
        return experiment_id(client(uri), experiment)


def flatten(cfg: Mapping[str, Any], prefix: str = "") -> dict[str, str]:
    """``{"a": {"b": 1}}`` -> ``{"a.b": "1"}``: a nested config as MLflow params."""
    out: dict[str, str] = {}
    for key, value in cfg.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(flatten(value, f"{name}."))
        else:
            out[name] = json.dumps(value) if isinstance(value, (list, tuple)) else str(value)
    return out


def config_hash(cfg: Mapping[str, Any]) -> str:
    """Stable short hash of a job's config without its seed and tracking settings."""
    content = {k: v for k, v in cfg.items() if k not in {"seed", "tracking", "progress"}}
    content["optimiser"] = {k: v for k, v in content.get("optimiser", {}).items() if k != "label"}
    blob = json.dumps(content, sort_keys=True, default=str).encode()
    return hashlib.sha256(blob).hexdigest()[:16]


@functools.cache
def git_commit() -> str:
    """Commit of the tcbench source tree, or ``unknown`` outside a git checkout (asked once per
    process)."""
    src = Path(tcbench.__file__).resolve().parent
    try:
        out = subprocess.run(
            ["git", "-C", str(src), "rev-parse", "HEAD"],
            capture_output=True, text=True, timeout=5, check=True,
        )
        return out.stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def finished_run(cfg: Mapping[str, Any]) -> str | None:
    """Id of a FINISHED run of the same config (hash) and seed in the job's experiment, if any."""
    track = cfg["tracking"]
    c = client(track.get("uri"))
    exp = c.get_experiment_by_name(track["experiment"])
    if exp is None:
        return None
    query = (f"tags.`{TAG_PREFIX}config_hash` = '{config_hash(cfg)}' and "
             f"tags.`{TAG_PREFIX}seed` = '{cfg['seed']}' and attributes.status = 'FINISHED'")
    runs = c.search_runs([exp.experiment_id], filter_string=query, max_results=1)
    return runs[0].info.run_id if runs else None


class JobRun:
    """Handle on an active MLflow run that knows how to log a tcbench job. Params, metrics and
    tags are kept until :meth:`flush` (called when the job ends, finished or failed) and sent in
    as few ``log_batch`` calls as MLflow's limits allow, each one a database transaction."""

    def __init__(self, c: MlflowClient, run_id: str) -> None:
        self.client = c
        self.run_id = run_id
        self._params: list[Param] = []
        self._metrics: list[Metric] = []
        self._tags: list[RunTag] = []

    def log_params(self, params: Mapping[str, str]) -> None:
        self._params += [Param(k, str(v)[:6000]) for k, v in params.items()]

    def log_series(self, name: str, values: list[float], steps: list[int]) -> None:
        """Log ``values`` of metric ``name`` at ``steps``."""
        ts = mlflow.utils.time.get_current_time_millis()
        self._metrics += [Metric(name, float(v), ts, int(s)) for v, s in zip(values, steps, strict=True)]

    def log_metrics(self, values: Mapping[str, float]) -> None:
        ts = mlflow.utils.time.get_current_time_millis()
        self._metrics += [Metric(k, float(v), ts, 0) for k, v in values.items()]

    def log_artifact(self, path: Path) -> None:
        self.client.log_artifact(self.run_id, str(path))

    def set_tag(self, key: str, value: str) -> None:
        self._tags.append(RunTag(key, value))

    def flush(self) -> None:
        """Send what was logged: MLflow takes at most 1000 metrics, 100 params and 100 tags in
        one batch."""
        params, metrics, tags = self._params, self._metrics, self._tags
        self._params, self._metrics, self._tags = [], [], []
        while params or metrics or tags:
            self.client.log_batch(self.run_id, metrics=metrics[:_BATCH], params=params[:100], tags=tags[:100])
            params, metrics, tags = params[100:], metrics[_BATCH:], tags[100:]


@functools.cache
def _experiment_id(uri: str, name: str) -> str:
    return experiment_id(client(uri), name)


@contextmanager
def job_run(
    cfg: Mapping[str, Any], run_name: str, tags: Mapping[str, str]
) -> Iterator[JobRun]:
    """Open a run for one job; mark it FAILED (with the error as a tag) if the body raises.
    What the body logs is sent when it ends (:meth:`JobRun.flush`)."""
    track = cfg["tracking"]
    uri = tracking_uri(track.get("uri"))
    c = client(uri)
    exp = _experiment_id(uri, track["experiment"])
    all_tags = {
        f"{TAG_PREFIX}version": tcbench.__version__,
        f"{TAG_PREFIX}git_commit": git_commit(),
        f"{TAG_PREFIX}config_hash": config_hash(cfg),
        **tags,
    }
    run = c.create_run(exp, run_name=run_name, tags=all_tags)
    handle = JobRun(c, run.info.run_id)
    handle.log_params(flatten(cfg))
    try:
        yield handle
    except BaseException as exc:
        handle.set_tag(f"{TAG_PREFIX}error", f"{type(exc).__name__}: {exc}"[:4900])
        handle.flush()
        c.set_terminated(run.info.run_id, status=RunStatus.to_string(RunStatus.FAILED))
        raise
    handle.flush()
    c.set_terminated(run.info.run_id, status="FINISHED")
