"""Several sweeps started at once on a fresh tracking store: all of them are recorded."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import mlflow
import pytest


# the unusable cache's race (MLflow migrating under the store lock, 17 s) in the slow suite: the lock is
# tested in test_store_template (a blocking exclusive flock), the migration there in one process
@pytest.mark.slow  # three sweeps in processes of their own; one store made by many workers (test_launcher*.py) stays in CI
@pytest.mark.parametrize("cache", ["empty", "unusable"])
def test_three_sweeps_at_once_on_a_fresh_store(workdir: Path, cache: str) -> None:
    """``empty``: the three race to build the store template and copy it; ``unusable`` (the cache
    path is a file): MLflow migrates the store itself, once, under the store lock. One job a sweep:
    the race is the store's, before any job runs."""
    cache_dir = workdir / "cache"
    if cache == "unusable":
        cache_dir.write_text("not a folder")
    env = {**os.environ, "TCBENCH_CACHE_DIR": str(cache_dir)}
    procs = [subprocess.Popen([sys.executable, "-m", "tcbench", "run", "-m", "task=sphere", "optimiser=pso",
                               "budget=40", f"seed={i}", f"hydra.sweep.dir=multirun/s{i}"],
                              cwd=workdir, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for i in range(3)]
    outs = [p.communicate(timeout=300) for p in procs]
    for p, (_, err) in zip(procs, outs, strict=True):
        assert p.returncode == 0, err[-2000:]
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    runs = client.search_runs([client.get_experiment_by_name("tcbench").experiment_id])
    assert sorted(int(r.data.tags["tcbench.seed"]) for r in runs) == list(range(3))
    assert all(r.info.status == "FINISHED" for r in runs)
