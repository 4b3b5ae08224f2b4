"""FA and IFA: the equations of seed 000 checked on hand-worked cases, and the ask/tell loop."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tcbench.optimisers import ProtocolError, create
from tcbench.optimisers.firefly_moves import (
    attractiveness,
    brighter_mask,
    move_towards,
    pull_layout,
    squared_distances,
)
from tcbench.optimisers.ifa import (
    adaptive_step,
    annealing_temperature,
    metropolis_accept,
    mutation_step,
    random_subsets,
)
from tcbench.tasks.functions import rastrigin, sphere


def test_eq4_attractiveness() -> None:
    r2 = np.array([0.0, 1.0, 4.0])
    np.testing.assert_allclose(attractiveness(r2, 1.0, 0.5), [1.0, math.exp(-0.5), math.exp(-2.0)])
    np.testing.assert_allclose(attractiveness(r2, 1.0, 0.5, 0.2), 0.2 + 0.8 * np.exp(-0.5 * r2))


def test_squared_distances() -> None:
    x = np.array([[0.0, 0.0], [3.0, 4.0]])
    np.testing.assert_allclose(squared_distances(x), [[0, 25], [25, 0]])


def test_eq5_closed_form_equals_sequential_moves() -> None:
    """The vectorised chain equals visiting each brighter firefly in turn (eq. 5 each time)."""
    rng = np.random.default_rng(3)
    n, d, alpha = 6, 3, 0.3
    x = rng.normal(size=(n, d))
    f = np.sort(rng.normal(size=n))
    coef = np.where(brighter_mask(f), attractiveness(squared_distances(x), 0.9, 0.4), 0.0)
    got = move_towards(x, coef, alpha, np.random.default_rng(11))
    draws = np.random.default_rng(11)
    n_moves = int(np.count_nonzero(coef))
    noise = iter((draws.random((n_moves, d)) - 0.5) * alpha)  # one step per move, row-major
    want = x.copy()
    for i in range(n):
        for j in range(n):
            if coef[i, j] > 0:
                want[i] = want[i] + coef[i, j] * (x[j] - want[i]) + next(noise)
    want[0] = x[0] + (draws.random((1, d)) - 0.5) * alpha  # the brightest walks randomly
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


def sequential_moves(x, coef, step, rng):
    """Eq. 5 firefly by firefly, pull by pull: the random steps of the moves in (i, j) row-major
    order, then one step for each firefly that moves toward nobody, in row order."""
    n, d = x.shape
    noise = iter((rng.random((int(np.count_nonzero(coef)), d)) - 0.5) * step)
    want = x.copy()
    for i in range(n):
        for j in range(n):
            if coef[i, j] > 0:
                want[i] = want[i] + coef[i, j] * (x[j] - want[i]) + next(noise)
    for i in np.flatnonzero(~(coef > 0).any(axis=1)):
        want[i] = x[i] + (rng.random((1, d))[0] - 0.5) * step
    return want


@pytest.mark.parametrize("lone_rows", [[0], [0, 1], [0, 3, 5], [2, 6]])
def test_eq5_closed_form_with_any_pattern_of_pulls(lone_rows) -> None:
    """Random subsets of brighter fireflies (IFA) and fireflies that follow nobody anywhere in
    the population: still the sequential chain, steps drawn in the same order."""
    rng = np.random.default_rng(5)
    n, d = 7, 4
    x = rng.normal(size=(n, d))
    step = np.array([0.1, 0.2, 0.3, 0.4])
    coef = np.tril(rng.uniform(0.1, 0.9, (n, n)), -1) * (rng.random((n, n)) < 0.6)
    coef[:, 0] = np.where(np.arange(n) > 0, 0.5, 0.0)  # every row but the first has a pull
    coef[lone_rows] = 0.0
    got = move_towards(x, coef, step, np.random.default_rng(11))
    want = sequential_moves(x, coef, step, np.random.default_rng(11))
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize(
    ("mask", "moving", "starts"),
    [
        (np.tri(4, k=-1, dtype=bool), [1, 2, 3], [0, 1, 3]),  # everyone brighter (FA)
        (np.array([[0, 0, 0, 0], [0, 0, 0, 0], [1, 1, 0, 0], [1, 1, 1, 0]], dtype=bool),
         [2, 3], [0, 2]),  # the two brightest tie: neither pulls the other
        (np.array([[0, 0, 0, 0], [1, 0, 0, 0], [0, 0, 0, 0], [1, 1, 1, 0]], dtype=bool),
         [1, 3], [0, 1]),  # a lone firefly between movers
    ],
)
def test_pull_layout(mask, moving, starts) -> None:
    layout = pull_layout(mask)
    rows = np.arange(len(mask))
    assert layout.pulls == mask.sum()
    np.testing.assert_array_equal(rows[layout.moving], moving)
    np.testing.assert_array_equal(rows[layout.lone], np.setdiff1d(rows, moving))
    assert layout.n_lone == len(mask) - len(moving)
    np.testing.assert_array_equal(layout.starts, starts)


def test_scalar_step_gives_the_same_bits_as_a_uniform_per_axis_step() -> None:
    rng = np.random.default_rng(2)
    x = rng.uniform(-5, 5, (12, 6))
    f = np.sort(rng.normal(size=12))
    coef = np.where(brighter_mask(f), attractiveness(squared_distances(x), 1.0, 0.05), 0.0)
    a = move_towards(x, coef, 0.37, np.random.default_rng(4))
    b = move_towards(x, coef, np.full(6, 0.37), np.random.default_rng(4))
    np.testing.assert_array_equal(a, b)


def test_eq6_adaptive_step() -> None:
    assert adaptive_step(0.25, 0, 50, 1.0) == pytest.approx(0.25)
    assert adaptive_step(0.25, 25, 50, 0.9) == pytest.approx(0.9 * 0.25 * math.exp(-1.0))
    assert adaptive_step(1.0, 49, 50, 1.0) == pytest.approx(math.exp(-49.0))
    with pytest.raises(ValueError, match="0 <= n < maxgen"):
        adaptive_step(1.0, 50, 50, 1.0)


def test_eq7_metropolis() -> None:
    rng = np.random.default_rng(0)
    assert metropolis_accept(1.0, 0.5, 1e-9, rng)
    accepted = np.mean([metropolis_accept(0.0, 1.0, 1.0, rng) for _ in range(20000)])
    assert accepted == pytest.approx(math.exp(-1.0), abs=0.012)
    assert not any(metropolis_accept(0.0, np.inf, 1.0, rng) for _ in range(100))


def test_eq8_temperature() -> None:
    assert annealing_temperature(10, 50, 0.01) == pytest.approx(0.4)
    assert annealing_temperature(49, 50, 0.01) == pytest.approx(0.01)


def test_eq9_mutation_shrinks_with_cosine() -> None:
    width = np.array([10.0, 2.0])
    rng = np.random.default_rng(0)
    early = np.array([mutation_step(0, 50, width, rng) for _ in range(4000)])
    late = np.array([mutation_step(45, 50, width, rng) for _ in range(4000)])
    np.testing.assert_array_less(np.abs(early).max(axis=0), width / 2)
    np.testing.assert_allclose(np.abs(early).max(axis=0), width / 2, rtol=0.01)
    bound = math.cos(math.pi / 2 * 45 / 50) * width / 2
    np.testing.assert_array_less(np.abs(late).max(axis=0), bound + 1e-12)


def test_random_subsets() -> None:
    mask = random_subsets(10, 3, np.random.default_rng(0))
    assert mask.sum(axis=1).tolist() == [3] * 10
    assert not mask.diagonal().any()


def _run(name: str, fn, dim: int, budget: int, seed: int, params=None, lower=-5.12, upper=5.12):
    lo, hi = np.full(dim, lower), np.full(dim, upper)
    opt = create(name, lo, hi, budget, np.random.default_rng(seed), params or {})
    asked = 0
    while not opt.done:
        x = opt.ask()
        assert np.all(x >= lo) and np.all(x <= hi)  # eq. 11
        asked += len(x)
        opt.tell(x, fn(x))
    return opt, asked


@pytest.mark.parametrize("name", ["fa", "ifa"])
def test_same_seed_same_result(name: str) -> None:
    a, _ = _run(name, rastrigin, 3, 300, seed=7)
    b, _ = _run(name, rastrigin, 3, 300, seed=7)
    c, _ = _run(name, rastrigin, 3, 300, seed=8)
    np.testing.assert_array_equal(a.best.x, b.best.x)
    assert a.best.f == b.best.f and a.best.f != c.best.f


@pytest.mark.parametrize("name", ["fa", "ifa"])
@pytest.mark.parametrize("budget", [10, 11, 95, 510])
def test_budget_is_spent_exactly(name: str, budget: int) -> None:
    opt, asked = _run(name, rastrigin, 2, budget, seed=0)
    assert asked == opt.evaluations == budget


@pytest.mark.parametrize("name", ["fa", "ifa"])
def test_converges_on_sphere(name: str) -> None:
    params = {"alpha0": 0.05, "beta_min": 0.2, "population": 20}
    errors = [_run(name, sphere, 2, 2000, seed=s, params=params)[0].best.f for s in range(5)]
    assert np.median(errors) < 1e-3


def test_ifa_generation_costs_population_evaluations() -> None:
    opt, _ = _run("ifa", rastrigin, 2, 510, seed=1)
    assert opt.generation == opt.maxgen == 50


@pytest.mark.parametrize("name", ["fa", "ifa"])
def test_nonfinite_objective_survives(name: str) -> None:
    def nasty(x):
        f = sphere(x)
        f[::3] = np.nan
        f[1::7] = np.inf
        return f

    opt, _ = _run(name, nasty, 2, 300, seed=2)
    assert np.isfinite(opt.best.f) and opt.nonfinite > 0
    assert opt.best.f == pytest.approx(sphere(opt.best.x[None, :])[0])


def test_budget_smaller_than_a_generation() -> None:
    with pytest.raises(ValueError, match="smaller than one generation"):
        create("fa", np.zeros(2), np.ones(2), 5, np.random.default_rng(0), {"population": 10})


@pytest.mark.parametrize(
    ("name", "params", "message"),
    [
        ("fa", {"population": 1}, "population must be >= 2"),
        ("fa", {"beta0": 1.5}, "beta0 must be in"),
        ("fa", {"gamma": -1.0}, "gamma must be >= 0"),
        ("fa", {"alpha0": "big"}, "fa.alpha0 must be float"),
        ("fa", {"colour": 1}, "no parameter 'colour'"),
        ("ifa", {"k": 0.0}, "k must be in"),
        ("ifa", {"epsilon": 0.0}, "epsilon must be > 0"),
        ("ifa", {"subset_fraction": 2.0}, "subset_fraction"),
        ("ifa", {"alpha_decay": 0.9}, "IFA's step follows eq. 6"),
    ],
)
def test_invalid_parameters(name, params, message) -> None:
    with pytest.raises(ValueError, match=message):
        create(name, np.zeros(2), np.ones(2), 100, np.random.default_rng(0), params)


def test_protocol_misuse() -> None:
    opt = create("fa", np.zeros(2), np.ones(2), 100, np.random.default_rng(0))
    x = opt.ask()
    with pytest.raises(ProtocolError, match="twice"):
        opt.ask()
    with pytest.raises(ProtocolError, match="points of the last ask"):
        opt.tell(x + 0.1, sphere(x))
    with pytest.raises(ProtocolError, match=r"values of shape \(9,\) for 10 points"):
        opt.tell(x, sphere(x)[:-1])
    opt.tell(x, sphere(x))
    with pytest.raises(ProtocolError, match="without a preceding ask"):
        opt.tell(x, sphere(x))
