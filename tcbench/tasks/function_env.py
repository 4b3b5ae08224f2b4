"""Black-box minimisation of a test function as a gymnasium environment.

An action is a candidate point (shape ``(d,)``) or a batch of them (``(n, d)``); the
observation is the objective value of each candidate (``(1,)`` or ``(n,)``) and the reward its
negation, so a higher reward is a better point. There is no terminal state: an episode is
truncated when the evaluation budget is spent, and a step that would exceed the budget raises
:class:`BudgetExceededError`. ``info`` carries best-so-far, evaluations used, the budget, the
bounds, the optimum value, and the evaluation at which the target precision was first reached.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from tcbench.tasks.checks import is_integer, is_real
from tcbench.tasks.functions import ObjectiveFunction, get_function


class BudgetExceededError(RuntimeError):
    """A step asked for more evaluations than the budget has left."""


def as_batch(action: np.ndarray, dim: int) -> tuple[np.ndarray, bool]:
    """An action as an ``(n, dim)`` batch, and whether it was a single ``(dim,)`` point."""
    x = np.asarray(action, dtype=np.float64)
    single = x.ndim == 1
    x2 = x.reshape(1, -1) if single else x
    if x2.ndim != 2 or x2.shape[1] != dim:
        raise ValueError(f"action must have shape ({dim},) or (n, {dim}), got {x.shape}")
    return x2, single


def check_budget(evaluations: int, n: int, budget: int) -> None:
    """Raise :class:`BudgetExceededError` if ``n`` more evaluations do not fit in ``budget``."""
    if evaluations + n > budget:
        raise BudgetExceededError(
            f"{n} evaluations requested but only {budget - evaluations} of the "
            f"budget of {budget} are left; call reset()"
        )


class FunctionEnv(gym.Env[np.ndarray, np.ndarray]):
    """Minimise ``function`` in ``dim`` dimensions within ``budget`` evaluations.

    Parameters
    ----------
    function: key of a function in :data:`tcbench.tasks.functions.FUNCTIONS`.
    dim: number of decision variables.
    budget: maximum number of objective evaluations per episode.
    shift: if true, ``reset(seed=...)`` moves the optimum to a point drawn from the seed
        (inside the function's admissible shift box), so a method gains nothing from optima at
        the origin; if false the function is the paper's unshifted one.
    target_precision: ``best - f_opt`` at or below which the target counts as reached.
    lower, upper: override the function's documented domain (scalars, same for every axis).
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        function: str = "rastrigin",
        dim: int = 2,
        budget: int = 1000,
        shift: bool = False,
        target_precision: float = 1e-8,
        lower: float | None = None,
        upper: float | None = None,
    ) -> None:
        self.function: ObjectiveFunction = get_function(function)
        if not is_integer(dim) or dim < self.function.min_dim:
            raise ValueError(
                f"dim must be an integer >= {self.function.min_dim} for {function}, got {dim}"
            )
        if not is_integer(budget) or budget < 1:
            raise ValueError(f"budget must be a positive integer, got {budget}")
        if not is_real(target_precision) or target_precision <= 0:
            raise ValueError(f"target_precision must be a positive number, got {target_precision}")
        for label, value in (("lower", lower), ("upper", upper)):
            if value is not None and not is_real(value):
                raise ValueError(f"{label} must be a finite number or None, got {value!r}")
        lo = self.function.lower if lower is None else float(lower)
        hi = self.function.upper if upper is None else float(upper)
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise ValueError(f"bounds must be finite with lower < upper, got [{lo}, {hi}]")
        if not lo <= self.function.x_opt <= hi:
            raise ValueError(
                f"bounds [{lo}, {hi}] exclude the optimum x*={self.function.x_opt} of {function}"
            )
        self.dim = int(dim)
        self.budget = int(budget)
        self.shift_enabled = bool(shift)
        self.target_precision = float(target_precision)
        self.lower = np.full(self.dim, lo)
        self.upper = np.full(self.dim, hi)
        self.f_opt = self.function.f_opt(self.dim)
        self.action_space = gym.spaces.Box(self.lower, self.upper, dtype=np.float64)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(1,), dtype=np.float64)
        self.shift = np.zeros(self.dim)
        self._reset_counters()

    def _reset_counters(self) -> None:
        self.evaluations = 0
        self.best_f = np.inf
        self.best_x = np.full(self.dim, np.nan)
        self.target_hit_at: int | None = None
        self.nonfinite = 0

    @property
    def x_opt(self) -> np.ndarray:
        """Location of the global optimum of the current instance."""
        return np.full(self.dim, self.function.x_opt) + self.shift

    def evaluate(self, x: np.ndarray) -> np.ndarray:
        """Objective values of ``x`` (``(n, d)``) for this instance, without counting them."""
        return self.function.fn(x - self.shift)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        if self.shift_enabled:
            low, high = self.function.shift_box()
            x_opt = self.function.x_opt + self.np_random.uniform(low, high, size=self.dim)
            # Keep the moved optimum strictly inside the (possibly overridden) domain.
            x_opt = np.clip(x_opt, self.lower, self.upper)
            self.shift = x_opt - self.function.x_opt
        self._reset_counters()
        return np.array([np.inf]), self._info()

    def step(
        self, action: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray | float, bool, bool, dict[str, Any]]:
        x2, single = as_batch(action, self.dim)
        check_budget(self.evaluations, x2.shape[0], self.budget)
        f = np.asarray(self.evaluate(x2), dtype=np.float64)
        self._record(x2, f)
        truncated = self.evaluations >= self.budget
        reward: np.ndarray | float = float(-f[0]) if single else -f
        return f, reward, False, truncated, self._info()

    def _record(self, x: np.ndarray, f: np.ndarray) -> None:
        finite = np.isfinite(f)
        self.nonfinite += int(np.count_nonzero(~finite))
        ranked = np.where(finite, f, np.inf)
        if self.target_hit_at is None:
            hits = np.flatnonzero(ranked - self.f_opt <= self.target_precision)
            if hits.size:
                self.target_hit_at = self.evaluations + int(hits[0]) + 1
        i = int(np.argmin(ranked))
        if ranked[i] < self.best_f:
            self.best_f = float(ranked[i])
            self.best_x = x[i].copy()
        self.evaluations += len(f)

    def _info(self) -> dict[str, Any]:
        return {
            "best_f": self.best_f,
            "best_x": self.best_x.copy(),
            "evaluations": self.evaluations,
            "budget": self.budget,
            "lower": self.lower.copy(),
            "upper": self.upper.copy(),
            "f_opt": self.f_opt,
            "target_hit_at": self.target_hit_at,
            "nonfinite": self.nonfinite,
        }
