"""CMA-ES and IPOP-CMA-ES as tcbench optimisers: adapters over the ``cma`` package's ES.

CMA-ES (Hansen & Ostermeier 2001; Hansen 2016, "The CMA Evolution Strategy: A Tutorial") runs
as ``cma.CMAEvolutionStrategy`` with its own ask/tell, in the box mapped to ``[0, 1]^d`` (so one
step size serves every axis) with ``cma``'s bound handling on ``[0, 1]``. One tcbench ask is one
generation of ``lambda`` points, the last one shortened to the evaluations left (the run then
ends: the shortened generation is never told to the ES). Values that the task reports as NaN or
inf reach the ES as ``1e300``, the worst finite value it can rank.

- ``cmaes``: one run from a uniform random start; it ends when ``cma``'s own stopping rules
  fire (``tolfun``, ``tolx``, ...) or the budget is spent.
- ``ipop_cmaes`` (Auger & Hansen 2005): when a run stops by itself, a new one starts from a new
  uniform random start with the population doubled, until the budget is spent.

Defaults are ``cma``'s: ``lambda = 4 + floor(3 ln d)`` (``population = 0``) and an initial step
of 0.3 of the box width per axis (``sigma0``), inside the 1/4-1/3 the tutorial recommends.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import ClassVar

import cma
import numpy as np

from tcbench.optimisers.protocol import Optimiser, OptimiserParams
from tcbench_peers.seeding import library_seed

WORST = 1e300


@dataclass(frozen=True)
class CMAESParams(OptimiserParams):
    """CMA-ES parameters.

    population: offspring per generation lambda; 0 takes cma's default ``4 + floor(3 ln d)``.
    sigma0: initial step size as a fraction of the box width, in (0, 1].
    incpopsize: IPOP's population factor at each restart (``ipop_cmaes`` only), >= 1.
    """

    population: int = 0
    sigma0: float = 0.3
    incpopsize: float = 2.0

    def __post_init__(self) -> None:
        if self.population != 0 and self.population < 2:
            raise ValueError(f"population must be 0 (cma's default) or >= 2, got {self.population}")
        if not 0.0 < self.sigma0 <= 1.0:
            raise ValueError(f"sigma0 must be in (0, 1], got {self.sigma0}")
        if not (math.isfinite(self.incpopsize) and self.incpopsize >= 1.0):
            raise ValueError(f"incpopsize must be a finite number >= 1, got {self.incpopsize}")


class CMAES(Optimiser):
    """CMA-ES (``cma`` package), one run; see the module docstring."""

    name: ClassVar[str] = "cmaes"
    Params: ClassVar[type[OptimiserParams]] = CMAESParams
    restarts: ClassVar[bool] = False

    @classmethod
    def memory_bytes(cls, params: OptimiserParams, dim: int, n_objectives: int = 1) -> int:
        """cma keeps a ``dim x dim`` covariance, its eigenvectors and a few copies: about five
        ``dim x dim`` arrays beside the population."""
        lam = params.population or 4 + int(3 * math.log(max(dim, 1)))
        return 8 * int(dim) * (5 * int(dim) + 16 * lam + 64)

    def __init__(self, *args, **kwargs) -> None:  # type: ignore[no-untyped-def]
        super().__init__(*args, **kwargs)
        p: CMAESParams = self.params  # type: ignore[assignment]
        self.lam = p.population or 4 + int(3 * math.log(self.dim))
        self.runs = 0
        self.fitness = np.empty(0)
        self._es = self._start(self.lam)
        self._asked: list[np.ndarray] = []

    def _start(self, lam: int) -> cma.CMAEvolutionStrategy:
        """A new ES from a uniform random start in ``[0, 1]^d`` with ``lam`` offspring."""
        p: CMAESParams = self.params  # type: ignore[assignment]
        options = {"bounds": [0.0, 1.0], "popsize": int(lam), "seed": library_seed(self.rng), "verbose": -9,
                   "verb_log": 0, "verb_disp": 0, "maxfevals": float("inf"), "CMA_diagonal": False}
        if self.dim == 1:  # cma 4.x fails to cap the step size to the bounds in 1-D; leave it uncapped
            options["maxstd"] = float("inf")
        self.runs += 1
        x0 = self.rng.uniform(0.0, 1.0, self.dim)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return cma.CMAEvolutionStrategy(x0, p.sigma0, options)

    def _ask(self) -> np.ndarray:
        self._asked = self._es.ask()
        unit = np.clip(np.asarray(self._asked, dtype=np.float64), 0.0, 1.0)
        x = self.lower + unit * (self.upper - self.lower)
        return np.clip(x, self.lower, self.upper)[: self.remaining]

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        self.generation += 1
        self.fitness = f
        if len(f) < len(self._asked):  # the budget cut the generation short: the run is over
            return
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self._es.tell(self._asked, np.where(np.isfinite(f), f, WORST).tolist())
        if self._es.stop() and self.restarts:
            self.lam = int(round(self.lam * self.params.incpopsize))  # type: ignore[attr-defined]
            self._es = self._start(self.lam)

    def _stopped(self) -> bool:
        return not self.restarts and bool(self._es.stop())


class IPOPCMAES(CMAES):
    """IPOP-CMA-ES: CMA-ES restarted with a doubled population whenever it stops by itself."""

    name: ClassVar[str] = "ipop_cmaes"
    restarts: ClassVar[bool] = True
