"""One compensation job: run it, record it in MLflow with the paper's figures."""

from __future__ import annotations

import json
import logging
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from tcbench.compensation.methods import BASELINES
from tcbench.compensation.scoring import CONVENTIONS, PRIMARY, Score
from tcbench.compensation_config import learner_of
from tcbench.config import validate
from tcbench.runner import CompensationResult, VMDTuning, run_compensation
from tcbench.tasks import is_gyro

log = logging.getLogger(__name__)


def compensation_task_key(task: dict[str, Any]) -> str:
    """Leaderboard key of a compensation task, e.g. ``msra_fulltemp-dev0``."""
    if task.get("train_files"):
        return f"{task['name']}-files"
    key = f"{task['name']}-dev{task.get('device_seed', 0)}"
    if task.get("recordings_seed", 0) != 0:
        key += f"-rec{task.get('recordings_seed')}"
    for effect, params in sorted((task.get("effects") or {}).items()):
        key += "-" + "-".join(f"{effect}.{p}={v:g}" for p, v in sorted(params.items()))
    return key


def compensation_label(learner: dict[str, Any], optimiser: dict[str, Any], task: dict[str, Any] | None = None) -> str:
    """Leaderboard name: ``raw``, ``oracle``, ``poly3``, ``IFA-BP-gd``, ``random-BP-lm`` ...; for
    the gyro task prefixed by its pipeline: ``MOVMD-TFPF+BAS-elman-adam``, ``WTD``, ``EMD-WTD+SA-BP-gd``."""
    if learner.get("label"):
        return str(learner["label"])
    name = str(learner["name"])
    if name in BASELINES or name == "poly":
        label = f"poly{learner.get('degree', 3)}" if name == "poly" else name
    else:
        opt = str(optimiser.get("label") or optimiser["name"])
        prefix = "random" if opt == "none" else opt.upper()
        label = f"{prefix}-{name.upper() if name == 'bp' else name}"
        label = f"{label}-{learner['training']}" if learner.get("training") else label
    if task is None or not is_gyro(str(task.get("name"))) or name == "oracle":
        return label
    decomposition = task.get("decomposition", "vmd")
    front = {"vmd": "MOVMD" if task.get("k") is None or task.get("alpha") is None else "VMD",
             "emd": "EMD", "none": ""}[decomposition]
    front = "-".join(p for p in (front, {"tfpf": "TFPF", "wavelet": "WTD", "none": ""}[task.get("denoise", "tfpf")]) if p)
    back = "" if name == "raw" else label + ("(T)" if task.get("inputs") == "t" else "")
    return "+".join(p for p in (front, back) if p) or "raw"


def score_document(score: Score) -> dict[str, Any]:
    """Per-recording metrics before and after, with the conventions used."""
    return {
        "protocol": score.protocol,
        "conventions": CONVENTIONS[score.protocol],
        score.train_key: score.train_rmse,
        "recordings": [{"name": r.name, "before": r.before, "after": r.after} for r in score.recordings],
        "summary": score.summary(),
    }


def figures(score: Score, history_loss: list[float] | None, where: Path, title: str,
            tuning: VMDTuning | None = None) -> list[Path]:
    """The paper's figures for this run: Fig. 7 (zero bias) or Figs. 8-10 (full temperature) of
    seed 000; Figs. 11-14 and 17-19 of seed 001 (gyro)."""
    from tcbench.compensation import plots as cplots

    if score.protocol == "gyro":
        from tcbench.compensation.gyro.plots import run_figures

        paths = run_figures(score, tuning, where, title)
    else:
        paths = _msra_figures(score, where, title)
    if history_loss and len(history_loss) > 1:
        paths.append(cplots.training_curve(where / "training_curve.png", history_loss, f"{title}: training"))
    return paths


def _msra_figures(score: Score, where: Path, title: str) -> list[Path]:
    """Seed 000's Fig. 7 (zero bias) or Figs. 8-9 (full temperature) per test recording."""
    from tcbench.compensation import plots as cplots

    paths = []
    for i, r in enumerate(score.recordings, start=1):
        if r.nodes_before is not None and r.nodes_after is not None:
            paths.append(cplots.four_position_before_after(
                where / f"fig8_test{i}.png", r.nodes_before, r.nodes_after, f"{title}: test {i} ({r.name})"))
            paths.append(cplots.positions_vs_temperature(
                where / f"fig9_test{i}.png", r.nodes_before, r.nodes_after, f"{title}: test {i} ({r.name})"))
        elif r.t_s is not None:
            paths.append(cplots.zero_bias_before_after(
                where / f"fig7_test{i}.png", r.t_s, r.before_ug, r.after_ug, f"{title}: test {i} ({r.name})"))
    return paths


def gyro_tables(result: CompensationResult, where: Path) -> list[Path]:
    """CSV artifacts of a gyro run: the Allan deviation before and after per test record
    (``allan_test<i>.csv``: tau_s, adev_before_dph, adev_after_dph) and the VMD tuning's
    non-dominated set (``vmd_front.csv``)."""
    files = []
    for i, r in enumerate(result.score.recordings, start=1):
        before, after = getattr(r, "allan_before", None), getattr(r, "allan_after", None)
        if before is None or after is None:
            continue
        path = where / f"allan_test{i}.csv"
        np.savetxt(path, np.column_stack([before.tau_s, before.adev * 3600.0, after.adev * 3600.0]),
                   delimiter=",", header="tau_s,adev_before_dph,adev_after_dph", comments="")
        files.append(path)
    if result.tuning is not None:
        path = where / "vmd_front.csv"
        np.savetxt(path, np.column_stack([result.tuning.front_x, result.tuning.front_f]), delimiter=",",
                   header="k,alpha,mean_fuzzy_entropy,mean_permutation_entropy", comments="")
        files.append(path)
    return files


def compensation_job_name(c: dict[str, Any]) -> str:
    """``<method>-<task key>-s<seed>`` of a compensation job, as its MLflow run is named."""
    learner = learner_of(c)
    return f"{compensation_label(learner, c['optimiser'], c['task'])}-{compensation_task_key(c['task'])}-s{c['seed']}"


def run_compensation_job(c: dict[str, Any]) -> CompensationResult | None:
    """Run one compensation job (None when resume skips it); what it raises, tracked jobs
    record as FAILED before it propagates (:func:`tcbench.job.run_job` reports it)."""
    learner = learner_of(c)
    c = {**c, "learner": learner}  # the default learner made explicit, so it is logged and hashed
    optimiser = {k: v for k, v in c["optimiser"].items() if k != "label"}
    learner_cfg = {k: v for k, v in learner.items() if k != "label"}
    if not c["tracking"]["enabled"]:
        validate(c)
        return run_compensation(c["task"], learner_cfg, optimiser, c["budget"], c["seed"], c["progress"])

    from tcbench import tracking

    sweep = c["tracking"].get("sweep_id") or tracking.sweep_id_from_hydra()
    tkey, method = compensation_task_key(c["task"]), compensation_label(learner, c["optimiser"], c["task"])
    name = f"{method}-{tkey}-s{c['seed']}"
    if c["tracking"].get("resume"):
        done = tracking.finished_run(c)
        if done is not None:
            log.info("%s already FINISHED in run %s; skipped", name, done)
            return None
    tags = {
        "tcbench.sweep_id": sweep, "tcbench.task": tkey, "tcbench.method": method,
        "tcbench.seed": str(c["seed"]), "tcbench.task_name": str(c["task"]["name"]),
        "tcbench.kind": "compensation",
    }
    with tracking.job_run(c, name, tags) as run:
        validate(c)
        result = run_compensation(c["task"], learner_cfg, optimiser, c["budget"], c["seed"], c["progress"])
        summary = result.score.summary()
        primary = PRIMARY[result.score.protocol]
        tuned = {"vmd_k": float(result.tuning.k), "vmd_alpha": result.tuning.alpha,
                 "seconds_tuning": result.tuning.seconds} if result.tuning else {}
        values = summary | tuned | {
            "final_error": summary[primary], "search_evaluations": result.search_evaluations,
            "init_loss": result.init_loss, "seconds_search": result.seconds_search,
            "seconds_train": result.seconds_train,
        }
        run.log_metrics({k: v for k, v in values.items() if not np.isnan(v)})
        if result.trace.evaluations:
            run.log_series("init_best_f", result.trace.best_f, result.trace.evaluations)
        loss = result.history.loss if result.history else None
        if loss:
            run.log_series("train_loss", loss, list(range(len(loss))))
        with tempfile.TemporaryDirectory() as tmp:
            where = Path(tmp)
            (where / "config.yaml").write_text(yaml.safe_dump(c, sort_keys=False))
            (where / "scores.json").write_text(json.dumps(score_document(result.score), indent=2))
            files = [where / "config.yaml", where / "scores.json"]
            for i, r in enumerate(result.score.recordings, start=1):
                if r.nodes_after is not None:
                    nodes = r.nodes_after.add_suffix("_after").join(r.nodes_before.add_suffix("_before"))
                    nodes.to_csv(where / f"nodes_test{i}.csv", index=False)
                    files.append(where / f"nodes_test{i}.csv")
            files += gyro_tables(result, where)
            if c["tracking"]["plots"] is not False:  # null: plot (a sweep's launcher decides)
                files += figures(result.score, loss, where, f"{method} on {tkey}, seed {c['seed']}",
                                 result.tuning)
            for f in files:
                run.log_artifact(f)
    s = result.score.summary()
    log.info("%s: %s %.4g (raw %.4g), %s %.3g", name, primary, s[primary], s[f"raw_{primary}"],
             result.score.train_key, s[result.score.train_key])
    return result
