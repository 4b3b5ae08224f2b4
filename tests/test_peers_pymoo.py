"""pymoo's NSGA-II and MOEA/D from the tcbench-peers plugin, driven through pymoo's ask-and-tell
interface (tcbench_peers.pymoo_moo)."""

from __future__ import annotations

import math
import statistics

import numpy as np
import pytest
from optimiser_runs import drive
from pymoo.algorithms.moo.moead import MOEAD as PymooMOEAD
from pymoo.algorithms.moo.nsga2 import NSGA2 as PymooNSGA2
from pymoo.optimize import minimize
from pymoo.problems.multi.zdt import ZDT1
from pymoo.util.ref_dirs import get_reference_directions
from tcbench_peers.pymoo_moo import (
    MOEAD,
    NSGA2,
    WORST,
    BoxProblem,
    das_dennis_partitions,
)
from tcbench_peers.seeding import library_seed

from tcbench import check_optimizer
from tcbench.optimisers import available
from tcbench.pareto import nondominated
from tcbench.runner.loop import run_optimisation


def two_spheres(x: np.ndarray) -> np.ndarray:
    return np.stack([np.sum(x**2, axis=1), np.sum((x - 1.0) ** 2, axis=1)], axis=1)


def box(d: int) -> tuple[np.ndarray, np.ndarray]:
    return np.full(d, -2.0), np.full(d, 3.0)


@pytest.mark.parametrize("name", ["nsga2", "moead"])
def test_registered_through_the_entry_point_and_contract(name: str) -> None:
    entry = available()[name]
    assert entry.package == "tcbench-peers"
    assert not entry.cls.single_objective and entry.cls.multi_objective
    assert check_optimizer(entry.cls) >= 2
    assert check_optimizer(entry.cls, params={"population": 12}) >= 4  # budget 60 runs too


# Hypervolume share 1 - best_f on ZDT1 (30 variables, reference point (1.1, 1.1)) after 10000
# evaluations, measured over seeds 0-11 with the default parameters:
#   nsga2: 0.961-0.975 on every seed (0, 1, 2: 0.964, 0.969, 0.969)
#   moead: 0.820-0.988, 11 of 12 seeds >= 0.92, median 0.964 (0, 1, 2: 0.980, 0.964, 0.820)
# pymoo's MOEA/D (Tchebycheff, one offspring per step, no duplicate elimination) is far less
# steady than NSGA-II at this budget: with seed 2 its front, converged to within 0.006 of the
# true one, covers only f1 < 0.5. So NSGA-II must reach 0.95 on each seed, MOEA/D 0.93 in the
# median of seeds 0-2 and 0.78 on every one (margins of at least 0.01 and 0.03).
def test_nsga2_covers_the_zdt1_front() -> None:
    for seed in (0, 1, 2):
        r = run_optimisation({"name": "zdt1"}, {"name": "nsga2"}, 10000, seed)
        assert r.evaluations == 10000 and r.generations == 100
        assert 1.0 - r.best_f >= 0.95, seed


@pytest.mark.slow  # 43 s; the adapter's runs are pymoo's own: test_the_adapters_reproduce_pymoos_own_runs
def test_moead_covers_the_zdt1_front() -> None:
    shares = []
    for seed in (0, 1, 2):
        r = run_optimisation({"name": "zdt1"}, {"name": "moead"}, 10000, seed)
        assert r.evaluations == 10000 and r.generations == 100  # initial population + 99 sweeps
        shares.append(1.0 - r.best_f)
    assert min(shares) >= 0.78 and statistics.median(shares) >= 0.93, shares


def test_the_adapters_reproduce_pymoos_own_runs() -> None:
    """Same pymoo seed and objective: the adapter's final population is exactly the one of
    ``pymoo.optimize.minimize``, so ask/tell changes nothing in the algorithms."""
    zdt1 = ZDT1()  # 30 variables in [0, 1]

    def objective(x: np.ndarray) -> np.ndarray:
        return zdt1.evaluate(x, return_values_of=["F"])

    lower, upper = zdt1.xl, zdt1.xu
    for cls, mine, theirs, budget in (
        (NSGA2, {"population": 50}, PymooNSGA2(pop_size=50), 1000),
        (MOEAD, {"population": 50}, PymooMOEAD(get_reference_directions("das-dennis", 2, n_partitions=49)), 1000),
    ):
        opt = cls(lower, upper, budget, np.random.default_rng(7), mine, n_objectives=2)
        drive(opt, objective)
        res = minimize(zdt1, theirs, ("n_eval", budget), seed=library_seed(np.random.default_rng(7)))
        assert np.array_equal(opt.population_fitness, res.pop.get("F")), cls.name
        assert np.array_equal(opt.algorithm.pop.get("X"), res.pop.get("X")), cls.name


def test_batches_and_the_budget() -> None:
    nsga2 = NSGA2(*box(3), 1050, np.random.default_rng(0), n_objectives=2)
    sizes = [len(x) for x in drive(nsga2, two_spheres)]
    assert sizes == [100] * 10 + [50] and nsga2.evaluations == 1050  # cut to the budget, then done
    assert nsga2.algorithm.evaluator.n_eval == 1000  # the cut generation was never told to pymoo
    moead = MOEAD(*box(3), 250, np.random.default_rng(0), {"population": 20}, n_objectives=2)
    sizes = [len(x) for x in drive(moead, two_spheres)]
    assert sizes == [20] + [1] * 230 and moead.evaluations == 250
    assert moead.algorithm.n_iter - 1 == 12  # initial population + 11 full sweeps of 20
    assert moead.generation == 13  # ... + the last 10 offspring, a partial sweep
    for cls in (NSGA2, MOEAD):
        for budget in (100, 101, 137, 333):
            opt = cls(*box(2), budget, np.random.default_rng(budget), n_objectives=2)
            used = sum(len(x) for x in drive(opt, two_spheres))
            assert used == opt.evaluations == budget


def test_same_seed_same_front_other_seed_other_front() -> None:
    for cls in (NSGA2, MOEAD):
        def run(seed: int, cls=cls):  # type: ignore[no-untyped-def]
            opt = cls(*box(4), 600, np.random.default_rng(seed), {"population": 30}, n_objectives=2)
            return drive(opt, two_spheres), opt.front

        (a, fa), (b, fb), (_, fc) = run(3), run(3), run(4)
        assert len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
        assert np.array_equal(fa.x, fb.x) and np.array_equal(fa.f, fb.f)
        assert not np.array_equal(fa.f, fc.f)


def test_points_stay_inside_the_bounds() -> None:
    lower, upper = np.array([0.0, -1e-3, 5.0]), np.array([1e-9, 1e-3, 5.0 + 1e-12])
    for cls in (NSGA2, MOEAD):
        opt = cls(lower, upper, 500, np.random.default_rng(1), {"population": 20}, n_objectives=2)
        for x in drive(opt, lambda x: np.stack([x[:, 0], -x[:, 0] + x[:, 1] ** 2], axis=1)):
            assert np.all(x >= lower) and np.all(x <= upper)


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize(("cls", "params"), [
    (NSGA2, {"population": 20}),
    (MOEAD, {"population": 21, "decomposition": "tchebicheff"}),
    (MOEAD, {"population": 21, "decomposition": "pbi"}),
])
def test_nonfinite_rows_reach_pymoo_as_a_large_finite_value(cls, params) -> None:  # type: ignore[no-untyped-def]
    def nasty(x: np.ndarray) -> np.ndarray:
        f = np.stack([x[:, 0] ** 2, (x[:, 0] - 1) ** 2 + x[:, 1] ** 2, np.sum(x, axis=1)], axis=1)
        f[x[:, 1] > 0.5, 1] = np.nan
        f[x[:, 2] > 2.0, 2] = -np.inf
        return f

    opt = cls(*box(3), 800, np.random.default_rng(2), params, n_objectives=3)
    told = np.concatenate([nasty(x) for x in drive(opt, nasty)])
    bad = ~np.isfinite(told).all(axis=1)
    assert opt.nonfinite == bad.sum() > 0 and opt.evaluations == 800
    pymoo_f = opt.algorithm.pop.get("F")
    assert np.all(np.isfinite(pymoo_f)) and np.all((pymoo_f < 1e10) | (pymoo_f == WORST))
    assert np.array_equal(np.isinf(opt.population_fitness), pymoo_f == WORST)
    front = opt.front
    assert len(front.f) and np.all(np.isfinite(front.f)) and np.all(nondominated(front.f))
    everything_bad = cls(*box(2), 300, np.random.default_rng(2), params, n_objectives=2)
    drive(everything_bad, lambda x: np.full((len(x), 2), np.nan))
    assert everything_bad.done and everything_bad.front.f.shape == (0, 2)


def test_pymoo_running_out_of_offspring_ends_the_run() -> None:
    opt = NSGA2(*box(2), 1000, np.random.default_rng(0), {"population": 10}, n_objectives=2)
    x = opt.ask()
    opt.algorithm.ask = lambda: None  # what NSGA-II's ask returns when mating finds no new point
    opt.tell(x, two_spheres(x))
    assert opt.done and opt._stopped() and opt.evaluations == 10


def test_moead_weight_vectors() -> None:
    assert das_dennis_partitions(100, 2) == 99 and das_dennis_partitions(2, 2) == 1
    assert das_dennis_partitions(100, 3) == 12 and math.comb(14, 2) == 91  # 105 for H = 13
    assert das_dennis_partitions(3, 3) == 1
    three = MOEAD(*box(4), 1000, np.random.default_rng(0), n_objectives=3)
    assert three.ref_dirs.shape == (91, 3) and len(three.ask()) == 91
    assert three.algorithm.neighbors.shape == (91, 20)
    assert type(three.algorithm.decomposition).__name__ == "PBI"
    two = MOEAD(*box(4), 1000, np.random.default_rng(0), {"population": 8, "n_neighbors": 15}, n_objectives=2)
    assert two.ref_dirs.shape == (8, 2) and two.algorithm.neighbors.shape == (8, 8)
    assert type(two.algorithm.decomposition).__name__ == "Tchebicheff"
    with pytest.raises(ValueError, match="population"):
        MOEAD(*box(4), 1000, np.random.default_rng(0), {"population": 2}, n_objectives=3)


def test_the_box_problem_only_hands_back_told_values() -> None:
    problem = BoxProblem(*box(2), 2)
    with pytest.raises(RuntimeError, match="tcbench"):
        problem.evaluate(np.zeros((1, 2)))
    with problem.told(np.array([[1.0, 2.0]])) as told:
        assert np.array_equal(told.evaluate(np.zeros((1, 2))), [[1.0, 2.0]])
        with pytest.raises(RuntimeError, match="shape"):
            told.evaluate(np.zeros((3, 2)))
    with pytest.raises(RuntimeError, match="tcbench"):
        problem.evaluate(np.zeros((1, 2)))


@pytest.mark.parametrize(
    ("cls", "params", "words"),
    [
        (NSGA2, {"population": 1}, "population"),
        (NSGA2, {"pop_size": 10}, "pop_size"),
        (MOEAD, {"population": 1}, "population"),
        (MOEAD, {"n_neighbors": 1}, "n_neighbors"),
        (MOEAD, {"prob_neighbor_mating": 1.5}, "prob_neighbor_mating"),
        (MOEAD, {"decomposition": "weighted_sum"}, "decomposition"),
    ],
)
def test_invalid_parameters_are_refused(cls, params, words) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=words):
        cls(*box(2), 1000, np.random.default_rng(0), params, n_objectives=2)


def test_single_objective_tasks_and_small_budgets_are_refused() -> None:
    for cls in (NSGA2, MOEAD):
        with pytest.raises(ValueError, match="multi-objective only"):
            cls(*box(2), 1000, np.random.default_rng(0))
        with pytest.raises(ValueError, match="budget"):
            cls(*box(2), 99, np.random.default_rng(0), n_objectives=2)
