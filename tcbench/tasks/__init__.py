"""Benchmark tasks as gymnasium environments, registered under the ``tcbench`` namespace."""

from __future__ import annotations

from tcbench.tasks.function_env import BudgetExceededError, FunctionEnv
from tcbench.tasks.functions import FUNCTIONS, ObjectiveFunction, get_function
from tcbench.tasks.mo_env import MultiObjectiveEnv, mo_env_id, register_mo_envs
from tcbench.tasks.msra_env import ENV_IDS as MSRA_ENV_IDS
from tcbench.tasks.msra_env import MSRACompensationEnv
from tcbench.tasks.multiobjective import PROBLEMS
from tcbench.tasks.registration import register_tasks

ENV_VERSION = "v0"


def env_id(function_key: str) -> str:
    """Gymnasium id of a function task, e.g. ``tcbench/Rastrigin-v0``."""
    return f"tcbench/{function_key.capitalize()}-{ENV_VERSION}"


def register_envs() -> None:
    """Register every function task with gymnasium (idempotent)."""
    register_tasks(FUNCTIONS, env_id, "tcbench.tasks.function_env:FunctionEnv")


def register_msra_envs() -> None:
    """Register the MSRA compensation tasks (idempotent)."""
    register_tasks(MSRA_ENV_IDS, MSRA_ENV_IDS.__getitem__, "tcbench.tasks.msra_env:MSRACompensationEnv", "task")


def is_compensation(name: str) -> bool:
    """True for the sensor compensation tasks (``msra_fulltemp``, ``msra_zerobias``)."""
    return name.lower() in MSRA_ENV_IDS


def is_multiobjective(name: str) -> bool:
    """True for the multi-objective problems (ZDT1-3, DTLZ2)."""
    return name.lower() in PROBLEMS


def task_id(name: str) -> str:
    """Gymnasium id of any task by its config name (``rastrigin``, ``zdt1``, ...)."""
    if is_compensation(name):
        return MSRA_ENV_IDS[name.lower()]
    return mo_env_id(name) if is_multiobjective(name) else env_id(name)


def task_class(name: str) -> type[FunctionEnv] | type[MultiObjectiveEnv]:
    """The env class serving a task name."""
    return MultiObjectiveEnv if is_multiobjective(name) else FunctionEnv


register_envs()
register_mo_envs()
register_msra_envs()

__all__ = [
    "FUNCTIONS",
    "MSRA_ENV_IDS",
    "PROBLEMS",
    "BudgetExceededError",
    "FunctionEnv",
    "MSRACompensationEnv",
    "MultiObjectiveEnv",
    "ObjectiveFunction",
    "env_id",
    "get_function",
    "is_compensation",
    "is_multiobjective",
    "mo_env_id",
    "register_envs",
    "register_mo_envs",
    "register_msra_envs",
    "task_class",
    "task_id",
]
