"""Differential evolution and dual annealing as tcbench optimisers: adapters over ``scipy.optimize``.

- ``scipy_de``: ``scipy.optimize.differential_evolution``, DE of Storn & Price (1997),
  "Differential Evolution - A Simple and Efficient Heuristic for Global Optimization over
  Continuous Spaces", J. Global Optim. 11, 341-359.
- ``dual_annealing``: ``scipy.optimize.dual_annealing``, generalized simulated annealing of
  Xiang, Sun, Fan & Gong (1997), "Generalized simulated annealing algorithm and its application
  to the Thomson model", Phys. Lett. A 233, 216-220, with scipy's local search.

Both scipy functions call the objective themselves; each run goes through
:class:`tcbench_peers.inverted.InvertedRun`: scipy runs in a worker thread whose objective hands
the points to ``ask`` and waits for ``tell``. The algorithms are scipy's own, untouched; seeds
come from the run's generator (:func:`tcbench_peers.seeding.library_seed`), so the same seed
asks the same points.

Shared rules:

- **Budget.** A batch larger than the evaluations left is cut to them, and once the budget is
  spent scipy is stopped (a private exception unwinds it inside the worker). scipy therefore
  never receives a made-up value: the points it asked beyond the budget are simply never
  answered, and the last batch it was told is always a complete one.
- **Non-finite values.** NaN/inf (``+inf`` after the base class) reach scipy as ``1e300``
  (:data:`WORST`), a huge finite value: ``inf`` would switch off DE's convergence test, make
  dual annealing re-draw its start point (and raise after 1000 non-finite starts) and turn the
  finite-difference gradients of its local search into NaN. (DE's convergence
  test then squares values near 1e300; the resulting overflow to ``inf``, which just means "not
  converged", is not reported as a warning.)
- **Bounds.** scipy keeps its points in the box; they are clamped anyway against float round-off
  in its scaling (a change of at most an ulp or so).
- **Stopping.** A run also ends when scipy returns by itself (``done`` becomes True): DE when all
  population values are equal (``tol = atol = 0``), dual annealing after ``maxiter`` iterations.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from scipy.optimize import differential_evolution, dual_annealing
from scipy.stats import qmc

from tcbench.optimisers.protocol import Optimiser, OptimiserParams, make_params
from tcbench_peers.inverted import Evaluate, InvertedRun
from tcbench_peers.seeding import library_seed

WORST = 1e300  # what scipy receives for a NaN/inf value

DE_STRATEGIES = (
    "best1bin", "best1exp", "rand1bin", "rand1exp", "rand2bin", "rand2exp", "randtobest1bin",
    "randtobest1exp", "currenttobest1bin", "currenttobest1exp", "best2bin", "best2exp",
)
DE_INITS = ("latinhypercube", "random")
DE_DEFAULT_POPSIZE = 15  # scipy's popsize: population = 15 d when population = 0
DE_MIN_POPULATION = 5  # scipy refuses an initial population of fewer members
DE_MIN_POPULATION_RAND2 = 6  # rand2* draws 5 members besides the target


class InvertedOptimiser(Optimiser):
    """Base of the scipy adapters: ask/tell over an :class:`InvertedRun` of ``_library()``."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.fitness = np.empty(0)
        self.library_result: Any = None
        self._run = InvertedRun(self._library(), name=self.name)

    def _library(self) -> Callable[[Evaluate], Any]:
        """``target(evaluate)`` running scipy; built from plain values, never from ``self``."""
        raise NotImplementedError

    def _ask(self) -> np.ndarray:
        return self.clip(self._run.ask())[: self.remaining]

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        self.generation += 1
        self.fitness = f
        if self.remaining <= 0:  # budget spent, maybe mid-batch: stop scipy, tell it nothing
            self._run.close()
            return
        self._run.tell(np.where(np.isfinite(f), f, WORST))
        if self._run.finished:
            self.library_result = self._run.result

    def _stopped(self) -> bool:
        return self._run.finished

    def close(self) -> None:
        """Abandon the run now: stop scipy and end its worker thread (also done on collection)."""
        self._run.close()


# -- differential evolution -------------------------------------------------------------------


@dataclass(frozen=True)
class ScipyDEParams(OptimiserParams):
    """Parameters of ``scipy.optimize.differential_evolution``.

    population: total population S, exact. 0 takes scipy's default size ``15 d`` (its
        ``popsize = 15`` multiplies the dimension d); otherwise >= 5 (>= 6 for the rand2
        strategies). It is passed as an explicit initial population (scipy's ``init`` array)
        of S rows, so any S is possible, not only multiples of d; scipy's ``popsize`` is then
        unused.
    init: how the S initial rows are drawn from the run's generator: "latinhypercube" (scipy's
        default, ``scipy.stats.qmc.LatinHypercube``) or "random" (uniform).
    mutation_low, mutation_high: the differential weight F; scipy draws it uniformly in
        ``[mutation_low, mutation_high)`` once per generation (dithering, scipy's default
        ``(0.5, 1)``); equal values give a constant F. 0 <= low <= high < 2.
    recombination: crossover probability CR, in [0, 1] (scipy's default 0.7).
    strategy: scipy's strategy name (default "best1bin").
    """

    population: int = 0
    init: str = "latinhypercube"
    mutation_low: float = 0.5
    mutation_high: float = 1.0
    recombination: float = 0.7
    strategy: str = "best1bin"

    def __post_init__(self) -> None:
        if self.strategy not in DE_STRATEGIES:
            raise ValueError(f"strategy must be one of {DE_STRATEGIES}, got {self.strategy!r}")
        least = DE_MIN_POPULATION_RAND2 if self.strategy.startswith("rand2") else DE_MIN_POPULATION
        if self.population != 0 and self.population < least:
            raise ValueError(
                f"population must be 0 (scipy's default 15 d) or >= {least} for strategy "
                f"{self.strategy!r}, got {self.population}"
            )
        if self.init not in DE_INITS:
            raise ValueError(f"init must be one of {DE_INITS}, got {self.init!r}")
        if not 0.0 <= self.mutation_low <= self.mutation_high < 2.0:
            raise ValueError(
                "mutation must satisfy 0 <= mutation_low <= mutation_high < 2, got "
                f"mutation_low={self.mutation_low}, mutation_high={self.mutation_high}"
            )
        if not 0.0 <= self.recombination <= 1.0:
            raise ValueError(f"recombination must be in [0, 1], got {self.recombination}")


def _run_de(
    evaluate: Evaluate,
    bounds: list[tuple[float, float]],
    init: np.ndarray,
    strategy: str,
    mutation: float | tuple[float, float],
    recombination: float,
    maxiter: int,
    seed: int,
) -> Any:
    """``differential_evolution`` with one objective call per generation (``vectorized``)."""

    def objective(x: np.ndarray) -> np.ndarray | float:
        x = np.asarray(x, dtype=np.float64)
        if x.ndim == 1:  # a single point (not used with polish=False, kept for safety)
            return float(evaluate(x[None, :])[0])
        return evaluate(x.T)  # scipy sends (d, S)

    with np.errstate(over="ignore"):  # the spread of values holding 1e300 overflows to inf: harmless
        return differential_evolution(
            objective, bounds, strategy=strategy, maxiter=maxiter, tol=0.0, atol=0.0,
            mutation=mutation, recombination=recombination, seed=seed, polish=False, init=init,
            updating="deferred", vectorized=True,
        )


class ScipyDE(InvertedOptimiser):
    """Differential evolution (Storn & Price 1997), adapting ``scipy.optimize.differential_evolution``.

    One ask is one generation: first the S initial members, then S trial vectors per generation
    (``vectorized=True, updating="deferred"``: scipy evaluates a whole generation in one
    objective call and replaces members afterwards). ``polish=False``: scipy's final L-BFGS-B
    polish would evaluate points one by one after the last generation, outside the generation
    batches. ``maxiter`` is the budget (never reached: a generation costs >= 5 evaluations) and
    ``tol = atol = 0``, so the budget ends the run, unless all S values become equal.
    """

    name: ClassVar[str] = "scipy_de"
    Params: ClassVar[type[OptimiserParams]] = ScipyDEParams
    single_objective: ClassVar[bool] = True
    multi_objective: ClassVar[bool] = False
    params: ScipyDEParams

    def __init__(
        self,
        lower: np.ndarray,
        upper: np.ndarray,
        budget: int,
        rng: np.random.Generator,
        params: OptimiserParams | dict[str, Any] | None = None,
        n_objectives: int = 1,
    ) -> None:
        checked = make_params(type(self), params)
        dim = np.asarray(lower).size
        self.size = checked.population or DE_DEFAULT_POPSIZE * dim
        if int(budget) != budget or budget < self.size:
            origin = "population" if checked.population else f"scipy's default 15 d, d = {dim}"
            raise ValueError(
                f"budget of {budget} evaluations is smaller than one generation "
                f"(population {self.size}, {origin})"
            )
        super().__init__(lower, upper, budget, rng, checked, n_objectives)

    def _library(self) -> Callable[[Evaluate], Any]:
        p = self.params
        if p.init == "latinhypercube":
            unit = qmc.LatinHypercube(self.dim, seed=library_seed(self.rng)).random(self.size)
        else:
            unit = self.rng.random((self.size, self.dim))
        init = self.clip(self.lower + unit * (self.upper - self.lower))
        mutation = (
            p.mutation_low if p.mutation_low == p.mutation_high else (p.mutation_low, p.mutation_high)
        )
        return functools.partial(
            _run_de,
            bounds=list(zip(self.lower.tolist(), self.upper.tolist(), strict=True)),
            init=init,
            strategy=p.strategy,
            mutation=mutation,
            recombination=p.recombination,
            maxiter=self.budget,
            seed=library_seed(self.rng),
        )


# -- dual annealing ---------------------------------------------------------------------------


@dataclass(frozen=True)
class DualAnnealingParams(OptimiserParams):
    """Parameters of ``scipy.optimize.dual_annealing`` (ranges as scipy documents them).

    population: must be 1 (dual annealing evaluates one point at a time).
    initial_temp: initial temperature, in (0.01, 5e4] (scipy 5230).
    restart_temp_ratio: re-annealing starts when the temperature falls to this fraction of
        ``initial_temp``, in (0, 1) (scipy 2e-5).
    visit: visiting distribution parameter q_v, in (1, 3] (scipy 2.62).
    accept: acceptance distribution parameter q_a, in (-1e4, -5] (scipy -5).
    maxiter: global search iterations; None (default): as many as the budget allows (scipy
        passes ``maxiter = budget``; an iteration costs >= 2 d evaluations). scipy's own default
        is 1000.
    no_local_search: True skips scipy's local search (L-BFGS-B) after the strategy chains,
        i.e. plain generalized simulated annealing. Default False, as scipy: every local search
        evaluation also goes through ask/tell and counts against the budget.
    """

    population: int = 1
    initial_temp: float = 5230.0
    restart_temp_ratio: float = 2e-5
    visit: float = 2.62
    accept: float = -5.0
    maxiter: int | None = None
    no_local_search: bool = False

    def __post_init__(self) -> None:  # one point at a time: no call to the base check
        if self.population != 1:
            raise ValueError(
                f"population must be 1 (dual annealing evaluates one point at a time), got {self.population}"
            )
        if not 0.01 < self.initial_temp <= 5e4:
            raise ValueError(f"initial_temp must be in (0.01, 5e4], got {self.initial_temp}")
        if not 0.0 < self.restart_temp_ratio < 1.0:
            raise ValueError(f"restart_temp_ratio must be in (0, 1), got {self.restart_temp_ratio}")
        if not 1.0 < self.visit <= 3.0:
            raise ValueError(f"visit must be in (1, 3], got {self.visit}")
        if not -1e4 < self.accept <= -5.0:
            raise ValueError(f"accept must be in (-1e4, -5], got {self.accept}")
        if self.maxiter is not None and self.maxiter < 1:
            raise ValueError(f"maxiter must be >= 1 or null (the budget decides), got {self.maxiter}")


def _run_dual_annealing(evaluate: Evaluate, bounds: list[tuple[float, float]], **options: Any) -> Any:
    """``dual_annealing`` on single points (scipy calls the objective with ``x`` of shape (d,))."""

    def objective(x: np.ndarray) -> float:
        return float(evaluate(np.asarray(x, dtype=np.float64)[None, :])[0])

    return dual_annealing(objective, bounds, **options)


class DualAnnealing(InvertedOptimiser):
    """Dual annealing (Xiang et al. 1997), adapting ``scipy.optimize.dual_annealing``.

    One point per ask. scipy's ``maxfun`` is set to the budget; it is a soft limit (a local
    search may overrun it), so the hard limit is the adapter's: scipy is stopped, unanswered, as
    soon as the budget is spent.
    """

    name: ClassVar[str] = "dual_annealing"
    Params: ClassVar[type[OptimiserParams]] = DualAnnealingParams
    single_objective: ClassVar[bool] = True
    multi_objective: ClassVar[bool] = False
    params: DualAnnealingParams

    def _library(self) -> Callable[[Evaluate], Any]:
        p = self.params
        return functools.partial(
            _run_dual_annealing,
            bounds=list(zip(self.lower.tolist(), self.upper.tolist(), strict=True)),
            maxiter=p.maxiter if p.maxiter is not None else self.budget,
            initial_temp=p.initial_temp,
            restart_temp_ratio=p.restart_temp_ratio,
            visit=p.visit,
            accept=p.accept,
            maxfun=self.budget,
            seed=library_seed(self.rng),
            no_local_search=p.no_local_search,
        )
