"""Sweeps beyond one process: Hydra's joblib and submitit launchers (both in the slow suite), and a shared MLflow
tracking server on 127.0.0.1 taking parallel jobs without losing or mixing runs. Each runs as
``python -m tcbench`` (the launchers' smoke tests: their worker processes keep the folder and
environment they were started with, which a test process would share between tests), on two
seeds per optimiser: four jobs on two workers. The sweep against the server starts in this
process (:mod:`cli_here`) on tcbench's own launcher, whose workers are spawned afresh."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import mlflow
import pytest
from cli_here import tcbench as here

from tcbench.tracking.template import create_store


def tcbench(*args: str, cwd: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    full = {**os.environ, **(env or {})}
    if env is None:
        full.pop("MLFLOW_TRACKING_URI", None)
    return subprocess.run([sys.executable, "-m", "tcbench", *args], cwd=cwd, env=full,
                          capture_output=True, text=True, timeout=600)


def check_runs(client: mlflow.MlflowClient, experiment: str, expected: set[tuple[str, int]]) -> None:
    """Every (optimiser, seed) exactly once, FINISHED, with params, tags and metrics that agree."""
    exp = client.get_experiment_by_name(experiment)
    runs = client.search_runs([exp.experiment_id], max_results=1000)
    seen = []
    for r in runs:
        p, t, m = r.data.params, r.data.tags, r.data.metrics
        assert r.info.status == "FINISHED"
        assert t["tcbench.method"] == p["optimiser.name"] and t["tcbench.seed"] == p["seed"]
        assert r.info.run_name == f"{p['optimiser.name']}-sphere-2d-s{p['seed']}"
        assert m["evaluations"] == float(p["budget"]) and "final_best" in m
        history = client.get_metric_history(r.info.run_id, "best_f")
        assert len(history) == m["generations"] + 1
        seen.append((p["optimiser.name"], int(p["seed"])))
    assert sorted(seen) == sorted(expected)


@pytest.mark.slow  # a sweep in a process of its own on Hydra's joblib launcher; tcbench's own launcher (test_launcher*.py) stays in CI
def test_joblib_launcher_parallel_jobs(workdir: Path) -> None:
    out = tcbench("run", "-m", "hydra/launcher=joblib", "hydra.launcher.n_jobs=2", "task=sphere",
                  "optimiser=fa,ifa", "seed=range(2)", "budget=100", "tracking.experiment=par", cwd=workdir)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "4 finished, 0 failed" in out.stdout
    check_runs(mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}"), "par",
               {(o, s) for o in ("fa", "ifa") for s in range(2)})


@pytest.mark.slow  # an optional launcher; the joblib one above and tcbench's own (test_launcher*.py) stay in CI
def test_submitit_local_launcher(workdir: Path) -> None:
    out = tcbench("run", "-m", "hydra/launcher=submitit_local", "task=sphere", "optimiser=fa,ifa",
                  "seed=0", "budget=100", "tracking.experiment=sub", cwd=workdir)
    assert out.returncode == 0, out.stderr[-2000:]
    check_runs(mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}"), "sub", {("fa", 0), ("ifa", 0)})


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def tracking_server(tmp_path: Path):
    """``mlflow server`` on 127.0.0.1 with a SQLite database backend, stopped after the test."""
    port = _free_port()
    log = (tmp_path / "server.log").open("w")
    # one server worker: the parallel jobs are its clients, served concurrently; it starts in about half the
    # time two take (12.6 s against 22.2 s to answer /health on two busy cores). Its store is a copy of the
    # migrated empty one where the user cache allows (no migrations at start; else MLflow migrates), and it
    # starts no job runner (MLflow's seven huey consumers, which tcbench does not use)
    create_store(tmp_path / "server.db")
    proc = subprocess.Popen(
        [sys.executable, "-m", "mlflow", "server", "--host", "127.0.0.1", "--port", str(port),
         "--backend-store-uri", f"sqlite:///{tmp_path / 'server.db'}",
         "--artifacts-destination", str(tmp_path / "artifacts"), "--workers", "1"],
        stdout=log, stderr=subprocess.STDOUT, cwd=tmp_path,
        env={**os.environ, "MLFLOW_SERVER_ENABLE_JOB_EXECUTION": "false"},
    )
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            try:
                with urllib.request.urlopen(f"{url}/health", timeout=2) as r:
                    if r.status == 200:
                        break
            except OSError:
                time.sleep(0.5)
        else:
            raise RuntimeError(f"mlflow server did not start: {(tmp_path / 'server.log').read_text()[-2000:]}")
        yield url
    finally:
        proc.terminate()
        proc.wait(timeout=30)
        log.close()


@pytest.mark.slow  # an MLflow server of its own; the server-store checks (tests/test_tracking_checks.py) stay in CI
def test_parallel_jobs_against_a_tracking_server(tracking_server: str, tmp_path: Path) -> None:
    work = tmp_path / "work"
    work.mkdir()
    # tcbench's own launcher: fresh spawned workers for each sweep, so the sweep can start here
    out = here("run", "-m", "hydra.launcher.n_jobs=2", "task=sphere", "optimiser=fa,ifa", "seed=range(2)",
               "budget=100", "tracking.experiment=shared", "tracking.plots=true",  # a PNG for the server to keep
               cwd=work, env={"MLFLOW_TRACKING_URI": tracking_server})
    assert out.returncode == 0, out.stderr[-2000:]
    assert "4 finished, 0 failed" in out.stdout
    client = mlflow.MlflowClient(tracking_server)
    check_runs(client, "shared", {(o, s) for o in ("fa", "ifa") for s in range(2)})
    run = client.search_runs([client.get_experiment_by_name("shared").experiment_id], max_results=1)[0]
    assert {a.path for a in client.list_artifacts(run.info.run_id)} == {"config.yaml", "convergence.png"}
    assert not (work / "mlflow.db").exists()  # nothing went to a local store
