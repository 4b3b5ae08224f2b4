"""MLflow tracking of tcbench jobs: one run per job, embedded store by default.

The store is ``sqlite:///mlflow.db`` in the working directory unless ``MLFLOW_TRACKING_URI`` (or
the ``tracking.uri`` config key) says otherwise; artifacts go to ``mlartifacts/<experiment>`` beside
a SQLite store's database (its lock file ``<db>.lock`` too), in the working directory for any
other local store (set explicitly when the experiment is created, so they never land relative to
another directory). MLflow's telemetry is off unless ``MLFLOW_DISABLE_TELEMETRY`` is set by the user.
"""

from __future__ import annotations

import functools
import hashlib
import json
import logging
import os
import shutil
import socket
import subprocess
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any
from urllib.parse import urlparse
from urllib.request import url2pathname

os.environ.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")
os.environ.setdefault("MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR", "false")  # a board reads small artifacts: no bars in its output

import mlflow  # noqa: E402
from mlflow.entities import Metric, Param, RunTag  # noqa: E402
from mlflow.tracking import MlflowClient  # noqa: E402

from tcbench._version import __version__  # noqa: E402
from tcbench.errors import disk_full  # noqa: E402
from tcbench.tracking import announce  # noqa: E402
from tcbench.tracking.checks import (  # noqa: E402,F401 - the checks are part of this module's interface
    StoreError,
    check_store,
    first_line,
    sqlite_path,
    tracking_uri,
)

TAG_PREFIX = "tcbench."
log = logging.getLogger(__name__)
# MLflow logs every failed database call with its whole traceback before raising it; tcbench
# reports the error it raises in one line (the run FAILED with it, or the command's error).
logging.getLogger("mlflow.store.db.utils").setLevel(logging.CRITICAL)
_BATCH = 1000


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
    location = None if remote else (artifact_root(str(c.tracking_uri)) / name).resolve().as_uri()
    try:
        return c.create_experiment(name, artifact_location=location)
    except mlflow.exceptions.MlflowException:  # created meanwhile by a concurrent job
        found = c.get_experiment_by_name(name)
        if found is None:
            raise
        return found.experiment_id


def artifact_root(uri: str | None = None) -> Path:
    """The folder a local store's experiments keep their artifacts in: ``mlartifacts/`` beside a
    SQLite store's database (``sqlite:///my-imu/mlflow.db``: ``my-imu/mlartifacts``), else in the
    working directory."""
    db = sqlite_path(uri)
    return (db.parent if db is not None else Path.cwd()) / "mlartifacts"


@contextmanager
def store_lock(uri: str | None = None) -> Iterator[None]:
    """Exclusive lock on a local SQLite store (a ``<db>.lock`` file beside it) while held; a no-op
    for other stores. MLflow creates or upgrades a SQLite store's tables the first time a client
    touches it, and two processes doing so at once collide (``table ... already exists``)."""
    db = sqlite_path(uri)
    if db is None:
        yield
        return
    from filelock import FileLock

    with FileLock(db.with_name(db.name + ".lock")):
        yield


def prepare_store(uri: str | None, experiment: str) -> str:
    """Create or upgrade the store and the experiment once, under :func:`store_lock`, before any
    job of a sweep starts; the experiment's id. A :class:`StoreError` if that fails."""
    db = sqlite_path(uri)
    new = db is not None and not db.exists()
    try:
        with store_lock(uri):
            if db is not None and (not db.exists() or db.stat().st_size == 0):
                from tcbench.tracking.template import create_store

                create_store(db)  # a copy of a migrated empty store; MLflow builds it if this fails
            return experiment_id(client(uri), experiment)
    except Exception as exc:  # noqa: BLE001 - a full disk, a locked or corrupt database, a refused login
        if new and db is not None:  # a store this call began is not left half-made
            db.unlink(missing_ok=True)
        raise StoreError(f"tracking store {tracking_uri(uri)}: cannot be prepared ({first_line(exc)})") from exc


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
    src = Path(__file__).resolve().parent
    try:
        out = subprocess.run(
            ["git", "-C", str(src), "rev-parse", "HEAD"],
            capture_output=True, text=True, timeout=5, check=True,
        )
        return out.stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def sweep_id_from_hydra() -> str:
    """Id shared by the jobs of one multirun (hash of its sweep dir), or the run dir's."""
    try:
        from hydra.core.hydra_config import HydraConfig
        from hydra.types import RunMode

        hc = HydraConfig.get()
        where = hc.sweep.dir if hc.mode == RunMode.MULTIRUN else hc.run.dir
        return hashlib.sha256(str(Path(where).resolve()).encode()).hexdigest()[:12]
    except (ImportError, ValueError):
        return "interactive"


def finished_run(cfg: Mapping[str, Any]) -> str | None:
    """Id of a FINISHED run of the same config (hash) and seed in the job's experiment, if any."""
    track = cfg["tracking"]
    db = sqlite_path(track.get("uri"))
    if db is not None and not db.exists():  # no store yet: no run (and no store made to say so)
        return None
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

    def __init__(self, c: MlflowClient, run_id: str, artifact_uri: str | None = None) -> None:
        self.client = c
        self.run_id = run_id
        self.artifact_dir = local_artifact_dir(artifact_uri)
        self._params: list[Param] = []
        self._metrics: list[Metric] = []
        self._tags: list[RunTag] = []
        self.announcements: list[str] = []  # printed once the run is recorded FINISHED

    def announce(self, line: str) -> None:
        """Print ``line`` (where the run is logged) once the run is recorded FINISHED, never before."""
        self.announcements.append(line)

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
        """Copy ``path`` into the run's artifacts; a copy that fails (a full disk) is removed, so
        the bytes it took do not stop the run's end from being recorded."""
        try:
            self.client.log_artifact(self.run_id, str(path))
        except BaseException:
            if self.artifact_dir is not None:
                (self.artifact_dir / Path(path).name).unlink(missing_ok=True)
            raise

    def drop_artifacts(self) -> None:
        """Remove the run's local artifacts (what a run that cannot be recorded leaves on a full disk)."""
        if self.artifact_dir is not None and self.artifact_dir.is_dir():
            shutil.rmtree(self.artifact_dir, ignore_errors=True)

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


def local_artifact_dir(artifact_uri: str | None) -> Path | None:
    """The folder of a run's artifacts when they are on this machine's file system, else None."""
    if not artifact_uri:
        return None
    parsed = urlparse(artifact_uri)
    if parsed.scheme not in ("", "file"):
        return None
    return Path(url2pathname(parsed.path))


@functools.cache
def _experiment_id(uri: str, name: str) -> str:
    """The experiment's id; a local store not made yet is made first by :func:`prepare_store` (a
    copy of the migrated empty store, not MLflow's migrations: seconds saved on each new store)."""
    db = sqlite_path(uri)
    if db is not None and (not db.exists() or db.stat().st_size == 0):
        return prepare_store(uri, name)
    return experiment_id(client(uri), name)


def _host() -> str:
    return socket.gethostname()


def process_alive(pid: int) -> bool:
    """Whether a process ``pid`` exists on this machine."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


INTERRUPTED = "interrupted (Ctrl-C)"


def end_run(c: MlflowClient, run_id: str, error: str, status: str = "FAILED") -> str | None:
    """Mark a run ended with ``status`` and ``error`` as its ``tcbench.error`` tag; None, or why
    the store could not be written (one line)."""
    try:
        c.set_tag(run_id, f"{TAG_PREFIX}error", error[:4900])
        c.set_terminated(run_id, status=status)
    except Exception as exc:  # noqa: BLE001 - a full disk or a dead server: said by the caller
        return first_line(exc)
    return None


def mark_failed(c: MlflowClient, run_id: str, error: str, status: str = "FAILED") -> bool:
    """Mark a run ended with ``status`` and ``error`` as its ``tcbench.error`` tag; False (and one
    logged line) if the store cannot be written."""
    if (problem := end_run(c, run_id, error, status)) is not None:
        log.error("run %s could not be marked %s in %s: %s", run_id, status, c.tracking_uri, problem)
        return False
    return True


def ended_by(exc: BaseException) -> tuple[str, str]:
    """The status and error a job's run ends with when ``exc`` ends it: KILLED for Ctrl-C,
    FAILED for anything else (a store that cannot be written included)."""
    if isinstance(exc, KeyboardInterrupt):
        return "KILLED", INTERRUPTED
    return "FAILED", f"sys.exit({exc.code})" if isinstance(exc, SystemExit) else \
        disk_full(exc) or f"{type(exc).__name__}: {exc}"


def unwritable(uri: str, why: str, runs: str, sweep_id: str | None = None) -> StoreError:
    """The one-line error of a store that cannot be written, with the runs it leaves RUNNING and,
    given the sweep, how to mark them once it can be written."""
    advice = (f"; a resume (tracking.resume=true tracking.sweep_id={sweep_id}) marks them KILLED once the store "
              "can be written") if sweep_id else ""
    return StoreError(f"tracking store {uri} cannot be written ({why}): {runs} left RUNNING{advice}")


@contextmanager
def job_run(
    cfg: Mapping[str, Any], run_name: str, tags: Mapping[str, str]
) -> Iterator[JobRun]:
    """Open a run for one job; mark it FAILED (with the error as a tag) if the body, sending what
    it logged or ending it FINISHED raises, KILLED on Ctrl-C; a :class:`StoreError` saying the run
    is left RUNNING when the store cannot be written at all. What the job announced
    (:meth:`JobRun.announce`) is printed once the run is FINISHED. The run carries the host and
    process id that ran it, so a run left RUNNING by a killed process can be told from one still
    running (:func:`mark_dead_runs`)."""
    track = cfg["tracking"]
    uri = tracking_uri(track.get("uri"))
    exp = _experiment_id(uri, track["experiment"])  # first: a new store is made before a client opens it
    c = client(uri)
    all_tags = {
        f"{TAG_PREFIX}version": __version__,
        f"{TAG_PREFIX}git_commit": git_commit(),
        f"{TAG_PREFIX}config_hash": config_hash(cfg),
        f"{TAG_PREFIX}host": _host(),
        f"{TAG_PREFIX}pid": str(os.getpid()),
        **tags,
    }
    run = c.create_run(exp, run_name=run_name, tags=all_tags)
    run_id = run.info.run_id
    if announce.on_run_created is not None:
        announce.on_run_created(run_id)
    handle = JobRun(c, run_id, run.info.artifact_uri)
    handle.log_params(flatten(cfg))
    try:
        yield handle
        handle.flush()
        c.set_terminated(run_id, status="FINISHED")
    except BaseException as exc:
        status, error = ended_by(exc)
        try:
            handle.flush()
        except Exception:  # noqa: BLE001 - what the job logged is lost; its end is still recorded below
            log.debug("params and metrics of run %s could not be sent", run_id)
        problem = end_run(c, run_id, error, status)
        if problem is not None and handle.artifact_dir is not None:
            handle.drop_artifacts()  # a full disk: the failed run's files give the room to record its end
            problem = end_run(c, run_id, error, status)
        if problem is not None and not isinstance(exc, KeyboardInterrupt):
            raise unwritable(uri, problem, f"run {run_id}") from exc
        raise
    for line in handle.announcements:
        print(line)


def mark_dead_runs(uri: str | None, experiment: str, sweep_id: str, ended_pids: frozenset[int] = frozenset(),
                   reason: str | None = None) -> int:
    """Mark ``KILLED`` every RUNNING run of a sweep whose process is gone: it ran on this host and
    its process no longer exists, or is one of ``ended_pids`` (this process, after its jobs
    ended); ``reason`` is their error (default: which process ended). Runs of other hosts, or of
    live processes, are left alone. The number marked; a :class:`StoreError` naming how many are
    left RUNNING when the store cannot be written."""
    c = client(uri)
    exp = c.get_experiment_by_name(experiment)
    if exp is None:
        return 0
    query = f"tags.`{TAG_PREFIX}sweep_id` = '{sweep_id}' and attributes.status = 'RUNNING'"
    host, marked, problems = _host(), 0, []
    for run in c.search_runs([exp.experiment_id], filter_string=query, max_results=10000):
        tags = run.data.tags
        pid = tags.get(f"{TAG_PREFIX}pid", "")
        if tags.get(f"{TAG_PREFIX}host") != host or not pid.isdigit():
            continue
        if int(pid) in ended_pids or not process_alive(int(pid)):
            how = "ended without marking it" if int(pid) in ended_pids else "killed"
            problem = end_run(c, run.info.run_id, reason or f"process {pid} on {host} {how} (found RUNNING)",
                              status="KILLED")
            marked += problem is None
            problems += [problem] if problem is not None else []
    if problems:
        n = len(problems)
        raise unwritable(tracking_uri(uri), problems[0], f"{n} run{'s' * (n != 1)} of sweep {sweep_id}", sweep_id)
    return marked
