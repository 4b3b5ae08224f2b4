"""Particle swarm optimisation (PSO), global-best topology; seed 001 §3.2, eq. 21-22.

Each particle ``i`` keeps a position ``x``, a velocity ``v`` and its best position so far ``p``;
the swarm shares the best of all ``p``, ``g``. One generation moves every particle by

    v' = chi (w v + c1 r1 (p - x) + c2 r2 (g - x))      (eq. 21, chi the paper's mu)
    x' = x + v'                                          (eq. 22)

with ``r1``, ``r2 ~ U[0, 1]`` drawn per particle and per variable.

Choices (all but the first are parameters, see :class:`PSOParams`):

- Initialisation as seed 001 step B: positions uniform in the bounds, velocities zero (so the
  first move is driven by ``p`` and ``g`` alone).
- Synchronous updates: ``p`` and ``g`` change after the whole swarm has been told; a generation
  costs ``population`` evaluations. When the budget shortens the last generation to ``k``
  evaluations, only the first ``k`` particles move.
- ``chi``: 1 unless ``constriction``; then Clerc & Kennedy's (IEEE TEC 6(1), 2002) constriction
  ``chi = 2 / |2 - phi - sqrt(phi^2 - 4 phi)|`` with ``phi = c1 + c2 > 4`` (their type 1''
  model, written for ``w = 1``; with ``w < 1`` eq. 21 damps the momentum term further). The
  default ``w = 0.7298, c1 = c2 = 1.49618`` without constriction is the same swarm as
  ``w = 1, c1 = c2 = 2.05`` with it (``chi(4.1) = 0.7298``).
- Velocity clamp: each component of ``v'`` is limited to ``+- v_max_fraction (upper - lower)``
  of its axis, after the constriction.
- Bounds: a position component that leaves the box is clamped to the bound it crossed and that
  velocity component is set to zero ("absorbing wall"), so the particle does not keep pushing
  against the wall in the next generation.

Non-finite objective values arrive as ``+inf`` and never replace a personal best.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.optimisers.protocol import Optimiser, OptimiserParams


@dataclass(frozen=True)
class PSOParams(OptimiserParams):
    """PSO parameters; defaults are Clerc-Kennedy's constricted swarm written as inertia form.

    w: inertia weight of eq. 21, in [0, 1].
    c1: cognitive coefficient (pull toward the particle's own best), >= 0.
    c2: social coefficient (pull toward the swarm's best), >= 0; c1 + c2 > 0.
    constriction: multiply eq. 21 by Clerc's chi(c1 + c2); needs c1 + c2 > 4.
    v_max_fraction: velocity clamp per axis as a fraction of the domain width, in (0, 1].
    """

    population: int = 40
    w: float = 0.7298
    c1: float = 1.49618
    c2: float = 1.49618
    constriction: bool = False
    v_max_fraction: float = 0.2

    def __post_init__(self) -> None:
        super().__post_init__()
        if not 0 <= self.w <= 1:
            raise ValueError(f"w must be in [0, 1], got {self.w}")
        if not 0 <= self.c1 < np.inf:
            raise ValueError(f"c1 must be a finite number >= 0, got {self.c1}")
        if not 0 <= self.c2 < np.inf:
            raise ValueError(f"c2 must be a finite number >= 0, got {self.c2}")
        if self.c1 + self.c2 <= 0:
            raise ValueError("c1 + c2 must be > 0: with both zero the swarm never moves")
        if self.constriction and not self.c1 + self.c2 > 4:
            raise ValueError(
                f"constriction needs phi = c1 + c2 > 4, got {self.c1 + self.c2} "
                "(Clerc-Kennedy use c1 = c2 = 2.05 with w = 1)"
            )
        if not 0 < self.v_max_fraction <= 1:
            raise ValueError(f"v_max_fraction must be in (0, 1], got {self.v_max_fraction}")


def constriction_factor(phi: float) -> float:
    """Clerc-Kennedy constriction ``chi = 2 / |2 - phi - sqrt(phi^2 - 4 phi)|`` for ``phi > 4``."""
    if not phi > 4:
        raise ValueError(f"the constriction factor needs phi > 4, got {phi}")
    return 2.0 / abs(2.0 - phi - math.sqrt(phi * phi - 4.0 * phi))


def pso_velocity(
    v: np.ndarray,
    x: np.ndarray,
    pbest: np.ndarray,
    gbest: np.ndarray,
    w: float,
    c1: float,
    c2: float,
    r1: np.ndarray,
    r2: np.ndarray,
    chi: float = 1.0,
) -> np.ndarray:
    """Eq. 21: ``v' = chi (w v + c1 r1 (pbest - x) + c2 r2 (gbest - x))``, row-wise over particles
    (``gbest`` of shape (d,) broadcasts to the whole swarm)."""
    return chi * (w * v + c1 * r1 * (pbest - x) + c2 * r2 * (gbest - x))


def clamp_velocity(v: np.ndarray, v_max: np.ndarray) -> np.ndarray:
    """Limit each velocity component to ``[-v_max, v_max]`` of its axis."""
    return np.clip(v, -v_max, v_max)


def move_within_bounds(
    x: np.ndarray, v: np.ndarray, lower: np.ndarray, upper: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 22 ``x' = x + v`` with an absorbing wall: components beyond a bound are clamped to it
    and their velocity zeroed. Returns ``(x', v')``."""
    moved = x + v
    inside = np.clip(moved, lower, upper)
    return inside, np.where(inside != moved, 0.0, v)


class ParticleSwarm(Optimiser):
    """Global-best particle swarm (eq. 21-22), population-vectorised ask/tell."""

    name = "pso"
    Params = PSOParams
    params: PSOParams

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        p = self.params
        self.chi = constriction_factor(p.c1 + p.c2) if p.constriction else 1.0
        self.v_max = p.v_max_fraction * (self.upper - self.lower)
        self.x = np.empty((0, self.dim))
        self.v = np.empty((0, self.dim))
        self.fitness = np.empty(0)
        self.pbest = np.empty((0, self.dim))
        self.pbest_f = np.empty(0)
        self._proposal: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def gbest(self) -> np.ndarray:
        """Best personal best of the swarm (the global-best topology's attractor)."""
        return self.pbest[int(np.argmin(self.pbest_f))]

    def _ask(self) -> np.ndarray:
        p = self.params
        if len(self.x) == 0:
            return self.uniform(p.population)
        r1 = self.rng.random(self.x.shape)
        r2 = self.rng.random(self.x.shape)
        v = pso_velocity(self.v, self.x, self.pbest, self.gbest, p.w, p.c1, p.c2, r1, r2, self.chi)
        x, v = move_within_bounds(self.x, clamp_velocity(v, self.v_max), self.lower, self.upper)
        self._proposal = (x, v)
        return x[: self.remaining]

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        if len(self.x) == 0:
            self.x, self.v, self.fitness = x, np.zeros_like(x), f
            self.pbest, self.pbest_f = x.copy(), f.copy()
            return
        assert self._proposal is not None
        k = len(f)
        self.x[:k], self.v[:k], self.fitness[:k] = x, self._proposal[1][:k], f
        self._proposal = None
        better = f < self.pbest_f[:k]
        self.pbest[:k][better], self.pbest_f[:k][better] = x[better], f[better]
        self.generation += 1
