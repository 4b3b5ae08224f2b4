"""Simulated annealing: the Metropolis rule, White's T0, reflection and the cooling schedule on
hand-worked cases, then the ask/tell loop, SA-BP and the command line.

The class is constructed directly (not through the registry) except in the registry, SA-BP and
command-line tests at the end.
"""

from __future__ import annotations

import dataclasses
import math
import subprocess
from pathlib import Path

import numpy as np
import optimiser_runs
import pytest
from cli_here import tcbench as here

from tcbench.optimisers.sa import (
    SAParams,
    SimulatedAnnealing,
    initial_temperature,
    metropolis_accept,
    reflect,
)
from tcbench.tasks.functions import rastrigin, sphere


def _make(dim=2, budget=100, seed=0, params=None, lower=-5.12, upper=5.12):
    return optimiser_runs.make(SimulatedAnnealing, dim, budget, seed, params, lower, upper)


def _run(fn, dim=2, budget=100, seed=0, params=None, lower=-5.12, upper=5.12):
    return optimiser_runs.run(SimulatedAnnealing, fn, dim, budget, seed, params, lower, upper)


# -- Metropolis rule -------------------------------------------------------------------------
def test_metropolis_by_hand() -> None:
    f_cur = np.array([5.0, 5.0, 5.0, 5.0, 5.0])
    f_new = np.array([4.0, 5.0, 6.0, 6.0, 7.0])
    u = np.array([0.99, 0.99, 0.36, 0.37, 0.13])  # exp(-1) = 0.3679, exp(-2) = 0.1353
    np.testing.assert_array_equal(metropolis_accept(f_new, f_cur, 1.0, u), [1, 1, 1, 0, 1])
    # the same uphill step of 1 at T = 2: exp(-0.5) = 0.607
    hot = metropolis_accept([6.0, 6.0], [5.0, 5.0], 2.0, [0.6, 0.61])
    np.testing.assert_array_equal(hot, [1, 0])


def test_metropolis_hot_accepts_worse_cold_never() -> None:
    rng = np.random.default_rng(0)
    n = 10000
    worse, cur = np.full(n, 1.0), np.zeros(n)
    assert metropolis_accept(worse, cur, 1e6, rng.random(n)).mean() > 0.99
    assert not metropolis_accept(worse, cur, 1e-6, rng.random(n)).any()
    assert not metropolis_accept(worse, cur, 0.0, rng.random(n)).any()  # T = 0: greedy
    rate = metropolis_accept(worse, cur, 1.0 / math.log(2.0), rng.random(n)).mean()
    assert rate == pytest.approx(0.5, abs=0.02)  # exp(-1 / T) = 1/2


def test_metropolis_nonfinite() -> None:
    f_new = np.array([np.inf, np.nan, 1.0, np.inf])
    f_cur = np.array([1.0, 1.0, np.inf, np.inf])
    with np.errstate(all="raise"):  # no warnings either
        accepted = metropolis_accept(f_new, f_cur, 1e300, np.zeros(4))
    np.testing.assert_array_equal(accepted, [0, 0, 1, 1])  # inf -> inf is a harmless walk


# -- T0 ----------------------------------------------------------------------------------------
def test_initial_temperature_is_the_robust_spread() -> None:
    f = np.array([1.0, 2.0, 3.0, 4.0, 1e9])  # median 3, MAD 1: the outlier does not count
    assert initial_temperature(f) == pytest.approx(1.4826)
    assert initial_temperature(1e-6 * f) == pytest.approx(1.4826e-6)  # scales with the objective
    big = np.random.default_rng(0).normal(7.0, 3.0, 20000)
    assert initial_temperature(big) == pytest.approx(3.0, rel=0.03)  # sigma of a normal sample


@pytest.mark.parametrize(
    ("f", "t0"),
    [
        ([1.0, 1.0, 1.0, 5.0], math.sqrt(3.0)),  # MAD 0 -> standard deviation
        ([-4.0, -4.0], 4.0),  # no spread -> |median|
        ([0.0], 1.0),
        ([np.inf, np.nan], 1.0),  # nothing finite
        ([2.0, np.nan, 4.0, np.inf], 1.4826),  # non-finite values are left out
    ],
)
def test_initial_temperature_fallbacks(f, t0) -> None:
    assert initial_temperature(np.array(f)) == pytest.approx(t0)


# -- bounds --------------------------------------------------------------------------------------
def test_reflect_by_hand() -> None:
    lo, hi = np.zeros(1), np.ones(1)
    x = np.array([[1.2], [-0.3], [2.5], [-1.75], [1.0], [0.0], [0.4]])
    want = [[0.8], [0.3], [0.5], [0.25], [1.0], [0.0], [0.4]]
    np.testing.assert_allclose(reflect(x, lo, hi), want)
    wild = np.random.default_rng(0).normal(0.0, 1e4, (1000, 3))
    lo3, hi3 = np.array([-1.0, 0.0, 5.0]), np.array([2.0, 1e-3, 6.0])
    inside = reflect(wild, lo3, hi3)
    assert np.all(inside >= lo3) and np.all(inside <= hi3)


# -- schedule and moves --------------------------------------------------------------------------
def _temperatures(opt: SimulatedAnnealing, fn=sphere) -> list[float]:
    """Temperature in force at each move generation (after the initial sample)."""
    seen = []
    while not opt.done:
        x = opt.ask()
        if opt.evaluations > 0:
            seen.append(opt.temperature)
        opt.tell(x, fn(x))
    return seen


@pytest.mark.parametrize(("budget", "population"), [(220, 1), (1000, 1), (1001, 4), (30, 3)])
def test_budget_fitted_cooling_ends_at_t_final(budget: int, population: int) -> None:
    opt = _make(budget=budget, params={"population": population, "t_final": 1e-4})
    temps = _temperatures(opt)
    assert len(temps) == math.ceil((budget - max(20, population)) / population)
    assert temps[0] == opt.t0 and temps[-1] == pytest.approx(1e-4 * opt.t0)
    np.testing.assert_allclose(np.diff(np.log(temps)), math.log(opt.cooling))


def test_fixed_cooling_is_geometric_with_a_floor() -> None:
    opt = _make(budget=2000, params={"cooling": 0.95, "t_final": 1e-3})
    temps = np.array(_temperatures(opt))
    k = np.arange(len(temps))
    np.testing.assert_allclose(temps, opt.t0 * np.maximum(0.95**k, 1e-3))


def test_given_t0_is_used() -> None:
    opt = _make(budget=50, params={"t0": 123.0, "t_final": 1.0})
    assert _temperatures(opt) == [123.0] * 30


def test_initial_sample_starts_and_first_move_replayed() -> None:
    """Non-cubic box: first ask is the uniform sample, chains start at its best points, and the
    first move is Gaussian with per-axis sigma = step x width (T = T0), reflected."""
    lo, hi = np.array([0.0, -10.0, 3.0]), np.array([1.0, 10.0, 3.5])
    params = {"population": 3, "init_samples": 8, "step": 0.3}
    opt = SimulatedAnnealing(lo, hi, 100, np.random.default_rng(5), params)
    replay = np.random.default_rng(5)
    sample = opt.ask()
    np.testing.assert_array_equal(sample, replay.uniform(lo, hi, size=(8, 3)))
    f = sphere(sample)
    opt.tell(sample, f)
    order = np.argsort(f)[:3]
    np.testing.assert_array_equal(opt.x, sample[order])
    np.testing.assert_array_equal(opt.fitness, f[order])
    assert opt.t0 == initial_temperature(f) and opt.generation == 0
    np.testing.assert_allclose(opt.sigma, 0.3 * (hi - lo))
    z = replay.standard_normal((3, 3))
    np.testing.assert_allclose(opt.ask(), reflect(sample[order] + 0.3 * (hi - lo) * z, lo, hi))


def test_step_shrinks_with_sqrt_of_temperature() -> None:
    opt = _make(budget=500, params={"cooling": 0.5, "t_final": 1e-6})
    for _ in range(5):
        x = opt.ask()
        opt.tell(x, sphere(x))
    np.testing.assert_allclose(opt.sigma, 0.1 * 10.24 * math.sqrt(0.5**4))


def test_worse_move_accepted_hot_rejected_cold() -> None:
    """Tell every move one unit worse than the chain's state: a hot chain follows, a cold one
    stays put."""
    for t0, moves in ((1e12, True), (1e-12, False)):
        opt = _make(dim=3, budget=200, seed=1, params={"population": 4, "t0": t0, "t_final": 1.0})
        x = opt.ask()
        opt.tell(x, sphere(x))
        for _ in range(10):
            start, f_start = opt.x.copy(), opt.fitness.copy()
            x = opt.ask()
            opt.tell(x, f_start + 1.0)
            if moves:
                np.testing.assert_array_equal(opt.x, x)
                np.testing.assert_array_equal(opt.fitness, f_start + 1.0)
            else:
                np.testing.assert_array_equal(opt.x, start)


# -- the ask/tell loop ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("population", "budget"),
    [(1, 1), (1, 2), (1, 20), (1, 21), (1, 333), (3, 3), (3, 19), (3, 100), (25, 26), (4, 1001)],
)
def test_budget_is_spent_exactly(population: int, budget: int) -> None:
    opt, asked = _run(sphere, budget=budget, params={"population": population})
    assert asked == opt.evaluations == budget
    n_init = min(max(20, population), budget)
    assert opt.generation == math.ceil((budget - n_init) / population)


def test_budget_smaller_than_the_chains() -> None:
    with pytest.raises(ValueError, match="smaller than one generation"):
        _make(budget=3, params={"population": 4})


def test_asks_stay_in_bounds_with_large_steps() -> None:
    params = {"step": 1.0, "population": 3, "t_final": 1.0}
    opt, _ = _run(rastrigin, dim=4, budget=301, params=params, lower=-1.0, upper=2.0)
    assert np.all(opt.x >= -1.0) and np.all(opt.x <= 2.0)


@pytest.mark.parametrize("params", [{}, {"population": 4, "cooling": 0.9}])
def test_same_seed_same_result(params) -> None:
    a, _ = _run(rastrigin, dim=3, budget=300, seed=7, params=params)
    b, _ = _run(rastrigin, dim=3, budget=300, seed=7, params=params)
    c, _ = _run(rastrigin, dim=3, budget=300, seed=8, params=params)
    np.testing.assert_array_equal(a.best.x, b.best.x)
    np.testing.assert_array_equal(a.x, b.x)
    assert a.best.f == b.best.f and a.best.f != c.best.f
    assert not np.array_equal(a.best.x, c.best.x)


@pytest.mark.parametrize("population", [1, 3])
def test_nonfinite_objective_survives(population: int) -> None:
    count = [0]

    def nasty(x):  # every 3rd evaluation NaN, every 7th inf, counted over the whole run
        f = sphere(x)
        k = count[0] + np.arange(len(f))
        count[0] += len(f)
        f[k % 3 == 0] = np.nan
        f[k % 7 == 1] = np.inf
        return f

    opt, asked = _run(nasty, dim=2, budget=301, seed=2, params={"population": population})
    assert asked == 301 and opt.nonfinite > 0
    assert np.isfinite(opt.best.f) and opt.best.f == pytest.approx(sphere(opt.best.x[None, :])[0])
    assert np.all(np.isfinite(opt.fitness)) and np.all(np.isfinite(opt.x))  # no chain sits on NaN


def test_all_nan_objective() -> None:
    opt, asked = _run(lambda x: np.full(len(x), np.nan), budget=60, params={"population": 2})
    assert asked == 60 and opt.nonfinite == 60 and opt.best.f == np.inf and opt.t0 == 1.0


def test_converges_on_5d_sphere() -> None:
    """Defaults, budget 2000, five seeds: every run below 1e-3 (typically ~1e-5) from ~45."""
    errors = [_run(sphere, dim=5, budget=2000, seed=s)[0].best.f for s in range(5)]
    assert max(errors) < 1e-3


def test_several_chains_converge() -> None:
    errors = [_run(sphere, dim=5, budget=4000, seed=s, params={"population": 4})[0].best.f
              for s in range(3)]
    assert max(errors) < 1e-3


def test_contract_checker() -> None:
    from tcbench import check_optimizer

    assert check_optimizer(SimulatedAnnealing) >= 2
    assert check_optimizer(SimulatedAnnealing, params={"population": 3, "cooling": 0.9}) >= 2


# -- parameters ------------------------------------------------------------------------------------
def test_defaults_mirror_the_yaml() -> None:
    import yaml

    from tcbench.config_dir import conf_dir

    conf = conf_dir() / "optimiser" / "sa.yaml"
    values = yaml.safe_load(conf.read_text())
    assert values.pop("name") == SimulatedAnnealing.name == "sa"
    assert values == dataclasses.asdict(SAParams())


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ({"population": 0}, "population must be >= 1"),
        ({"step": 0.0}, "step must be in"),
        ({"step": -0.1}, "step must be in"),
        ({"step": 1.5}, "step must be in"),
        ({"cooling": 0.0}, "cooling must be in"),
        ({"cooling": 1.0}, "cooling must be in"),
        ({"cooling": 1.2}, "cooling must be in"),
        ({"t_final": 0.0}, "t_final must be in"),
        ({"t_final": 2.0}, "t_final must be in"),
        ({"init_samples": 0}, "init_samples must be >= 1"),
        ({"t0": 0.0}, "t0 must be a finite number > 0"),
        ({"t0": math.inf}, "t0 must be a finite number"),
        ({"step": "big"}, "sa.step must be float"),
        ({"temperature": 2}, "no parameter 'temperature'"),
    ],
)
def test_invalid_parameters(params, message) -> None:
    with pytest.raises(ValueError, match=message):
        _make(budget=100, params=params)
    if "temperature" not in params and params != {"step": "big"}:
        with pytest.raises(ValueError, match=message):
            SAParams(**params)


# -- registry, SA-BP, command line -----------------------------------------------------------
def test_registered_under_sa() -> None:
    from tcbench.optimisers import available

    entry = available()["sa"]
    assert entry.cls is SimulatedAnnealing and entry.package == "tcbench"


def test_sa_bp_initialises_and_compensates() -> None:
    from tcbench.runner.loop import run_compensation

    learner = {"name": "bp", "training": "lm", "epochs": 20}
    result = run_compensation({"name": "msra_fulltemp"}, learner, {"name": "sa"}, 200, 1)
    assert result.search_evaluations == 200 and np.isfinite(result.init_loss)
    assert result.history is not None and result.history.loss[0] == pytest.approx(result.init_loss)
    s = result.score.summary()
    assert s["bias_variation_ug"] < s["raw_bias_variation_ug"]


def test_command_line(workdir: Path) -> None:
    def tcbench(*args: str) -> subprocess.CompletedProcess[str]:
        return here(*args, cwd=workdir)  # in this process (cli_here)

    listed = tcbench("list")
    assert listed.returncode == 0 and "tcbench.optimisers.sa.SimulatedAnnealing" in listed.stdout
    ran = tcbench("run", "task=sphere", "optimiser=sa", "budget=2000", "tracking.enabled=false")
    assert ran.returncode == 0, ran.stderr
    bad = tcbench("run", "task=sphere", "optimiser=sa", "optimiser.cooling=1.5",
                  "tracking.enabled=false")
    assert bad.returncode == 2 and "cooling must be in (0, 1)" in bad.stderr
