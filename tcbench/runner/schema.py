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


def _store_copied_as_itself() -> None:
    """A copy of Hydra's ConfigStore is the store itself.

    Hydra 1.3 deep-copies its config repository at every compose (``CachingConfigRepository``),
    and with it the whole ConfigStore its structured source keeps a reference to: every schema
    registered (tcbench's command schemas and Hydra's own), 11 of a job's 91 ms of composition
    (benchmarks/compose_speed.py). No copy is needed: ``ConfigStore.load`` hands out a deep copy
    of the node it loads, and a copied store would miss what is registered after the copy
    (Hydra's later code refetches the singleton instead of keeping it, its pull request 2928)."""
    from hydra.core.config_store import ConfigStore

    if "__deepcopy__" not in vars(ConfigStore):
        ConfigStore.__deepcopy__ = lambda self, memo: self  # type: ignore[attr-defined]


def register_schema() -> None:
    """Make the schema of every command available to Hydra under the name its primary config's
    defaults list gives it (:attr:`~tcbench.commands.registry.CommandSpec.schema_node`:
    ``base_config`` for this one, ``simulate_schema`` ...); the store is shared by the copies
    Hydra makes of it (:func:`_store_copied_as_itself`)."""
    from hydra.core.config_store import ConfigStore

    from tcbench.commands.registry import SPECS

    _store_copied_as_itself()
    for spec in SPECS.values():
        ConfigStore.instance().store(name=spec.schema_node, node=spec.schema_class())


def as_dict(cfg: Any) -> dict[str, Any]:
    """Plain, resolved dict of a (sub)config; a ConfigError naming the key whose interpolation
    does not resolve (``${oc.env:NOPE}`` of a variable that is not set)."""
    if not isinstance(cfg, dict):
        from omegaconf import DictConfig, OmegaConf
        from omegaconf.errors import OmegaConfBaseException

        if isinstance(cfg, DictConfig):
            try:
                return OmegaConf.to_container(cfg, resolve=True)  # type: ignore[return-value]
            except OmegaConfBaseException as exc:
                from tcbench.errors import ConfigError, error_line

                key = getattr(exc, "full_key", None) or "config"
                raise ConfigError(f"{key}: {error_line(str(exc))}") from None
    return dict(cfg)
