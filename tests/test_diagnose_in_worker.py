"""A diagnosis in a sweep's worker (a daemon process) tries its two smoothing windows in turn,
where joblib would refuse to start workers of its own and warn in every job's log."""

from __future__ import annotations

import warnings
from typing import Any

from hydra_plugins.tcbench_launcher.pool import run_jobs


def _diagnose_fast_staircase(cfg: dict[str, Any]) -> tuple[bool, Any]:
    from tcbench.datasets.controls import Form, control_recording
    from tcbench.diagnose.diagnosis import diagnose

    rec, _ = control_recording("gyro", Form(3600.0, 1.0), 44_900_000)  # its corners shorten the smoothing
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        d = diagnose(rec, sensor="gyro")
    return True, (sorted(d.statistics.smooth_tried_s), [str(w.message) for w in caught])


def test_a_diagnosis_in_a_sweep_worker_tries_both_windows_without_a_warning() -> None:
    [(ok, (tried, caught))] = run_jobs([{}], 1, _diagnose_fast_staircase)
    assert ok and len(tried) == 2, tried  # the fitted window and the default both diagnosed
    assert not [m for m in caught if "multiprocessing" in m or "n_jobs" in m], caught
