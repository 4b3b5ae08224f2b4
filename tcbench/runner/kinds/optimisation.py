"""The optimisation job kind: an optimiser on a function, BBOB, multi-objective or VMD-tuning task."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np

from tcbench.runner.kinds import JobKind, JobNames
from tcbench.runner.loop import RunResult, run_optimisation
from tcbench.runner.optimisation_job import OptimisationJob, prepare_job
from tcbench.runner.prepared_job import keep
from tcbench.tasks import task_spec


def task_key(task: dict[str, Any]) -> str:
    """Leaderboard key of a task config from its spec: ``rastrigin-2d``, ``rastrigin-10d-shifted``,
    ``bbob-f03-5d``, ``gyro_vmdtuning-dev0``, ``msra_fulltemp-dev0`` ..."""
    return task_spec(str(task["name"])).key(task)


def method_label(opt: dict[str, Any]) -> str:
    """Leaderboard name of a method: the optimiser's ``label`` if set, else its name."""
    return str(opt.get("label") or opt["name"])


def result_metrics(result: RunResult) -> dict[str, float]:
    """Final metrics of a run as logged to MLflow."""
    metrics = {
        "final_best": result.best_f,
        "final_error": result.error,
        "evaluations": result.evaluations,
        "generations": result.generations,
        "nonfinite_evaluations": result.nonfinite,
        "target_hit": float(result.target_hit_at is not None),
    }
    if result.target_hit_at is not None:
        metrics["evals_to_target"] = result.target_hit_at
    if result.n_objectives > 1:
        metrics |= {"hypervolume": float(result.hypervolume), "igd": float(result.igd)}
    return metrics


def ioh_folder(c: dict[str, Any]) -> Path | None:
    """Where a job writes its IOHprofiler log (``tracking.ioh_dir``), or None:
    ``<ioh_dir>/<method>/<task key>-s<seed>-<hash of the job's config>``."""
    root = (c.get("tracking") or {}).get("ioh_dir")
    if not root:
        return None
    content = {k: v for k, v in c.items() if k not in {"tracking", "progress"}}
    digest = hashlib.sha256(json.dumps(content, sort_keys=True, default=str).encode()).hexdigest()[:8]
    return Path(root) / method_label(c["optimiser"]) / f"{task_key(c['task'])}-s{c['seed']}-{digest}"


class OptimisationKind(JobKind):
    """An optimisation job: checked and prepared once (:class:`~tcbench.runner.optimisation_job.OptimisationJob`,
    its env built once per process), then run, recorded and summed up from that job."""

    plots_in_sweeps = False  # a convergence PNG per run costs more than the run; the leaderboard draws them

    def plan_check(self, c: dict[str, Any]) -> None:
        keep(self.job(c))  # the env built for the check serves the job when it runs in this process

    def names(self, c: dict[str, Any]) -> JobNames:
        tkey, method = task_key(c["task"]), method_label(c["optimiser"])
        return JobNames(f"{method}-{tkey}-s{c['seed']}", tkey, method, int(c["seed"]),
                        {"tcbench.task_name": str(c["task"]["name"])})

    def job(self, c: dict[str, Any]) -> OptimisationJob:
        return prepare_job(c, self.names, ioh_folder)

    def execute(self, job: OptimisationJob) -> RunResult:
        return run_optimisation(job.task, job.optimiser_config, job.budget, job.seed, job.progress,
                                ioh_folder=job.ioh_folder, algorithm=job.names.method, env=job.env)

    def record(self, run: Any, result: RunResult, job: OptimisationJob, where: Path) -> list[Path]:
        t = result.trace
        multi = result.n_objectives > 1
        run.log_series("hv_gap" if multi else "best_f", t.best_f, t.evaluations)
        run.log_series("igd" if multi else "pop_mean_f", t.mean_f, t.evaluations)
        run.log_series("generation", [float(g) for g in t.generation], t.evaluations)
        run.log_metrics(result_metrics(result) | {"f_opt": result.f_opt})
        if result.nonfinite:
            run.set_tag("tcbench.warning", f"{result.nonfinite} NaN/inf evaluations")
        files = []
        if multi:
            front = where / "front.csv"
            np.savetxt(front, result.front_f, delimiter=",", header=",".join(
                f"f{i + 1}" for i in range(result.n_objectives)), comments="")
            files.append(front)
        if job.plots is not False:  # null: plot (a sweep's launcher decides)
            from tcbench import plots  # matplotlib only when a run draws

            names = job.names
            files.append(plots.run_convergence(
                where / "convergence.png", t.evaluations, t.best_f, t.mean_f, result.f_opt,
                f"{names.method} on {names.task}, seed {job.seed}",
                labels=("hypervolume gap 1 - HV/HV*", "IGD") if multi else None,
            ))
        return files

    def summary(self, result: RunResult, job: OptimisationJob) -> str:
        n = job.names
        return (f"{n.method} on {n.task} seed {job.seed}: best {result.best_f:.6g} (error {result.error:.3g}) "
                f"after {result.evaluations} evaluations")
