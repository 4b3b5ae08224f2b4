"""Benchmark tasks as gymnasium environments, registered under the ``tcbench`` namespace."""

from __future__ import annotations

from typing import Any

from tcbench.tasks.function_env import BudgetExceededError, FunctionEnv
from tcbench.tasks.functions import FUNCTIONS, ObjectiveFunction, get_function
from tcbench.tasks.ids import BBOB_ID, ENV_VERSION, GYRO_ENV_IDS, MSRA_ENV_IDS, env_id
from tcbench.tasks.mo_env import MultiObjectiveEnv, mo_env_id, register_mo_envs
from tcbench.tasks.multiobjective import PROBLEMS
from tcbench.tasks.registration import register_tasks

# The sensor tasks' classes pull in simulators, learners and signal processing: imported when
# first used (``tcbench.tasks.GyroDriftNoiseEnv``), so that ``import tcbench`` stays light.
_LAZY = {"GyroDriftNoiseEnv": "tcbench.tasks.gyro_env", "GyroVMDTuningEnv": "tcbench.tasks.gyro_vmd_env",
         "MSRACompensationEnv": "tcbench.tasks.msra_env", "BBOBEnv": "tcbench.tasks.bbob_env"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'tcbench.tasks' has no attribute {name!r}")


def register_envs() -> None:
    """Register every function task with gymnasium (idempotent)."""
    register_tasks(FUNCTIONS, env_id, "tcbench.tasks.function_env:FunctionEnv")


def register_msra_envs() -> None:
    """Register the MSRA compensation tasks (idempotent)."""
    register_tasks(MSRA_ENV_IDS, MSRA_ENV_IDS.__getitem__, "tcbench.tasks.msra_env:MSRACompensationEnv", "task")


def register_gyro_envs() -> None:
    """Register the gyro drift/noise and VMD tuning tasks (idempotent)."""
    register_tasks(["gyro_driftnoise"], GYRO_ENV_IDS.__getitem__, "tcbench.tasks.gyro_env:GyroDriftNoiseEnv", None)
    register_tasks(["gyro_vmdtuning"], GYRO_ENV_IDS.__getitem__, "tcbench.tasks.gyro_vmd_env:GyroVMDTuningEnv", None)


def register_bbob_env() -> None:
    """Register the BBOB task (ioh's functions 1-24, idempotent)."""
    register_tasks(["bbob"], lambda _: BBOB_ID, "tcbench.tasks.bbob_env:BBOBEnv", None)


def is_bbob(name: str) -> bool:
    """True for the BBOB task (``bbob``: ioh's functions 1-24)."""
    return name.lower() == "bbob"


def is_compensation(name: str) -> bool:
    """True for the sensor compensation tasks (``msra_fulltemp``, ``msra_zerobias``,
    ``gyro_driftnoise``)."""
    return name.lower() in MSRA_ENV_IDS or name.lower() == "gyro_driftnoise"


def is_gyro(name: str) -> bool:
    """True for the gyro tasks (``gyro_driftnoise``, ``gyro_vmdtuning``)."""
    return name.lower() in GYRO_ENV_IDS


def is_multiobjective(name: str) -> bool:
    """True for the multi-objective tasks (ZDT1-3, DTLZ2, gyro_vmdtuning)."""
    return name.lower() in PROBLEMS or name.lower() == "gyro_vmdtuning"


def task_id(name: str) -> str:
    """Gymnasium id of any task by its config name (``rastrigin``, ``zdt1``, ...)."""
    if name.lower() in MSRA_ENV_IDS:
        return MSRA_ENV_IDS[name.lower()]
    if is_gyro(name):
        return GYRO_ENV_IDS[name.lower()]
    if is_bbob(name):
        return BBOB_ID
    return mo_env_id(name) if name.lower() in PROBLEMS else env_id(name)


def task_kwargs(task: dict[str, Any]) -> dict[str, Any]:
    """The env's keyword arguments from a task config: every key but ``name``, a null passed as
    None, which the envs read as documented in the task configs (VMD's ``k``/``alpha`` to be tuned,
    MSRA recordings drawn from the run seed, a function's own domain, the default split ...)."""
    return {k: v for k, v in task.items() if k != "name"}


def task_class(name: str) -> type[FunctionEnv] | type[MultiObjectiveEnv]:
    """The env class serving a function or multi-objective problem name."""
    return MultiObjectiveEnv if name.lower() in PROBLEMS else FunctionEnv


register_envs()
register_mo_envs()
register_msra_envs()
register_gyro_envs()
register_bbob_env()

__all__ = [
    "BBOB_ID",
    "ENV_VERSION",
    "BBOBEnv",
    "FUNCTIONS",
    "GYRO_ENV_IDS",
    "MSRA_ENV_IDS",
    "PROBLEMS",
    "BudgetExceededError",
    "FunctionEnv",
    "GyroDriftNoiseEnv",
    "GyroVMDTuningEnv",
    "MSRACompensationEnv",
    "MultiObjectiveEnv",
    "ObjectiveFunction",
    "env_id",
    "get_function",
    "is_bbob",
    "is_compensation",
    "is_gyro",
    "is_multiobjective",
    "mo_env_id",
    "register_bbob_env",
    "register_envs",
    "register_gyro_envs",
    "register_mo_envs",
    "register_msra_envs",
    "task_class",
    "task_id",
    "task_kwargs",
]
