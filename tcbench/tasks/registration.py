"""Registering tcbench's tasks with gymnasium under the ``tcbench/`` namespace."""

from __future__ import annotations

from collections.abc import Callable, Iterable

import gymnasium as gym


def register_tasks(keys: Iterable[str], env_id: Callable[[str], str], entry_point: str,
                   key_arg: str | None = "function") -> None:
    """Register ``entry_point`` once per task key as ``env_id(key)``, passing the key as the
    keyword ``key_arg`` (``None``: no keyword; idempotent)."""
    for key in keys:
        eid = env_id(key)
        if eid not in gym.registry:
            gym.register(id=eid, entry_point=entry_point, kwargs={key_arg: key} if key_arg else {},
                         disable_env_checker=True)
