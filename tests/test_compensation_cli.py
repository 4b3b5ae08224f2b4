"""Compensation from the command line: one IFA-BP job, baselines and a leaderboard, bad input
(the commands run in this process: :mod:`cli_here`)."""

from __future__ import annotations

import json
from pathlib import Path

import mlflow
import pytest
from cli_here import tcbench

from tcbench.sensors.recording import write_recording
from tcbench.sensors.simulate import simulate_recording


def test_ifa_bp_job_is_tracked_with_figures(workdir: Path) -> None:
    out = tcbench("run", "task=msra_fulltemp", "learner=bp", "optimiser=ifa", "budget=60", "learner.epochs=40",
                  cwd=workdir)
    assert out.returncode == 0, out.stderr
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    (run,) = client.search_runs([client.get_experiment_by_name("tcbench").experiment_id])
    m, t = run.data.metrics, run.data.tags
    assert t["tcbench.kind"] == "compensation" and t["tcbench.method"] == "IFA-BP-gd"
    assert t["tcbench.task"] == "msra_fulltemp-dev0"
    assert m["search_evaluations"] == 60 and m["bias_variation_ug"] < m["raw_bias_variation_ug"]
    assert {"test1.bias_variation_ug", "test2.sf_variation_ppm", "halfg_error_ug", "train_rmse_ug"} <= set(m)
    assert len(client.get_metric_history(run.info.run_id, "train_loss")) == 41  # start + one per epoch
    curve = [h.value for h in sorted(client.get_metric_history(run.info.run_id, "init_best_f"), key=lambda h: h.step)]
    assert all(b <= a for a, b in zip(curve, curve[1:]))
    names = {a.path for a in client.list_artifacts(run.info.run_id)}
    assert {"scores.json", "fig8_test1.png", "fig9_test2.png", "training_curve.png", "nodes_test1.csv"} <= names
    doc = json.loads(Path(client.download_artifacts(run.info.run_id, "scores.json", str(workdir))).read_text())
    assert doc["conventions"][0].startswith("scale factor K1") and len(doc["recordings"]) == 2


@pytest.mark.figures
def test_baselines_and_leaderboard(workdir: Path) -> None:
    # no figures per run (the board reads none; test_ifa_bp_job_is_tracked_with_figures draws the task's)
    out = tcbench("run", "-m", "task=msra_fulltemp", "learner=raw,oracle,poly", "optimiser=none",
                  "tracking.experiment=c", "tracking.plots=false", cwd=workdir)
    assert out.returncode == 0, out.stderr
    assert "3 finished, 0 failed" in out.stdout
    lb = tcbench("leaderboard", "--experiment", "c", "--out", "lb", cwd=workdir)
    assert lb.returncode == 0, lb.stderr
    text = (workdir / "lb" / "msra_fulltemp-dev0.md").read_text()
    rows = [line.split("|")[2].strip() for line in text.splitlines() if line.startswith("| ") and "rank" not in line]
    assert rows == ["oracle", "poly3", "raw"]
    assert (workdir / "lb" / "msra_fulltemp-dev0.png").stat().st_size > 5000


def test_zero_bias_job(workdir: Path) -> None:
    out = tcbench("run", "task=msra_zerobias", "learner=lagpoly", "optimiser=none", cwd=workdir)
    assert out.returncode == 0, out.stderr
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    (run,) = client.search_runs([client.get_experiment_by_name("tcbench").experiment_id])
    m = run.data.metrics
    assert m["zb_zero_start_ug"] < m["raw_zb_zero_start_ug"]
    assert "fig7_test1.png" in {a.path for a in client.list_artifacts(run.info.run_id)}


@pytest.fixture
def foreign_files(workdir: Path) -> tuple[str, str]:
    full, gyro = workdir / "full.csv", workdir / "gyro.csv"
    write_recording(simulate_recording("msra", "fulltemp", 0, 0), full)
    write_recording(simulate_recording("gyro", "static", 0, 0, duration_s=100.0, sample_rate_hz=1.0), gyro)
    return str(full), str(gyro)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["learner=nope"], "unknown learner 'nope'; known: bp, elman, lagpoly, memoriser, model, oracle, oracle_thermometer, poly, raw"),
        (["learner.hidden=0"], "learner bp: hidden"),
        (["learner.training=sgd"], "learner bp: training"),
        (["task.n_train=0"], "n_train and n_test must be integers >= 1"),
        (["task.device_seed=abc"], "task.device_seed must be int"),
        (["+task.colour=3"], "task.colour: no such key"),
        (["optimiser=mopso"], "multi-objective only"),
        (["budget=5"], "smaller than one generation"),
        (["task=rastrigin"], "learners apply to compensation tasks"),
        (["task=gyro_driftnoise", "learner=lagpoly", "optimiser=none"],
         "learner lagpoly is not a baseline of task gyro_driftnoise"),
    ],
)
def test_bad_input_one_line_exit_2(workdir: Path, args: list[str], message: str) -> None:
    base = ["task=msra_fulltemp", "learner=bp"]
    out = tcbench("run", *base, *args, cwd=workdir)
    lines = out.stderr.strip().splitlines()
    assert out.returncode == 2 and len(lines) == 1 and message in lines[0], out.stderr
    assert "Traceback" not in out.stderr + out.stdout
    assert not (workdir / "mlflow.db").exists()


def test_foreign_test_set_is_refused(workdir: Path, foreign_files: tuple[str, str]) -> None:
    full, gyro = foreign_files
    out = tcbench("run", "task=msra_fulltemp", "learner=poly", "optimiser=none", f"task.train_files=[{full}]",
                  f"task.test_files=[{gyro}]", cwd=workdir)
    lines = out.stderr.strip().splitlines()
    assert out.returncode == 2 and len(lines) == 1, out.stderr
    assert "gyro.csv: test recording is from a gyro sensor" in lines[0]
    out = tcbench("run", "task=msra_fulltemp", "learner=poly", "optimiser=none", f"task.train_files=[{gyro}]",
                  f"task.test_files=[{full}]", cwd=workdir)
    assert out.returncode == 2 and "training recording is from a gyro sensor" in out.stderr
    room = workdir / "room.csv"
    write_recording(simulate_recording("msra", "roomtemp", 0, 0), room)
    out = tcbench("run", "task=msra_fulltemp", "learner=poly", "optimiser=none", f"task.train_files=[{room}]",
                  f"task.test_files=[{full}]", cwd=workdir)
    lines = out.stderr.strip().splitlines()
    assert out.returncode == 2 and len(lines) == 1 and "room.csv: training recording has no four-position test" in lines[0]
    assert not (workdir / "mlflow.db").exists()
