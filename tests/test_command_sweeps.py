"""The recording commands are Hydra apps run by the one job runner: ``-m`` sweeps a population
or a fleet on the launchers of ``tcbench run``, every job is checked before the first starts, and
each job is one MLflow run (a diagnosis with the effects it found, its RMSEs and its report)."""

from __future__ import annotations

import json
from pathlib import Path

import mlflow
import numpy as np
import pytest

from tcbench.cli import main
from tcbench.datasets.concealed import concealed_recording
from tcbench.sensors.recording import make_recording, write_recording

SHORT_GYRO = ["sensor=gyro", "protocol=static", "protocol_params.duration_s=600", "metrics=false"]


def _runs(workdir: Path, experiment: str) -> list:
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    exp = client.get_experiment_by_name(experiment)
    return client.search_runs([exp.experiment_id]) if exp else []


def test_simulate_sweeps_a_population(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", "-m", "device_seed=range(3)", "out=population", *SHORT_GYRO]) == 0
    out = capsys.readouterr().out
    assert "3 jobs recorded" in out and "3 finished, 0 failed" in out
    files = sorted(p.name for p in (workdir / "population").glob("*.csv"))
    assert files == [f"gyro-static-dev{d}-seed0.csv" for d in range(3)]
    runs = _runs(workdir, "simulations")
    assert len(runs) == 3 and {r.info.status for r in runs} == {"FINISHED"}
    assert {r.data.tags["tcbench.kind"] for r in runs} == {"simulation"}
    assert len({r.data.tags["tcbench.sweep_id"] for r in runs}) == 1
    assert sorted(r.data.tags["tcbench.device_seed"] for r in runs) == ["0", "1", "2"]
    assert (workdir / "population" / "multirun").is_dir()  # Hydra's sweep folder, under out=
    assert not (workdir / "multirun").exists()


def test_a_sweep_whose_jobs_would_share_an_output_runs_nothing(workdir: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", "-m", "device_seed=0,1", "name=same", *SHORT_GYRO]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "jobs 1 and 2 of the sweep would both write" in err[0] and "same.csv" in err[0]
    assert not (workdir / "recordings").exists() and not (workdir / "mlflow.db").exists()


def test_one_job_takes_any_path_literally(workdir: Path) -> None:
    """Without -m a value is a literal string: commas, parentheses and brackets in a path are no
    sweep and no grammar error."""
    assert main(["simulate", "out=run (1),[a]", "tracking.enabled=false", *SHORT_GYRO]) == 0
    assert (workdir / "run (1),[a]" / "gyro-static-dev0-seed0.csv").is_file()


@pytest.mark.slow  # two full diagnoses; the sweep and its tracking stay in CI in the next test
def test_diagnose_sweeps_a_fleet_and_tracks_each_diagnosis(workdir: Path,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    paths = []
    for effect, seed in ((None, 5), ("bias_instability", 1)):
        rec, _ = concealed_recording("gyro", effect, seed)
        paths.append(write_recording(rec, workdir / f"unit{seed}.csv"))
    assert main(["diagnose", "-m", f"recording={paths[0]},{paths[1]}", "out=fleet/${stem:recording}"]) == 0
    assert "2 jobs recorded" in capsys.readouterr().out
    for p in paths:
        assert (workdir / "fleet" / p.stem / "report.md").is_file()
    runs = {Path(r.data.tags["tcbench.task"]).stem: r for r in _runs(workdir, "diagnoses")}
    assert set(runs) == {"unit5", "unit1"}
    assert runs["unit5"].data.tags["tcbench.effects_found"] == "none"
    assert runs["unit1"].data.tags["tcbench.effects_found"] == "bias_instability"
    for r in runs.values():
        assert r.info.status == "FINISHED" and r.data.tags["tcbench.kind"] == "diagnosis"
        m = r.data.metrics
        assert m["rmse_heldout_after"] <= m["rmse_heldout_before"] and m["white_sigma"] > 0
        client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
        assert {"report.md", "report.json", "model.yaml", "config.yaml"} <= {
            a.path for a in client.list_artifacts(r.info.run_id)}


def test_a_failed_job_of_a_sweep_is_recorded_and_the_sweep_goes_on(workdir: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """A recording the diagnosis cannot use (constant temperature, long enough for a full
    diagnosis: a shorter one gets the short-record report) fails its job only; the good one beside
    it (40 min warming by 10 degC, read with 0.01 degC of thermometer noise: a full diagnosis at the
    default smoothing window, of a record small enough to be quick) gets its report."""
    rng = np.random.default_rng(0)
    t_s = np.arange(2400.0)
    temp_c = 20.0 + np.linspace(0.0, 10.0, t_s.size)
    output = 0.01 * temp_c + rng.normal(0.0, 0.01, t_s.size)
    good = write_recording(make_recording(t_s, temp_c + rng.normal(0.0, 0.01, t_s.size), np.zeros(t_s.size), output,
                                          sensor="gyro", sample_rate_hz=1.0, device_id="good"), workdir / "good.csv")
    flat = [a for a in SHORT_GYRO if not a.startswith("protocol_params.duration_s")] + ["protocol_params.duration_s=1500"]
    assert main(["simulate", "name=flat", "out=.", *flat, "tracking.enabled=false"]) == 0
    code = main(["diagnose", "-m", f"recording={good},flat.csv", "out=fleet/${stem:recording}"])
    out = capsys.readouterr().out
    assert code == 1 and "1 finished, 1 failed" in out and "FAILED" in out
    assert (workdir / "fleet" / "good" / "report.md").is_file() and not (workdir / "fleet" / "flat").exists()
    # each job is its own run: the finished one a diagnosis with what its report found, the other FAILED
    runs = {Path(r.data.tags["tcbench.task"]).stem: r for r in _runs(workdir, "diagnoses")}
    assert runs["flat"].info.status == "FAILED"
    done = runs["good"]
    found = [e["id"] for e in json.loads((workdir / "fleet" / "good" / "report.json").read_text())["effects"]]
    assert done.info.status == "FINISHED" and done.data.tags["tcbench.kind"] == "diagnosis"
    assert done.data.tags["tcbench.effects_found"] == (",".join(found) or "none")
    assert done.data.metrics["rmse_heldout_after"] <= done.data.metrics["rmse_heldout_before"]
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    assert {"report.md", "report.json", "model.yaml", "config.yaml"} <= {
        a.path for a in client.list_artifacts(done.info.run_id)}


def test_a_key_of_a_swept_group_is_set_in_every_job(workdir: Path) -> None:
    """``task.split`` exists in the compensation tasks, not in the default task (rastrigin), the one
    Hydra composes a multirun's config with before it sweeps: the key is set in each job instead."""
    assert main(["run", "-m", "task=msra_zerobias,msra_fulltemp", "task.split=replay", "learner=raw",
                 "optimiser=none", "tracking.experiment=split"]) == 0
    runs = _runs(workdir, "split")
    assert {r.info.status for r in runs} == {"FINISHED"} and len(runs) == 2
    assert {(r.data.params["task.name"], r.data.params["task.split"]) for r in runs} == {
        ("msra_zerobias", "replay"), ("msra_fulltemp", "replay")}


def test_only_plain_keys_inside_swept_groups_are_deferred() -> None:
    from tcbench.cli.app import deferred_to_the_jobs

    args = ["-m", "task=a,b", "task.split=replay", "seed=range(3)", "budget=5", "task.k=choice(1,2)",
            "learner.epochs=3", "~task.upper", "task.note=${oc.env:HOME}", "task.lower=null",
            "task.effects={bias_instability:{b:8.3e-4}}"]
    assert deferred_to_the_jobs(args, ("task", "seed")) == [
        "-m", "task=a,b", "task.split=choice(replay)", "seed=range(3)", "budget=5", "task.k=choice(1,2)",
        "learner.epochs=3", "~task.upper", "task.note=${oc.env:HOME}", "task.lower=null",
        "task.effects=choice({bias_instability:{b:8.3e-4}})"]
