"""Benchmark tasks as gymnasium environments, registered under the ``tcbench`` namespace."""

from __future__ import annotations

from typing import Any

from tcbench.tasks.function_env import BudgetExceededError, FunctionEnv
from tcbench.tasks.functions import FUNCTIONS, ObjectiveFunction, get_function
from tcbench.tasks.ids import BBOB_ID, ENV_VERSION, GYRO_ENV_IDS, MSRA_ENV_IDS, env_id
from tcbench.tasks.mo_env import MultiObjectiveEnv, mo_env_id
from tcbench.tasks.multiobjective import PROBLEMS
from tcbench.tasks.specs import TASKS, TaskSpec, UnknownTaskError, task_spec
from tcbench.tasks.specs import register_specs as register_specs

# The sensor tasks' classes pull in simulators, learners and signal processing: imported when
# first used (``tcbench.tasks.GyroDriftNoiseEnv``), so that ``import tcbench`` stays light.
_LAZY = {"GyroDriftNoiseEnv": "tcbench.tasks.gyro_env", "GyroVMDTuningEnv": "tcbench.tasks.gyro_vmd_env",
         "MSRACompensationEnv": "tcbench.tasks.msra_env", "BBOBEnv": "tcbench.tasks.bbob_env"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'tcbench.tasks' has no attribute {name!r}")


def task_id(name: str) -> str:
    """Gymnasium id of any task by its config name (``rastrigin``, ``zdt1``, ...)."""
    return task_spec(name).gym_id


def task_kwargs(task: dict[str, Any]) -> dict[str, Any]:
    """The env's keyword arguments from a task config: every key but ``name``, a null passed as
    None, which the envs read as documented in the task configs (VMD's ``k``/``alpha`` to be tuned,
    MSRA recordings drawn from the run seed, a function's own domain, the default split ...)."""
    return {k: v for k, v in task.items() if k != "name"}


register_specs()

__all__ = [
    "BBOB_ID",
    "ENV_VERSION",
    "BBOBEnv",
    "FUNCTIONS",
    "GYRO_ENV_IDS",
    "MSRA_ENV_IDS",
    "PROBLEMS",
    "TASKS",
    "TaskSpec",
    "UnknownTaskError",
    "BudgetExceededError",
    "FunctionEnv",
    "GyroDriftNoiseEnv",
    "GyroVMDTuningEnv",
    "MSRACompensationEnv",
    "MultiObjectiveEnv",
    "ObjectiveFunction",
    "env_id",
    "get_function",
    "mo_env_id",
    "task_id",
    "task_spec",
    "register_specs",
    "task_kwargs",
]
