"""A diagnosis tries its two smoothing windows on two joblib workers in a user's process, and in turn
in a sweep's worker (a daemon process, where joblib would refuse to start workers of its own and warn
in every job's log); both ways give the same diagnosis."""

from __future__ import annotations

import json
import warnings
from typing import Any

import pytest
from joblib import parallel_config

from hydra_plugins.tcbench_launcher.pool import run_jobs


def _diagnose_fast_staircase(cfg: dict[str, Any]) -> tuple[bool, Any]:
    from tcbench.datasets.controls import Form, control_recording
    from tcbench.diagnose.diagnosis import diagnose

    rec, _ = control_recording("gyro", Form(3600.0, 1.0), 44_900_000)  # its corners shorten the smoothing
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        d = diagnose(rec, sensor="gyro")
    report = json.dumps(d.to_json(), default=float, sort_keys=True)
    return True, (d.statistics.smooth_tried_s, [str(w.message) for w in caught], report)


def test_a_diagnosis_in_a_sweep_worker_tries_both_windows_without_a_warning() -> None:
    [(ok, (tried, caught, _))] = run_jobs([{}], 1, _diagnose_fast_staircase)
    assert ok and len(tried) == 2, tried  # the fitted window and the default both diagnosed
    assert not [m for m in caught if "multiprocessing" in m or "n_jobs" in m], caught


@pytest.mark.worker_processes
def test_the_two_windows_on_two_workers_give_the_diagnosis_made_in_turn() -> None:
    _, (tried, _, two_workers) = _diagnose_fast_staircase({})
    with parallel_config(backend="sequential"):
        _, (tried_in_turn, _, in_turn) = _diagnose_fast_staircase({})
    assert len(tried) == 2 and tried == tried_in_turn
    assert two_workers == in_turn


def test_a_tests_joblib_work_runs_in_turn() -> None:
    """tests/conftest.py: outside the tests marked ``worker_processes`` joblib runs in turn (module
    fixtures included); the marked ones get joblib's process pool, as a user's process does."""
    from joblib.parallel import get_active_backend

    assert type(get_active_backend()[0]).__name__ == "SequentialBackend"


@pytest.mark.worker_processes
def test_a_marked_tests_joblib_work_runs_on_processes() -> None:
    from joblib.parallel import get_active_backend

    assert type(get_active_backend()[0]).__name__ == "LokyBackend"
