"""tcbench: benchmarks for temperature compensation of MEMS inertial sensors.

Importing the package registers its tasks with gymnasium under the ``tcbench/`` namespace.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("tcbench")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

from tcbench import tasks as tasks  # noqa: E402  (registers the gymnasium envs)
from tcbench.check import OptimizerContractError, check_optimizer  # noqa: E402

__all__ = ["OptimizerContractError", "__version__", "check_optimizer", "tasks"]
