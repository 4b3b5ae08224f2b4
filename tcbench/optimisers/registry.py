"""Optimiser registry fed by the ``tcbench.optimisers`` entry-point group.

Built-in optimisers are declared in tcbench's own ``pyproject.toml`` under that group, exactly as
a third-party package declares a plugin::

    [project.entry-points."tcbench.optimisers"]
    de = "my_package.de:DifferentialEvolution"

An entry point that fails to load is logged with its error and skipped; the others still work.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Any

import numpy as np

from tcbench.optimisers.protocol import Optimiser, OptimiserParams

GROUP = "tcbench.optimisers"
log = logging.getLogger(__name__)


class UnknownOptimiserError(KeyError):
    """No optimiser of that name is registered."""

    def __str__(self) -> str:
        return str(self.args[0])


@dataclass(frozen=True)
class Entry:
    """A registered optimiser class and the distribution that provides it."""

    cls: type[Optimiser]
    package: str


_entries: dict[str, Entry] | None = None
_broken: dict[str, str] = {}


def _load() -> dict[str, Entry]:
    global _entries
    if _entries is None:
        _entries = {}
        for ep in entry_points(group=GROUP):
            package = ep.dist.name if ep.dist is not None else "?"
            try:
                cls = ep.load()
                _check_class(ep.name, cls)
            except Exception as exc:  # a broken plugin must not take the others down
                _broken[ep.name] = f"{type(exc).__name__}: {exc}"
                log.warning("optimiser plugin %r from %s skipped: %s", ep.name, package, exc)
                continue
            _entries[ep.name] = Entry(cls, package)
    return _entries


def _check_class(name: str, cls: Any) -> None:
    if not (isinstance(cls, type) and issubclass(cls, Optimiser)):
        raise TypeError(f"{name!r} does not name a tcbench.optimisers.Optimiser subclass")


def register(name: str, cls: type[Optimiser], package: str = "__main__") -> None:
    """Register ``cls`` under ``name`` for this process (entry points are the lasting way)."""
    _check_class(name, cls)
    _load()[name] = Entry(cls, package)


def available() -> dict[str, Entry]:
    """Registered optimisers by name."""
    return dict(sorted(_load().items()))


def broken() -> dict[str, str]:
    """Entry points that failed to load, with their error."""
    _load()
    return dict(_broken)


def get(name: str) -> type[Optimiser]:
    """The optimiser class registered as ``name``."""
    entries = _load()
    if name not in entries:
        known = ", ".join(sorted(entries)) or "none"
        hint = f" (plugin failed to load: {_broken[name]})" if name in _broken else ""
        raise UnknownOptimiserError(f"unknown optimiser {name!r}{hint}; known: {known}")
    return entries[name].cls


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
