"""Standard firefly algorithm (FA), seed 000 §2.2.1, eq. 4-5 (Yang 2008).

Each generation every firefly moves toward every brighter one with attractiveness
``beta0 exp(-gamma r^2)`` (eq. 4) plus a random step ``alpha (xi - 1/2)`` (eq. 5); the brightest
firefly, having nobody to follow, takes a random step only. Positions leaving the domain are
clamped to it (eq. 11 of the IFA, applied here too so every candidate is feasible). The step
size is constant, as eq. 5 states; ``alpha_decay < 1`` gives the geometric decay of later FA
variants. One generation costs ``population`` evaluations.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.optimisers.firefly_moves import (
    attractiveness,
    brighter_mask,
    move_towards,
    squared_distances,
)
from tcbench.optimisers.protocol import Optimiser, OptimiserParams


@dataclass(frozen=True)
class FAParams(OptimiserParams):
    """FA parameters; defaults are seed 000 §2.2.3 (population 10, alpha0 0.25, beta0 = gamma = 1).

    alpha0: random step size (domain units, or a fraction of the domain width if
        ``alpha_relative``).
    beta0: attractiveness at distance 0, in (0, 1].
    gamma: light absorption coefficient, >= 0 (per squared domain unit).
    beta_min: attractiveness floor at large distance, in [0, beta0]; 0 is eq. 4 as printed
        (Yang's reference implementation uses 0.2).
    alpha_decay: factor applied to alpha after each generation; 1 keeps it constant (eq. 5).
    alpha_relative: scale the random step by the domain width of each axis.
    max_generations: stop after this many generations (None: run until the budget is spent).
    """

    population: int = 10
    alpha0: float = 0.25
    beta0: float = 1.0
    gamma: float = 1.0
    beta_min: float = 0.0
    alpha_decay: float = 1.0
    alpha_relative: bool = False
    max_generations: int | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.alpha0 >= 0:
            raise ValueError(f"alpha0 must be >= 0, got {self.alpha0}")
        if not 0 < self.beta0 <= 1:
            raise ValueError(f"beta0 must be in (0, 1], got {self.beta0}")
        if not self.gamma >= 0:
            raise ValueError(f"gamma must be >= 0, got {self.gamma}")
        if not 0 <= self.beta_min <= self.beta0:
            raise ValueError(f"beta_min must be in [0, beta0], got {self.beta_min}")
        if not 0 < self.alpha_decay <= 1:
            raise ValueError(f"alpha_decay must be in (0, 1], got {self.alpha_decay}")
        if self.max_generations is not None and self.max_generations < 1:
            raise ValueError(f"max_generations must be >= 1, got {self.max_generations}")


class FireflyAlgorithm(Optimiser):
    """Firefly algorithm, population-vectorised ask/tell (eq. 4-5)."""

    name = "fa"
    Params = FAParams
    params: FAParams

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.width = self.upper - self.lower
        self.alpha = self.params.alpha0 * (self.width if self.params.alpha_relative else 1.0)
        if np.ndim(self.alpha) and np.all(self.alpha == self.alpha[0]):
            self.alpha = float(self.alpha[0])  # the same step on every axis, kept as a scalar
        self.x = np.empty((0, self.dim))
        self.fitness = np.empty(0)

    def _stopped(self) -> bool:
        limit = self.params.max_generations
        return limit is not None and self.generation >= limit

    def moved(self, follow: np.ndarray | None = None) -> np.ndarray:
        """The population after one round of moves, firefly i pulled by every brighter j, or only
        by those with ``follow[i, j]`` when ``follow`` is given; positions clamped to the domain
        (eq. 11)."""
        p = self.params
        beta = attractiveness(squared_distances(self.x), p.beta0, p.gamma, p.beta_min)
        pulls = brighter_mask(self.fitness)
        if follow is not None:
            pulls &= follow
        coef = np.where(pulls, beta, 0.0)
        return self.clip(move_towards(self.x, coef, self.alpha, self.rng))

    def _ask(self) -> np.ndarray:
        if self.fitness.size == 0:
            return self.uniform(self.params.population)
        return self.moved()[: self.remaining]

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        if self.fitness.size:
            k = len(f)
            if k < len(self.fitness):  # a last, partial generation: the rest stay where they are
                x = np.concatenate([x, self.x[k:]])
                f = np.concatenate([f, self.fitness[k:]])
            self.generation += 1
            if self.params.alpha_decay != 1.0:
                self.alpha = self.alpha * self.params.alpha_decay
        order = np.argsort(f, kind="stable")
        self.x, self.fitness = x[order], f[order]
