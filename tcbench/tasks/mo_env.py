"""Black-box multi-objective minimisation as a gymnasium environment.

An action is a candidate point in ``[0, 1]^d`` (shape ``(d,)``) or a batch of them
(``(n, d)``); the observation is the objective vector of each candidate (``(m,)`` or
``(n, m)``). Multi-objective methods should use the observation (and the archive in ``info``);
the reward exists because gymnasium needs a scalar per step: for one candidate it is the
negated sum of its objectives (a float), for a batch the array of those. There is no terminal
state: an episode is truncated when the evaluation budget is spent, and a step that would
exceed the budget raises :class:`~tcbench.tasks.function_env.BudgetExceededError`.

``info`` carries ``evaluations``, ``budget``, ``lower``, ``upper``, ``n_objectives``, the
non-dominated set of everything evaluated so far in the episode (``front_f`` ``(k, m)`` and
``front_x`` ``(k, d)``, first-evaluated copy kept among equal objective vectors), its
``hypervolume`` against the problem's ``ref_point`` (also in ``info``) and
``hypervolume_ratio``, that hypervolume divided by the true front's (at most 1).

Register the ids ``tcbench/ZDT1-v0``, ``tcbench/ZDT2-v0``, ``tcbench/ZDT3-v0`` and
``tcbench/DTLZ2-v0`` (:mod:`tcbench.tasks.specs`).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from tcbench.metrics.multiobjective import hypervolume
from tcbench.pareto import merge_front
from tcbench.tasks.checks import is_integer, is_real
from tcbench.tasks.function_env import as_batch, check_budget
from tcbench.tasks.multiobjective import MultiObjectiveProblem, get_problem

MO_ENV_VERSION = "v0"

# New points are merged into the archive this many at a time, so the dominance matrices stay
# at (archive size x chunk) rather than growing with the square of a large batch.
_MERGE_CHUNK = 256


def record_front(env: Any, x: np.ndarray, f: np.ndarray) -> None:
    """Count evaluations ``x`` (n, d) with objectives ``f`` (n, m) on ``env`` and merge the finite
    ones into its non-dominated set (``front_x``, ``front_f``), updating ``hypervolume``
    against ``env.ref_point`` when the set changed."""
    finite = np.all(np.isfinite(f), axis=1)
    env.nonfinite += int(np.count_nonzero(~finite))
    env.evaluations += f.shape[0]
    x, f = x[finite], f[finite]
    changed = False
    for start in range(0, f.shape[0], _MERGE_CHUNK):
        chunk = slice(start, start + _MERGE_CHUNK)
        old = env.front_f
        env.front_x, env.front_f = merge_front(env.front_x, old, x[chunk], f[chunk])
        changed |= not np.array_equal(old, env.front_f)
    if changed:
        env.hypervolume = hypervolume(env.front_f, env.ref_point)


class MultiObjectiveEnv(gym.Env[np.ndarray, np.ndarray]):
    """Minimise the objectives of ``function`` in ``dim`` variables within ``budget`` evaluations.

    Parameters
    ----------
    function: key of a problem in :data:`tcbench.tasks.multiobjective.PROBLEMS`
        (``zdt1``, ``zdt2``, ``zdt3``, ``dtlz2``; case-insensitive).
    dim: number of decision variables; ``None`` for the problem's default (30 for ZDT, 12 for
        DTLZ2 with 3 objectives).
    budget: maximum number of evaluations per episode.
    shift, target_precision, lower, upper: accepted so that a task config written for
        :class:`~tcbench.tasks.function_env.FunctionEnv` also builds this env, and otherwise
        ignored: ``shift`` must be false (no shifted variants), ``target_precision`` must be
        a positive number (unused: no single target), ``lower``/``upper`` must be ``None`` or
        the problem's own bounds 0 and 1 (the problems are undefined outside them).
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        function: str = "zdt1",
        dim: int | None = None,
        budget: int = 1000,
        shift: bool = False,
        target_precision: float = 1e-8,
        lower: float | None = None,
        upper: float | None = None,
    ) -> None:
        self.problem: MultiObjectiveProblem = get_problem(function)
        p = self.problem
        d = p.default_dim if dim is None else dim
        if not is_integer(d) or d < p.min_dim:
            raise ValueError(f"dim must be an integer >= {p.min_dim} for {p.key}, got {dim}")
        if not is_integer(budget) or budget < 1:
            raise ValueError(f"budget must be a positive integer, got {budget}")
        if shift:
            raise ValueError(f"shift is not supported for the multi-objective problem {p.key}")
        if not is_real(target_precision) or target_precision <= 0:
            raise ValueError(f"target_precision must be a positive number, got {target_precision}")
        for label, value, own in (("lower", lower, p.lower), ("upper", upper, p.upper)):
            if value is not None and (not is_real(value) or float(value) != own):
                raise ValueError(
                    f"{label} must be null or {own} for {p.key} (domain [{p.lower}, {p.upper}]), "
                    f"got {value}"
                )
        self.dim = int(d)
        self.budget = int(budget)
        self.n_objectives = p.n_objectives
        self.ref_point = np.asarray(p.ref_point, dtype=np.float64)
        self.lower = np.full(self.dim, p.lower)
        self.upper = np.full(self.dim, p.upper)
        self.action_space = gym.spaces.Box(self.lower, self.upper, dtype=np.float64)
        self.observation_space = gym.spaces.Box(
            -np.inf, np.inf, shape=(self.n_objectives,), dtype=np.float64
        )
        self._reset_counters()

    def _reset_counters(self) -> None:
        self.evaluations = 0
        self.nonfinite = 0
        self.front_f = np.empty((0, self.n_objectives))
        self.front_x = np.empty((0, self.dim))
        self.hypervolume = 0.0

    def evaluate(self, x: np.ndarray) -> np.ndarray:
        """Objective vectors ``(n, m)`` of ``x`` (``(n, d)``), without counting them."""
        return self.problem.fn(x)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self._reset_counters()
        return np.full(self.n_objectives, np.inf), self._info()

    def step(
        self, action: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray | float, bool, bool, dict[str, Any]]:
        x2, single = as_batch(action, self.dim)
        if not np.all((x2 >= self.lower) & (x2 <= self.upper)):
            raise ValueError(
                f"action outside the domain [{self.problem.lower}, {self.problem.upper}]^"
                f"{self.dim} of {self.problem.name} (or not finite)"
            )
        check_budget(self.evaluations, x2.shape[0], self.budget)
        f = np.asarray(self.evaluate(x2), dtype=np.float64)
        self._record(x2, f)
        truncated = self.evaluations >= self.budget
        sums = -f.sum(axis=1)
        reward: np.ndarray | float = float(sums[0]) if single else sums
        obs = f[0] if single else f
        return obs, reward, False, truncated, self._info()

    def _record(self, x: np.ndarray, f: np.ndarray) -> None:
        record_front(self, x, f)

    def _info(self) -> dict[str, Any]:
        return {
            "evaluations": self.evaluations,
            "budget": self.budget,
            "lower": self.lower.copy(),
            "upper": self.upper.copy(),
            "n_objectives": self.n_objectives,
            "front_f": self.front_f.copy(),
            "front_x": self.front_x.copy(),
            "hypervolume": self.hypervolume,
            "hypervolume_ratio": self.hypervolume / self.problem.front_hypervolume,
            "ref_point": self.ref_point.copy(),
            "nonfinite": self.nonfinite,
        }


def mo_env_id(problem_key: str) -> str:
    """Gymnasium id of a multi-objective task, e.g. ``tcbench/ZDT1-v0``."""
    return f"tcbench/{get_problem(problem_key).name}-{MO_ENV_VERSION}"
