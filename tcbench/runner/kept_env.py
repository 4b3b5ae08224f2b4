"""The env a plan check built, handed to the job that runs next in the same process.

A job kind's plan check (:meth:`~tcbench.runner.kinds.JobKind.plan_check`, before any job starts)
builds and checks the job's env; it keeps that env here under a key naming what the env is built
from (:func:`keep`), and the next job of the process prepared from the same arguments takes it
(:func:`take`) instead of building another. An env is fresh until its first ``reset``: a check
reads it, never steps it. One env is kept at most (a sweep's plan checks keep their last one); a
job on a worker process finds none and builds its own.
"""

from __future__ import annotations

from typing import Any

# The env a plan check built, by its key, for the job that runs next in this process (one at most).
_kept: dict[str, Any] = {}


def keep(key: str, env: Any) -> None:
    """Keep ``env``, built from the arguments ``key`` names, for the next job of this process
    prepared from the same arguments; the env kept before is dropped."""
    _kept.clear()
    _kept[key] = env


def take(key: str) -> Any:
    """The env kept for ``key``, handed over once (no longer kept), or None."""
    return _kept.pop(key, None)
