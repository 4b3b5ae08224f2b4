"""Simulated annealing (SA), Kirkpatrick, Gelatt & Vecchi, Science 220 (1983), Metropolis rule.

``population`` independent chains run side by side; one generation asks one Gaussian move per
chain and accepts it by the Metropolis rule (Metropolis et al., J. Chem. Phys. 21, 1953): always
if ``f_new <= f_cur``, else with probability ``exp(-(f_new - f_cur) / T)``, ``u ~ U[0, 1)`` drawn
from the run's generator. ``T`` is one temperature shared by all chains.

Choices (parameters in :class:`SAParams`):

- **Initial sample and T0.** The first ask is ``max(init_samples, population)`` uniform points
  (capped by the budget); the chains start at the ``population`` best of them. ``T0`` follows
  White (Proc. IEEE ICCD 1984, "Concepts of scale in simulated annealing"): the standard
  deviation of the objective over random states, so that at ``T0`` an uphill move of one such
  deviation is accepted with probability ``exp(-1)``. It is estimated robustly, ``1.4826 MAD`` of
  the finite values (one huge value, common for a random network's error, does not inflate it);
  fallbacks if that is 0: their standard deviation, then ``|median|``, then 1. ``t0`` overrides.
- **Cooling.** Geometric, ``T_{k+1} = cooling T_k`` once per generation, never below
  ``t_final T0``. ``cooling = None`` (default) fits the rate to the budget,
  ``cooling = t_final^(1 / (G - 1))`` with ``G`` the move generations left after the initial
  sample, so ``T`` falls from ``T0`` to exactly ``t_final T0`` on the last generation.
- **Moves.** ``x' = x + sigma z``, ``z ~ N(0, I)``, per axis ``sigma = step (upper - lower)
  sqrt(T / T0)``: near a quadratic minimum the Boltzmann distribution at ``T`` has a width
  proportional to ``sqrt(T)``, so the step follows the region the chain samples.
- **Bounds.** A coordinate that leaves the box is reflected at the wall it crossed (folded as
  often as needed); reflection keeps the proposal symmetric, clamping would pile chains on walls.
- Non-finite values arrive as ``+inf``: never accepted from a finite state, never the best.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.optimisers.protocol import Optimiser, OptimiserParams

MAD_TO_SIGMA = 1.4826  # standard deviation of a normal sample from its median absolute deviation


@dataclass(frozen=True)
class SAParams(OptimiserParams):
    """SA parameters.

    population: independent chains, >= 1; one generation costs ``population`` evaluations.
    step: initial Gaussian step per axis as a fraction of the domain width, in (0, 1].
    cooling: geometric factor ``T <- cooling T`` per generation, in (0, 1); None fits it to the
        budget so that ``T`` reaches ``t_final T0`` on the last generation.
    t_final: lowest temperature as a fraction of ``T0``, in (0, 1].
    init_samples: uniform points evaluated first to set ``T0`` and the starts, >= 1.
    t0: initial temperature in objective units, > 0; None: White's rule on the initial sample.
    """

    population: int = 1
    step: float = 0.1
    cooling: float | None = None
    t_final: float = 1e-6
    init_samples: int = 20
    t0: float | None = None

    def __post_init__(self) -> None:  # a single chain is classic SA: no call to the base check
        if self.population < 1:
            raise ValueError(f"population must be >= 1, got {self.population}")
        if not 0 < self.step <= 1:
            raise ValueError(f"step must be in (0, 1] (fraction of the width), got {self.step}")
        if self.cooling is not None and not 0 < self.cooling < 1:
            raise ValueError(
                f"cooling must be in (0, 1) or null (fit to the budget), got {self.cooling}"
            )
        if not 0 < self.t_final <= 1:
            raise ValueError(f"t_final must be in (0, 1] (fraction of T0), got {self.t_final}")
        if self.init_samples < 1:
            raise ValueError(f"init_samples must be >= 1, got {self.init_samples}")
        if self.t0 is not None and not 0 < self.t0 < np.inf:
            raise ValueError(f"t0 must be a finite number > 0 or null, got {self.t0}")


def metropolis_accept(f_new: np.ndarray, f_cur: np.ndarray, t: float, u: np.ndarray) -> np.ndarray:
    """Metropolis rule: True where ``f_new <= f_cur`` or ``u < exp(-(f_new - f_cur) / t)``."""
    f_new, f_cur = np.asarray(f_new, dtype=np.float64), np.asarray(f_cur, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        p = np.exp(-(f_new - f_cur) / t)  # inf - inf = nan: caught by the first test
    return (f_new <= f_cur) | (u < p)


def initial_temperature(f: np.ndarray) -> float:
    """White's T0: robust standard deviation (``1.4826 MAD``) of the finite values; then their
    standard deviation, ``|median|``, 1 when the previous one is 0 or undefined."""
    f = np.asarray(f, dtype=np.float64)
    f = f[np.isfinite(f)]
    if f.size == 0:
        return 1.0
    median = float(np.median(f))
    for t in (MAD_TO_SIGMA * float(np.median(np.abs(f - median))), float(np.std(f)), abs(median)):
        if 0 < t < np.inf:
            return t
    return 1.0


def reflect(x: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Fold coordinates back into ``[lower, upper]`` by mirror reflection at the walls."""
    width = upper - lower
    y = np.mod(x - lower, 2.0 * width)
    return np.clip(lower + np.where(y > width, 2.0 * width - y, y), lower, upper)


class SimulatedAnnealing(Optimiser):
    """Simulated annealing, ``population`` Metropolis chains per ask/tell, geometric cooling."""

    name = "sa"
    Params = SAParams
    params: SAParams

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        p = self.params
        self.width = self.upper - self.lower
        self.n_init = min(max(p.init_samples, p.population), self.budget)
        moves = -(-(self.budget - self.n_init) // p.population)  # generations after the sample
        fitted = p.t_final ** (1.0 / max(moves - 1, 1))  # t_final T0 on the last generation
        self.cooling = p.cooling if p.cooling is not None else fitted
        self.t0 = self.temperature = float(p.t0 or 1.0)
        self.x = np.empty((0, self.dim))
        self.fitness = np.empty(0)

    @property
    def sigma(self) -> np.ndarray:
        """Per-axis standard deviation of the next move."""
        return self.params.step * self.width * np.sqrt(self.temperature / self.t0)

    def _ask(self) -> np.ndarray:
        if len(self.x) == 0:
            return self.uniform(self.n_init)
        k = min(self.params.population, self.remaining)
        z = self.rng.standard_normal((k, self.dim))
        return reflect(self.x[:k] + self.sigma * z, self.lower, self.upper)

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        p = self.params
        if len(self.x) == 0:  # the initial sample: starts and T0
            keep = np.argsort(f, kind="stable")[: p.population]
            self.x, self.fitness = x[keep].copy(), f[keep].copy()
            self.t0 = self.temperature = p.t0 if p.t0 is not None else initial_temperature(f)
            return
        k = len(f)
        accept = metropolis_accept(f, self.fitness[:k], self.temperature, self.rng.random(k))
        self.x[:k][accept], self.fitness[:k][accept] = x[accept], f[accept]
        self.generation += 1
        self.temperature = max(self.cooling * self.temperature, p.t_final * self.t0)
