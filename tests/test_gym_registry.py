"""Every environment registered under ``tcbench/`` is made as registered and is a standard env.

For each id in ``gymnasium.registry`` under the ``tcbench/`` namespace: ``gymnasium.make(id)``
with the registered defaults, gymnasium's ``check_env`` on the unwrapped env, and determinism of
a seeded episode (same seed, same observations).

``check_env`` runs with every warning turned into an error except two recommendations that do
not apply to black-box search tasks, listed in :data:`NOT_APPLICABLE` with the reason.

One id is too slow to reset with its defaults for the default test run:
``tcbench/Gyro-DriftNoise-v0`` simulates two 14 h oven runs at 10 Hz and decomposes the training
record with VMD on its first reset (about 25-60 s, most of it VMD on ~500 000 samples; later
resets reuse the decomposition). The default run makes it with its defaults and checks its
spaces, and runs ``check_env`` and the determinism test on the same env with shorter simulated
runs (:data:`CHEAP`: 1 Hz, 10 min soaks, the same code path); the tests marked ``slow`` run
both on the registered defaults themselves.
"""

from __future__ import annotations

import re
import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tcbench  # noqa: F401  (registers the envs)
from tcbench.tasks.ids import ACCEL_CHAMBER_ID
from tcbench.tasks import BBOB_ID, FUNCTIONS, GYRO_ENV_IDS, MSRA_ENV_IDS, PROBLEMS, env_id, mo_env_id

IDS = sorted(i for i in gym.registry if i.startswith("tcbench/"))

# Keyword arguments that keep an expensive env's code path but make its episode cheap.
CHEAP: dict[str, dict[str, Any]] = {"tcbench/Gyro-DriftNoise-v0": {"sample_rate_hz": 1.0, "hold_s": 600.0}}

# check_env's warnings that are recommendations for RL tasks, not faults of these tasks:
NOT_APPLICABLE = (
    # The action space is the search domain (a test function's documented bounds, a learner's
    # initial-weight range, VMD's [4, 12] x [1000, 10000]); rescaling it to [-1, 1] would change
    # the published problems and the optimisers' step sizes.
    r"For Box action spaces, we recommend using a symmetric and normalized space",
    # Observations are objective values (unbounded for the test functions, >= 0 for errors and
    # entropies) and the reset observation is +inf, "nothing evaluated yet".
    r"A Box observation space (minimum|maximum) value is (-)?infinity",
)


def _params(ids: list[str], slow_when_default: bool = False) -> list[Any]:
    return [pytest.param(i, marks=pytest.mark.slow) if slow_when_default and i in CHEAP else i for i in ids]


def _strict_check(env: gym.Env) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for pattern in NOT_APPLICABLE:
            warnings.filterwarnings("ignore", message=f".*{pattern}")
        check_env(env)


def _episode(env: gym.Env, seed: int) -> tuple[np.ndarray, np.ndarray, Any]:
    """Observation of a reset with ``seed`` and of a first step with an action drawn from it."""
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    action = env.action_space.sample()
    step_obs, reward, _, _, _ = env.step(action)
    return np.asarray(obs), np.asarray(step_obs), reward


def _assert_deterministic(make: Any) -> None:
    env = make()
    first = _episode(env, 123)
    again = _episode(env, 123)  # the same env reset again
    fresh = _episode(make(), 123)  # a new env
    for other in (again, fresh):
        for a, b in zip(first, other, strict=True):
            np.testing.assert_array_equal(a, b)
    other_seed = _episode(env, 124)
    assert not np.array_equal(first[1], other_seed[1]) or env.action_space.shape == (0,)


def test_registry_holds_every_task_and_nothing_else() -> None:
    expected = ({env_id(f) for f in FUNCTIONS} | {mo_env_id(p) for p in PROBLEMS} | set(MSRA_ENV_IDS.values())
                | set(GYRO_ENV_IDS.values()) | {BBOB_ID, ACCEL_CHAMBER_ID})
    assert set(IDS) == expected


@pytest.mark.parametrize("env_id", IDS)
def test_made_with_defaults(env_id: str) -> None:
    env = gym.make(env_id)
    assert env.spec is not None and env.spec.id == env_id
    inner = env.unwrapped
    assert isinstance(inner, gym.Env)
    assert isinstance(inner.action_space, gym.spaces.Box) and isinstance(inner.observation_space, gym.spaces.Box)
    assert inner.action_space.shape == (inner.dim,)
    env.close()


@pytest.mark.parametrize("env_id", _params(IDS, slow_when_default=True))
def test_defaults_pass_check_env(env_id: str) -> None:
    _strict_check(gym.make(env_id).unwrapped)


@pytest.mark.parametrize("env_id", _params(IDS, slow_when_default=True))
def test_defaults_are_deterministic(env_id: str) -> None:
    _assert_deterministic(lambda: gym.make(env_id).unwrapped)


@pytest.mark.parametrize("env_id", sorted(CHEAP))
def test_cheap_variant_passes_check_env_and_is_deterministic(env_id: str) -> None:
    _strict_check(gym.make(env_id, **CHEAP[env_id]).unwrapped)
    _assert_deterministic(lambda: gym.make(env_id, **CHEAP[env_id]).unwrapped)


@pytest.mark.parametrize("env_id", IDS)
def test_unknown_keyword_is_named(env_id: str) -> None:
    with pytest.raises(TypeError, match="unexpected keyword argument 'no_such_parameter'"):
        gym.make(env_id, no_such_parameter=1)


BAD_VALUES = [
    ("tcbench/Rastrigin-v0", "dim", 0), ("tcbench/Rastrigin-v0", "dim", None), ("tcbench/Rastrigin-v0", "dim", "abc"),
    ("tcbench/Rastrigin-v0", "budget", 1.5), ("tcbench/Rastrigin-v0", "budget", "x"),
    ("tcbench/Rastrigin-v0", "lower", "x"), ("tcbench/Rastrigin-v0", "target_precision", None),
    ("tcbench/Rastrigin-v0", "function", "nope"),
    ("tcbench/ZDT1-v0", "dim", 0), ("tcbench/ZDT1-v0", "budget", None), ("tcbench/ZDT1-v0", "lower", "x"),
    ("tcbench/ZDT1-v0", "function", "nope"),
    ("tcbench/BBOB-v0", "function", 25), ("tcbench/BBOB-v0", "dim", "x"), ("tcbench/BBOB-v0", "instance", None),
    ("tcbench/BBOB-v0", "target_precision", "x"),
    ("tcbench/MSRA-FullTemp-v0", "task", "x"), ("tcbench/MSRA-FullTemp-v0", "learner", "nope"),
    ("tcbench/MSRA-FullTemp-v0", "n_train", -1), ("tcbench/MSRA-FullTemp-v0", "budget", None),
    ("tcbench/MSRA-FullTemp-v0", "device_seed", None), ("tcbench/MSRA-FullTemp-v0", "recordings_seed", "x"),
    ("tcbench/MSRA-FullTemp-v0", "rate_window_s", -1), ("tcbench/MSRA-FullTemp-v0", "train_on", "x"),
    ("tcbench/MSRA-ZeroBias-v0", "bias_form", "x"),
    ("tcbench/Gyro-DriftNoise-v0", "k", 0), ("tcbench/Gyro-DriftNoise-v0", "alpha", -1),
    ("tcbench/Gyro-DriftNoise-v0", "tfpf_window", 4), ("tcbench/Gyro-DriftNoise-v0", "learner", "nope"),
    ("tcbench/Gyro-DriftNoise-v0", "tuning_samples", 0), ("tcbench/Gyro-DriftNoise-v0", "tuner", "nope"),
    ("tcbench/Gyro-DriftNoise-v0", "tuning_budget", None), ("tcbench/Gyro-DriftNoise-v0", "hold_s", -1),
    ("tcbench/Gyro-DriftNoise-v0", "sample_rate_hz", None), ("tcbench/Gyro-DriftNoise-v0", "decomposition", "x"),
    ("tcbench/Gyro-DriftNoise-v0", "budget", None), ("tcbench/Gyro-DriftNoise-v0", "n_train", 0),
    ("tcbench/Gyro-DriftNoise-v0", "device_seed", "x"), ("tcbench/Gyro-DriftNoise-v0", "bandwidth_amplitude_dps", None),
    ("tcbench/Gyro-VMDTuning-v0", "tuning_samples", 0), ("tcbench/Gyro-VMDTuning-v0", "hold_s", -1),
    ("tcbench/Gyro-VMDTuning-v0", "sample_rate_hz", 0), ("tcbench/Gyro-VMDTuning-v0", "budget", None),
    ("tcbench/Gyro-VMDTuning-v0", "recordings_seed", -1),
]


@pytest.mark.parametrize(("env_id", "name", "value"), BAD_VALUES)
def test_invalid_value_is_refused_naming_the_parameter(env_id: str, name: str, value: Any) -> None:
    """A bad value raises ValueError (KeyError for an unknown function or learner name) whose
    message starts with the parameter's name, or names the unknown value with what is known."""
    with pytest.raises((ValueError, KeyError)) as info:
        gym.make(env_id, **{name: value})
    text = str(info.value).strip("\"'")
    named = re.match(rf"{name}\b", text) or (re.search(r"unknown .*; known: ", text) and repr(value) in text)
    assert named, f"{name}={value!r}: {text}"
