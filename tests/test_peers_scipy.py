"""scipy's differential evolution and dual annealing from the tcbench-peers plugin, driven by
ask/tell through a worker thread (tcbench_peers.inverted)."""

from __future__ import annotations

import functools
import gc
import threading
import time
import weakref

import numpy as np
import pytest
from scipy import optimize
from tcbench_peers import scipy_opt
from tcbench_peers.inverted import InvertedRun
from tcbench_peers.scipy_opt import DualAnnealing, ScipyDE

from tcbench import check_optimizer
from tcbench.optimisers import available
from tcbench.runner.loop import run_optimisation
from optimiser_runs import drive


def sphere(x: np.ndarray) -> np.ndarray:
    return np.sum(x**2, axis=1)


def rastrigin(x: np.ndarray) -> np.ndarray:
    return 10 * x.shape[1] + np.sum(x**2 - 10 * np.cos(2 * np.pi * x), axis=1)


def workers() -> int:
    """The live threads of inverted runs (named ``inverted-*``): other tests' threads in the same
    process (a tracking client's, a process pool's) come and go on their own."""
    return sum(t.name.startswith("inverted-") for t in threading.enumerate())


def threads_back_to(count: int, wait: float = 2.0) -> bool:
    """True once no more inverted-run threads than ``count`` are alive (polled up to ``wait`` seconds)."""
    end = time.monotonic() + wait
    while workers() > count and time.monotonic() < end:
        time.sleep(0.01)
    return workers() <= count


def box(d: int, half: float = 5.12) -> tuple[np.ndarray, np.ndarray]:
    return np.full(d, -half), np.full(d, half)


@pytest.mark.parametrize("name", ["scipy_de", "dual_annealing"])
def test_registered_through_the_entry_point_and_contract(name: str) -> None:
    entry = available()[name]
    assert entry.package == "tcbench-peers"
    start = workers()
    assert check_optimizer(entry.cls) >= 2
    assert threads_back_to(start)


def test_de_solves_the_5d_sphere() -> None:
    r = run_optimisation({"name": "sphere", "dim": 5}, {"name": "scipy_de"}, 5000, 0)
    assert r.best_f < 1e-6 and r.evaluations == 5000


def test_dual_annealing_solves_the_2d_rastrigin() -> None:
    r = run_optimisation({"name": "rastrigin", "dim": 2}, {"name": "dual_annealing"}, 3000, 0)
    assert r.best_f < 1e-3 and r.evaluations <= 3000


def test_de_batches_are_generations_and_the_last_one_is_cut_to_the_budget() -> None:
    start = workers()
    opt = ScipyDE(*box(3), 107, np.random.default_rng(0), {"population": 10})
    sizes = [len(x) for x in drive(opt, sphere)]
    assert sizes == [10] * 10 + [7] and opt.evaluations == 107
    assert opt._run.closed and not opt._run.finished and threads_back_to(start)
    default = ScipyDE(*box(4), 100, np.random.default_rng(0))
    assert default.ask().shape == (60, 4)  # population 0: scipy's 15 d
    default.close()


def test_dual_annealing_uses_the_whole_budget_one_point_at_a_time() -> None:
    start = workers()
    opt = DualAnnealing(*box(3), 500, np.random.default_rng(3))
    sizes = {len(x) for x in drive(opt, rastrigin)}
    assert sizes == {1} and opt.evaluations == 500 and threads_back_to(start)


def test_scipy_stopping_by_itself_ends_the_run() -> None:
    start = workers()
    flat = ScipyDE(*box(2), 1000, np.random.default_rng(0), {"population": 8})
    drive(flat, lambda x: np.ones(len(x)))  # equal values: DE converges (tol = atol = 0)
    assert flat.done and flat._stopped() and flat.evaluations == 16
    assert flat.library_result is not None and flat.library_result.nit == 1
    short = DualAnnealing(*box(2), 5000, np.random.default_rng(0), {"maxiter": 3})
    drive(short, rastrigin)
    assert short._stopped() and short.evaluations < 5000
    assert threads_back_to(start)


def test_same_seed_same_points_other_seed_other_points() -> None:
    for cls, f in ((ScipyDE, rastrigin), (DualAnnealing, rastrigin)):
        def run(seed: int, cls=cls, f=f) -> list[np.ndarray]:  # type: ignore[no-untyped-def]
            return drive(cls(*box(3), 300, np.random.default_rng(seed)), f)

        a, b, c = run(4), run(4), run(5)
        assert len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
        assert not np.array_equal(a[0], c[0])


def test_nonfinite_values_reach_scipy_as_a_large_finite_value() -> None:
    for cls in (ScipyDE, DualAnnealing):
        opt = cls(*box(2), 400, np.random.default_rng(1))
        drive(opt, lambda x: np.where(x[:, 0] > 0, np.nan, sphere(x)))
        assert np.isfinite(opt.best.f) and opt.best.x[0] <= 0 and opt.nonfinite > 0
        nothing = cls(*box(2), 400, np.random.default_rng(1))
        drive(nothing, lambda x: np.full(len(x), np.inf))
        assert nothing.best.f == np.inf and nothing.done


def test_an_exception_inside_scipy_is_raised_by_the_next_ask(monkeypatch: pytest.MonkeyPatch) -> None:
    start = workers()
    broken = functools.partial(optimize.dual_annealing, minimizer_kwargs={"method": "no-such-method"})
    monkeypatch.setattr(scipy_opt, "dual_annealing", broken)
    opt = DualAnnealing(*box(2), 1000, np.random.default_rng(0))
    with pytest.raises(ValueError, match="no-such-method"):
        drive(opt, rastrigin)  # the strategy chain runs, then the local search fails
    assert 0 < opt.evaluations < 1000 and not opt.done and threads_back_to(start)


def test_inverted_run_reraises_once_then_refuses() -> None:
    def target(evaluate):  # type: ignore[no-untyped-def]
        evaluate(np.zeros((2, 1)))
        raise KeyError("inside the library")

    run = InvertedRun(target, name="demo")
    assert not run.started and run.ask().shape == (2, 1)
    run.tell([1.0, 2.0])
    with pytest.raises(KeyError, match="inside the library"):
        run.ask()
    with pytest.raises(RuntimeError, match="failed"):
        run.ask()
    assert not run.alive and not run.finished


def test_an_abandoned_run_is_collected_and_its_thread_ends() -> None:
    start = workers()
    for cls in (ScipyDE, DualAnnealing):
        opt = cls(*box(2), 1000, np.random.default_rng(0))
        x = opt.ask()
        opt.tell(x, sphere(x))
        opt.ask()  # scipy is now blocked in its objective, waiting for values
        assert workers() == start + 1
        ref = weakref.ref(opt)
        del opt, x
        gc.collect()
        assert ref() is None and threads_back_to(start)


@pytest.mark.parametrize(
    ("cls", "params", "words"),
    [
        (ScipyDE, {"population": 4}, "population"),
        (ScipyDE, {"population": 5, "strategy": "rand2bin"}, "population"),
        (ScipyDE, {"strategy": "best3bin"}, "strategy"),
        (ScipyDE, {"mutation_low": 1.0, "mutation_high": 0.5}, "mutation"),
        (ScipyDE, {"mutation_high": 2.0}, "mutation"),
        (ScipyDE, {"recombination": 1.5}, "recombination"),
        (ScipyDE, {"init": "sobol"}, "init"),
        (DualAnnealing, {"population": 2}, "population"),
        (DualAnnealing, {"initial_temp": 0.0}, "initial_temp"),
        (DualAnnealing, {"restart_temp_ratio": 1.0}, "restart_temp_ratio"),
        (DualAnnealing, {"visit": 1.0}, "visit"),
        (DualAnnealing, {"accept": -1.0}, "accept"),
        (DualAnnealing, {"maxiter": 0}, "maxiter"),
    ],
)
def test_invalid_parameters_are_refused(cls, params, words) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=words):
        cls(*box(2), 1000, np.random.default_rng(0), params)


def test_a_budget_below_one_generation_is_refused() -> None:
    with pytest.raises(ValueError, match="budget"):
        ScipyDE(*box(4), 59, np.random.default_rng(0))  # 15 x 4 = 60 members
