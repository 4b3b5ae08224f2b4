"""tcbench's Hydra sweeper and launcher (a Hydra plugin: Hydra only loads plugins from the
``hydra_plugins`` package): a sweep composes its config once per combination of
non-seed values, not once (twice) per job.

Hydra's basic sweeper composes every job's config to check it, and its basic launcher composes it
again before running it: about 0.15 s per compose, which is most of a small job's cost. The jobs
of a tcbench sweep usually differ only in ``seed``, so here the jobs are grouped by their other
overrides, each group's config is composed (and so checked) once, and every job gets a copy with
its own seed and job number.

- :class:`GroupingSweeper` is Hydra's basic sweeper (same ``params`` and batching) checking one
  config per group ahead of another launcher, none ahead of tcbench's, which composes every group
  before its first job starts (Hydra's sweeper would compose each group a second time).
- :class:`GroupedLauncher` runs the jobs in this process (``n_jobs: 1``, the default) or in
  ``n_jobs`` worker processes, each importing tcbench once and keeping its MLflow client for all
  the jobs it runs. Every job still gets its folder ``<sweep dir>/<subdir>`` with
  ``.hydra/config.yaml`` and ``.hydra/overrides.yaml``; the job's log goes to the console, and
  everything else it records goes to MLflow as before. ``tracking.plots: null`` becomes false for
  the jobs of an optimisation sweep (a convergence PNG per run costs more than the run; the
  leaderboard draws them over seeds) and true for compensation sweeps. A job that raises, calls ``sys.exit`` or
  whose worker dies is recorded FAILED (or, untracked, listed by ``tcbench run`` after the sweep)
  and the sweep goes on; workers exit with the sweep's main process (:mod:`.pool`).

Both are the defaults of ``tcbench run`` (``hydra/sweeper: tcbench``, ``hydra/launcher: tcbench``);
``hydra/launcher=joblib`` or ``submitit_slurm`` still work as before.
"""

from __future__ import annotations

import copy
import hashlib
import json
import logging
import os
import re
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml
from hydra._internal.core_plugins.basic_sweeper import BasicSweeper
from hydra.core.utils import JobReturn, JobStatus, setup_globals
from hydra.plugins.launcher import Launcher
from hydra.types import HydraContext, TaskFunction
from omegaconf import DictConfig, OmegaConf, open_dict

from hydra_plugins.tcbench_launcher.pool import run_jobs
from tcbench.runner.job import plots_default

log = logging.getLogger(__name__)


def _literal_seed(override: str) -> bool:
    return override.startswith("seed=") and override[5:].lstrip("-").isdigit()


def split_seed(overrides: Sequence[str]) -> tuple[tuple[str, ...], str | None]:
    """A job's overrides without its ``seed=<integer>`` one, and that seed (None if absent). A
    seed given any other way (``seed='${task.instance}'``) stays with the overrides, so it is
    composed and resolved like any other value."""
    rest = tuple(o for o in overrides if not _literal_seed(o))
    seeds = [o[5:] for o in overrides if _literal_seed(o)]
    return rest, (seeds[-1] if seeds else None)


def groups(job_overrides: Sequence[Sequence[str]]) -> dict[tuple[str, ...], list[int]]:
    """Job indices by their overrides without the seed, in first-seen order."""
    out: dict[tuple[str, ...], list[int]] = {}
    for i, overrides in enumerate(job_overrides):
        out.setdefault(split_seed(overrides)[0], []).append(i)
    return out


class GroupedLauncher(Launcher):
    """Runs a sweep's jobs from one composed config per group; see the module docstring."""

    def __init__(self, n_jobs: int = 1) -> None:
        if int(n_jobs) != n_jobs or n_jobs < 1:
            raise ValueError(f"hydra.launcher.n_jobs must be a positive integer, got {n_jobs}")
        self.n_jobs = int(n_jobs)
        self.config: DictConfig | None = None
        self.hydra_context: HydraContext | None = None
        self.task_function: TaskFunction | None = None

    def setup(self, *, hydra_context: HydraContext, task_function: TaskFunction, config: DictConfig) -> None:
        self.config = config
        self.hydra_context = hydra_context
        self.task_function = task_function

    def launch(self, job_overrides: Sequence[Sequence[str]], initial_job_idx: int) -> Sequence[JobReturn]:
        assert self.config is not None and self.hydra_context is not None
        setup_globals()
        sweep_dir = Path(str(self.config.hydra.sweep.dir))
        sweep_id = hashlib.sha256(str(sweep_dir.resolve()).encode()).hexdigest()[:12]
        jobs: list[tuple[int, list[str], dict[str, Any], str]] = []
        folders: list[tuple[Path, str | None, dict[str, Any], list[str]]] = []
        loader = self.hydra_context.config_loader
        for indices in groups(job_overrides).values():
            composed = loader.load_sweep_config(self.config, list(job_overrides[indices[0]]))
            per_job = interpolates_seed(composed)  # e.g. out=cal/${seed}: each seed its own resolution
            hydra_cfg = composed.hydra
            task = _task_config(composed, sweep_id)
            for i in indices:
                num = initial_job_idx + i
                overrides = list(job_overrides[i])
                seed = split_seed(overrides)[1]
                if per_job and i != indices[0]:
                    composed = loader.load_sweep_config(self.config, overrides)
                    hydra_cfg, task = composed.hydra, _task_config(composed, sweep_id)
                cfg = copy.deepcopy(task)
                if seed is not None:
                    cfg["seed"] = int(seed)
                with open_dict(hydra_cfg):
                    hydra_cfg.job.num = num
                    hydra_cfg.job.id = num
                out = sweep_dir / str(OmegaConf.select(hydra_cfg, "sweep.subdir"))
                folders.append((out, str(hydra_cfg.output_subdir) if hydra_cfg.output_subdir else None, cfg, overrides))
                jobs.append((num, overrides, cfg, str(out)))
        sweep_dir.mkdir(parents=True, exist_ok=True)  # every config composed: the job folders
        for folder in folders:
            _write_job_dir(*folder)
        jobs.sort(key=lambda j: j[0])
        log.info("Launching %d jobs (%d configs composed) %s", len(jobs), len(groups(job_overrides)),
                 "in this process" if self.n_jobs == 1 else f"on {self.n_jobs} worker processes")
        progress = Progress(len(jobs))
        if self.n_jobs == 1 or len(jobs) == 1:
            outcomes = []
            for i, (_, _, cfg, _) in enumerate(jobs):
                outcomes.append(_run_one(cfg))
                progress(i, outcomes[-1][0])
        else:
            outcomes = _run_parallel([cfg for _, _, cfg, _ in jobs], self.n_jobs, progress)
        returns = []
        for (_, overrides, cfg, out), (_ok, value) in zip(jobs, outcomes, strict=True):
            # COMPLETED either way: a failed job's JobFailure is no exception for Hydra to raise,
            # which would end the sweep; tcbench reports the failures after it.
            ret = JobReturn(overrides=overrides, cfg=OmegaConf.create(cfg), working_dir=out,
                            task_name=str(self.config.hydra.job.name), status=JobStatus.COMPLETED)
            ret.return_value = value
            returns.append(ret)
        return returns


class Progress:
    """The sweep's one progress display, the same for every job kind: a log line as each job
    ends with the jobs done, failed, the time taken and the time left at this pace."""

    def __init__(self, total: int) -> None:
        self.total, self.done, self.failed = total, 0, 0
        self.started = time.monotonic()

    def __call__(self, index: int, ok: bool) -> None:
        self.done += 1
        self.failed += not ok
        elapsed = time.monotonic() - self.started
        left = elapsed / self.done * (self.total - self.done)
        log.info("sweep: %d/%d jobs done (%d failed), %.0f s so far, about %.0f s left",
                 self.done, self.total, self.failed, elapsed, left)


def interpolates_seed(cfg: DictConfig) -> bool:
    """True when a value of the job's config (``hydra`` aside) interpolates ``seed``: such a
    config is resolved per job, not once for all the seeds of a group."""
    plain = OmegaConf.to_container(cfg, resolve=False)
    plain.pop("hydra", None)  # type: ignore[union-attr]
    return bool(_SEED_INTERPOLATION.search(json.dumps(plain, default=str)))


_SEED_INTERPOLATION = re.compile(r"\$\{[^}]*\bseed\b")


def _task_config(composed: DictConfig, sweep_id: str) -> dict[str, Any]:
    """The job's plain, resolved config (``hydra`` aside) with the sweep's tracking defaults."""
    task = {key: _resolved(composed, key) for key in composed if key != "hydra"}
    track = task.setdefault("tracking", {})
    if not track.get("sweep_id"):
        track["sweep_id"] = sweep_id
    if track.get("plots") is None:  # per kind: a convergence PNG per optimisation run is noise
        track["plots"] = plots_default(task)
    return task


def _resolved(cfg: DictConfig, key: str) -> Any:
    """``cfg[key]`` as plain, resolved data (interpolations resolved against the whole config)."""
    node = cfg._get_node(key)
    return OmegaConf.to_container(node, resolve=True) if OmegaConf.is_config(node) else cfg[key]


def _write_job_dir(out: Path, subdir: str | None, cfg: dict[str, Any], overrides: list[str]) -> None:
    """The job's folder with its resolved config and overrides, as Hydra writes them; an
    ``OSError`` naming the folder if it cannot be written (a full disk)."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        if subdir is None:
            return
        meta = out / subdir
        meta.mkdir(parents=True, exist_ok=True)
        dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
        (meta / "config.yaml").write_text(yaml.dump(cfg, Dumper=dumper, sort_keys=False))
        (meta / "overrides.yaml").write_text(yaml.dump(overrides, Dumper=dumper))
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror, str(out)) from None


def _run_one(cfg: dict[str, Any]) -> tuple[bool, Any]:
    """Run one job's config; (True, result), or (False, its :class:`~tcbench.runner.job.JobFailure`)."""
    from tcbench.runner.job import JobFailure, run_job

    value = run_job(cfg)  # never raises: a failure comes back as a JobFailure
    return not isinstance(value, JobFailure), value


def _worker_job(cfg: dict[str, Any]) -> tuple[bool, Any]:
    ok, value = _run_one(cfg)
    return ok, (value if not ok else None)


def _worker_init() -> None:
    logging.basicConfig(level=logging.INFO, format="[%(asctime)s][%(name)s][%(levelname)s] - %(message)s")


def _run_parallel(configs: list[dict[str, Any]], n_jobs: int,
                  on_done: Any = None) -> list[tuple[bool, Any]]:
    """Run the configs on ``n_jobs`` fresh worker processes (spawned: no inherited database
    connections), results in order; a worker that dies fails its job only
    (:func:`.pool.run_jobs`). The workers' failures join this process's :data:`tcbench.runner.job.FAILURES`."""
    from tcbench.runner.job import FAILURES, JobFailure, job_name

    def lost(index: int, run_id: str, why: str) -> None:
        from tcbench.tracking import store as tracking

        tracking.mark_failed(tracking.client((configs[index].get("tracking") or {}).get("uri")), run_id, why)

    workers = min(n_jobs, len(configs), os.cpu_count() or n_jobs)
    outcomes = run_jobs(configs, workers, _worker_job, init=_worker_init, on_lost_run=lost, on_done=on_done)
    for cfg, (ok, value) in zip(configs, outcomes, strict=True):
        if not ok:
            if not isinstance(value, JobFailure):
                value = JobFailure(job_name(cfg), f"{type(value).__name__}: {value}")
                log.error("job %s failed: %s", value.name, value.error)
            FAILURES.append(value)
    return outcomes


class GroupingSweeper(BasicSweeper):
    """Hydra's basic sweeper, checking one composed config per group of jobs that differ only in
    their seed; none ahead of tcbench's launcher, which composes every group in this process before
    its first job starts (a config that does not compose stops the sweep there, with nothing run
    and no job folder written)."""

    def validate_batch_is_legal(self, batch: Sequence[Sequence[str]]) -> None:
        if isinstance(self.launcher, GroupedLauncher):
            return
        firsts = [batch[idx[0]] for idx in groups(batch).values()]
        super().validate_batch_is_legal(firsts)
