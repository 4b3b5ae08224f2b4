"""NSGA-II and MOEA/D as tcbench optimisers: adapters over pymoo 0.6's implementations.

- ``nsga2``: ``pymoo.algorithms.moo.nsga2.NSGA2``, the elitist non-dominated sorting genetic
  algorithm of Deb, Pratap, Agarwal & Meyarivan (2002), "A fast and elitist multiobjective
  genetic algorithm: NSGA-II", IEEE Trans. Evol. Comput. 6(2), 182-197.
- ``moead``: ``pymoo.algorithms.moo.moead.MOEAD``, the decomposition-based algorithm of Zhang &
  Li (2007), "MOEA/D: A Multiobjective Evolutionary Algorithm Based on Decomposition", IEEE
  Trans. Evol. Comput. 11(6), 712-731.

The algorithms are pymoo's own, untouched; this module only drives them through pymoo's
ask-and-tell interface. The tcbench box becomes a pymoo ``Problem`` (:class:`BoxProblem`,
``n_var = d``, ``n_obj = m``, ``xl``/``xu`` = the bounds) with no objective of its own:
``algorithm.setup(problem, termination=NoTermination(), seed=..., verbose=False)``, then per
tcbench round ``algorithm.ask()`` gives the infill, tcbench evaluates it, and the told values
``F`` (k, m) are written into it by ``algorithm.evaluator.eval(problem, infill)`` while the
problem hands them back (as pymoo's ``StaticProblem`` would) before
``algorithm.tell(infills=infill)``. pymoo's seed is drawn from the run's generator
(:func:`tcbench_peers.seeding.library_seed`), so the same seed asks the same points, and with
the same seed and objective a run is exactly ``pymoo.optimize.minimize``'s.

Shared rules:

- **Batches.** One tcbench ask is whatever pymoo's next ``ask()`` returns. NSGA-II: the initial
  population, then one generation of offspring (``population`` of them, fewer if pymoo's
  duplicate elimination could not produce that many). MOEA/D: the initial population (one
  member per reference direction), then a single offspring per ask: pymoo's MOEA/D walks the
  subproblems one at a time and updates the neighbourhood with each offspring before mating
  the next, so nothing larger can be batched without changing the algorithm.
- **Budget.** A batch larger than the evaluations left is cut to them; the run then ends with
  that batch (``done``), and the cut batch is not told to pymoo, which only ever sees complete
  infills. pymoo's own termination is switched off (``NoTermination``): the budget ends the run,
  or pymoo running out of offspring (NSGA-II's mating finds no new non-duplicate point), which
  ends it early (``done`` becomes True).
- **Generations.** ``generation`` counts pymoo's iterations: the initial population, then one
  per NSGA-II generation or per MOEA/D sweep over all N subproblems, so the runner records
  progress once per N evaluations for both; a cut batch or a partial last sweep counts as one
  more.
- **Non-finite values.** A NaN/inf objective makes the whole row ``+inf`` (base class); pymoo
  receives such rows as ``1e300`` (:data:`WORST`) in every objective, a huge finite value it can
  rank: ``inf`` can turn NSGA-II's crowding distances (``inf - inf``, ``inf / inf``) and
  MOEA/D's decomposition values (``inf - inf`` against an infinite ideal point, ``0 * inf``
  for a zero weight) into NaN. (PBI's distance to the weight vector squares such values; the
  overflow to ``inf`` still means "worst" and is not reported as a warning.)
- **Bounds.** pymoo's SBX and polynomial mutation keep points inside ``[xl, xu]``; points are
  clamped anyway against float round-off.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from pymoo.algorithms.moo.moead import MOEAD as PymooMOEAD
from pymoo.algorithms.moo.nsga2 import NSGA2 as PymooNSGA2
from pymoo.core.algorithm import Algorithm
from pymoo.core.individual import Individual
from pymoo.core.problem import Problem
from pymoo.core.termination import NoTermination
from pymoo.decomposition.pbi import PBI
from pymoo.decomposition.tchebicheff import Tchebicheff
from pymoo.util.ref_dirs import get_reference_directions

from tcbench.optimisers.protocol import Optimiser, OptimiserParams
from tcbench_peers.seeding import library_seed

WORST = 1e300  # what pymoo receives for a row with a NaN/inf objective

DECOMPOSITIONS = ("auto", "tchebicheff", "pbi")


class BoxProblem(Problem):
    """The tcbench box as a pymoo problem: bounds and sizes, no objective of its own. Inside
    :meth:`told` its evaluation hands back the values tcbench was told for the infill (what
    ``pymoo.problems.static.StaticProblem`` does, without copying the problem at every step);
    evaluating it otherwise is an error."""

    def __init__(self, lower: np.ndarray, upper: np.ndarray, n_obj: int) -> None:
        super().__init__(n_var=lower.size, n_obj=n_obj, n_ieq_constr=0, xl=lower, xu=upper)
        self._told: np.ndarray | None = None

    @contextmanager
    def told(self, f: np.ndarray) -> Iterator[BoxProblem]:
        """Within the block, evaluating ``k`` points returns ``f`` (k, m)."""
        self._told = f
        try:
            yield self
        finally:
            self._told = None

    def _evaluate(self, x: np.ndarray, out: dict[str, Any], *args: Any, **kwargs: Any) -> None:
        if self._told is None:
            raise RuntimeError("BoxProblem has no objective: tcbench evaluates and tells the values")
        if self._told.shape != (x.shape[0], self.n_obj):
            raise RuntimeError(f"told values of shape {self._told.shape} for {x.shape[0]} points")
        out["F"] = self._told


def das_dennis_partitions(population: int, m: int) -> int:
    """Largest number of partitions ``H`` whose Das-Dennis simplex lattice, ``C(H + m - 1, m - 1)``
    directions for ``m`` objectives, has at most ``population`` directions (exactly
    ``population`` for two objectives, ``H = population - 1``); needs ``population >= m``."""
    if population < m:
        raise ValueError(f"population must be >= the {m} objectives for MOEA/D, got {population}")
    h = 1
    while math.comb(h + m, m - 1) <= population:
        h += 1
    return h


class PymooOptimiser(Optimiser):
    """Base of the pymoo adapters: ask/tell over a pymoo algorithm built by ``_algorithm()``."""

    single_objective: ClassVar[bool] = False
    multi_objective: ClassVar[bool] = True

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.problem = BoxProblem(self.lower, self.upper, self.n_objectives)
        self.algorithm = self._algorithm()
        self.algorithm.setup(
            self.problem, termination=NoTermination(), seed=library_seed(self.rng), verbose=False
        )
        self._cut = False
        # pymoo's next infill (a Population, or an Individual for MOEA/D's offspring), fetched
        # one step ahead so that pymoo running dry is known before the next ask (``done``)
        self._infill: Any = self._next_infill()

    def _algorithm(self) -> Algorithm:
        raise NotImplementedError

    def _next_infill(self) -> Any:
        """pymoo's next infill, or None when it could not produce one (NSGA-II's mating found
        no new non-duplicate offspring)."""
        infill = self.algorithm.ask()
        if infill is None or (not isinstance(infill, Individual) and len(infill) == 0):
            return None
        return infill

    def _ask(self) -> np.ndarray:
        x = np.atleast_2d(np.asarray(self._infill.get("X"), dtype=np.float64))
        self._cut = x.shape[0] > self.remaining
        return self.clip(x[: self.remaining])

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        if self._cut:  # budget spent mid-batch: the run ends here, pymoo is told nothing
            self._infill = None
            self.generation += 1
            return
        values = np.where(np.isfinite(f), f, WORST)
        with np.errstate(over="ignore"):
            with self.problem.told(values) as problem:
                self.algorithm.evaluator.eval(problem, self._infill)
            self.algorithm.tell(infills=self._infill)
            self._infill = self._next_infill() if self.remaining > 0 else None
        # pymoo's completed iterations (initial population, NSGA-II generations, MOEA/D sweeps);
        # a partial last sweep still counts, so that the end of the run is recorded
        before = self.generation
        self.generation = self.algorithm.n_iter - 1
        if self.remaining <= 0 and self.generation == before:
            self.generation += 1

    def _stopped(self) -> bool:
        return self._infill is None

    @property
    def population_fitness(self) -> np.ndarray:
        """Objective values (k, m) of pymoo's current population, ``inf`` where pymoo was told
        :data:`WORST`; empty before the initial population was told."""
        pop = self.algorithm.pop
        if pop is None or len(pop) == 0 or not self.algorithm.is_initialized:
            return np.empty((0, self.n_objectives))
        f = np.asarray(pop.get("F"), dtype=np.float64)
        return np.where(f >= WORST, np.inf, f)


# -- NSGA-II ------------------------------------------------------------------------------------


@dataclass(frozen=True)
class NSGA2Params(OptimiserParams):
    """Parameters of pymoo's NSGA-II.

    population: population size N (pymoo's ``pop_size``, default 100); also the number of
        offspring per generation. Everything else is pymoo's default: uniform random initial
        population, binary tournament by dominance then crowding distance, SBX crossover
        (probability 0.9 per pair, each variable with probability 0.5, eta 15), polynomial
        mutation (probability 0.9 per child, each variable with probability min(0.5, 1/d),
        eta 20), elimination of duplicate offspring, rank-and-crowding survival.
    """

    population: int = 100

    def __post_init__(self) -> None:
        super().__post_init__()


class NSGA2(PymooOptimiser):
    """NSGA-II (Deb et al. 2002), pymoo's implementation driven by ask/tell: one ask is one
    generation of offspring; see the module docstring."""

    name: ClassVar[str] = "nsga2"
    Params: ClassVar[type[OptimiserParams]] = NSGA2Params
    params: NSGA2Params

    def _algorithm(self) -> Algorithm:
        return PymooNSGA2(pop_size=self.params.population)


# -- MOEA/D -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class MOEADParams(OptimiserParams):
    """Parameters of pymoo's MOEA/D.

    population: upper bound on the number of subproblems N. The weight vectors are pymoo's
        Das-Dennis lattice ``get_reference_directions("das-dennis", m, n_partitions=H)`` with
        the largest ``H`` giving at most ``population`` vectors: exactly ``population`` for two
        objectives, e.g. 91 of 100 for three (:func:`das_dennis_partitions`). Must be >= m.
    n_neighbors: neighbourhood size T (pymoo's default 20; Zhang & Li used 20 too), >= 2; cut
        to N when there are fewer subproblems.
    prob_neighbor_mating: probability that both parents come from the neighbourhood rather than
        the whole population (pymoo's default 0.9), in [0, 1].
    decomposition: "auto" (pymoo's default: Tchebycheff for two objectives, PBI with
        theta = 5 for three or more), "tchebicheff" or "pbi" (theta = 5).

    Operators are pymoo's MOEA/D defaults: uniform random initial population, SBX crossover
    (probability 1, each variable with probability 0.5, eta 20) of which one child is kept at
    random, polynomial mutation (probability 0.9, each variable with probability
    min(0.5, 1/d), eta 20), no duplicate elimination; the ideal point is the running minimum
    of every value told.
    """

    population: int = 100
    n_neighbors: int = 20
    prob_neighbor_mating: float = 0.9
    decomposition: str = "auto"

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.n_neighbors < 2:
            raise ValueError(f"n_neighbors must be >= 2, got {self.n_neighbors}")
        if not 0.0 <= self.prob_neighbor_mating <= 1.0:
            raise ValueError(f"prob_neighbor_mating must be in [0, 1], got {self.prob_neighbor_mating}")
        if self.decomposition not in DECOMPOSITIONS:
            raise ValueError(f"decomposition must be one of {DECOMPOSITIONS}, got {self.decomposition!r}")


class MOEAD(PymooOptimiser):
    """MOEA/D (Zhang & Li 2007), pymoo's implementation driven by ask/tell: the initial
    population, then one offspring per ask; see the module docstring."""

    name: ClassVar[str] = "moead"
    Params: ClassVar[type[OptimiserParams]] = MOEADParams
    params: MOEADParams

    def _algorithm(self) -> Algorithm:
        p = self.params
        h = das_dennis_partitions(p.population, self.n_objectives)
        self.ref_dirs = get_reference_directions("das-dennis", self.n_objectives, n_partitions=h)
        decomposition = {"auto": None, "tchebicheff": Tchebicheff(), "pbi": PBI()}[p.decomposition]
        return PymooMOEAD(
            ref_dirs=self.ref_dirs,
            n_neighbors=min(p.n_neighbors, len(self.ref_dirs)),
            decomposition=decomposition,
            prob_neighbor_mating=p.prob_neighbor_mating,
        )
