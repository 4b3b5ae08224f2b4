"""The ask/tell loop: the one place where a task and an optimiser meet."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm.auto import tqdm

import tcbench.tasks as tasks
from tcbench.optimisers import registry
from tcbench.optimisers.protocol import Optimiser, ProtocolError

log = logging.getLogger(__name__)


@dataclass
class Trace:
    """Per-generation history of one run (generation 0 is the initial population)."""

    generation: list[int] = field(default_factory=list)
    evaluations: list[int] = field(default_factory=list)
    best_f: list[float] = field(default_factory=list)
    mean_f: list[float] = field(default_factory=list)


@dataclass
class RunResult:
    """Outcome of one optimisation run."""

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

    @property
    def error(self) -> float:
        """``best_f - f_opt``: distance of the final best from the optimum value."""
        return self.best_f - self.f_opt


def seed_streams(seed: int) -> tuple[int, np.random.Generator]:
    """Independent streams for the task instance and the optimiser from one run seed."""
    env_seq, opt_seq = np.random.SeedSequence(seed).spawn(2)
    return int(env_seq.generate_state(1)[0]), np.random.default_rng(opt_seq)


def make_task(task: dict[str, Any], budget: int) -> tasks.FunctionEnv:
    """Build the task environment from its config (``name``, ``dim``, ``shift`` ...)."""
    kwargs = {k: v for k, v in task.items() if k != "name" and v is not None}
    env = gym.make(tasks.env_id(task["name"]), budget=budget, **kwargs)
    return env.unwrapped  # type: ignore[return-value]


def checked_batch(opt: Optimiser, x: np.ndarray, env: tasks.FunctionEnv) -> np.ndarray:
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


def run_optimisation(
    task: dict[str, Any],
    optimiser: dict[str, Any],
    budget: int,
    seed: int,
    progress: bool = False,
) -> RunResult:
    """Minimise ``task`` with ``optimiser`` (configs as mappings) under ``budget`` and ``seed``."""
    env = make_task(task, budget)
    env_seed, rng = seed_streams(seed)
    env.reset(seed=env_seed)
    params = {k: v for k, v in optimiser.items() if k != "name"}
    opt = registry.create(optimiser["name"], env.lower, env.upper, budget, rng, params)
    trace = Trace()
    info: dict[str, Any] = {}
    last_generation = -1
    with tqdm(total=budget, disable=not progress, unit="eval", leave=False) as bar:
        while not opt.done:
            x = checked_batch(opt, opt.ask(), env)
            f, _, _, _, info = env.step(x)
            opt.tell(x, f)
            bar.update(len(f))
            if opt.generation != last_generation:
                last_generation = opt.generation
                trace.generation.append(opt.generation)
                trace.evaluations.append(info["evaluations"])
                trace.best_f.append(info["best_f"])
                trace.mean_f.append(_population_mean(opt))
    if env.nonfinite:
        log.warning("%d evaluations returned NaN or inf; they were treated as worst", env.nonfinite)
    return RunResult(
        best_f=float(info["best_f"]),
        best_x=np.asarray(info["best_x"]),
        f_opt=env.f_opt,
        evaluations=int(info["evaluations"]),
        budget=budget,
        target_precision=env.target_precision,
        target_hit_at=info["target_hit_at"],
        nonfinite=int(info["nonfinite"]),
        generations=opt.generation,
        trace=trace,
    )
