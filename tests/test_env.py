"""The function tasks as gymnasium environments."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tcbench  # noqa: F401  (registers the envs)
from tcbench.tasks import FUNCTIONS, BudgetExceededError, FunctionEnv, env_id


@pytest.mark.parametrize("key", sorted(FUNCTIONS))
def test_check_env_passes(key: str) -> None:
    for shift in (False, True):
        env = gym.make(env_id(key), dim=3, shift=shift)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            check_env(env.unwrapped)


def test_make_without_import_prefix() -> None:
    env = gym.make("tcbench:tcbench/Rastrigin-v0", dim=4)
    assert env.unwrapped.dim == 4


def test_step_single_and_batch() -> None:
    env = FunctionEnv("sphere", dim=2, budget=5)
    env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(np.array([1.0, 2.0]))
    assert obs.shape == (1,) and obs[0] == 5.0 and reward == -5.0
    assert not terminated and not truncated and info["evaluations"] == 1
    obs, reward, _, truncated, info = env.step(np.array([[0.0, 1.0], [0.0, 0.5]]))
    np.testing.assert_allclose(obs, [1.0, 0.25])
    np.testing.assert_allclose(reward, [-1.0, -0.25])
    assert info["best_f"] == 0.25 and info["evaluations"] == 3 and not truncated
    with pytest.raises(BudgetExceededError, match="only 2 of the budget of 5"):
        env.step(np.zeros((3, 2)))
    *_, truncated, info = env.step(np.zeros((2, 2)))
    assert truncated and info["target_hit_at"] == 4


def test_shift_moves_optimum_by_seed() -> None:
    env = FunctionEnv("rastrigin", dim=3, shift=True)
    env.reset(seed=1)
    a = env.x_opt.copy()
    env.reset(seed=1)
    np.testing.assert_array_equal(env.x_opt, a)
    assert np.all(np.abs(a) > 0) and np.all(np.abs(a) <= 0.4 * 5.12 + 1e-12)
    assert env.evaluate(a[None, :])[0] == pytest.approx(0.0, abs=1e-12)
    assert env.evaluate(np.zeros((1, 3)))[0] > 0.0
    env.reset(seed=2)
    assert not np.allclose(env.x_opt, a)


@pytest.mark.parametrize("key", sorted(FUNCTIONS))
def test_shifted_optimum_is_global_minimum(key: str) -> None:
    f = FUNCTIONS[key]
    env = FunctionEnv(key, dim=2, shift=True)
    rng = np.random.default_rng(5)
    for seed in range(5):
        env.reset(seed=seed)
        assert np.all(env.x_opt >= env.lower) and np.all(env.x_opt <= env.upper)
        assert env.evaluate(env.x_opt[None, :])[0] == pytest.approx(env.f_opt, abs=1e-9)
        x = rng.uniform(f.lower, f.upper, size=(20000, 2))
        assert env.evaluate(x).min() >= env.f_opt - 1e-9


def test_nonfinite_values_counted_as_worst(monkeypatch) -> None:
    env = FunctionEnv("sphere", dim=1, budget=10)
    env.reset(seed=0)
    monkeypatch.setattr(env, "evaluate", lambda x: np.array([np.nan, -np.inf, 4.0]))
    _, _, _, _, info = env.step(np.zeros((3, 1)))
    assert info["nonfinite"] == 2 and info["best_f"] == 4.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"dim": 0}, "dim must be an integer >= 1"),
        ({"function": "schaffer", "dim": 1}, "dim must be an integer >= 2"),
        ({"budget": 0}, "budget must be a positive integer"),
        ({"target_precision": -1.0}, "target_precision"),
        ({"lower": 1.0, "upper": 2.0}, "exclude the optimum"),
        ({"function": "nope"}, "unknown function 'nope'"),
    ],
)
def test_invalid_parameters(kwargs, message) -> None:
    with pytest.raises((ValueError, KeyError), match=message):
        FunctionEnv(**{"function": "sphere", **kwargs})


def test_wrong_action_shape() -> None:
    env = FunctionEnv("sphere", dim=2)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(2,\) or \(n, 2\)"):
        env.step(np.zeros(3))
