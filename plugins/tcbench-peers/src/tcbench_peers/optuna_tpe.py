"""TPE as a tcbench optimiser: an adapter over optuna's ``TPESampler`` through ``study.ask()`` and
``study.tell()``.

The tree-structured Parzen estimator of Bergstra, Bardenet, Bengio & Kégl (2011), "Algorithms
for Hyper-Parameter Optimization", NeurIPS 24, as implemented by optuna (Akiba et al. 2019,
"Optuna: A Next-generation Hyperparameter Optimization Framework", KDD; Watanabe 2023,
"Tree-Structured Parzen Estimator: Understanding Its Algorithm Components and Their Roles for
Better Empirical Performance", arXiv:2304.11127). The sampler is optuna's own, untouched.

- **Study.** ``optuna.create_study(direction="minimize", sampler=TPESampler(...))`` in memory (no
  storage). Each coordinate is a float parameter ``x0 .. x{d-1}`` with
  ``FloatDistribution(lower_i, upper_i)``, given to ``study.ask(fixed_distributions=...)``;
  optuna samples inside these bounds (points are clamped anyway against float round-off).
- **Batches and budget.** One tcbench ask is ``min(population, remaining)`` trials from
  ``study.ask()``; the tell completes each with ``study.tell(trial, value)`` in order, so no trial
  is left running and optuna never sees more trials than the budget. The default
  ``population = 1`` is optuna's sequential use (``study.optimize`` with one job). With a larger
  population the trials of one batch are sampled while the others are still running:
  ``constant_liar = False`` (optuna 4's default) samples them from the same model, ``True`` makes
  TPE treat the running ones as bad so that the batch spreads out.
- **Seeds.** ``TPESampler(seed=...)`` with the seed drawn from the run's generator
  (:func:`tcbench_peers.seeding.library_seed`); the sampler draws only from its own random state,
  so the same seed asks the same points.
- **Non-finite values.** NaN/inf (``+inf`` after the base class) reach optuna as ``1e300``
  (:data:`WORST`), a huge finite value that TPE ranks worst: a NaN told to optuna would mark the
  trial failed, and TPE would then ignore the point instead of learning that it is bad.
- **Logging.** optuna logs every finished trial at INFO; each call into optuna runs with optuna's
  verbosity at WARNING, restored afterwards, and without its experimental-feature warnings.
- **Cost.** TPE refits its Parzen estimators on all past trials at every trial, so a trial costs
  O(n) in the n trials so far and a run O(n^2). Measured on one core (5-D, univariate TPE): 400
  trials take ~2 s, 1000 ~9 s, 2000 ~30 s (~20 ms per trial by then; multivariate TPE about
  two thirds of that). Budgets up to a few thousand evaluations are practical; beyond that the
  sampler, not the task, dominates the run time.

Defaults are optuna 4's: ``n_startup_trials = 10`` random trials, ``n_ei_candidates = 24``,
univariate TPE (``multivariate = False``), ``constant_liar = False``.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import optuna
from optuna.distributions import FloatDistribution
from optuna.exceptions import ExperimentalWarning
from optuna.samplers import TPESampler

from tcbench.optimisers.protocol import Optimiser, OptimiserParams
from tcbench_peers.seeding import library_seed

WORST = 1e300  # what optuna receives for a NaN/inf value


@contextmanager
def _quiet() -> Iterator[None]:
    """optuna's verbosity at WARNING and its experimental warnings off, both restored after."""
    verbosity = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ExperimentalWarning)
            yield
    finally:
        optuna.logging.set_verbosity(verbosity)


@dataclass(frozen=True)
class TPEParams(OptimiserParams):
    """Parameters of optuna's ``TPESampler``.

    population: trials per ask, >= 1; default 1 (one trial at a time, optuna's sequential use).
    n_startup_trials: trials sampled uniformly at random before TPE starts, >= 1 (optuna's 10).
    n_ei_candidates: candidates drawn from the good-points density, of which the one with the
        best expected improvement ratio is asked, >= 1 (optuna's 24).
    multivariate: True fits one joint Parzen estimator over all coordinates instead of one per
        coordinate (optuna 4's default False).
    constant_liar: True treats the trials still running (the rest of a batch) as bad when
        sampling, to spread a batch out; only matters for population > 1 (optuna 4's default False).
    """

    population: int = 1
    n_startup_trials: int = 10
    n_ei_candidates: int = 24
    multivariate: bool = False
    constant_liar: bool = False

    def __post_init__(self) -> None:  # population 1 is allowed: no call to the base check
        if self.population < 1:
            raise ValueError(f"population must be >= 1, got {self.population}")
        if self.n_startup_trials < 1:
            raise ValueError(f"n_startup_trials must be >= 1, got {self.n_startup_trials}")
        if self.n_ei_candidates < 1:
            raise ValueError(f"n_ei_candidates must be >= 1, got {self.n_ei_candidates}")


class TPE(Optimiser):
    """TPE (Bergstra et al. 2011) from optuna's ``TPESampler``; see the module docstring."""

    name: ClassVar[str] = "tpe"
    Params: ClassVar[type[OptimiserParams]] = TPEParams
    single_objective: ClassVar[bool] = True
    multi_objective: ClassVar[bool] = False
    params: TPEParams

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        p = self.params
        self.fitness = np.empty(0)
        self._names = [f"x{i}" for i in range(self.dim)]
        self._space = {
            name: FloatDistribution(lo, hi)
            for name, lo, hi in zip(self._names, self.lower.tolist(), self.upper.tolist(), strict=True)
        }
        self._trials: list[optuna.trial.Trial] = []
        with _quiet():
            sampler = TPESampler(
                n_startup_trials=p.n_startup_trials, n_ei_candidates=p.n_ei_candidates,
                multivariate=p.multivariate, constant_liar=p.constant_liar, seed=library_seed(self.rng),
            )
            self.study = optuna.create_study(direction="minimize", sampler=sampler)

    def _ask(self) -> np.ndarray:
        k = min(self.params.population, self.remaining)
        with _quiet():
            self._trials = [self.study.ask(fixed_distributions=self._space) for _ in range(k)]
        x = np.array([[t.params[name] for name in self._names] for t in self._trials], dtype=np.float64)
        return self.clip(x)

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        self.generation += 1
        self.fitness = f
        values = np.where(np.isfinite(f), f, WORST)
        with _quiet():
            for trial, value in zip(self._trials, values.tolist(), strict=True):
                self.study.tell(trial, value)
        self._trials = []
