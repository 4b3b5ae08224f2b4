"""Task kinds are specs and job kinds are modules: every task config has a spec and every spec a
config, every command's config names a known kind, and a new kind runs through the one runner with
its MLflow run, its FAILED path and resume, without touching anything else."""

from __future__ import annotations

import sys
import types
from pathlib import Path
from typing import Any

import gymnasium as gym
import mlflow
import pytest
import yaml

from tcbench.commands.registry import SPECS, CommandSpec
from tcbench.config_dir import conf_dir
from tcbench.errors import ConfigError
from tcbench.runner import kinds
from tcbench.runner.job import FAILURES, JobFailure, run_job
from tcbench.tasks import TASKS, task_spec


def test_every_task_config_has_a_spec_and_every_spec_a_registered_env() -> None:
    names = {yaml.safe_load(p.read_text())["name"] for p in (conf_dir() / "task").glob("*.yaml")}
    assert names == set(TASKS)
    for spec in TASKS.values():
        assert spec.gym_id in gym.registry and spec.job_kind in SPECS["run"].kinds
        assert "name" in spec.schema.__dataclass_fields__
        assert spec.is_compensation == (spec.protocol is not None)
    with pytest.raises(KeyError, match="unknown task 'nope'; known: accel_chamber, ackley"):
        task_spec("nope")


@pytest.mark.parametrize("command", ["simulate", "metrics", "import", "diagnose"])
def test_every_command_config_names_its_kind(command: str) -> None:
    cfg = yaml.safe_load((conf_dir() / f"{command}.yaml").read_text())
    assert f"{command}_schema" in cfg["defaults"]
    assert kinds.kind_of({"kind": command}).name == command


def test_an_unknown_kind_is_one_line() -> None:
    with pytest.raises(ConfigError, match="kind: unknown job kind 'nope'; known: optimisation, compensation"):
        kinds.kind_of({"kind": "nope"})


class EchoKind(kinds.JobKind):
    """A kind in a dozen lines: says its message, or raises it."""

    def names(self, c: dict[str, Any]) -> kinds.JobNames:
        return kinds.JobNames(f"echo-{c['message']}", "echo-task", "echo", int(c["seed"]))

    def execute(self, c: dict[str, Any]) -> str:
        if c["message"] == "boom":
            raise RuntimeError("boom went the job")
        return str(c["message"])

    def record(self, run: Any, outcome: str, c: dict[str, Any], where: Path) -> list[Path]:
        run.log_metrics({"length": len(outcome)})
        (where / "said.txt").write_text(outcome)
        return [where / "said.txt"]


@pytest.fixture
def echo(monkeypatch: pytest.MonkeyPatch) -> None:
    """A command ``echo`` with its kind: one spec in the registry, and its module."""
    module = types.ModuleType("echo_kind")
    module.EchoKind = EchoKind  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "echo_kind", module)
    monkeypatch.setitem(SPECS, "echo", CommandSpec(name="echo", summary="say a message", schema="echo_kind:Echo",
                                                    kinds={"echo": "echo_kind:EchoKind"}))


def test_a_new_kind_runs_through_the_one_runner(echo: None, workdir: Path) -> None:
    uri = f"sqlite:///{workdir / 'mlflow.db'}"
    track = {"enabled": True, "uri": uri, "experiment": "echoes", "sweep_id": "s1", "resume": True}
    FAILURES.clear()
    assert run_job({"kind": "echo", "message": "hello", "seed": 3, "tracking": track}) == "hello"
    assert run_job({"kind": "echo", "message": "hello", "seed": 3, "tracking": track}) is None  # resumed
    failure = run_job({"kind": "echo", "message": "boom", "seed": 4, "tracking": track})
    assert isinstance(failure, JobFailure) and failure.error == "RuntimeError: boom went the job"
    assert failure.name == "echo-boom" and not failure.user and FAILURES == [failure]

    client = mlflow.MlflowClient(uri)
    runs = {r.info.run_name: r for r in client.search_runs([client.get_experiment_by_name("echoes").experiment_id])}
    assert set(runs) == {"echo-hello", "echo-boom"}
    ok, bad = runs["echo-hello"], runs["echo-boom"]
    assert ok.info.status == "FINISHED" and bad.info.status == "FAILED"
    assert ok.data.tags["tcbench.kind"] == "echo" and ok.data.tags["tcbench.sweep_id"] == "s1"
    assert ok.data.tags["tcbench.seed"] == "3" and ok.data.params["message"] == "hello"
    assert ok.data.metrics["length"] == 5
    assert {a.path for a in client.list_artifacts(ok.info.run_id)} == {"config.yaml", "said.txt"}
    assert "boom went the job" in bad.data.tags["tcbench.error"]


def test_untracked_jobs_of_a_new_kind_fail_into_the_list(echo: None) -> None:
    FAILURES.clear()
    track = {"enabled": False}
    assert run_job({"kind": "echo", "message": "hi", "seed": 0, "tracking": track}) == "hi"
    assert isinstance(run_job({"kind": "echo", "message": "boom", "seed": 0, "tracking": track}), JobFailure)
    assert [f.name for f in FAILURES] == ["echo-boom"]
