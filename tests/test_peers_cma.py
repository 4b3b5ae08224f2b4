"""CMA-ES and IPOP-CMA-ES from the tcbench-peers plugin (adapters over the cma package)."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench import check_optimizer
from tcbench.optimisers import available
from tcbench.runner.loop import run_optimisation
from tcbench_peers.cma_es import CMAES, IPOPCMAES
from optimiser_runs import assert_initialises_bp


@pytest.mark.parametrize("name", ["cmaes", "ipop_cmaes"])
def test_registered_through_the_entry_point_and_contract(name: str) -> None:
    entry = available()[name]
    assert entry.package == "tcbench-peers"
    assert check_optimizer(entry.cls) >= 2


def test_cmaes_solves_the_sphere_and_stops_by_itself() -> None:
    r = run_optimisation({"name": "sphere", "dim": 5}, {"name": "cmaes"}, 5000, 0)
    assert r.best_f < 1e-10
    assert r.evaluations < 5000  # cma's own stopping rules ended the run


def test_ipop_restarts_with_a_doubled_population_until_the_budget_is_spent() -> None:
    opt = IPOPCMAES(np.full(5, -5.12), np.full(5, 5.12), 6000, np.random.default_rng(0), {})
    first = opt.lam
    while not opt.done:
        x = opt.ask()
        opt.tell(x, np.sum(x**2 - 10 * np.cos(2 * np.pi * x), axis=1) + 50)
    assert opt.evaluations == 6000 and opt.runs >= 2 and opt.lam == first * 2 ** (opt.runs - 1)


def test_same_seed_same_points_and_nan_survived() -> None:
    def run(seed: int) -> list[np.ndarray]:
        opt = CMAES(np.zeros(3), np.ones(3), 200, np.random.default_rng(seed), {"population": 8})
        asked = []
        while not opt.done:
            x = opt.ask()
            asked.append(x)
            f = np.sum((x - 0.3) ** 2, axis=1)
            f[0] = np.nan
            opt.tell(x, f)
        assert opt.evaluations <= 200 and np.isfinite(opt.best.f)
        return asked

    a, b, c = run(1), run(1), run(2)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not np.array_equal(a[0], c[0])


def test_invalid_parameters_are_refused() -> None:
    for params, words in (({"population": 1}, "population"), ({"sigma0": 0.0}, "sigma0"),
                          ({"incpopsize": 0.5}, "incpopsize")):
        with pytest.raises(ValueError, match=words):
            CMAES(np.zeros(2), np.ones(2), 100, np.random.default_rng(0), params)


def test_cmaes_initialises_a_learner() -> None:
    assert_initialises_bp("cmaes")
