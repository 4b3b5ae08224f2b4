"""The search half shared by the compensation envs: candidates of a learner's initial weights
scored by their training error (the "brightness" FA/IFA rank by; BAS-Elman's fitness)."""

from __future__ import annotations

from typing import Any

import numpy as np

from tcbench.tasks.function_env import as_batch, check_budget


class WeightSearch:
    """Mixin of a gymnasium env with ``data``, ``learner``, ``learner_name``, ``dim``, ``budget``,
    ``lower``, ``upper``, ``f_opt`` and the training set ``_x``, ``_y`` built by ``reset``."""

    data: Any
    learner: Any
    learner_name: str | None
    dim: int
    budget: int
    lower: np.ndarray
    upper: np.ndarray
    f_opt: float
    _x: Any
    _y: Any

    def _reset_counters(self) -> None:
        self.evaluations = 0
        self.best_f = np.inf
        self.best_x = np.full(self.dim, np.nan)
        self.nonfinite = 0

    def step(self, action: np.ndarray) -> tuple[np.ndarray, np.ndarray | float, bool, bool, dict[str, Any]]:
        """Training error (normalised eq. 3) of each candidate weight vector; reward its negation."""
        if self.data is None:
            raise RuntimeError("call reset() before step()")
        if self.learner is None or not self.learner.searchable:
            raise TypeError(f"learner {self.learner_name!r} has no initial parameters to search")
        x2, single = as_batch(action, self.dim)
        check_budget(self.evaluations, x2.shape[0], self.budget)
        f = np.asarray(self.learner.loss_batch(x2, self._x, self._y), dtype=np.float64)
        finite = np.isfinite(f)
        self.nonfinite += int(np.count_nonzero(~finite))
        ranked = np.where(finite, f, np.inf)
        i = int(np.argmin(ranked))
        if ranked[i] < self.best_f:
            self.best_f, self.best_x = float(ranked[i]), x2[i].copy()
        self.evaluations += len(f)
        reward: np.ndarray | float = float(-f[0]) if single else -f
        return f, reward, False, self.evaluations >= self.budget, self._info()

    def _info(self) -> dict[str, Any]:
        return {
            "best_f": self.best_f, "best_x": self.best_x.copy(), "evaluations": self.evaluations,
            "budget": self.budget, "lower": self.lower.copy(), "upper": self.upper.copy(),
            "f_opt": self.f_opt, "target_hit_at": None, "nonfinite": self.nonfinite,
        }
