"""The sweep's worker pool (:mod:`hydra_plugins.tcbench_launcher.pool`) in-process."""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from hydra_plugins.tcbench_launcher.pool import BLAS_THREAD_VARS, blas_threads_per_worker, run_jobs


def _sleep_job(cfg: dict[str, Any]) -> tuple[bool, Any]:
    Path(cfg["started"]).touch()
    time.sleep(cfg["sleep_s"])
    return True, cfg["sleep_s"]


@pytest.mark.skipif(sys.platform != "linux", reason="signals as on Linux")
def test_a_ctrl_c_taken_by_another_thread_still_ends_the_sweep(tmp_path: Path) -> None:
    """The kernel may hand a Ctrl-C to any thread of the sweep that does not block SIGINT; the main
    thread, waiting on its workers with no timeout, then ran the handler only when a worker next
    reported (a sweep of long jobs ignored Ctrl-C until one ended)."""
    started = tmp_path / "started"

    def ctrl_c_on_this_thread() -> None:
        deadline = time.monotonic() + 120
        while not started.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        time.sleep(0.5)  # the main thread is back in its wait
        signal.pthread_kill(threading.get_ident(), signal.SIGINT)

    # Python's Ctrl-C handler, as a process started in the foreground has it (a test run started in
    # a shell's background inherits SIGINT ignored)
    saved = signal.signal(signal.SIGINT, signal.default_int_handler)
    other = threading.Thread(target=ctrl_c_on_this_thread, daemon=True)
    other.start()
    t0 = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            run_jobs([{"started": str(started), "sleep_s": 300.0}], 1, _sleep_job)
    finally:
        signal.signal(signal.SIGINT, saved)
    assert started.exists()
    assert time.monotonic() - t0 < 100, "the Ctrl-C waited for the job to end"
    other.join(5)


def test_every_job_ends_in_order(tmp_path: Path) -> None:
    outcomes = run_jobs([{"started": str(tmp_path / f"s{i}"), "sleep_s": 0.01 * i} for i in range(3)], 2, _sleep_job)
    assert outcomes == [(True, 0.0), (True, 0.01), (True, 0.02)]


def _imports_job(cfg: dict[str, Any]) -> tuple[bool, Any]:
    return True, sorted(m for m in ("mlflow", "tcbench.tracking.store") if m in sys.modules)


def test_a_worker_leaves_mlflow_to_the_jobs_that_track() -> None:
    """A worker hooked its run announcements onto the tracking store, importing MLflow (about 2 s
    of each worker's start) before a job that tracks nothing."""
    assert run_jobs([{}], 1, _imports_job) == [(True, [])]


def _blas_job(cfg: dict[str, Any]) -> tuple[bool, Any]:
    import os

    import numpy  # noqa: F401 - its BLAS loaded, as in a job
    from threadpoolctl import threadpool_info

    return True, ({v: os.environ.get(v) for v in BLAS_THREAD_VARS},
                  sorted({p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"}))


def test_workers_share_the_cores_between_their_blas_threads(monkeypatch: pytest.MonkeyPatch) -> None:
    """Two workers of a two-core machine each ran OpenBLAS on every core: their spinning threads
    made a Gram 340x slower. Each gets its share, the user's own setting wins, and the sweep's
    process keeps its environment."""
    for var in BLAS_THREAD_VARS:
        monkeypatch.delenv(var, raising=False)
    share = blas_threads_per_worker(2)
    outcomes = run_jobs([{}, {}], 2, _blas_job)
    for ok, (env, threads) in outcomes:
        assert ok and set(env.values()) == {str(share)} and threads == [share]
    assert all(var not in os.environ for var in BLAS_THREAD_VARS)
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")  # one worker would get every core
    [(ok, (env, threads))] = run_jobs([{}], 1, _blas_job)
    assert env["OPENBLAS_NUM_THREADS"] == "1" and env["OMP_NUM_THREADS"] is None and threads == [1]


def test_the_blas_share_never_drops_below_one_thread() -> None:
    cores = len(os.sched_getaffinity(0))
    assert blas_threads_per_worker(1) == cores
    assert blas_threads_per_worker(cores + 5) == 1
    assert blas_threads_per_worker(0) == cores
