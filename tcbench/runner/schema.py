"""The schema of a ``tcbench run`` job (:class:`JobConfig`), kept apart from its checks
(:mod:`.config`): the help, the composition and the runner read it without importing the
tasks' libraries, Hydra or OmegaConf."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from tcbench.tracking.config import TrackingConfig

MISSING = "???"  # OmegaConf's mark of a value the config must give


@dataclass
class JobConfig:
    """One optimisation job: task, optimiser, seed and evaluation budget."""

    task: dict[str, Any] = field(default_factory=lambda: {"name": MISSING})
    optimiser: dict[str, Any] = field(default_factory=lambda: {"name": MISSING})
    learner: dict[str, Any] | None = None
    seed: int = 0
    budget: int = 1000
    progress: bool = False
    tracking: TrackingConfig = field(default_factory=TrackingConfig)


def register_schema() -> None:
    """Make the structured schema available to Hydra as ``base_config``."""
    from hydra.core.config_store import ConfigStore

    ConfigStore.instance().store(name="base_config", node=JobConfig)


def as_dict(cfg: Any) -> dict[str, Any]:
    """Plain, resolved dict of a (sub)config."""
    if not isinstance(cfg, dict):
        from omegaconf import DictConfig, OmegaConf

        if isinstance(cfg, DictConfig):
            return OmegaConf.to_container(cfg, resolve=True)  # type: ignore[return-value]
    return dict(cfg)
