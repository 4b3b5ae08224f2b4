"""Multi-objective tasks: ZDT1-3 and DTLZ2, their true fronts, hypervolume/IGD, and the env."""

from __future__ import annotations

import math
import warnings

import gymnasium as gym
import numpy as np
import pytest
import yaml
from gymnasium.utils.env_checker import check_env

from tcbench.config_dir import conf_dir
from tcbench.metrics.multiobjective import hypervolume, igd, igd_plus
from tcbench.pareto import dominates, nondominated
from tcbench.tasks.function_env import BudgetExceededError
from tcbench.tasks import register_specs
from tcbench.tasks.mo_env import MultiObjectiveEnv, mo_env_id
from tcbench.tasks.multiobjective import (
    PROBLEMS,
    dtlz2,
    get_problem,
    zdt1,
    zdt2,
    zdt3,
    zdt3_front_hypervolume,
    zdt3_front_intervals,
)

IDS = ["tcbench/ZDT1-v0", "tcbench/ZDT2-v0", "tcbench/ZDT3-v0", "tcbench/DTLZ2-v0"]
CONF = conf_dir() / "task"


def zdt3_curve(t):
    return 1.0 - np.sqrt(t) - t * np.sin(10.0 * np.pi * t)


def mc_hypervolume(f: np.ndarray, ref: np.ndarray, n: int, seed: int) -> tuple[float, float]:
    """Monte Carlo hypervolume in the box [min f, ref] and its standard error."""
    rng = np.random.default_rng(seed)
    lo = f.min(axis=0)
    box = float(np.prod(ref - lo))
    s = rng.uniform(lo, ref, size=(n, f.shape[1]))
    hit = np.zeros(n, dtype=bool)
    for p in f:
        hit |= np.all(s >= p, axis=1)
    q = hit.mean()
    return box * q, box * math.sqrt(q * (1 - q) / n)


def grid_hypervolume(f: np.ndarray, ref: np.ndarray) -> float:
    """Exact hypervolume by brute force: the distinct coordinates cut the box into cells, a
    cell counts if some point dominates its lower corner (independent of the sweeps)."""
    axes = [np.unique(np.append(f[:, k], ref[k])) for k in range(f.shape[1])]
    corners = np.stack(np.meshgrid(*[a[:-1] for a in axes], indexing="ij"), axis=-1)
    sizes = np.prod(np.stack(np.meshgrid(*[np.diff(a) for a in axes], indexing="ij")), axis=0)
    covered = np.zeros(corners.shape[:-1], dtype=bool)
    for p in f:
        covered |= np.all(corners >= p, axis=-1)
    return float(np.sum(sizes[covered]))


# -- problems ------------------------------------------------------------------------------


def test_registry_defaults() -> None:
    assert sorted(PROBLEMS) == ["dtlz2", "zdt1", "zdt2", "zdt3"]
    for key in ("zdt1", "zdt2", "zdt3"):
        p = PROBLEMS[key]
        assert (p.n_objectives, p.default_dim, p.ref_point) == (2, 30, (1.1, 1.1))
    p = PROBLEMS["dtlz2"]
    assert (p.n_objectives, p.default_dim, p.ref_point) == (3, 12, (1.1, 1.1, 1.1))
    assert get_problem("ZDT1") is PROBLEMS["zdt1"]
    with pytest.raises(KeyError, match="unknown problem 'zdt9'; known: dtlz2, zdt1"):
        get_problem("zdt9")


def test_zdt_hand_values() -> None:
    # f1 = 0.25, x2 = 1/9 so g = 2; sin(10 pi 0.25) = 1.
    x = np.array([[0.25, 1.0 / 9.0]])
    np.testing.assert_allclose(zdt1(x), [[0.25, 2.0 - math.sqrt(0.5)]])
    np.testing.assert_allclose(zdt2(x), [[0.25, 1.96875]])
    np.testing.assert_allclose(zdt3(x), [[0.25, 2.0 - math.sqrt(0.5) - 0.25]])
    # all ones, d = 30: g = 10
    np.testing.assert_allclose(zdt1(np.ones((1, 30))), [[1.0, 10.0 * (1.0 - math.sqrt(0.1))]])


@pytest.mark.parametrize(
    ("fn", "curve"),
    [(zdt1, lambda t: 1 - np.sqrt(t)), (zdt2, lambda t: 1 - t**2), (zdt3, zdt3_curve)],
)
def test_zdt_on_pareto_set_is_on_curve_and_random_points_above(fn, curve) -> None:
    rng = np.random.default_rng(0)
    x = np.zeros((200, 30))
    x[:, 0] = rng.uniform(size=200)
    f = fn(x)
    np.testing.assert_allclose(f[:, 0], x[:, 0])
    np.testing.assert_allclose(f[:, 1], curve(x[:, 0]), atol=1e-12)
    y = rng.uniform(size=(500, 30))
    g = fn(y)
    assert np.all(g[:, 1] >= curve(g[:, 0]) - 1e-12)


def test_dtlz2_hand_values_and_sphere() -> None:
    x = np.full((1, 12), 0.5)
    np.testing.assert_allclose(dtlz2(x), [[0.5, 0.5, math.sqrt(0.5)]])
    x = np.zeros((1, 12))
    x[0, 2:] = 0.5
    np.testing.assert_allclose(dtlz2(x), [[1.0, 0.0, 0.0]], atol=1e-15)
    x[0, 1] = 1.0
    np.testing.assert_allclose(dtlz2(x), [[0.0, 1.0, 0.0]], atol=1e-15)
    x[0, 0] = 1.0
    np.testing.assert_allclose(dtlz2(x), [[0.0, 0.0, 1.0]], atol=1e-15)
    x = np.ones((1, 12))  # g = 10 * 0.25
    np.testing.assert_allclose(np.linalg.norm(dtlz2(x)), 3.5)
    rng = np.random.default_rng(1)
    x = rng.uniform(size=(300, 12))
    g = np.sum((x[:, 2:] - 0.5) ** 2, axis=1)
    np.testing.assert_allclose(np.linalg.norm(dtlz2(x), axis=1), 1 + g)
    x[:, 2:] = 0.5
    f = dtlz2(x)
    np.testing.assert_allclose(np.linalg.norm(f, axis=1), 1.0)
    assert np.all(f >= 0)
    # 4 objectives: still on the unit sphere on the Pareto set
    x4 = rng.uniform(size=(50, 13))
    x4[:, 3:] = 0.5
    np.testing.assert_allclose(np.linalg.norm(dtlz2(x4, 4), axis=1), 1.0)


def test_zdt3_front_intervals_match_literature() -> None:
    want = [
        (0.0, 0.0830015349), (0.1822287280, 0.2577623634), (0.4093136748, 0.4538821041),
        (0.6183967944, 0.6525117038), (0.8233317983, 0.8518328654),
    ]
    np.testing.assert_allclose(zdt3_front_intervals(), want, atol=1e-9)


@pytest.mark.parametrize("key", sorted(PROBLEMS))
def test_true_front_nondominated_on_curve_and_mapped_by_pareto_set(key: str) -> None:
    p = PROBLEMS[key]
    f = p.true_front(400)
    assert f.shape == (400, p.n_objectives)
    assert nondominated(f).all()
    if key == "zdt1":
        np.testing.assert_allclose(f[:, 1], 1 - np.sqrt(f[:, 0]))
    elif key == "zdt2":
        np.testing.assert_allclose(f[:, 1], 1 - f[:, 0] ** 2)
    elif key == "zdt3":
        np.testing.assert_allclose(f[:, 1], zdt3_curve(f[:, 0]))
    else:
        np.testing.assert_allclose(np.linalg.norm(f, axis=1), 1.0)
        assert np.all(f >= 0)
    if key.startswith("zdt"):
        assert f[0, 0] == 0.0 and f[-1, 0] == pytest.approx(
            1.0 if key != "zdt3" else zdt3_front_intervals()[-1][1]
        )
    x = p.pareto_set(400)
    assert x.shape == (400, p.default_dim)
    assert np.all((x >= 0) & (x <= 1))
    np.testing.assert_allclose(p.evaluate(x), f, atol=1e-12)
    with pytest.raises(ValueError, match="n_points"):
        p.true_front(0)


def test_zdt3_front_not_dominated_by_the_curve() -> None:
    """No point of the whole curve (g = 1) dominates a sampled front point."""
    f = PROBLEMS["zdt3"].true_front(3000)
    t = np.linspace(0.0, 1.0, 400_001)
    best_left = np.minimum.accumulate(zdt3_curve(t))
    # lowest curve value at f1 <= the front point's f1 (grid points left of it)
    j = np.searchsorted(t, f[:, 0], side="right") - 1
    assert np.all(f[:, 1] <= best_left[j] + 1e-12)
    # and the pieces really are dominated between them: mid-gap curve points are
    t_gap = np.array([0.13, 0.33, 0.53, 0.73, 0.93])
    gap = np.stack([t_gap, zdt3_curve(t_gap)], axis=1)
    assert dominates(f, gap).any(axis=0).all()


def test_front_hypervolumes_recorded() -> None:
    assert PROBLEMS["zdt1"].front_hypervolume == pytest.approx(1.21 - 1 / 3, rel=1e-15)
    assert PROBLEMS["zdt2"].front_hypervolume == pytest.approx(1.21 - 2 / 3, rel=1e-15)
    assert PROBLEMS["zdt3"].front_hypervolume == pytest.approx(zdt3_front_hypervolume(), abs=1e-12)
    assert PROBLEMS["dtlz2"].front_hypervolume == pytest.approx(1.331 - math.pi / 6, rel=1e-15)
    # Numerically: the exact hypervolume of dense samples approaches the recorded value from below.
    for key, n, tol in (("zdt1", 20000, 1e-4), ("zdt2", 20000, 1e-4), ("zdt3", 20000, 1e-4),
                        ("dtlz2", 2500, 0.02)):
        p = PROBLEMS[key]
        coarse = hypervolume(p.true_front(n // 10), p.ref_point)
        fine = hypervolume(p.true_front(n), p.ref_point)
        assert coarse < fine <= p.front_hypervolume
        assert fine == pytest.approx(p.front_hypervolume, rel=tol)
    # ZDT3 independently: midpoint rule on the running minimum of the curve over [0, 1.1].
    t = (np.arange(1_100_000) + 0.5) / 1e6
    env = np.minimum.accumulate(zdt3_curve(np.minimum(t, 1.0)))
    # past the last piece the envelope is flat (the curve never goes lower)
    assert np.sum(1.1 - env) * 1e-6 == pytest.approx(zdt3_front_hypervolume(), abs=1e-6)


# -- indicators ----------------------------------------------------------------------------


def test_hypervolume_2d_hand_cases() -> None:
    stair = np.array([[1.0, 3.0], [2.0, 2.0], [3.0, 1.0]])
    ref = np.array([4.0, 4.0])
    assert hypervolume(stair, ref) == pytest.approx(6.0)
    assert hypervolume(stair[::-1], ref) == pytest.approx(6.0)
    noisy = np.vstack([stair, [[2.5, 2.5], [2.0, 2.0], [3.5, 3.0], [5.0, 0.0], [4.0, 0.5]]])
    assert hypervolume(noisy, ref) == pytest.approx(6.0)  # dominated, duplicate, outside ref
    assert hypervolume(np.array([0.0, 0.0]), [1.0, 2.0]) == pytest.approx(2.0)
    assert hypervolume(np.empty((0, 2)), ref) == 0.0
    assert hypervolume(np.array([[np.nan, 0.0], [1.0, np.inf]]), ref) == 0.0
    with pytest.raises(ValueError, match="objectives"):
        hypervolume(stair, [1.0, 1.0, 1.0])


def test_hypervolume_3d_hand_cases() -> None:
    assert hypervolume([[0.0, 0.0, 0.0]], [1.0, 2.0, 3.0]) == pytest.approx(6.0)
    two = np.array([[0.0, 0.0, 1.0], [1.0, 1.0, 0.0]])
    assert hypervolume(two, [2.0, 2.0, 2.0]) == pytest.approx(4.0 + 2.0 - 1.0)
    three = np.vstack([two, [[1.0, 0.0, 1.5], [0.5, 0.5, 1.0]]])  # dominated, and one adding 0
    assert hypervolume(three, [2.0, 2.0, 2.0]) == pytest.approx(5.0)
    # objectives permuted: same volume
    for perm in ([1, 2, 0], [2, 0, 1], [0, 2, 1]):
        assert hypervolume(two[:, perm], [2.0, 2.0, 2.0]) == pytest.approx(5.0)
    # constant third objective: 2-D area times depth
    stair = np.array([[1.0, 3.0, 0.5], [2.0, 2.0, 0.5], [3.0, 1.0, 0.5]])
    assert hypervolume(stair, [4.0, 4.0, 2.0]) == pytest.approx(6.0 * 1.5)


@pytest.mark.parametrize(("seed", "n"), [(0, 30), (1, 60)])
def test_hypervolume_3d_matches_monte_carlo(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    # points near a sphere octant, so many are mutually non-dominated
    u = rng.normal(size=(n, 3))
    f = np.abs(u) / np.linalg.norm(u, axis=1, keepdims=True) * rng.uniform(1, 1.2, (n, 1))
    ref = np.array([1.3, 1.3, 1.3])
    hv = hypervolume(f, ref)
    est, se = mc_hypervolume(f, ref, 300_000, seed + 10)
    assert abs(hv - est) < 4 * se
    assert hv == pytest.approx(grid_hypervolume(f, ref), rel=1e-12)
    assert hypervolume(f[rng.permutation(n)], ref) == pytest.approx(hv, rel=1e-12)


def test_hypervolume_4d_matches_monte_carlo() -> None:
    rng = np.random.default_rng(7)
    f = rng.uniform(size=(12, 4))
    ref = np.ones(4)
    est, se = mc_hypervolume(f, ref, 200_000, 8)
    assert abs(hypervolume(f, ref) - est) < 4 * se
    assert hypervolume(f, ref) == pytest.approx(grid_hypervolume(f, ref), rel=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_hypervolume_3d_exact_with_ties(seed: int) -> None:
    """Coordinates on a coarse grid: many ties in every objective, duplicates and dominated
    points; the sweep must still match the brute-force cell count."""
    rng = np.random.default_rng(100 + seed)
    f = rng.integers(0, 6, size=(40, 3)).astype(float) / 5
    ref = np.array([1.2, 1.1, 1.0])  # some points lie on the reference's faces: ignored
    inside = np.all(f < ref, axis=1)
    assert hypervolume(f, ref) == pytest.approx(grid_hypervolume(f[inside], ref), rel=1e-12)
    g = rng.integers(0, 6, size=(30, 2)).astype(float) / 5
    assert hypervolume(g, [1.1, 1.1]) == pytest.approx(grid_hypervolume(g, np.array([1.1, 1.1])))


def test_igd_and_igd_plus() -> None:
    front = PROBLEMS["zdt1"].true_front(100)
    assert igd(front, front) == 0.0 and igd_plus(front, front) == 0.0
    ref = np.array([[0.0, 1.0], [1.0, 0.0]])
    assert igd([[0.0, 0.0]], ref) == pytest.approx(1.0)
    assert igd([[0.0, 2.0]], ref) == pytest.approx((1 + math.sqrt(5)) / 2)
    assert igd([[0.0, 2.0], [1.0, 0.0]], ref) == pytest.approx(0.5)
    assert igd_plus([[0.0, 0.0]], ref) == 0.0  # dominates every reference point
    assert igd_plus([[0.0, 2.0]], ref) == pytest.approx(1.5)
    rng = np.random.default_rng(3)
    a, z = rng.uniform(size=(300, 3)), PROBLEMS["dtlz2"].true_front(500)
    assert igd(a, z, chunk_elements=100) == pytest.approx(igd(a, z), rel=1e-12)
    assert igd_plus(a, z, chunk_elements=7) == pytest.approx(igd_plus(a, z), rel=1e-12)
    d = np.linalg.norm(z[:, None, :] - a[None, :, :], axis=2).min(axis=1).mean()
    assert igd(a, z) == pytest.approx(d, rel=1e-12)
    assert igd(np.empty((0, 3)), z) == math.inf
    with pytest.raises(ValueError, match="objectives"):
        igd(a[:, :2], z)


# -- environment ---------------------------------------------------------------------------


@pytest.fixture(scope="module", autouse=True)
def _registered() -> None:
    register_specs()
    register_specs()  # idempotent


def test_ids() -> None:
    assert [mo_env_id(k) for k in ("zdt1", "zdt2", "zdt3", "dtlz2")] == IDS
    assert all(i in gym.registry for i in IDS)


@pytest.mark.parametrize("eid", IDS)
def test_check_env_passes(eid: str) -> None:
    env = gym.make(eid)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(env.unwrapped)
    u = env.unwrapped
    p = u.problem
    assert u.dim == p.default_dim and env.observation_space.shape == (p.n_objectives,)
    assert gym.make(eid, dim=5, budget=7).unwrapped.dim == 5


def test_step_single_and_batch() -> None:
    env = MultiObjectiveEnv("zdt1", dim=2, budget=5)
    obs, info = env.reset(seed=0)
    assert obs.shape == (2,) and info["evaluations"] == 0 and info["hypervolume"] == 0.0
    assert info["front_f"].shape == (0, 2) and info["front_x"].shape == (0, 2)
    obs, reward, terminated, truncated, info = env.step(np.array([0.25, 1.0 / 9.0]))
    np.testing.assert_allclose(obs, [0.25, 2.0 - math.sqrt(0.5)])
    assert isinstance(reward, float) and reward == pytest.approx(-obs.sum())
    assert not terminated and not truncated and info["evaluations"] == 1
    assert info["n_objectives"] == 2 and info["budget"] == 5
    np.testing.assert_array_equal(info["lower"], [0, 0])
    np.testing.assert_array_equal(info["upper"], [1, 1])
    assert info["hypervolume"] == 0.0  # f2 > 1.1: outside the reference box
    batch = np.array([[0.0, 0.0], [1.0, 0.0]])
    obs, reward, _, truncated, info = env.step(batch)
    np.testing.assert_allclose(obs, [[0.0, 1.0], [1.0, 0.0]])
    np.testing.assert_allclose(reward, [-1.0, -1.0])
    assert obs.shape == (2, 2) and reward.shape == (2,) and not truncated
    assert info["front_f"].shape == (2, 2)  # the first point is dominated by (0, 1)
    assert info["hypervolume"] == pytest.approx(1.1 * 1.1 - 1.0)
    with pytest.raises(BudgetExceededError, match="only 2 of the budget of 5"):
        env.step(np.zeros((3, 2)))
    assert env.evaluations == 3
    *_, truncated, info = env.step(np.full((2, 2), 0.5))
    assert truncated and info["evaluations"] == 5
    with pytest.raises(BudgetExceededError):
        env.step(np.zeros(2))
    _, info = env.reset()
    assert info["evaluations"] == 0 and info["front_f"].shape == (0, 2)


def test_invalid_actions_and_parameters() -> None:
    env = MultiObjectiveEnv("dtlz2")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(12,\) or \(n, 12\)"):
        env.step(np.zeros(3))
    with pytest.raises(ValueError, match="outside the domain"):
        env.step(np.full(12, 1.5))
    with pytest.raises(ValueError, match="outside the domain"):
        env.step(np.full(12, np.nan))
    assert env.evaluations == 0
    for kwargs, message in (
        ({"dim": 1}, "dim must be an integer >= 2"),
        ({"budget": 0}, "budget must be a positive integer"),
        ({"shift": True}, "shift is not supported"),
        ({"lower": -1.0}, "lower must be null or 0.0"),
        ({"target_precision": 0.0}, "target_precision"),
        ({"function": "nope"}, "unknown problem 'nope'"),
    ):
        with pytest.raises((ValueError, KeyError), match=message):
            MultiObjectiveEnv(**{"function": "zdt1", **kwargs})
    with pytest.raises(ValueError, match="dim must be an integer >= 3"):
        MultiObjectiveEnv("dtlz2", dim=2)
    MultiObjectiveEnv("zdt1", lower=0.0, upper=1.0, target_precision=1e-3)  # accepted


@pytest.mark.parametrize("key", sorted(PROBLEMS))
def test_front_and_hypervolume_grow_monotonically(key: str) -> None:
    p = PROBLEMS[key]
    env = MultiObjectiveEnv(key, dim=p.min_dim + 2, budget=2000)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    prev_f, prev_hv, seen_x, seen_f = None, 0.0, [], []
    for i in range(40):
        # random points biased towards the Pareto set so the hypervolume becomes positive
        x = rng.uniform(size=(1 + i % 7, env.dim))
        x[:, p.n_objectives - 1 :] = (
            0.5 + (x[:, p.n_objectives - 1 :] - 0.5) * 0.2 if key == "dtlz2"
            else x[:, 1:] * 0.02
        )
        obs, *_, info = env.step(x[0] if i % 5 == 0 else x)
        seen_x.append(x[:1] if i % 5 == 0 else x)
        seen_f.append(np.atleast_2d(obs))
        front = info["front_f"]
        assert info["hypervolume"] >= prev_hv
        assert info["hypervolume_ratio"] == pytest.approx(info["hypervolume"] / p.front_hypervolume)
        assert info["hypervolume_ratio"] <= 1.0
        assert nondominated(front).all()
        np.testing.assert_allclose(p.evaluate(info["front_x"]), front)
        if prev_f is not None:  # every earlier front point is matched or dominated
            weak = np.all(front[:, None, :] <= prev_f[None, :, :], axis=2).any(axis=0)
            assert weak.all()
        prev_f, prev_hv = front, info["hypervolume"]
    assert prev_hv > 0.0
    all_f = np.concatenate(seen_f)
    assert info["evaluations"] == all_f.shape[0]
    keep = nondominated(all_f)
    assert sorted(map(tuple, all_f[keep])) == sorted(map(tuple, front))
    assert info["hypervolume"] == pytest.approx(hypervolume(all_f, p.ref_point), rel=1e-12)


@pytest.mark.parametrize("key", sorted(PROBLEMS))
def test_pareto_set_batch_nearly_fills_the_true_hypervolume(key: str) -> None:
    p = PROBLEMS[key]
    env = MultiObjectiveEnv(key, budget=600)
    env.reset(seed=0)
    x = p.pareto_set(600)
    *_, truncated, info = env.step(x)  # merged into the archive in chunks
    assert truncated and info["front_f"].shape[0] == 600
    assert 0.9 < info["hypervolume_ratio"] <= 1.0
    assert igd(info["front_f"], p.true_front(600)) < 1e-12


@pytest.mark.parametrize("key", sorted(PROBLEMS))
def test_task_yaml_builds_the_env(key: str) -> None:
    cfg = yaml.safe_load((CONF / f"{key}.yaml").read_text())
    assert cfg["name"] == key and cfg["dim"] == PROBLEMS[key].default_dim
    task = {k: v for k, v in cfg.items() if k != "name"}
    env = MultiObjectiveEnv(function=cfg["name"], budget=10, **task)
    assert env.dim == cfg["dim"]
