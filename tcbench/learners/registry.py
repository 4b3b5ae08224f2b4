"""Learner registry fed by the ``tcbench.learners`` entry-point group (like optimisers)::

    [project.entry-points."tcbench.learners"]
    rbf = "my_package.rbf:RBFNetwork"
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tcbench.learners.base import Learner, LearnerParams
from tcbench.plugins import PluginRegistry, UnknownPluginError

GROUP = "tcbench.learners"


class UnknownLearnerError(UnknownPluginError):
    """No learner of that name is registered."""


REGISTRY: PluginRegistry[Learner] = PluginRegistry(GROUP, Learner, "learner", UnknownLearnerError)
register = REGISTRY.register
available = REGISTRY.available
broken = REGISTRY.broken
get = REGISTRY.get


def create(name: str, n_inputs: int, params: LearnerParams | dict[str, Any] | None = None,
           rng: np.random.Generator | None = None) -> Learner:
    """Instantiate the learner ``name`` for ``n_inputs`` inputs."""
    return get(name)(n_inputs, params, rng)
