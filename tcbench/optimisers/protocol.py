"""The ask/tell optimiser protocol shared by built-in and plugin optimisers.

An optimiser is built with box bounds, an evaluation budget, an explicit
``numpy.random.Generator`` and its parameters (a dataclass, mirrored by the Hydra config). The
caller loops ``X = opt.ask(); F = f(X); opt.tell(X, F)`` until ``opt.done``. The optimiser never
calls the objective itself. This base class owns the bookkeeping every optimiser needs: budget
accounting, checking that ``tell`` answers the last ``ask``, treating NaN/inf values as worst,
and the best point seen so far. Subclasses implement :meth:`_ask` and :meth:`_tell`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from tcbench.params import coerce_param, make_params  # noqa: F401  (plugins import both from here)
from tcbench.pareto import merge_front


class ProtocolError(RuntimeError):
    """An optimiser or its caller broke the ask/tell contract."""


@dataclass(frozen=True)
class Best:
    """Best point seen so far and its objective value (``inf`` before any finite value)."""

    x: np.ndarray
    f: float


@dataclass(frozen=True)
class ParetoSet:
    """Non-dominated points told so far (multi-objective): ``x`` (p, d) and ``f`` (p, m)."""

    x: np.ndarray
    f: np.ndarray


@dataclass(frozen=True)
class OptimiserParams:
    """Base class for optimiser parameter dataclasses; subclasses validate in ``__post_init__``."""

    population: int = 10

    def __post_init__(self) -> None:
        if self.population < 2:
            raise ValueError(f"population must be >= 2, got {self.population}")


def worst_if_nonfinite(f: np.ndarray) -> np.ndarray:
    """Replace NaN and +-inf objective values by +inf (the worst for minimisation); in a
    multi-objective row (``f`` of shape (k, m)) one non-finite value makes the whole row worst."""
    if f.ndim == 2:
        return np.where(np.isfinite(f).all(axis=1, keepdims=True), f, np.inf)
    return np.where(np.isfinite(f), f, np.inf)


class Optimiser(ABC):
    """Base class of ask/tell optimisers (single objective, minimisation)."""

    name: ClassVar[str] = ""
    Params: ClassVar[type[OptimiserParams]] = OptimiserParams
    single_objective: ClassVar[bool] = True  # can minimise one objective
    multi_objective: ClassVar[bool] = False  # can handle n_objectives > 1

    @classmethod
    def memory_bytes(cls, params: OptimiserParams, dim: int, n_objectives: int = 1) -> int:
        """A generous estimate of a run's peak memory in ``dim`` dimensions (bytes): 16 float
        arrays per individual and 64 more of the problem's size, which bounds tcbench's own
        optimisers (measured: 6-14 per individual). Override where an optimiser holds more,
        e.g. a ``dim x dim`` covariance; the config check refuses a job that cannot fit."""
        return 8 * int(dim) * (16 * int(params.population) + 64)

    def __init__(
        self,
        lower: np.ndarray,
        upper: np.ndarray,
        budget: int,
        rng: np.random.Generator,
        params: OptimiserParams | dict[str, Any] | None = None,
        n_objectives: int = 1,
    ) -> None:
        if int(n_objectives) != n_objectives or n_objectives < 1:
            raise ValueError(f"n_objectives must be a positive integer, got {n_objectives}")
        if n_objectives > 1 and not self.multi_objective:
            raise ValueError(f"optimiser {self.name!r} is single-objective; the task has {n_objectives} objectives")
        if n_objectives == 1 and not self.single_objective:
            raise ValueError(f"optimiser {self.name!r} is multi-objective only; the task has one objective")
        self.n_objectives = int(n_objectives)
        self.lower = np.asarray(lower, dtype=np.float64).reshape(-1)
        self.upper = np.asarray(upper, dtype=np.float64).reshape(-1)
        if self.lower.shape != self.upper.shape or not np.all(self.lower < self.upper):
            raise ValueError("bounds must have equal shapes with lower < upper everywhere")
        if not isinstance(rng, np.random.Generator):
            raise TypeError("rng must be a numpy.random.Generator")
        self.params = make_params(type(self), params)
        if int(budget) != budget or budget < self.params.population:
            raise ValueError(
                f"budget of {budget} evaluations is smaller than one generation "
                f"(population {self.params.population})"
            )
        self.dim = self.lower.size
        self._finite_bounds = bool(np.isfinite(self.lower).all() and np.isfinite(self.upper).all())
        # The same interval on every axis: checked and clamped with scalars, which is cheaper.
        same = np.all(self.lower == self.lower[:1]) and np.all(self.upper == self.upper[:1])
        self._box = (float(self.lower[0]), float(self.upper[0])) if same and self.dim else None
        self.budget = int(budget)
        self.rng = rng
        self.evaluations = 0
        self.generation = 0
        self.nonfinite = 0
        self._best = Best(np.full(self.dim, np.nan), np.inf)
        self._front = ParetoSet(np.empty((0, self.dim)), np.empty((0, self.n_objectives)))
        self._pending: np.ndarray | None = None

    # -- public protocol -------------------------------------------------------------------
    @property
    def remaining(self) -> int:
        """Evaluations left in the budget."""
        return self.budget - self.evaluations

    @property
    def done(self) -> bool:
        """True once the budget (or the optimiser's own stopping rule) ends the run."""
        return self.remaining <= 0 or self._stopped()

    @property
    def best(self) -> Best:
        """Best point told so far (single objective)."""
        if self.n_objectives > 1:
            raise ProtocolError(f"{self.name}: best is single-objective; use front")
        return self._best

    @property
    def front(self) -> ParetoSet:
        """Non-dominated points among everything told so far (multi-objective)."""
        return self._front

    @property
    def population_fitness(self) -> np.ndarray:
        """Objective values of the current population (``inf`` where non-finite)."""
        return np.asarray(getattr(self, "fitness", np.empty(0)))

    def ask(self) -> np.ndarray:
        """Candidates to evaluate next, shape ``(k, d)``, inside the bounds, ``k <= remaining``."""
        if self._pending is not None:
            raise ProtocolError(f"{self.name}: ask() called twice without tell()")
        if self.done:
            raise ProtocolError(f"{self.name}: ask() after the run is done")
        x = np.asarray(self._ask(), dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != self.dim or not 0 < x.shape[0] <= self.remaining:
            raise ProtocolError(
                f"{self.name}: ask() returned shape {x.shape}; expected (k, {self.dim}) "
                f"with 0 < k <= {self.remaining}"
            )
        # NaN fails the comparisons (and is the min/max of any array holding it); with finite
        # bounds they also reject +-inf.
        if self._box is not None:
            inside = x.min() >= self._box[0] and x.max() <= self._box[1]
        else:
            inside = (x >= self.lower).all() and (x <= self.upper).all()
        if not inside or not (self._finite_bounds or np.isfinite(x).all()):
            raise ProtocolError(f"{self.name}: ask() returned points outside the bounds")
        self._pending = x
        return x.copy()

    def tell(self, x: np.ndarray, f: np.ndarray) -> None:
        """Report objective values ``f`` of the points returned by ``ask``: shape ``(k,)`` for
        one objective, ``(k, m)`` for ``m`` objectives."""
        if self._pending is None:
            raise ProtocolError(f"{self.name}: tell() without a preceding ask()")
        x = np.asarray(x, dtype=np.float64)
        f = np.asarray(f, dtype=np.float64)
        if self.n_objectives == 1:
            f = f.reshape(-1)
        if x.shape != self._pending.shape or not (x == self._pending).all():
            raise ProtocolError(f"{self.name}: tell() must receive the points of the last ask()")
        want = (x.shape[0],) if self.n_objectives == 1 else (x.shape[0], self.n_objectives)
        if f.shape != want:
            raise ProtocolError(f"{self.name}: tell() got values of shape {f.shape} for {x.shape[0]} points; expected {want}")
        self._pending = None
        finite = np.isfinite(f)
        if finite.ndim == 2:
            finite = finite.all(axis=1)
        if finite.all():
            f = f.copy()  # the optimiser keeps its own copy, as worst_if_nonfinite gives
        else:
            self.nonfinite += int(finite.size - np.count_nonzero(finite))
            f = worst_if_nonfinite(f)
        self.evaluations += f.shape[0]
        if self.n_objectives == 1:
            i = int(f.argmin())
            if f[i] < self._best.f:
                self._best = Best(x[i].copy(), float(f[i]))
        else:
            self._update_front(x, f)
        self._tell(x, f)

    def _update_front(self, x: np.ndarray, f: np.ndarray) -> None:
        finite = np.isfinite(f).all(axis=1)
        self._front = ParetoSet(*merge_front(self._front.x, self._front.f, x[finite], f[finite]))

    # -- subclass hooks --------------------------------------------------------------------
    @abstractmethod
    def _ask(self) -> np.ndarray:
        """Return the next candidates; may use ``self.remaining`` to shorten the last batch."""

    @abstractmethod
    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        """Absorb finite-or-``inf`` values ``f`` of ``x`` (``(k,)``, or ``(k, m)`` for ``m``
        objectives); advance ``self.generation``."""

    def _stopped(self) -> bool:
        """Optimiser-specific stopping rule (e.g. a generation limit); none by default."""
        return False

    # -- helpers for subclasses ------------------------------------------------------------
    def clip(self, x: np.ndarray) -> np.ndarray:
        """Put points back inside the bounds by clamping each coordinate (seed 000 eq. 11)."""
        lower, upper = self._box or (self.lower, self.upper)
        return np.minimum(np.maximum(x, lower), upper)

    def uniform(self, n: int) -> np.ndarray:
        """``n`` points drawn uniformly in the bounds."""
        return self.rng.uniform(self.lower, self.upper, size=(n, self.dim))
