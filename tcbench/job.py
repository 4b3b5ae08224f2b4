"""One Hydra job: validate the config, run the optimisation, record it in MLflow."""

from __future__ import annotations

import hashlib
import json
import logging
import tempfile
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from tcbench.compensation_job import compensation_job_name, compensation_task_key, run_compensation_job
from tcbench.config import as_dict, validate
from tcbench.errors import error_line
from tcbench.runner import RunResult, run_optimisation
from tcbench.tasks import is_bbob, is_compensation, is_gyro

log = logging.getLogger(__name__)


def task_key(task: dict[str, Any]) -> str:
    """Leaderboard key of a task config, e.g. ``rastrigin-2d`` or ``rastrigin-10d-shifted``
    (``gyro_vmdtuning-dev0`` for the VMD tuning of a gyro, ``bbob-f03-5d`` for BBOB f3 in 5-D,
    whose instances play the part of seeds)."""
    if is_gyro(str(task["name"])):
        return compensation_task_key(task)
    if is_bbob(str(task["name"])):
        return f"bbob-f{task.get('function')!s:0>2}-{task.get('dim')}d"
    key = f"{task['name']}-{task['dim']}d"
    if task.get("shift"):
        key += "-shifted"
    if task.get("lower") is not None or task.get("upper") is not None:
        key += f"-domain{task.get('lower')}_{task.get('upper')}"
    return key


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


@dataclass(frozen=True)
class JobFailure:
    """A job that raised (or called ``sys.exit``): its name and the error, one line."""

    name: str
    error: str


# The failures of the jobs run in this process (and, in a sweep's parent, those its workers
# reported): ``tcbench run`` lists them when no tracking store records them.
FAILURES: list[JobFailure] = []


def failed(name: str, exc: BaseException) -> JobFailure:
    """Log and remember a job's failure; the sweep goes on."""
    error = f"sys.exit({exc.code})" if isinstance(exc, SystemExit) else f"{type(exc).__name__}: {exc}"
    if isinstance(exc, MemoryError):
        from tcbench.memory import ENV

        error += f" (more than one job may use here: the memory free when it started, or ${ENV})"
    failure = JobFailure(name, error_line(error))
    log.error("job %s failed: %s", name, failure.error)
    log.debug("%s", traceback.format_exc())
    FAILURES.append(failure)
    return failure


def job_name(c: dict[str, Any]) -> str:
    """``<method>-<task key>-s<seed>`` of a job, as its MLflow run is named."""
    try:
        if is_compensation(str(c["task"].get("name"))):
            return compensation_job_name(c)
        return f"{method_label(c['optimiser'])}-{task_key(c['task'])}-s{c['seed']}"
    except Exception:  # noqa: BLE001 - a config too broken to name: its failure still needs a name
        return f"job-s{c.get('seed')}"


def run_job(cfg: Any) -> RunResult | JobFailure | None:
    """Run one configured job: its result, None when resume skipped it, or a :class:`JobFailure`
    when it raised or called ``sys.exit`` (recorded FAILED when tracked); never raises but for
    ``KeyboardInterrupt``."""
    from tcbench import memory

    c = as_dict(cfg)
    try:
        with memory.limited(memory.job_budget_bytes()):
            if is_compensation(str(c["task"].get("name"))):
                return run_compensation_job(c)  # type: ignore[return-value]
            return _run_optimisation_job(c)
    except (Exception, SystemExit) as exc:  # recorded as FAILED by job_run when tracked
        return failed(job_name(c), exc)


def _run_optimisation_job(c: dict[str, Any]) -> RunResult | None:
    optimiser = {k: v for k, v in c["optimiser"].items() if k != "label"}
    ioh = {"ioh_folder": ioh_folder(c), "algorithm": method_label(c["optimiser"])}
    if not c["tracking"]["enabled"]:
        validate(c)
        return run_optimisation(c["task"], optimiser, c["budget"], c["seed"], c["progress"], **ioh)

    from tcbench import tracking

    sweep = c["tracking"].get("sweep_id") or tracking.sweep_id_from_hydra()
    tkey, method = task_key(c["task"]), method_label(c["optimiser"])
    if c["tracking"].get("resume"):
        done = tracking.finished_run(c)
        if done is not None:
            log.info("%s on %s seed %d already FINISHED in run %s; skipped", method, tkey, c["seed"], done)
            return None
    tags = {
        "tcbench.sweep_id": sweep,
        "tcbench.task": tkey,
        "tcbench.method": method,
        "tcbench.seed": str(c["seed"]),
        "tcbench.task_name": str(c["task"]["name"]),
        "tcbench.kind": "optimisation",
    }
    with tracking.job_run(c, f"{method}-{tkey}-s{c['seed']}", tags) as run:
        validate(c)
        result = run_optimisation(c["task"], optimiser, c["budget"], c["seed"], c["progress"], **ioh)
        t = result.trace
        multi = result.n_objectives > 1
        run.log_series("hv_gap" if multi else "best_f", t.best_f, t.evaluations)
        run.log_series("igd" if multi else "pop_mean_f", t.mean_f, t.evaluations)
        run.log_series("generation", [float(g) for g in t.generation], t.evaluations)
        run.log_metrics(result_metrics(result) | {"f_opt": result.f_opt})
        with tempfile.TemporaryDirectory() as tmp:
            cfg_path = Path(tmp) / "config.yaml"
            cfg_path.write_text(yaml.safe_dump(c, sort_keys=False))
            run.log_artifact(cfg_path)
            if multi:
                front = Path(tmp) / "front.csv"
                np.savetxt(front, result.front_f, delimiter=",", header=",".join(
                    f"f{i + 1}" for i in range(result.n_objectives)), comments="")
                run.log_artifact(front)
            if c["tracking"]["plots"] is not False:  # null: plot (a sweep's launcher decides)
                from tcbench import plots  # matplotlib only when a run draws

                png = plots.run_convergence(
                    Path(tmp) / "convergence.png", t.evaluations, t.best_f, t.mean_f,
                    result.f_opt, f"{method} on {tkey}, seed {c['seed']}",
                    labels=("hypervolume gap 1 - HV/HV*", "IGD") if multi else None,
                )
                run.log_artifact(png)
            if result.nonfinite:
                run.set_tag("tcbench.warning", f"{result.nonfinite} NaN/inf evaluations")
    log.info(
        "%s on %s seed %d: best %.6g (error %.3g) after %d evaluations",
        method, tkey, c["seed"], result.best_f, result.error, result.evaluations,
    )
    return result
