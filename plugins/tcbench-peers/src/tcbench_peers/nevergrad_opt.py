"""NGOpt and differential evolution as tcbench optimisers: adapters over nevergrad's ask/tell.

- ``ngopt``: ``nevergrad.optimizers.NGOpt``, nevergrad's algorithm-selection wizard (Meunier et
  al. 2022, "Black-Box Optimization Revisited: Improving Algorithm Selection Wizards Through
  Massive Benchmarking", IEEE Trans. Evol. Comput. 26(3), 490-500). From the dimension, the
  budget and the number of workers it picks one of nevergrad's optimisers and runs it: for a
  box, e.g. CMA-ES, CMA-ES with a quadratic metamodel, or portfolios of these.
- ``ng_de``: the optimiser nevergrad registers as ``"DE"``, i.e. ``DifferentialEvolution()`` with
  nevergrad's defaults (Storn & Price 1997): current-to-best/1 mutation with ``F1 = F2 = 0.8``,
  binomial crossover with ``CR = 0.5``, an initial population drawn uniformly in the box
  (``initialization="parametrization"``), a population of ``max(30, num_workers)`` and a child
  replacing its parent when it is no worse.

The algorithms are nevergrad's own, untouched; this module only drives them through nevergrad's
ask/tell (``opt.ask()`` gives a candidate, ``opt.tell(candidate, loss)`` returns its value).

Shared rules:

- **Box.** The tcbench box is ``ng.p.Array(shape=(d,), lower=lower, upper=upper)``, nevergrad's
  bounded array: it starts at the centre of the box, with a step of a sixth of the box width per
  axis, samples uniformly in the box and folds candidates back into it ("bouncing"). Points are
  clamped anyway against float round-off. (As with any nevergrad user, the centre is where NGOpt's CMA-ES
  starts: on functions whose optimum sits at the centre of the box, use shifted instances.)
- **Batches and budget.** ``population`` is nevergrad's ``num_workers``: one tcbench ask is
  ``min(population, remaining)`` calls of ``opt.ask()``, and the tell passes each value back in
  order, so nevergrad never holds an unanswered candidate. nevergrad's budget is the run's.
- **Why population >= 2.** With ``num_workers = 1`` (nevergrad's default) NGOpt picks sequential
  optimisers that run scipy or ``cma.fmin`` in a non-daemon background thread, and ``cma.fmin``
  seeds numpy from the clock: not reproducible, and a run abandoned mid-way leaves that thread
  blocked, so the interpreter never exits. nevergrad refuses every such ("no_parallelization")
  optimiser when ``num_workers > 1``.
- **Seeds.** nevergrad draws from its parametrization's random state, set to
  ``np.random.RandomState(seed)`` with the seed drawn from the run's generator
  (:func:`tcbench_peers.seeding.library_seed`). Some of it still uses numpy's global random
  state: a parametrization created without a random state seeds itself from it (building the
  box's ``Array`` draws once), and so do the inner Powell/DE optimisers with which NGOpt's
  metamodel minimises its surrogate. So every call into nevergrad runs with numpy's global
  state swapped for the run's own one (a second ``RandomState`` seeded from the generator), and
  the caller's global state is put back afterwards (:class:`_Scope`; calls from several threads
  are serialised by a lock). The same seed gives the same points, whatever the global state,
  and a run leaves the global state as it found it.
- **Threads.** The metamodel's inner Powell runs scipy in a nevergrad thread for the length of
  one surrogate search. Any such thread still alive when a call into nevergrad returns is
  stopped and joined, so no thread outlives a call and an abandoned run never holds up the
  interpreter's exit.
- **Non-finite values.** NaN/inf (``+inf`` after the base class) reach nevergrad as ``5e20``
  (:data:`WORST`), the ceiling to which nevergrad's ``tell`` clips every loss; finite values
  above it are clipped too, as nevergrad would (without its warning).
- **Warnings.** Two warnings about what the adapter or nevergrad do on purpose are silenced
  during calls into nevergrad: nevergrad's about clipping a loss to 5e20, and ``cma``'s
  ``InjectionWarning``, raised at nearly every step where NGOpt's metamodel injects its
  surrogate's optimum into CMA-ES while asking one point at a time.
- **numpy >= 2.4.** nevergrad 1.0.12's metamodel calls ``float()`` on a one-element array
  (nevergrad issue #1612), which numpy 2.4 turned from a deprecation into a ``TypeError``, so
  NGOpt fails wherever it picks a metamodel (low dimensions, small budgets). Only while a call
  into nevergrad runs, and only with such a numpy, ``float`` in
  ``nevergrad.optimization.metamodel`` converts one-element arrays as numpy < 2.4 did.
- **Wall clock.** nevergrad stops the metamodel's inner surrogate search after 20 s; far below
  that in practice (milliseconds in 5-D), but in high dimensions on a slow machine a run could
  then depend on the machine's speed.
- **Cost.** Measured on one core: ``ngopt`` takes ~1 ms per point where NGOpt runs CMA-ES (5-D,
  2000 evaluations in ~2 s) and up to ~10 ms where it refits a metamodel at every step (4-D, 400
  evaluations in ~4 s); ``ng_de`` ~0.25 ms per point.
"""

from __future__ import annotations

import builtins
import threading
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, ClassVar

import nevergrad as ng
import numpy as np
from cma.evolution_strategy import InjectionWarning
from nevergrad.common.errors import LossTooLargeWarning
from nevergrad.optimization import metamodel, recaster

from tcbench.optimisers.protocol import Optimiser, OptimiserParams
from tcbench_peers.seeding import library_seed

WORST = 5.0e20  # nevergrad clips every loss to this in tell; NaN/inf reach it as this value
JOIN_TIMEOUT = 10.0  # seconds to wait for a stopped nevergrad helper thread to end

_LOCK = threading.Lock()  # one call into nevergrad at a time: the scope swaps process-wide state


def _size1_float_fails() -> bool:
    """True when this numpy refuses ``float()`` of a one-element array (numpy >= 2.4)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            float(np.ones(1))  # type: ignore[arg-type]
        except TypeError:
            return True
    return False


_FLOAT_SHIM = _size1_float_fails()


def _float(value: Any = 0.0) -> float:
    """``float`` that converts a one-element array as numpy < 2.4 did (nevergrad issue #1612)."""
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(())
    return builtins.float(value)


class _Scope:
    """Context for every call into nevergrad (see the module docstring): numpy's global random
    state swapped for the run's own, the ``float`` fix for nevergrad's metamodel under numpy >=
    2.4, two warnings silenced and no helper thread left behind."""

    def __init__(self, seed: int) -> None:
        self._state = np.random.RandomState(seed).get_state()

    @contextmanager
    def __call__(self) -> Iterator[None]:
        with _LOCK, warnings.catch_warnings():
            warnings.simplefilter("ignore", LossTooLargeWarning)
            warnings.simplefilter("ignore", InjectionWarning)
            before = set(threading.enumerate())
            caller = np.random.get_state()
            np.random.set_state(self._state)
            if _FLOAT_SHIM:
                metamodel.float = _float  # type: ignore[attr-defined]
            try:
                yield
            finally:
                if _FLOAT_SHIM:
                    del metamodel.float  # type: ignore[attr-defined]
                self._state = np.random.get_state()
                np.random.set_state(caller)
                _end_helper_threads(before)


def _end_helper_threads(before: set[threading.Thread]) -> None:
    """Stop and join nevergrad's recast threads started since ``before`` that are still alive."""
    for thread in threading.enumerate():
        if thread not in before and isinstance(thread, recaster._MessagingThread) and thread.is_alive():
            thread.stop()
            thread.join(JOIN_TIMEOUT)


class NevergradOptimiser(Optimiser):
    """Base of the nevergrad adapters: ask/tell over the optimiser nevergrad registers as
    :attr:`library_name`, with ``num_workers = population``."""

    library_name: ClassVar[str] = ""
    single_objective: ClassVar[bool] = True
    multi_objective: ClassVar[bool] = False

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.fitness = np.empty(0)
        self._candidates: list[Any] = []
        self._scope = _Scope(library_seed(self.rng))
        with self._scope():  # even building the parametrization draws from numpy's global state
            parametrization = ng.p.Array(shape=(self.dim,), lower=self.lower, upper=self.upper)
            parametrization.random_state = np.random.RandomState(library_seed(self.rng))
            self.library = ng.optimizers.registry[self.library_name](
                parametrization=parametrization, budget=self.budget, num_workers=self.params.population
            )

    def _ask(self) -> np.ndarray:
        k = min(self.params.population, self.remaining)
        with self._scope():
            self._candidates = [self.library.ask() for _ in range(k)]
            x = np.array([c.value for c in self._candidates], dtype=np.float64).reshape(k, self.dim)
        return self.clip(x)

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        self.generation += 1
        self.fitness = f
        losses = np.minimum(np.where(np.isfinite(f), f, WORST), WORST)
        with self._scope():
            for candidate, loss in zip(self._candidates, losses.tolist(), strict=True):
                self.library.tell(candidate, loss)
        self._candidates = []


@dataclass(frozen=True)
class NGOptParams(OptimiserParams):
    """NGOpt parameters.

    population: points per ask, nevergrad's ``num_workers`` (NGOpt's choice of optimiser depends
        on it), >= 2; default 2, the closest to nevergrad's default of 1 that keeps NGOpt off
        its sequential, thread-based optimisers (see the module docstring).
    """

    population: int = 2


class NGOpt(NevergradOptimiser):
    """nevergrad's NGOpt wizard (Meunier et al. 2022); see the module docstring."""

    name: ClassVar[str] = "ngopt"
    Params: ClassVar[type[OptimiserParams]] = NGOptParams
    library_name: ClassVar[str] = "NGOpt"


@dataclass(frozen=True)
class NevergradDEParams(OptimiserParams):
    """Parameters of nevergrad's ``DE``.

    population: points per ask, nevergrad's ``num_workers``, >= 2; DE's population is then
        ``max(30, population)`` (nevergrad's ``popsize="standard"``). Default 30, so that one
        ask is one generation of nevergrad's default population of 30.
    """

    population: int = 30


class NevergradDE(NevergradOptimiser):
    """nevergrad's registered ``DE`` (current-to-best/1, CR 0.5, F 0.8); see the module docstring."""

    name: ClassVar[str] = "ng_de"
    Params: ClassVar[type[OptimiserParams]] = NevergradDEParams
    library_name: ClassVar[str] = "DE"
