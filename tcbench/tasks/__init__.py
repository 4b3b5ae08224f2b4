"""Benchmark tasks as gymnasium environments, registered under the ``tcbench`` namespace."""

from __future__ import annotations

import gymnasium as gym

from tcbench.tasks.function_env import BudgetExceededError, FunctionEnv
from tcbench.tasks.functions import FUNCTIONS, ObjectiveFunction, get_function

ENV_VERSION = "v0"


def env_id(function_key: str) -> str:
    """Gymnasium id of a function task, e.g. ``tcbench/Rastrigin-v0``."""
    return f"tcbench/{function_key.capitalize()}-{ENV_VERSION}"


def register_envs() -> None:
    """Register every function task with gymnasium (idempotent)."""
    for key in FUNCTIONS:
        eid = env_id(key)
        if eid not in gym.registry:
            gym.register(
                id=eid,
                entry_point="tcbench.tasks.function_env:FunctionEnv",
                kwargs={"function": key},
                disable_env_checker=True,
            )


register_envs()

__all__ = [
    "FUNCTIONS",
    "BudgetExceededError",
    "FunctionEnv",
    "ObjectiveFunction",
    "env_id",
    "get_function",
    "register_envs",
]
