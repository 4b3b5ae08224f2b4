"""The compensation job kind: a learner (or a baseline) compensating an MSRA or gyro task,
scored with the paper's metrics and figures."""

from __future__ import annotations

import json
import logging
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from tcbench.compensation.methods import BASELINE_LABELS, BASELINES
from tcbench.compensation.scoring import CONVENTIONS, PRIMARY, Score
from tcbench.errors import ConfigError
from tcbench.optimisers.registry import NO_SEARCH
from tcbench.runner.compensation_config import learner_of
from tcbench.runner.compensation_job import CompensationJob, draw_of, in_sample, prepare_job
from tcbench.runner.prepared_job import keep
from tcbench.runner.kinds import JobKind, JobNames
from tcbench.runner.loop import CompensationResult, VMDTuning, compensate
from tcbench.sensors.data_hash import DataHashError, content_hash
from tcbench.tasks import task_spec

log = logging.getLogger(__name__)
TAG_FILES_CHARS = 1000  # the file lists in a run's tags, cut beyond this


def _poly_label(learner: dict[str, Any]) -> str:
    """``poly3``; ``_rate`` with the temperature rate, ``_runs`` fitted within runs."""
    label = f"poly{learner.get('degree', 3)}"
    label += "_rate" if learner.get("form") == "bias_rate" else ""
    return label + ("_runs" if learner.get("offsets") == "per_run" else "")


# A gyro task's rows named without its pipeline (the oracles and ``diagnosed``), and those that
# are the pipeline alone (``raw``: no drift learner).
WITHOUT_PIPELINE = frozenset(name for name in BASELINES if name.startswith("oracle")) | {"model"}
PIPELINE_ALONE = frozenset({"raw"})

UNCLAMPED = "-unclamped"  # the label's suffix when task.clamp_inputs=false (the default holds inputs to the training range)
LEARNER_LABELS = {"bp": "BP"}  # a searched learner's name in its row's label where it differs (IFA-BP-gd)

# The rows named without an optimiser, by learner: the baselines and the fitted polynomial.
FIXED_LABELS: dict[str, Callable[[dict[str, Any]], str]] = {
    **{name: lambda learner, name=name: BASELINE_LABELS.get(name, name) for name in BASELINES},
    "poly": _poly_label,
}


def compensation_label(learner: dict[str, Any], optimiser: dict[str, Any], task: dict[str, Any] | None = None) -> str:
    """Leaderboard name: ``raw``, ``oracle``, ``diagnosed`` (``learner=model``), ``poly3`` (``poly3_rate`` with the temperature rate, ``poly3_runs`` fitted within runs), ``IFA-BP-gd``, ``random-BP-lm``, ``random-BP-lm-matlab`` (``learner.preset=matlab``), ``poly3-unclamped`` (a fitted
    learner with ``task.clamp_inputs=false``) ...; for
    the gyro task prefixed by its pipeline: ``MOVMD-TFPF+BAS-elman-adam``, ``WTD``, ``EMD-WTD+SA-BP-gd``
    (not the rows that run without it: the oracles and ``diagnosed``)."""
    if learner.get("label"):
        return str(learner["label"])
    name = str(learner["name"])
    if name in FIXED_LABELS:
        label = FIXED_LABELS[name](learner)
    else:
        opt = str(optimiser.get("label") or optimiser["name"])
        prefix = "random" if opt == NO_SEARCH else opt.upper()
        label = f"{prefix}-{LEARNER_LABELS.get(name, name)}"
        label = f"{label}-{learner['training']}" if learner.get("training") else label
        label = f"{label}-{learner['preset']}" if learner.get("preset") else label  # IFA-BP-gd-matlab
    if task is not None and task.get("clamp_inputs") is False and name not in BASELINES:
        label += UNCLAMPED  # a fitted learner let to extrapolate beside the default's clamped row
    pipeline = task_spec(str(task["name"])).pipeline if task is not None else None
    if pipeline is None or name in WITHOUT_PIPELINE:
        return label
    front = pipeline(task)  # type: ignore[arg-type]
    back = "" if name in PIPELINE_ALONE else label + ("(T)" if task.get("inputs") == "t" else "")
    return "+".join(p for p in (front, back) if p) or "raw"


def in_sample_warning(shared: list[str]) -> str:
    """The one line a run that tests on its training data warns with."""
    its = "its" if len(shared) == 1 else "their"
    return f"train_files and test_files share {', '.join(shared)}: {its} test scores are in-sample"


def _listed(paths: list[str]) -> str:
    text = ", ".join(str(p) for p in paths)
    return text if len(text) <= TAG_FILES_CHARS else text[:TAG_FILES_CHARS - 1] + "…"


def data_tags(task: dict[str, Any]) -> dict[str, str]:
    """Tags of a run on the user's recordings: the content hash of its data (training then test
    files, :func:`~tcbench.sensors.data_hash.content_hash`), the files as given and, when it tests
    on training data, ``tcbench.in_sample`` naming the shared files; none on simulated data."""
    train, test = list(task.get("train_files") or []), list(task.get("test_files") or [])
    if not train:
        return {}
    tags = {"tcbench.data_hash": content_hash(train, test), "tcbench.train_files": _listed(train),
            "tcbench.test_files": _listed(test)}
    shared = in_sample(task)
    return tags | ({"tcbench.in_sample": _listed(shared)} if shared else {})


def score_document(score: Score) -> dict[str, Any]:
    """Per-recording metrics before and after, with the conventions used."""
    return {
        "protocol": score.protocol,
        "conventions": CONVENTIONS[score.protocol],
        score.train_key: score.train_rmse,
        "recordings": [{"name": r.name, "before": r.before, "after": r.after} for r in score.recordings],
        "summary": score.summary(),
    }


def _gyro_figures(score: Score, tuning: VMDTuning | None, where: Path, title: str) -> list[Path]:
    """Seed 001's Figs. 11-14 and 17-19."""
    from tcbench.compensation.gyro.plots import run_figures

    return run_figures(score, tuning, where, title)


def figures(score: Score, history_loss: list[float] | None, where: Path, title: str,
            tuning: VMDTuning | None = None) -> list[Path]:
    """The paper's figures for this run: Fig. 7 (zero bias) or Figs. 8-10 (full temperature) of
    seed 000; Figs. 11-14 and 17-19 of seed 001 (gyro)."""
    from tcbench.compensation import plots as cplots

    paths = FIGURES.get(score.protocol, _msra_figures)(score, tuning, where, title)
    if history_loss and len(history_loss) > 1:
        paths.append(cplots.training_curve(where / "training_curve.png", history_loss, f"{title}: training"))
    return paths


def _msra_figures(score: Score, tuning: VMDTuning | None, where: Path, title: str) -> list[Path]:
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


# A run's figures by protocol: ``(score, tuning, where, title) -> paths``; the MSRA tasks' otherwise.
FIGURES: dict[str, Callable[[Score, VMDTuning | None, Path, str], list[Path]]] = {"gyro": _gyro_figures}


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


class CompensationKind(JobKind):
    """A compensation job: checked and prepared once (:class:`~tcbench.runner.compensation_job.CompensationJob`,
    its env built once per process), then run, recorded and summed up from that job."""

    def plan_check(self, c: dict[str, Any]) -> None:
        keep(self.job(c))  # the env built for the check serves the job when it runs in this process

    def names(self, c: dict[str, Any]) -> JobNames:
        learner_of(c)  # a config without a learner: one line naming the key
        try:
            tkey = task_spec(str(c["task"]["name"])).key(c["task"])
            data = data_tags(c["task"])
        except DataHashError as exc:
            raise ConfigError(str(exc)) from None
        method = compensation_label(c["learner"], c["optimiser"], c["task"])
        draw, split = draw_of(c), "files" if c["task"].get("train_files") else c["task"].get("split")
        return JobNames(f"{method}-{tkey}-s{c['seed']}", tkey, method, int(c["seed"]),
                        {"tcbench.task_name": str(c["task"]["name"]), **data,
                         **({"tcbench.draw": str(draw)} if draw is not None else {}),
                         **({"tcbench.split": str(split)} if split is not None else {})})

    def job(self, c: dict[str, Any]) -> CompensationJob:
        return prepare_job(c, self.names)

    def execute(self, job: CompensationJob) -> CompensationResult:
        if job.in_sample:
            log.warning("%s", in_sample_warning(list(job.in_sample)))
        return compensate(job.env, job.learner.name, job.optimiser.name, job.optimiser.params, job.budget,
                          job.seed, job.progress)

    def record(self, run: Any, result: CompensationResult, job: CompensationJob, where: Path) -> list[Path]:
        summary = result.score.summary()
        primary = PRIMARY[result.score.protocol]
        tuned = {"vmd_k": float(result.tuning.k), "vmd_alpha": result.tuning.alpha,
                 "seconds_tuning": result.tuning.seconds} if result.tuning else {}
        values = summary | tuned | {
            "final_error": summary[primary], "search_evaluations": result.search_evaluations,
            "init_loss": result.init_loss, "seconds_search": result.seconds_search,
            "seconds_train": result.seconds_train,
        }
        for epochs, at in result.score.extra.get("checkpoints", {}).items():  # e.g. at1000.bias_variation_ug
            values |= {f"at{epochs}.{k}": v for k, v in at.items()}
        run.log_metrics({k: v for k, v in values.items() if not np.isnan(v)})
        if result.trace.evaluations:
            run.log_series("init_best_f", result.trace.best_f, result.trace.evaluations)
        loss = result.history.loss if result.history else None
        if loss:
            run.log_series("train_loss", loss, list(range(len(loss))))
        (where / "scores.json").write_text(json.dumps(score_document(result.score), indent=2))
        files = [where / "scores.json"]
        for i, r in enumerate(result.score.recordings, start=1):
            if r.nodes_after is not None:
                nodes = r.nodes_after.add_suffix("_after").join(r.nodes_before.add_suffix("_before"))
                nodes.to_csv(where / f"nodes_test{i}.csv", index=False)
                files.append(where / f"nodes_test{i}.csv")
        files += gyro_tables(result, where)
        from tcbench.compensation.run_device import BASELINE_FITS, FILE, device_document

        name, static = job.learner.name, hasattr(job.env, "clamp_inputs")  # a static-input task (not the gyro's)
        if (name in BASELINE_FITS and static) or (name not in BASELINES and getattr(job.env, "learner", None) is not None):
            fitted = result.score.extra.get(BASELINE_FITS.get(name) or "")  # a baseline's fitted model
            (where / FILE).write_text(json.dumps(device_document(job.env, name, job.names.method, fitted), indent=1))
            files.append(where / FILE)
        if job.plots is not False:  # null: plot (a sweep's launcher decides)
            n = job.names
            files += figures(result.score, loss, where, f"{n.method} on {n.task}, seed {job.seed}", result.tuning)
        return files

    def summary(self, result: CompensationResult, job: CompensationJob) -> str:
        s, primary = result.score.summary(), PRIMARY[result.score.protocol]
        return (f"{job.names.run}: {primary} {s[primary]:.4g} (raw {s[f'raw_{primary}']:.4g}), "
                f"{result.score.train_key} {s[result.score.train_key]:.3g}")
