"""Same seeds, same results; a sweep killed with SIGKILL and resumed ends with every job once."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from cli_here import tcbench

from tcbench.optimisers import registry
from tcbench.runner.loop import run_optimisation
from tcbench.sensors.recording import write_recording
from tcbench.sensors.simulate import simulate_recording


@pytest.mark.parametrize("sensor, protocol", [("gyro", "oven"), ("msra", "fulltemp")])
def test_same_seeds_give_a_byte_identical_recording(tmp_path: Path, sensor: str, protocol: str) -> None:
    paths = [write_recording(simulate_recording(sensor, protocol, 3, 7), tmp_path / f"r{i}.csv") for i in range(2)]
    assert paths[0].read_bytes() == paths[1].read_bytes()
    assert paths[0].with_suffix(".json").read_bytes() == paths[1].with_suffix(".json").read_bytes()
    other = write_recording(simulate_recording(sensor, protocol, 3, 8), tmp_path / "other.csv")
    assert other.read_bytes() != paths[0].read_bytes()


# In the slow suite only: ngopt's determinism (~20 s here) is in the default suite as
# test_peers_nevergrad's same-seed test, tpe's (~17 s) as test_peers_optuna's.
SLOW_DETERMINISM = {"ngopt", "tpe"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW_DETERMINISM else n
                                  for n in sorted(registry.available())])
def test_same_seed_gives_an_identical_optimiser_result(name: str) -> None:
    cls = registry.get(name)
    task = {"name": "zdt1" if not cls.single_objective else "rastrigin", "dim": 4}
    runs = [run_optimisation(task, {"name": name}, 400, 11) for _ in range(2)]
    a, b = runs
    assert a.best_f == b.best_f and np.array_equal(a.best_x, b.best_x)
    assert a.trace.best_f == b.trace.best_f and a.trace.evaluations == b.trace.evaluations
    assert run_optimisation(task, {"name": name}, 400, 12).trace.best_f != a.trace.best_f


def _finished(db: Path) -> list[int]:
    """Seeds of the FINISHED runs, read with sqlite3 directly (an MLflow client would create or
    migrate the store itself and race the sweep doing the same)."""
    if not db.exists():
        return []
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as con:
            rows = con.execute("SELECT t.value FROM runs r JOIN tags t ON t.run_uuid = r.run_uuid "
                               "WHERE r.status = 'FINISHED' AND t.key = 'tcbench.seed'").fetchall()
    except sqlite3.OperationalError:  # tables not created yet, or locked for a moment
        return []
    return [int(v) for (v,) in rows]


@pytest.mark.slow  # kill -9 of a sweep's process group; a resume marking a gone process's runs (tests/test_sweep_failures.py) stays in CI
def test_sweep_killed_and_resumed_runs_every_job_once(workdir: Path) -> None:
    args = [sys.executable, "-m", "tcbench", "run", "-m", "task=sphere", "optimiser=pso", "budget=2000",
            "seed=range(16)", "tracking.sweep_id=killed", "hydra.sweep.dir=multirun/killed"]
    proc = subprocess.Popen(args, cwd=workdir, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    deadline = time.monotonic() + 120
    while len(_finished(workdir / "mlflow.db")) < 4 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    before = _finished(workdir / "mlflow.db")
    assert 4 <= len(before) < 16, "the sweep was not caught in the middle"
    again = tcbench(*args[3:], "tracking.resume=true", cwd=workdir)  # the resume in this process
    assert again.returncode in (0, 1), again.stderr  # 1: the killed job's RUNNING run is reported
    seeds = _finished(workdir / "mlflow.db")
    assert sorted(seeds) == list(range(16))  # every job FINISHED exactly once
