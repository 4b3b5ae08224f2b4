"""How much memory a job may take: an estimate checked before the job, a limit while it runs.

A job that asks for more than the machine has (``task.dim=100000000``) used to grow until the
kernel killed it without a word. Two guards stop that: :func:`job_budget_bytes` is what one job
may use (free memory now, or ``$TCBENCH_JOB_MEMORY_MB``), which the config check compares with an
optimiser's own estimate before anything is allocated; and :func:`limited` caps the process's
data segment (``RLIMIT_DATA``) while a job runs, so an allocation past the budget raises
``MemoryError`` — a failed job with one line — instead of swapping the machine to a halt.
"""

from __future__ import annotations

import os
import resource
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

ENV = "TCBENCH_JOB_MEMORY_MB"
FREE_SHARE = 0.9  # of the memory free when a job starts


def _meminfo_kb(key: str, path: str = "/proc/meminfo") -> int | None:
    try:
        for line in Path(path).read_text().splitlines():
            if line.startswith(f"{key}:"):
                return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        return None
    return None


def job_budget_bytes() -> int | None:
    """Bytes one job may allocate: ``$TCBENCH_JOB_MEMORY_MB`` if set, else 90 % of the memory the
    machine has free now; None where neither is known (no limit)."""
    given = os.environ.get(ENV, "").strip()
    if given:
        try:
            mb = float(given)
        except ValueError:
            raise ValueError(f"${ENV} must be a number of megabytes, got {given!r}") from None
        if not mb > 0:
            raise ValueError(f"${ENV} must be positive, got {given!r}")
        return int(mb * 2**20)
    free_kb = _meminfo_kb("MemAvailable")
    return int(free_kb * 1024 * FREE_SHARE) if free_kb else None


def human(n_bytes: float) -> str:
    """``3.2 GB``, ``850 MB``: bytes for a message."""
    for unit, size in (("TB", 2**40), ("GB", 2**30), ("MB", 2**20)):
        if n_bytes >= size:
            return f"{n_bytes / size:.3g} {unit}"
    return f"{n_bytes / 2**10:.3g} kB"


def _data_segment_bytes() -> int | None:
    """The process's data segment now (``VmData``: what ``RLIMIT_DATA`` counts)."""
    kb = _meminfo_kb("VmData", "/proc/self/status")
    return kb * 1024 if kb is not None else None


@contextmanager
def limited(budget_bytes: int | None) -> Iterator[int | None]:
    """Within the block the process may grow its data segment by ``budget_bytes`` at most (an
    allocation beyond raises ``MemoryError``); the previous limit is restored after. A no-op
    where the size of the data segment is unknown (not Linux) or ``budget_bytes`` is None."""
    used = _data_segment_bytes()
    if budget_bytes is None or used is None:
        yield None
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_DATA)
    cap = used + int(budget_bytes)
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    if soft != resource.RLIM_INFINITY:
        cap = min(cap, soft)
    resource.setrlimit(resource.RLIMIT_DATA, (cap, hard))
    try:
        yield budget_bytes
    finally:
        resource.setrlimit(resource.RLIMIT_DATA, (soft, hard))
