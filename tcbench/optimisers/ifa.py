"""Improved firefly algorithm (IFA), seed 000 §2.2.2, eq. 6-11.

One generation ``n`` (0-based) has two ask/tell phases:

1. *Best firefly* (eq. 7-10): the brightest firefly is perturbed by
   ``dx = cos(pi/2 * n/maxgen) (zeta - 1/2) s`` (eq. 9, ``s`` the domain width per axis), clamped
   to the domain (eq. 11), evaluated, and accepted by the Metropolis rule (eq. 7) with
   temperature ``T = epsilon (maxgen - n)`` (eq. 8). One evaluation.
2. *Others* (eq. 4-5 restricted to a random subset): every other firefly draws a random subset
   of the population and moves toward the members of it that are brighter than itself, with the
   adaptive step ``alpha(n)``; a firefly whose subset holds nobody brighter takes a random step.
   Positions are clamped (eq. 11). ``population - 1`` evaluations.

A generation therefore costs ``population`` evaluations, the same as FA's. After it the step
follows eq. 6: ``alpha(n+1) = k alpha(n) exp(n / (n - maxgen))``.

Choices where the paper is silent (all parameters, see :class:`IFAParams`):

- ``k = 1``: eq. 6's nonlinear factor alone already decays the step to ~0.5 % of alpha0 by
  ``n = 0.4 maxgen``; ``k < 1`` decays it faster.
- ``epsilon = 0.01``: T runs from ``0.01 maxgen`` to 0.01 in objective units, so early on a
  best-firefly move that is worse by ``0.01 maxgen`` is accepted with probability 1/e.
- subset size: ``round(subset_fraction * (population - 1))``, at least 1; 0.3 gives 3 of 9.
- ``maxgen``: ``max_generations`` if set, else as many generations as the budget allows after
  the initial population (rounded up: the last may be partial). Eq. 6 and 8 are only evaluated
  for ``n = 0 .. maxgen-1`` and the run stops at ``maxgen``, so ``T`` never reaches 0 and
  ``n / (n - maxgen)`` never divides by zero; the last step is ``alpha e^-(maxgen-1)`` small.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.optimisers.fa import FAParams, FireflyAlgorithm


@dataclass(frozen=True)
class IFAParams(FAParams):
    """IFA parameters: FA's (``alpha0`` is the initial step) plus eq. 6, 8 and the subset size.

    k: adjustment factor of the adaptive step, eq. 6, in (0, 1].
    epsilon: correction factor of the annealing temperature, eq. 8, > 0 (objective units).
    subset_fraction: share of the other fireflies each firefly samples as candidate
        attractors, in (0, 1].
    """

    k: float = 1.0
    epsilon: float = 0.01
    subset_fraction: float = 0.3

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.alpha_decay != 1.0:
            raise ValueError("alpha_decay is FA's; IFA's step follows eq. 6 (use k)")
        if not 0 < self.k <= 1:
            raise ValueError(f"k must be in (0, 1], got {self.k}")
        if not self.epsilon > 0:
            raise ValueError(f"epsilon must be > 0, got {self.epsilon}")
        if not 0 < self.subset_fraction <= 1:
            raise ValueError(f"subset_fraction must be in (0, 1], got {self.subset_fraction}")


def adaptive_step(alpha: np.ndarray | float, n: int, maxgen: int, k: float) -> np.ndarray | float:
    """Eq. 6: ``alpha(n+1) = k alpha(n) exp(n / (n - maxgen))`` for ``0 <= n < maxgen``."""
    if not 0 <= n < maxgen:
        raise ValueError(f"eq. 6 is defined for 0 <= n < maxgen, got n={n}, maxgen={maxgen}")
    return k * alpha * math.exp(n / (n - maxgen))


def annealing_temperature(n: int, maxgen: int, epsilon: float) -> float:
    """Eq. 8: ``T = epsilon (maxgen - n)``."""
    return epsilon * (maxgen - n)


def metropolis_accept(
    c_old: float, c_new: float, temperature: float, rng: np.random.Generator
) -> bool:
    """Eq. 7: accept a better value always, a worse one with probability exp((C - C')/T)."""
    u = rng.random()
    if c_new < c_old:
        return True
    with np.errstate(invalid="ignore", over="ignore"):
        p = np.exp((c_old - c_new) / temperature)
    return bool(u < p)


def mutation_step(
    n: int, maxgen: int, width: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """Eq. 9: ``dx = cos(pi/2 * n/maxgen) (zeta - 1/2) s`` with zeta ~ U[0, 1] per axis."""
    return math.cos(0.5 * math.pi * n / maxgen) * (rng.random(width.shape) - 0.5) * width


def random_subsets(n: int, size: int, rng: np.random.Generator) -> np.ndarray:
    """``mask[i, j]``: j is among ``size`` fireflies drawn for i without replacement (j != i)."""
    keys = rng.random((n, n))
    np.fill_diagonal(keys, np.inf)
    chosen = np.argsort(keys, axis=1)[:, :size]
    mask = np.zeros((n, n), dtype=bool)
    np.put_along_axis(mask, chosen, True, axis=1)
    return mask


class ImprovedFireflyAlgorithm(FireflyAlgorithm):
    """Improved firefly algorithm (IFA), population-vectorised ask/tell."""

    name = "ifa"
    Params = IFAParams
    params: IFAParams

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        p = self.params
        after_init = self.budget - p.population
        self.maxgen = p.max_generations or max(1, math.ceil(after_init / p.population))
        self.subset_size = max(1, round(p.subset_fraction * (p.population - 1)))
        self.accepted_worse = 0
        self._phase = "init"

    def _stopped(self) -> bool:
        return self.generation >= self.maxgen

    def _ask(self) -> np.ndarray:
        if self._phase == "init":
            return self.uniform(self.params.population)
        if self._phase == "best":
            dx = mutation_step(self.generation, self.maxgen, self.width, self.rng)  # eq. 9
            return self.clip(self.x[:1] + dx)  # eq. 10-11
        follow = random_subsets(len(self.fitness), self.subset_size, self.rng)
        return self.moved(follow)[1:][: self.remaining]

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        if self._phase == "init":
            self.x, self.fitness = x, f
            self._phase = "best"
        elif self._phase == "best":
            temperature = annealing_temperature(self.generation, self.maxgen, self.params.epsilon)
            if metropolis_accept(self.fitness[0], f[0], temperature, self.rng):  # eq. 7
                self.accepted_worse += int(f[0] >= self.fitness[0])
                self.x[0], self.fitness[0] = x[0], f[0]
            self._phase = "others"
        else:
            k = len(f)
            self.x[1 : 1 + k], self.fitness[1 : 1 + k] = x, f
            self.alpha = adaptive_step(self.alpha, self.generation, self.maxgen, self.params.k)
            self.generation += 1
            self._phase = "best"
        order = np.argsort(self.fitness, kind="stable")
        self.x, self.fitness = self.x[order], self.fitness[order]
