"""The ask/tell loop: the one place where a task and an optimiser meet."""

from __future__ import annotations

import functools
import json
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np
from tqdm.auto import tqdm

import tcbench.tasks as tasks
from tcbench.metrics.multiobjective import igd
from tcbench.optimisers import registry
from tcbench.optimisers.protocol import Optimiser, ProtocolError
from tcbench.runner.remembered import key_of, remembered

if TYPE_CHECKING:  # the compensation side (simulators, scipy) loads only when a compensation run needs it
    from tcbench.compensation.scoring import Score
    from tcbench.learners.base import FitHistory

log = logging.getLogger(__name__)


@dataclass
class Trace:
    """Per-generation history of one run (generation 0 is the initial population).

    Single objective: ``best_f`` best so far, ``mean_f`` population mean. Several objectives:
    ``best_f`` is the hypervolume gap ``1 - HV/HV*`` of everything evaluated so far, ``mean_f``
    its IGD to the true front; for a task whose true front is unknown (``tcbench/Gyro-VMDTuning-v0``)
    ``best_f`` is ``-HV`` and ``mean_f`` the size of the non-dominated set."""

    generation: list[int] = field(default_factory=list)
    evaluations: list[int] = field(default_factory=list)
    best_f: list[float] = field(default_factory=list)
    mean_f: list[float] = field(default_factory=list)


@dataclass
class RunResult:
    """Outcome of one optimisation run. For several objectives ``best_f`` is the final
    hypervolume gap ``1 - HV/HV*`` (``f_opt`` = 0) and ``front_f`` the non-dominated set."""

    best_f: float
    best_x: np.ndarray
    f_opt: float
    evaluations: int
    budget: int
    target_precision: float
    target_hit_at: int | None
    nonfinite: int
    generations: int
    trace: Trace
    n_objectives: int = 1
    hypervolume: float | None = None
    igd: float | None = None
    front_f: np.ndarray | None = None

    @property
    def error(self) -> float:
        """``best_f - f_opt``: distance of the final best from the optimum value."""
        return self.best_f - self.f_opt


def seed_streams(seed: int) -> tuple[int, np.random.Generator]:
    """Independent streams for the task instance and the optimiser from one run seed."""
    env_seq, opt_seq = np.random.SeedSequence(seed).spawn(2)
    return int(env_seq.generate_state(1)[0]), np.random.default_rng(opt_seq)


def make_task(task: dict[str, Any], budget: int) -> Any:
    """Build the task environment from its config (``name``, ``dim``, ``shift`` ...)."""
    kwargs = tasks.task_kwargs(task)
    env = gym.make(tasks.task_id(task["name"]), budget=budget, **kwargs)
    return env.unwrapped


def checked_batch(opt: Optimiser, x: np.ndarray, env: Any) -> np.ndarray:
    """``x`` if it is a valid batch for ``env``; else a :class:`ProtocolError` naming ``opt``
    (guards against plugins that bypass the base class's own checks)."""
    x = np.asarray(x, dtype=np.float64)
    left = env.budget - env.evaluations
    problem = None
    if x.ndim != 2 or x.shape[1] != env.dim:
        problem = f"asked a batch of shape {x.shape}, expected (k, {env.dim})"
    elif not 0 < x.shape[0] <= left:
        problem = f"asked {x.shape[0]} evaluations with {left} left in the budget of {env.budget}"
    elif not np.all(np.isfinite(x)) or np.any(x < env.lower) or np.any(x > env.upper):
        problem = "asked points outside the bounds"
    if problem:
        raise ProtocolError(f"optimiser {opt.name or type(opt).__name__!r} broke the protocol: {problem}")
    return x


def _population_mean(opt: Optimiser) -> float:
    f = opt.population_fitness
    f = f[np.isfinite(f)]
    return float(np.mean(f)) if f.size else float("nan")


class _Progress:
    """Per-generation record: best so far and population mean, or HV gap and IGD."""

    def __init__(self, env: Any) -> None:
        self.trace = Trace()
        self.multi = getattr(env, "n_objectives", 1) > 1
        self.reference: np.ndarray | None = None
        self.hv_star = float("nan")
        if self.multi and hasattr(env, "problem"):
            self.reference = env.problem.true_front(500)
            self.hv_star = env.problem.front_hypervolume

    def hv_score(self, hypervolume: float) -> float:
        """``1 - HV/HV*`` when the true front is known, else ``-HV`` (both: lower is better)."""
        return 1.0 - hypervolume / self.hv_star if self.reference is not None else -hypervolume

    def record(self, opt: Optimiser, info: dict[str, Any]) -> None:
        t = self.trace
        t.generation.append(opt.generation)
        t.evaluations.append(info["evaluations"])
        if self.multi:
            t.best_f.append(self.hv_score(info["hypervolume"]))
            if self.reference is None:
                t.mean_f.append(float(len(info["front_f"])))
            else:
                t.mean_f.append(igd(info["front_f"], self.reference) if len(info["front_f"]) else float("inf"))
        else:
            t.best_f.append(info["best_f"])
            t.mean_f.append(_population_mean(opt))


def ask_tell(opt: Optimiser, env: Any, budget: int, progress: bool,
             on_step: Callable[[np.ndarray, np.ndarray], None] | None = None) -> tuple[_Progress, dict[str, Any]]:
    """Run ``opt`` on ``env`` until it is done or the env terminates the episode (a task that
    stops at its target): ``X = ask(); F = step(X); tell(X, F)``, one batch per ask, each batch
    also handed to ``on_step(X, F)``; the per-generation record and the last step's ``info``."""
    recorder = _Progress(env)
    info: dict[str, Any] = {}
    last_generation = -1
    with tqdm(total=budget, disable=not progress, unit="eval", leave=False) as bar:
        while not opt.done:
            x = checked_batch(opt, opt.ask(), env)
            f, _, terminated, _, info = env.step(x)
            if on_step is not None:
                on_step(x, f)
            opt.tell(x, f)
            bar.update(len(f))
            if opt.generation != last_generation or terminated:
                last_generation = opt.generation
                recorder.record(opt, info)
            if terminated:
                break
    return recorder, info


def run_optimisation(
    task: dict[str, Any],
    optimiser: dict[str, Any],
    budget: int,
    seed: int,
    progress: bool = False,
    ioh_folder: str | Path | None = None,
    algorithm: str | None = None,
    env: Any = None,
) -> RunResult:
    """Minimise ``task`` with ``optimiser`` (configs as mappings) under ``budget`` and ``seed``;
    with ``ioh_folder``, also write the run there in IOHprofiler's format under the name
    ``algorithm`` (default: the optimiser's name). ``env``: the task's env already built from
    ``task`` and ``budget`` (unwrapped, not yet reset; an optimisation job's, built once for its
    checks and its run); None: built here (:func:`make_task`)."""
    env = make_task(task, budget) if env is None else env
    env_seed, rng = seed_streams(seed)
    env.reset(seed=env_seed)
    params = {k: v for k, v in optimiser.items() if k != "name"}
    n_objectives = getattr(env, "n_objectives", 1)
    opt = registry.create(optimiser["name"], env.lower, env.upper, budget, rng, params, n_objectives)
    ioh_log = None
    if ioh_folder is not None:
        from tcbench.leaderboard.iohprofiler import RunLogger, problem_meta

        ioh_log = RunLogger(ioh_folder, problem_meta(env, seed), algorithm or optimiser["name"],
                            json.dumps(params, sort_keys=True, default=str), seed, {"budget": budget})
    recorder, info = ask_tell(opt, env, budget, progress, ioh_log.record if ioh_log else None)
    if ioh_log is not None:
        ioh_log.close()
    if env.nonfinite:
        log.warning("%d evaluations returned NaN or inf; they were treated as worst", env.nonfinite)
    common = {
        "evaluations": int(info["evaluations"]), "budget": budget, "nonfinite": int(info["nonfinite"]),
        "generations": opt.generation, "trace": recorder.trace, "n_objectives": n_objectives,
    }
    if recorder.multi:
        gap = recorder.hv_score(info["hypervolume"])
        precision = float(task.get("target_precision") or 1e-8)
        hits = [e for e, g in zip(recorder.trace.evaluations, recorder.trace.best_f, strict=True) if g <= precision]
        return RunResult(
            best_f=gap, best_x=np.asarray(info["front_x"]), f_opt=0.0, target_precision=precision,
            target_hit_at=hits[0] if hits else None, hypervolume=float(info["hypervolume"]),
            igd=recorder.trace.mean_f[-1] if recorder.reference is not None else float("nan"), front_f=np.asarray(info["front_f"]), **common,
        )
    return RunResult(
        best_f=float(info["best_f"]), best_x=np.asarray(info["best_x"]), f_opt=env.f_opt,
        target_precision=env.target_precision, target_hit_at=info["target_hit_at"], **common,
    )


@dataclass(frozen=True)
class VMDTuning:
    """Outcome of the multi-objective VMD tuning of a gyro task (seed 001 §3.2): the chosen
    ``[k, alpha]``, the non-dominated set and the chosen point's objectives, every evaluated
    objective pair and the cost."""

    k: int
    alpha: float
    front_x: np.ndarray
    front_f: np.ndarray
    chosen_f: np.ndarray
    evaluated_f: np.ndarray
    evaluations: int
    seconds: float


@functools.lru_cache(maxsize=4)
def _tune(env_kwargs_json: str, tuner: str, params_json: str, budget: int, samples: int,
          progress: bool) -> VMDTuning:
    t0 = time.perf_counter()
    env = tasks.GyroVMDTuningEnv(budget=budget, tuning_samples=samples, **json.loads(env_kwargs_json))
    env.reset(seed=0)
    opt = registry.create(tuner, env.lower, env.upper, budget, np.random.default_rng(0), json.loads(params_json), 2)
    ask_tell(opt, env, budget, progress)
    from tcbench.compensation.gyro.tuning import compromise, decode

    i = compromise(env.front_x, env.front_f)
    k, alpha = decode(env.front_x[i])
    return VMDTuning(k, alpha, env.front_x, env.front_f, env.front_f[i], np.concatenate(env.evaluated_f),
                     env.evaluations, time.perf_counter() - t0)


def tune_vmd(env_kwargs: dict[str, Any], tuner: str = "mopso", budget: int = 440, samples: int = 2048,
             progress: bool = False, tuner_params: dict[str, Any] | None = None) -> VMDTuning:
    """Tune VMD's ``[k, alpha]`` on ``tcbench/Gyro-VMDTuning-v0`` (built from ``env_kwargs``) with
    the multi-objective optimiser ``tuner`` (``tuner_params``, or its defaults) within ``budget``
    evaluations. The tuning's random stream is fixed (seed 0): the tuned
    decomposition is a property of the training record, shared by every restart of the learner
    (remembered for the process, and between processes in the user cache when the tuner is one of
    tcbench's own: :mod:`tcbench.runner.remembered`, keyed by the record, these settings and the code;
    a plugin's code is not in the key, so a plugin tuner tunes in every process)."""
    inputs = {"env": json.dumps(env_kwargs, sort_keys=True), "tuner": str(tuner),
              "params": json.dumps(tuner_params or {}, sort_keys=True), "budget": int(budget), "samples": int(samples)}

    def tune() -> VMDTuning:
        return _tune(*inputs.values(), bool(progress))

    if registry.available()[str(tuner)].package != "tcbench":
        return tune()
    return remembered("vmd-tuning", key_of(inputs, list(env_kwargs.get("train_files") or ())), tune)


@dataclass
class CompensationResult:
    """Outcome of one compensation run: the scores, how training went, the search trace."""

    score: Score
    history: FitHistory | None
    trace: Trace
    search_evaluations: int
    init_loss: float  # eq. 3 training error of the initial vector training started from
    seconds_search: float
    seconds_train: float
    tuning: VMDTuning | None = None


def run_compensation(
    task: dict[str, Any],
    learner: dict[str, Any],
    optimiser: dict[str, Any],
    budget: int,
    seed: int,
    progress: bool = False,
) -> CompensationResult:
    """Compensate an MSRA or gyro task: ``learner`` ``raw``/``oracle`` scores a baseline; a learner
    whose initial parameters an optimiser may search (``optimiser`` not ``none``) is trained
    from the best vector found within ``budget`` evaluations (X-BP, seed 000 Fig. 5); otherwise
    it trains from its own random start (or in closed form). The task's env is built here
    (:func:`compensate` runs on one already built)."""
    from tcbench.compensation.methods import BASELINES

    name = learner["name"]
    kwargs = tasks.task_kwargs(task)
    params = {k: v for k, v in learner.items() if k not in {"name", "label"}}
    env = gym.make(tasks.task_id(task["name"]), budget=budget, learner=None if name in BASELINES else name,
                   learner_params=params, **kwargs).unwrapped
    opt_params = {k: v for k, v in optimiser.items() if k not in {"name", "label"}}
    return compensate(env, name, optimiser["name"], opt_params, budget, seed, progress)


def compensate(env: Any, learner: str, optimiser: str, optimiser_params: dict[str, Any], budget: int, seed: int,
               progress: bool = False) -> CompensationResult:
    """:func:`run_compensation` on ``env``, the task's env built (not yet reset) for the learner or
    baseline named ``learner`` and ``budget`` evaluations; ``optimiser`` with ``optimiser_params``
    searches the learner's initial weights (``none``: a random start)."""
    from tcbench.compensation.methods import BASELINES

    baseline = learner in BASELINES
    env_seed, rng = seed_streams(seed)
    tuning = None
    if getattr(env, "needs_tuning", False):
        tuning = tune_vmd(env.tuning_kwargs(), env.tuning["tuner"], env.tuning["budget"], env.tuning["samples"],
                          progress, env.tuning["params"])
    env.reset(seed=env_seed, options={"k": tuning.k, "alpha": tuning.alpha} if tuning else None)
    trace = Trace()
    if baseline:
        return CompensationResult(env.score_baseline(learner), None, trace, 0, float("nan"), 0.0, 0.0, tuning)
    t0 = time.perf_counter()
    init = None
    init_loss = float("nan")
    if env.learner.searchable and optimiser != registry.NO_SEARCH:
        opt = registry.create(optimiser, env.lower, env.upper, budget, rng, optimiser_params)
        trace = ask_tell(opt, env, budget, progress)[0].trace
        init, init_loss = opt.best.x, float(opt.best.f)
    elif env.learner.searchable:
        init = env.learner.initial_params(rng)
        init_loss = float(env.step(init)[0][0])
    t1 = time.perf_counter()
    score, history = env.score(init)
    return CompensationResult(score, history, trace, env.evaluations, init_loss, t1 - t0,
                              time.perf_counter() - t1, tuning)
