"""The command line end to end: one job, a sweep with its leaderboard, and bad input. The one
job, the sweep and its first board go through ``python -m tcbench`` (the smoke tests of ``run``,
``run -m`` and ``leaderboard``); the rest runs the same commands in this process
(:mod:`cli_here`)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import mlflow
import pandas as pd
import pytest
from cli_here import tcbench as here


def tcbench(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``python -m tcbench ARGS`` in a process of its own."""
    return subprocess.run(
        [sys.executable, "-m", "tcbench", *args], cwd=cwd, capture_output=True, text=True,
        timeout=300,
    )


def test_single_run_is_tracked(workdir: Path) -> None:
    out = tcbench("run", "task=sphere", "optimiser=ifa", "seed=3", "budget=200", cwd=workdir)
    assert out.returncode == 0, out.stderr
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    exp = client.get_experiment_by_name("tcbench")
    assert exp.artifact_location == (workdir / "mlartifacts" / "tcbench").as_uri()
    (run,) = client.search_runs([exp.experiment_id])
    assert run.info.status == "FINISHED"
    p, m, t = run.data.params, run.data.metrics, run.data.tags
    assert p["task.name"] == "sphere" and p["optimiser.name"] == "ifa" and p["seed"] == "3"
    assert p["optimiser.epsilon"] == "0.01" and p["budget"] == "200"
    assert m["evaluations"] == 200 and m["final_best"] >= 0
    assert {"tcbench.version", "tcbench.git_commit", "tcbench.config_hash", "tcbench.sweep_id"} <= set(t)
    best = client.get_metric_history(run.info.run_id, "best_f")
    mean = client.get_metric_history(run.info.run_id, "pop_mean_f")
    assert len(best) == len(mean) == m["generations"] + 1
    values = [h.value for h in sorted(best, key=lambda h: h.step)]
    assert all(b <= a for a, b in zip(values, values[1:]))  # best so far never worsens
    assert values[-1] == m["final_best"]
    names = {a.path for a in client.list_artifacts(run.info.run_id)}
    assert names == {"config.yaml", "convergence.png"}


def test_sweep_then_leaderboard(workdir: Path) -> None:
    out = tcbench(
        "run", "-m", "task=sphere", "optimiser=fa,ifa", "seed=range(2)", "budget=100",
        "tracking.experiment=t", "task.target_precision=1e-2", cwd=workdir,
    )
    assert out.returncode == 0, out.stderr
    assert "4 jobs recorded" in out.stdout and "4 finished, 0 failed" in out.stdout
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    runs = client.search_runs([client.get_experiment_by_name("t").experiment_id])
    assert len({r.data.tags["tcbench.sweep_id"] for r in runs}) == 1
    lb = tcbench("leaderboard", "--experiment", "t", "--out", "lb", cwd=workdir)
    assert lb.returncode == 0, lb.stderr
    table = pd.read_csv(workdir / "lb" / "sphere-2d.csv")
    assert sorted(table["method"]) == ["fa", "ifa"]
    assert table["seeds"].tolist() == [2, 2] and table["failed"].tolist() == [0, 0]
    assert sorted(table["rank"]) == [1, 2]
    assert (workdir / "lb" / "sphere-2d_convergence.png").stat().st_size > 5000
    assert "| rank | method |" in (workdir / "lb" / "sphere-2d.md").read_text()

    # a sweep of leaderboards: one board folder per experiment, each filed as a run when asked
    assert here("run", "task=sphere", "optimiser=pso", "budget=100", "tracking.experiment=t2",
                cwd=workdir).returncode == 0
    boards = here("leaderboard", "-m", "experiments=t,t2", "out=boards/${experiments}", "tracking.enabled=true",
                     cwd=workdir)
    assert boards.returncode == 0, boards.stderr
    assert sorted(pd.read_csv(workdir / "boards" / "t" / "sphere-2d.csv")["method"]) == ["fa", "ifa"]
    assert pd.read_csv(workdir / "boards" / "t2" / "sphere-2d.csv")["method"].tolist() == ["pso"]
    filed = client.search_runs([client.get_experiment_by_name("leaderboards").experiment_id])
    assert sorted(r.data.tags["tcbench.task"] for r in filed) == ["t", "t2"]
    assert all(r.info.status == "FINISHED" and r.data.tags["tcbench.kind"] == "leaderboard" for r in filed)
    assert {"config.yaml", "sphere-2d.md", "sphere-2d.csv"} <= {a.path for a in client.list_artifacts(filed[0].info.run_id)}
    # the board runs are not optimisation runs: the board of every experiment stays as it was
    again = here("leaderboard", "--experiment", "t", "--experiment", "leaderboards", "--out", "lb2", cwd=workdir)
    assert again.returncode == 0, again.stderr
    assert pd.read_csv(workdir / "lb2" / "sphere-2d.csv")["seeds"].tolist() == [2, 2]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["task=nope"], "unknown task 'nope'; known: accel_chamber, ackley, "),
        (["optimiser=nope"], "unknown optimiser 'nope'; known: bas, "),
        (["seed=abc"], "seed: Value 'abc'"),
        (["seed=-1"], "seed must be >= 0"),
        (["budget=5"], "smaller than one generation"),
        (["optimiser.beta0=2"], "beta0 must be in (0, 1]"),
        (["+optimiser.colour=3"], "no parameter 'colour'"),
        (["task.dim=0"], "dim must be an integer >= 1"),
        (["tracking.plots=maybe"], "tracking.plots: Value 'maybe' is not a valid bool"),
        (["optimiser.alpha0=1,2"], "add -m"),
        (["-m", "optimiser=fa,ifa", "optimiser.gamma=-1"], "gamma must be >= 0"),
        (["optimiser=bas", "optimiser.population=8", "budget=10"], "smaller than one BAS iteration"),
        (["task=zdt1", "optimiser=ifa"], "single-objective; task zdt1 has 2 objectives"),
    ],
)
def test_bad_config_one_line_no_job(workdir: Path, args: list[str], message: str) -> None:
    out = here("run", *args, cwd=workdir)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], out.stderr
    assert "Traceback" not in out.stderr + out.stdout
    assert not (workdir / "mlflow.db").exists()  # validated before any job started


def test_unknown_command(workdir: Path) -> None:
    out = here("frobnicate", cwd=workdir)
    assert out.returncode == 2 and "unknown command 'frobnicate'" in out.stderr


def test_leaderboard_without_runs(workdir: Path) -> None:
    assert here("run", "budget=20", cwd=workdir).returncode == 0
    out = here("leaderboard", "--experiment", "none", cwd=workdir)
    assert out.returncode == 2 and "unknown experiment 'none' in sqlite:///" in out.stderr
    assert out.stderr.strip().endswith("; known: Default, tcbench")


def test_help_and_import_load_no_heavy_library() -> None:
    """``tcbench --help`` (and ``import tcbench``, which registers every task) must answer
    without loading the simulators' or tracking's libraries: the sensor tasks' classes are
    imported on first use. What it costs in time is measured in benchmarks/sweep_overhead.py."""
    import subprocess
    import sys

    heavy = ["scipy", "matplotlib", "mlflow", "pandas", "hydra", "omegaconf", "ioh", "nevergrad", "optuna", "pywt"]
    code = ("import sys, contextlib, io\n"
            "from tcbench.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()) as out:\n"
            "    main(['--help'])\n"
            "assert 'usage: tcbench' in out.getvalue()\n"
            "import gymnasium as gym, tcbench\n"
            "assert 'tcbench/Gyro-DriftNoise-v0' in gym.registry and 'tcbench/BBOB-v0' in gym.registry\n"
            f"print(sorted({{m.split('.')[0] for m in sys.modules}} & {set(heavy)!r}))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
    import tcbench.tasks

    assert tcbench.tasks.GyroDriftNoiseEnv.__name__ == "GyroDriftNoiseEnv"  # the lazy name resolves


def test_diagnose_from_the_command_line(workdir: Path) -> None:
    """``python -m tcbench diagnose`` (its smoke test: every other diagnosis runs in-process) on a
    record too short for a full diagnosis, which gets the short-record report."""
    import json

    import numpy as np

    from tcbench.sensors.recording import make_recording, write_recording

    t_s = np.arange(0.0, 300.0, 0.1)
    rng = np.random.default_rng(3)
    temp_c = 25.0 + 10.0 * t_s / t_s[-1]
    rec = make_recording(t_s, temp_c, np.zeros_like(t_s), 0.002 * (temp_c - 25.0) + 0.01 * rng.standard_normal(t_s.size),
                         sensor="gyro", sample_rate_hz=10.0, device_id="smoke")
    write_recording(rec, workdir / "short.csv")
    out = tcbench("diagnose", "recording=short.csv", "out=d", "tracking.enabled=false", cwd=workdir)
    assert out.returncode == 0, out.stderr
    assert "short record (299.9 s of the 1200 s a full diagnosis needs)" in out.stdout, out.stdout
    assert "ran: temperature_slope (significant)" in out.stdout  # the slope put in the output
    report = json.loads((workdir / "d" / "report.json").read_text())
    assert report["report"] == "short_record" and report["samples"] == t_s.size
