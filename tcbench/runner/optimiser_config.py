"""A job's optimiser as its config gives it: shared by the optimisation and compensation jobs,
so an optimisation job does not import the compensation stack (its simulators, scipy.signal)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from tcbench.optimisers import registry as optimisers


@dataclass(frozen=True)
class OptimiserConfig:
    """A job's optimiser (a compensation job's searches the learner's initial weights, ``none``:
    a random start; an optimisation job's minimises the task): its name, its parameters and its
    leaderboard label."""

    name: str
    params: dict[str, Any]
    label: Any = None

    @property
    def searches(self) -> bool:
        """Whether it searches (``none``, :data:`~tcbench.optimisers.registry.NO_SEARCH`: a random start)."""
        return self.name != optimisers.NO_SEARCH


def optimiser_of(c: dict[str, Any]) -> OptimiserConfig:
    """The job's optimiser (its config's ``optimiser``)."""
    params = dict(c["optimiser"])
    name = str(params.pop("name", None))
    label = params.pop("label", None)
    return OptimiserConfig(name, params, label)
