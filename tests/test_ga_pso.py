"""GA and PSO: the operators checked on hand-worked cases, and the ask/tell loop.

The optimisers are built from their classes, not through the entry-point registry.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tcbench.optimisers import ProtocolError
from tcbench.optimisers.ga import (
    GAParams,
    GeneticAlgorithm,
    binary_tournament,
    crowding_distance,
    nondominated_rank,
    nsga2_survivors,
    polynomial_mutation,
    sbx,
    sbx_spread,
    tournament_pairs,
)
from tcbench.optimisers.pso import (
    PSOParams,
    ParticleSwarm,
    clamp_velocity,
    constriction_factor,
    move_within_bounds,
    pso_velocity,
)
from tcbench.tasks.functions import rastrigin, sphere

CLASSES = {"ga": GeneticAlgorithm, "pso": ParticleSwarm}


# -- GA operators ---------------------------------------------------------------------------------
def test_sbx_spread_factor_formula() -> None:
    eta = 2.0
    u = np.array([0.0, 0.1, 0.5, 0.9])
    want = [0.0, 0.2 ** (1 / 3), 1.0, 5.0 ** (1 / 3)]  # (2u)^(1/3), then (1/(2(1-u)))^(1/3)
    np.testing.assert_allclose(sbx_spread(u, eta), want, rtol=1e-12)


def test_sbx_far_from_bounds_is_symmetric_with_the_spread_factor() -> None:
    """Bounds far away: children symmetric about the parents' mean, |c2 - c1| = beta |p2 - p1|."""
    u = np.array([[0.1, 0.5, 0.9, 0.3]])
    p1, p2 = np.array([[1.0, 3.0, -2.0, 0.0]]), np.array([[3.0, 1.0, 4.0, 0.5]])
    lo, hi = np.full(4, -1e6), np.full(4, 1e6)
    c1, c2 = sbx(p1, p2, lo, hi, 2.0, u)
    np.testing.assert_allclose((c1 + c2) / 2, (p1 + p2) / 2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.abs(c2 - c1), sbx_spread(u, 2.0) * np.abs(p2 - p1), rtol=1e-9)
    np.testing.assert_array_less(c1, c2 + 1e-12)  # no swap: first child takes the smaller value


def test_sbx_bounded_hand_case() -> None:
    """Parents 0.2, 0.8 in [0, 1], eta_c = 1, u = 1/4: beta = 1 + 2 (0.2/0.6) = 5/3,
    alpha = 2 - (3/5)^2 = 1.64, u alpha = 0.41 <= 1 so beta_q = sqrt(0.41) = 0.640312,
    children 0.5 -+ 0.5 * 0.640312 * 0.6 = 0.307906, 0.692094 (symmetric: the bounds are)."""
    lo, hi = np.zeros(1), np.ones(1)
    c1, c2 = sbx(np.array([[0.8]]), np.array([[0.2]]), lo, hi, 1.0, np.array([[0.25]]))
    assert c1[0, 0] == pytest.approx(0.5 - 0.3 * math.sqrt(0.41), abs=1e-12)
    assert c1[0, 0] == pytest.approx(0.307906, abs=1e-6)
    assert c2[0, 0] == pytest.approx(0.692094, abs=1e-6)


def test_sbx_children_stay_in_bounds_and_reach_them_at_u_to_1() -> None:
    rng = np.random.default_rng(0)
    lo, hi = np.array([-1.0, 0.0, 10.0]), np.array([1.0, 0.001, 20.0])
    p1 = rng.uniform(lo, hi, size=(5000, 3))
    p2 = np.where(rng.random((5000, 3)) < 0.3, lo, rng.uniform(lo, hi, size=(5000, 3)))
    c1, c2 = sbx(p1, p2, lo, hi, 0.0, rng.random((5000, 3)))
    for c in (c1, c2):
        assert np.all(c >= lo) and np.all(c <= hi)
    edge1, edge2 = sbx(np.array([[0.2]]), np.array([[0.8]]), 0.0, 1.0, 1.0, np.array([[1 - 1e-15]]))
    assert edge1[0, 0] == pytest.approx(0.0, abs=1e-6)
    assert edge2[0, 0] == pytest.approx(1.0, abs=1e-6)


def test_sbx_masks_cross_and_swap() -> None:
    p1, p2 = np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 1.0, 1.0]])
    u = np.full((1, 3), 0.3)
    c1, c2 = sbx(p1, p2, np.full(3, -5.0), np.full(3, 5.0), 5.0, u,
                 cross=np.array([[True, False, True]]), swap=np.array([[True, False, False]]))
    assert c1[0, 0] > 0.5 > c2[0, 0]  # crossed and swapped
    assert (c1[0, 1], c2[0, 1]) == (0.0, 1.0)  # not crossed: copies of the parents
    assert (c1[0, 2], c2[0, 2]) == (1.0, 1.0)  # equal parents are never crossed


def test_polynomial_mutation_hand_case_and_bounds() -> None:
    """y = 0.5 in [0, 1], eta_m = 1, u = 1/4: delta1 = 0.5, val = 0.5 + 0.5 * 0.5^2 = 0.625,
    delta_q = sqrt(0.625) - 1 = -0.209431, y' = 0.290569; u = 3/4 mirrors it to 0.709431."""
    y = np.array([[0.5, 0.5]])
    out = polynomial_mutation(y, np.zeros(2), np.ones(2), 1.0, np.array([[0.25, 0.75]]))
    np.testing.assert_allclose(out, [[0.5 + math.sqrt(0.625) - 1, 0.5 - math.sqrt(0.625) + 1]])
    np.testing.assert_allclose(out, [[0.290569, 0.709431]], atol=1e-6)
    # u = 0 and u = 1 (the ends of the draw) land on the bounds, from anywhere
    ends = polynomial_mutation(np.array([[0.3, 0.3]]), np.zeros(2), np.ones(2), 20.0,
                               np.array([[0.0, 1.0]]))
    np.testing.assert_allclose(ends, [[0.0, 1.0]], atol=1e-9)
    rng = np.random.default_rng(1)
    lo, hi = np.array([-3.0, 2.0]), np.array([-1.0, 2.5])
    y = np.where(rng.random((10000, 2)) < 0.2, hi, rng.uniform(lo, hi, size=(10000, 2)))
    out = polynomial_mutation(y, lo, hi, 0.0, rng.random((10000, 2)))
    assert np.all(out >= lo) and np.all(out <= hi)
    mask = np.array([[True, False]])
    kept = polynomial_mutation(np.array([[-2.0, 2.2]]), lo, hi, 20.0, np.array([[0.9, 0.9]]), mask)
    assert kept[0, 1] == 2.2 and kept[0, 0] > -2.0


def test_tournament_picks_the_better() -> None:
    f = np.array([3.0, 1.0, 2.0, np.inf])
    pairs = np.array([[0, 1], [2, 0], [1, 1], [3, 0], [2, 3]])
    assert binary_tournament(pairs, f).tolist() == [1, 2, 1, 0, 2]
    rank, crowd = np.array([0, 0, 1]), np.array([1.0, np.inf, 5.0])
    pairs = np.array([[0, 1], [1, 0], [2, 0], [0, 0], [0, 2]])
    assert binary_tournament(pairs, rank, crowd).tolist() == [1, 1, 0, 0, 0]


def test_permutation_tournaments_enter_everyone_twice() -> None:
    """NSGA-II code's tselect: N children take 2N tournaments from two shuffles, so every
    individual meets exactly two rivals and never itself; with replacement some miss out."""
    rng = np.random.default_rng(0)
    pairs = tournament_pairs(40, 40, rng)
    assert pairs.shape == (40, 2)
    assert np.bincount(pairs.ravel(), minlength=40).tolist() == [2] * 40
    assert np.all(pairs[:, 0] != pairs[:, 1])
    odd = tournament_pairs(7, 5, rng)  # 10 contestants from two shuffles of 7: nobody thrice
    assert odd.shape == (5, 2) and np.bincount(odd.ravel(), minlength=7).max() <= 2
    uniform = tournament_pairs(40, 40, rng, "random")
    assert np.bincount(uniform.ravel(), minlength=40).min() == 0  # 80 draws leave someone out


def test_permutation_tournaments_beat_uniform_on_sphere() -> None:
    """The selection change the NSGA-II code makes: over 12 seeds on 30-D sphere (20 000
    evaluations) the median best falls (measured 0.042 -> 0.033 over 20 seeds)."""
    def median_best(how: str) -> float:
        best = []
        for seed in range(12):
            opt = GeneticAlgorithm(np.full(30, -5.12), np.full(30, 5.12), 20000, np.random.default_rng(seed),
                                   {"population": 100, "tournament": how})
            while not opt.done:
                x = opt.ask()
                opt.tell(x, sphere(x))
            best.append(opt.best.f)
        return float(np.median(best))

    assert median_best("permutation") < 0.9 * median_best("random")


# A small hand-made population: front 0 = (0,5) (1,3) (3,1) (4,0); (2,4) is dominated by (1,3)
# only; (3,5) by (2,4) as well, so it is in front 2. Rows shuffled.
FRONT = np.array([[3.0, 1.0], [2.0, 4.0], [0.0, 5.0], [3.0, 5.0], [4.0, 0.0], [1.0, 3.0]])


def test_nondominated_sorting_ranks() -> None:
    assert nondominated_rank(FRONT).tolist() == [0, 1, 0, 2, 0, 0]
    assert nondominated_rank(np.array([[1.0, 1.0], [1.0, 1.0]])).tolist() == [0, 0]


def test_crowding_distance_hand_case() -> None:
    """Front 0, objective 1 sorted 0, 1, 3, 4 (range 4), objective 2 sorted 0, 1, 3, 5 (range 5):
    (1,3) gets (3-0)/4 + (5-1)/5 = 1.55, (3,1) gets (4-1)/4 + (3-0)/5 = 1.35; extremes inf.
    Fronts 1 and 2 hold one point each, both extremes."""
    d = crowding_distance(FRONT, nondominated_rank(FRONT))
    np.testing.assert_allclose(d, [1.35, np.inf, np.inf, np.inf, np.inf, 1.55])
    alone = crowding_distance(FRONT[[2, 5, 0, 4]])  # one front given without ranks
    np.testing.assert_allclose(alone, [np.inf, 1.55, 1.35, np.inf])
    all_inf = crowding_distance(np.full((3, 2), np.inf))
    assert all_inf.tolist() == [np.inf, 0.0, np.inf]


def test_nsga2_survival_by_front_then_crowding() -> None:
    assert sorted(nsga2_survivors(FRONT, 5).tolist()) == [0, 1, 2, 4, 5]
    assert sorted(nsga2_survivors(FRONT, 3).tolist()) == [2, 4, 5]  # the extremes, then 1.55


# -- PSO update ---------------------------------------------------------------------------------
def test_eq21_velocity_hand_case() -> None:
    """w v = (0.5, -0.5); c1 r1 (p - x) = 2 (0.5, 0.25)(1, 2) = (1, 1);
    c2 r2 (g - x) = (1, 0.5)(3, -1) = (3, -0.5); sum (4.5, 0); times chi 0.8 = (3.6, 0)."""
    v = pso_velocity(
        np.array([[1.0, -1.0]]), np.zeros((1, 2)), np.array([[1.0, 2.0]]), np.array([3.0, -1.0]),
        w=0.5, c1=2.0, c2=1.0, r1=np.array([[0.5, 0.25]]), r2=np.array([[1.0, 0.5]]), chi=0.8,
    )
    np.testing.assert_allclose(v, [[3.6, 0.0]], atol=1e-15)


def test_constriction_factor() -> None:
    """phi = 4.1: chi = 2 / (2.1 + sqrt(0.41)) = 0.729844; chi * 2.05 = 1.49618 (the defaults)."""
    chi = constriction_factor(4.1)
    assert chi == pytest.approx(2 / (2.1 + math.sqrt(0.41)))
    assert chi == pytest.approx(PSOParams().w, abs=1e-4)
    assert 2.05 * chi == pytest.approx(PSOParams().c1, abs=1e-5)
    with pytest.raises(ValueError, match="phi > 4"):
        constriction_factor(4.0)


def test_velocity_clamp_and_absorbing_wall() -> None:
    v = clamp_velocity(np.array([[3.0, -3.0, 0.1]]), np.array([1.0, 2.0, 1.0]))
    np.testing.assert_array_equal(v, [[1.0, -2.0, 0.1]])
    x, v = move_within_bounds(np.array([[0.9, 0.5, 0.1]]), np.array([[0.3, -0.2, -0.4]]), 0.0, 1.0)
    np.testing.assert_allclose(x, [[1.0, 0.3, 0.0]])
    np.testing.assert_allclose(v, [[0.0, -0.2, 0.0]])


# -- ask/tell -------------------------------------------------------------------------------------
def two_parabolas(x: np.ndarray) -> np.ndarray:
    """f1 = x^2, f2 = (x - 2)^2 in one dimension: the Pareto set is [0, 2]."""
    return np.column_stack([x[:, 0] ** 2, (x[:, 0] - 2.0) ** 2])


def _run(name, fn, dim, budget, seed, params=None, lower=-5.12, upper=5.12, n_objectives=1):
    lo, hi = np.full(dim, lower), np.full(dim, upper)
    rng = np.random.default_rng(seed)
    opt = CLASSES[name](lo, hi, budget, rng, params, n_objectives=n_objectives)
    asked = 0
    while not opt.done:
        x = opt.ask()
        assert np.all(x >= lo) and np.all(x <= hi)
        asked += len(x)
        opt.tell(x, fn(x))
    return opt, asked


RUNS = [("ga", sphere, 1), ("pso", sphere, 1), ("ga", two_parabolas, 2)]


@pytest.mark.parametrize(("name", "fn", "m"), RUNS)
@pytest.mark.parametrize("budget", [40, 41, 97, 1000])
def test_budget_is_spent_exactly_inside_the_bounds(name, fn, m, budget) -> None:
    opt, asked = _run(name, fn, 3 if m == 1 else 1, budget, seed=0, n_objectives=m)
    assert asked == opt.evaluations == budget
    assert len(opt.x) == 40


@pytest.mark.parametrize(("name", "fn", "m"), RUNS)
def test_same_seed_same_result(name, fn, m) -> None:
    dim = 3 if m == 1 else 1
    a, b, c = (_run(name, fn, dim, 500, seed=s, n_objectives=m)[0] for s in (7, 7, 8))
    np.testing.assert_array_equal(a.x, b.x)
    if m > 1:
        np.testing.assert_array_equal(a.front.x, b.front.x)
    else:
        np.testing.assert_array_equal(a.best.x, b.best.x)
    assert not np.array_equal(a.x, c.x)


@pytest.mark.parametrize(("name", "fn", "m"), RUNS)
def test_nonfinite_objective_survives(name, fn, m) -> None:
    def nasty(x):
        f = fn(x)
        f[::3] = np.nan
        f[1::7] = np.inf
        return f

    opt, _ = _run(name, nasty, 2 if m == 1 else 1, 600, seed=2, n_objectives=m)
    assert opt.nonfinite > 0
    if m == 1:
        assert np.isfinite(opt.best.f)
        assert opt.best.f == pytest.approx(fn(opt.best.x[None, :])[0])
    else:
        assert len(opt.front.x) > 0 and np.all(np.isfinite(opt.front.f))


def test_ga_elite_never_lost() -> None:
    lo, hi = np.full(3, -5.0), np.full(3, 5.0)
    opt = GeneticAlgorithm(lo, hi, 400, np.random.default_rng(3), {"elite": 1})
    history = []
    while not opt.done:
        x = opt.ask()
        assert len(x) == (40 if opt.generation == 0 and len(opt.x) == 0 else min(39, opt.remaining))
        opt.tell(x, rastrigin(x))
        history.append(opt.fitness[0])
        assert opt.fitness[0] == opt.best.f
    assert all(np.diff(history) <= 0)


@pytest.mark.parametrize("name", ["ga", "pso"])
def test_converges_on_5d_sphere(name) -> None:
    errors = [_run(name, sphere, 5, 5000, seed=s)[0].best.f for s in range(5)]
    assert np.median(errors) < 1e-3


def test_pso_constriction_form_matches_inertia_form() -> None:
    """w = 1, c = 2.05 with constriction is the default swarm up to rounding of 0.7298/1.49618."""
    params = {"constriction": True, "w": 1.0, "c1": 2.05, "c2": 2.05}
    opt, _ = _run("pso", sphere, 5, 3000, seed=0, params=params)
    assert opt.chi == pytest.approx(0.7298, abs=1e-4) and opt.best.f < 1e-3


def test_ga_two_objectives_finds_the_pareto_set() -> None:
    for seed in (0, 1):
        opt, _ = _run("ga", two_parabolas, 1, 1000, seed, lower=-5.0, upper=5.0, n_objectives=2)
        x = opt.front.x[:, 0]
        assert len(x) > 400  # random search would keep about 200 of 1000 points
        assert np.mean((x >= 0) & (x <= 2)) > 0.95
        assert np.mean((opt.x[:, 0] >= 0) & (opt.x[:, 0] <= 2)) > 0.9  # the population converged
        assert x.min() < 0.05 and x.max() > 1.95  # spread over the whole set
        assert opt.population_fitness.shape == (40, 2)
        with pytest.raises(ProtocolError, match="use front"):
            _ = opt.best


def test_pso_is_single_objective() -> None:
    with pytest.raises(ValueError, match="single-objective"):
        ParticleSwarm(np.zeros(1), np.ones(1), 100, np.random.default_rng(0), n_objectives=2)


def test_default_mutation_probability_is_one_over_d() -> None:
    opt = GeneticAlgorithm(np.zeros(8), np.ones(8), 100, np.random.default_rng(0))
    assert opt.mutation_prob == pytest.approx(1 / 8)
    assert GeneticAlgorithm(np.zeros(8), np.ones(8), 100, np.random.default_rng(0),
                            {"mutation_prob": 0.5}).mutation_prob == 0.5


@pytest.mark.parametrize(
    ("name", "params", "message"),
    [
        ("ga", {"population": 1}, "population must be >= 2"),
        ("ga", {"crossover_prob": 1.5}, "crossover_prob must be in"),
        ("ga", {"crossover_var_prob": 0.0}, "crossover_var_prob must be in"),
        ("ga", {"eta_c": -1.0}, "eta_c must be"),
        ("ga", {"eta_m": float("nan")}, "eta_m must be"),
        ("ga", {"mutation_prob": -0.1}, "mutation_prob must be in"),
        ("ga", {"elite": 40}, r"elite must be in \[0, population - 1\]"),
        ("ga", {"elite": -1}, "elite must be in"),
        ("ga", {"elite": 1.5}, "ga.elite must be int"),
        ("ga", {"sigma": 1.0}, "no parameter 'sigma'"),
        ("pso", {"w": 1.2}, "w must be in"),
        ("pso", {"c1": -1.0}, "c1 must be"),
        ("pso", {"c1": 0.0, "c2": 0.0}, "c1 \\+ c2 must be > 0"),
        ("pso", {"constriction": True}, "constriction needs phi = c1 \\+ c2 > 4"),
        ("pso", {"v_max_fraction": 0.0}, "v_max_fraction must be in"),
        ("pso", {"constriction": "yes"}, "pso.constriction must be bool"),
    ],
)
def test_invalid_parameters(name, params, message) -> None:
    with pytest.raises(ValueError, match=message):
        CLASSES[name](np.zeros(2), np.ones(2), 100, np.random.default_rng(0), params)


def test_params_dataclasses_defaults() -> None:
    assert GAParams() == GAParams(40, 0.9, 0.5, 15.0, None, 20.0, 2)
    assert PSOParams() == PSOParams(40, 0.7298, 1.49618, 1.49618, False, 0.2)
