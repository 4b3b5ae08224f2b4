"""Optimiser registry fed by the ``tcbench.optimisers`` entry-point group.

Built-in optimisers are declared in tcbench's own ``pyproject.toml`` under that group, exactly as
a third-party package declares a plugin::

    [project.entry-points."tcbench.optimisers"]
    de = "my_package.de:DifferentialEvolution"

An entry point that fails to load is logged with its error and skipped; the others still work.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tcbench.optimisers.protocol import Optimiser, OptimiserParams
from tcbench.plugins import Entry, PluginRegistry, UnknownPluginError

GROUP = "tcbench.optimisers"
NO_SEARCH = "none"  # a compensation job's optimiser that searches nothing: the learner's random start


class UnknownOptimiserError(UnknownPluginError):
    """No optimiser of that name is registered."""


REGISTRY: PluginRegistry[Optimiser] = PluginRegistry(GROUP, Optimiser, "optimiser", UnknownOptimiserError)
register = REGISTRY.register
available = REGISTRY.available
broken = REGISTRY.broken
get = REGISTRY.get

__all__ = ["GROUP", "NO_SEARCH", "Entry", "UnknownOptimiserError", "available", "broken", "create", "get", "register"]


def create(
    name: str,
    lower: np.ndarray,
    upper: np.ndarray,
    budget: int,
    rng: np.random.Generator,
    params: OptimiserParams | dict[str, Any] | None = None,
    n_objectives: int = 1,
) -> Optimiser:
    """Instantiate the optimiser ``name`` with bounds, budget, generator and parameters."""
    return get(name)(lower, upper, budget, rng, params, n_objectives=n_objectives)
