"""tcbench: benchmarks for temperature compensation of MEMS inertial sensors.

Importing the package registers its tasks with gymnasium under the ``tcbench/`` namespace.
"""

from tcbench import tasks as tasks  # (registers the gymnasium envs)
from tcbench._version import __version__
from tcbench.check import OptimizerContractError, check_optimizer

__all__ = ["OptimizerContractError", "__version__", "check_optimizer", "tasks"]
