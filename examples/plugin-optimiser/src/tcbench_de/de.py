"""DE/rand/1/bin (Storn & Price 1997) on tcbench's ask/tell protocol.

Each generation every target ``x_i`` gets a trial: mutant ``v = x_a + F (x_b - x_c)`` with
``a, b, c`` distinct and different from ``i``, binomial crossover with rate ``CR`` (one
coordinate always from the mutant), clamped to the bounds; the trial replaces the target when
it is no worse.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tcbench.optimisers import Optimiser, OptimiserParams


@dataclass(frozen=True)
class DEParams(OptimiserParams):
    """population (>= 4), differential weight ``f`` in (0, 2], crossover rate ``cr`` in [0, 1]."""

    population: int = 20
    f: float = 0.5
    cr: float = 0.9

    def __post_init__(self) -> None:
        if self.population < 4:
            raise ValueError(f"population must be >= 4 for DE/rand/1, got {self.population}")
        if not 0 < self.f <= 2:
            raise ValueError(f"f must be in (0, 2], got {self.f}")
        if not 0 <= self.cr <= 1:
            raise ValueError(f"cr must be in [0, 1], got {self.cr}")


def distinct_donors(n: int, rng: np.random.Generator) -> np.ndarray:
    """For each of ``n`` targets three distinct indices, all different from the target's."""
    keys = rng.random((n, n))
    np.fill_diagonal(keys, np.inf)
    return np.argsort(keys, axis=1)[:, :3]


class DifferentialEvolution(Optimiser):
    """DE/rand/1/bin, vectorised over the population."""

    name = "de"
    Params = DEParams
    params: DEParams

    def __init__(self, *args, **kwargs) -> None:  # type: ignore[no-untyped-def]
        super().__init__(*args, **kwargs)
        self.x = np.empty((0, self.dim))
        self.fitness = np.empty(0)

    def _ask(self) -> np.ndarray:
        n = self.params.population
        if self.fitness.size == 0:
            return self.uniform(n)
        donors = distinct_donors(n, self.rng)
        a, b, c = (self.x[donors[:, k]] for k in range(3))
        mutant = a + self.params.f * (b - c)
        cross = self.rng.random((n, self.dim)) < self.params.cr
        cross[np.arange(n), self.rng.integers(0, self.dim, n)] = True
        trial = self.clip(np.where(cross, mutant, self.x))
        return trial[: self.remaining]

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        if self.fitness.size == 0:
            self.x, self.fitness = x, f
            return
        k = len(f)
        better = f <= self.fitness[:k]
        self.x[:k][better] = x[better]
        self.fitness[:k][better] = f[better]
        self.generation += 1
