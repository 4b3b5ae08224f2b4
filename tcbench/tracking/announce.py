"""Who hears of each job run this process creates: a sweep's worker sets :data:`on_run_created`
to tell its parent, which can then mark the run FAILED if the worker dies. A leaf, so the worker
sets it without importing MLflow (a worker whose jobs track nothing never imports it)."""

from __future__ import annotations

from collections.abc import Callable

on_run_created: Callable[[str], None] | None = None  # called with the id of every job run created here
