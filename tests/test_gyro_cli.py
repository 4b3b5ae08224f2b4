"""The gyro track from the command line: a tuned BAS-Elman job, baselines and their leaderboard (in the slow
suite), bad input."""

from __future__ import annotations

import subprocess
from pathlib import Path

import mlflow
import pytest
from cli_here import tcbench as here

SMALL = ["task.sample_rate_hz=1", "task.hold_s=1800"]


def tcbench(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``tcbench ARGS`` run in this process (:mod:`cli_here`)."""
    return here(*args, cwd=cwd)


def test_tuned_bas_elman_job_is_tracked_with_the_seed_figures(workdir: Path) -> None:
    out = tcbench("run", "experiment=movmd_tfpf", *SMALL, "task.tuning_budget=80", "task.tuning_samples=256",
                  "learner.hidden=4", "learner.epochs=20", "budget=40", cwd=workdir)
    assert out.returncode == 0, out.stderr
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    (run,) = client.search_runs([client.get_experiment_by_name("tcbench").experiment_id])
    m, t = run.data.metrics, run.data.tags
    assert t["tcbench.method"] == "MOVMD-TFPF+BAS-elman-adam" and t["tcbench.task"] == "gyro_driftnoise-dev0"
    assert 4 <= m["vmd_k"] <= 12 and 1000 <= m["vmd_alpha"] <= 10000 and m["search_evaluations"] == 40
    assert {"drift_dph", "raw_arw_1s_deg_per_sqrt_h", "bandwidth_hz", "train_rmse_dph"} <= set(m)
    assert m["bandwidth_hz"] < m["raw_bandwidth_hz"] == 0.5
    names = {a.path for a in client.list_artifacts(run.info.run_id)}
    assert {"fig11_pareto.png", "fig12_modes_test1.png", "fig13_entropy_test1.png", "fig17_drift_test1.png",
            "fig19_allan_test1.png", "allan_test1.csv", "vmd_front.csv", "scores.json"} <= names


@pytest.mark.slow  # six gyro oven runs end to end; the notes are tested in-process (test_compensation_notes.py),
# a gyro run from the command line by the test above, a compensation board by test_compensation_cli.py
def test_baselines_make_a_leaderboard_with_the_bandwidth(workdir: Path) -> None:
    out = tcbench("run", "-m", "task=gyro_driftnoise", *SMALL, "task.k=6", "task.alpha=2000",
                  "task.decomposition=none", "task.denoise=none,wavelet", "learner=raw,oracle,poly",
                  "optimiser=none", "tracking.experiment=g", cwd=workdir)
    assert out.returncode == 0, out.stderr
    assert "6 finished, 0 failed" in out.stdout
    lb = tcbench("leaderboard", "--experiment", "g", "--out", "lb", cwd=workdir)
    assert lb.returncode == 0, lb.stderr
    text = (workdir / "lb" / "gyro_driftnoise-dev0.md").read_text()
    rows = {line.split("|")[2].strip(): line for line in text.splitlines()
            if line.startswith("| ") and "rank" not in line}
    assert {"raw", "oracle", "poly3", "WTD", "WTD+poly3"} <= set(rows)
    assert "bandwidth" in rows["WTD"] and "filtering" in rows["WTD"]
    assert "filtering" not in rows["poly3"]


def test_bad_gyro_settings_exit_2_with_one_line(workdir: Path) -> None:
    for arg, words in (("task.tuner=bas", "single-objective"), ("task.denoise=kalman", "denoise"),
                       ("task.nosuch=1", "task.nosuch"), ("task.tuner=ga", "task.tuner_params=null"),
                       ("task.tuner_params={bound_velocity:bounce}", "bound_velocity")):
        out = tcbench("run", "task=gyro_driftnoise", arg, cwd=workdir)
        assert out.returncode == 2, (arg, out.stderr)
        assert words in out.stderr and "Traceback" not in out.stderr
        assert len(out.stderr.strip().splitlines()) == 1


def test_vmd_tuning_runs_with_mopso_from_its_experiment(workdir: Path) -> None:
    out = tcbench("run", "experiment=movmd_tuning", *SMALL, "task.tuning_samples=256", "budget=80", cwd=workdir)
    assert out.returncode == 0, out.stderr
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    (run,) = client.search_runs([client.get_experiment_by_name("tcbench").experiment_id])
    assert run.data.tags["tcbench.task"] == "gyro_vmdtuning-dev0" and run.data.tags["tcbench.method"] == "mopso"
    assert run.data.metrics["hypervolume"] > 0 and run.data.metrics["evaluations"] == 80
    assert "front.csv" in {a.path for a in client.list_artifacts(run.info.run_id)}
    single = tcbench("run", "task=gyro_vmdtuning", "optimiser=pso", cwd=workdir)
    assert single.returncode == 2 and "single-objective" in single.stderr
