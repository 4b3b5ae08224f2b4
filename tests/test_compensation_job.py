"""A compensation job is prepared once (:mod:`tcbench.runner.compensation_job`): checked into a
typed job whose env is built once per job in a process, with the learner of its composed config
(a compensation task's defaults list chooses ``bp`` when the command line gives none)."""

from __future__ import annotations

import pickle
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from tcbench.cli.app import expand
from tcbench.cli.main import main
from tcbench.config_dir import conf_dir
from tcbench.errors import ConfigError
from tcbench.runner.job import JobFailure, run_job
from tcbench.runner.kinds import kind_of
from tcbench.tracking.store import config_hash

ZEROBIAS = "tcbench/MSRA-ZeroBias-v0"
QUICK = ["task=msra_zerobias", "learner=poly", "optimiser=none", "tracking.enabled=false"]


def _job(*overrides: str) -> dict[str, Any]:
    ((_, c),) = expand([*overrides], "config")
    return c


def test_a_compensation_job_builds_its_env_once(workdir: Path, builds: list[str]) -> None:
    """``tcbench run``: the plan check's env is the one the job runs on; in a sweep each job runs
    on an env of its own (an env is reset once)."""
    assert main(["run", *QUICK]) == 0
    assert builds == [ZEROBIAS]
    builds.clear()
    assert main(["run", "-m", *QUICK, "seed=0,1"]) == 0
    assert builds == [ZEROBIAS, ZEROBIAS]


def test_the_prepared_job_is_what_the_kind_runs_records_and_names(builds: list[str]) -> None:
    c = _job(*QUICK, "seed=3", "learner.degree=2", "budget=7")
    kind = kind_of(c)
    job = kind.job(c)
    assert builds == [ZEROBIAS]
    assert job.learner.name == "poly" and job.learner.params["degree"] == 2 and "name" not in job.learner.params
    assert job.optimiser.name == "none" and (job.budget, job.seed) == (7, 3)
    assert job.names == kind.names(c) and job.names.run == "poly2-msra_zerobias-dev0-s3"
    assert job.env.learner_name == "poly" and job.env.budget == 7 and job.env.data is None  # not yet reset
    assert job.task_kwargs == {k: v for k, v in job.task.items() if k != "name"}
    result = kind.execute(job)
    assert builds == [ZEROBIAS] and job.env.data is not None  # ran on the prepared env
    assert kind.summary(result, job).startswith("poly2-msra_zerobias-dev0-s3: zb_zero_start_ug ")
    restored = pickle.loads(pickle.dumps(job))  # a prepared job can cross to a worker process
    assert restored.names == job.names and restored.learner == job.learner


def test_a_planned_env_serves_one_job_of_the_same_arguments_only(builds: list[str]) -> None:
    kind = kind_of(_job(*QUICK))
    kind.plan_check(_job(*QUICK))
    other = kind.job(_job(*QUICK, "learner.degree=2"))  # other arguments: its own env
    first, second = kind.job(_job(*QUICK, "seed=4")), kind.job(_job(*QUICK))
    assert builds == [ZEROBIAS] * 3
    assert len({id(other.env), id(first.env), id(second.env)}) == 3


def test_the_checks_stay_one_line_naming_the_key(builds: list[str]) -> None:
    kind = kind_of(_job(*QUICK))
    with pytest.raises(ConfigError, match=r"^learner.offsets=per_run: task gyro_driftnoise"):
        kind.job(_job("task=gyro_driftnoise", "learner=poly", "learner.offsets=per_run", "optimiser=none"))
    with pytest.raises(ConfigError, match=r"^budget of 5 evaluations is smaller than one generation \(optimiser "
                                          r"ifa: population 10\)"):
        kind.job(_job("task=msra_zerobias", "budget=5"))
    with pytest.raises(ConfigError, match=r"^learner: a compensation task needs one; known: bp, .*raw"):
        kind.job({**_job(*QUICK), "learner": None})


def test_the_default_learner_comes_from_the_composed_config(monkeypatch: pytest.MonkeyPatch) -> None:
    """No ``learner=``: a compensation task's defaults list composes ``learner/bp.yaml`` (the
    config, its run name and its hash as when the runner read that file); the command line and an
    experiment choose another; optimisation tasks get none (they refuse one)."""
    bp = yaml.safe_load((conf_dir() / "learner" / "bp.yaml").read_text())
    for task in ("msra_zerobias", "msra_fulltemp", "accel_chamber", "gyro_driftnoise"):
        c = _job(f"task={task}")
        assert c["learner"] == bp and list(c) == list(_job(f"task={task}", "learner=poly"))
        assert config_hash(c) == config_hash({**c, "learner": dict(bp)})
    c = _job("task=msra_fulltemp")
    assert kind_of(c).names(c).run == "IFA-BP-gd-msra_fulltemp-dev0-s0"
    assert _job("task=msra_zerobias", "learner=elman")["learner"]["name"] == "elman"
    assert _job("experiment=movmd_tfpf")["learner"]["name"] == "elman"  # the experiment's, not the task's
    assert _job("experiment=quickstart")["learner"] == bp
    assert _job("task=sphere")["learner"] is None and _job()["learner"] is None
    read = Path.read_text
    monkeypatch.setattr(Path, "read_text", lambda self, *a, **k: pytest.fail(f"read {self}") if self.name == "bp.yaml"
                        else read(self, *a, **k))
    job = kind_of(c).job(c)  # the runner reads no learner file of its own
    assert job.learner.name == "bp" and job.learner.params == {k: v for k, v in bp.items() if k != "name"}


def test_a_job_without_a_learner_fails_with_one_line(workdir: Path) -> None:
    c = {**_job(*QUICK), "learner": None}
    failure = run_job(c)
    assert isinstance(failure, JobFailure) and failure.user and failure.error.startswith("learner: ")


def test_a_null_recordings_seed_makes_restart_i_meet_draw_i(builds: list[str]) -> None:
    """``task.recordings_seed=null``: the job trains and tests on draw ``seed`` — the very runs a job
    with ``task.recordings_seed=<seed>`` meets — and tags its draw, so a board pairs it with its limits
    on the same draw (:mod:`tcbench.leaderboard.paired`); a fixed seed tags that draw whatever the seed."""
    kind = kind_of(_job(*QUICK))
    drawn = kind.job(_job(*QUICK, "task.recordings_seed=null", "seed=4"))
    fixed = kind.job(_job(*QUICK, "task.recordings_seed=4", "seed=0"))
    other = kind.job(_job(*QUICK, "task.recordings_seed=null", "seed=5"))
    assert drawn.names.tags["tcbench.draw"] == "4" and fixed.names.tags["tcbench.draw"] == "4"
    assert other.names.tags["tcbench.draw"] == "5"
    # the tier is a tag from the start: a run killed before it sends its params still has it
    assert {job.names.tags["tcbench.split"] for job in (drawn, fixed, other)} == {"next_run"}
    for job in (drawn, fixed, other):
        job.env.reset(seed=0)
    same = [np.array_equal(a.recording.output, b.recording.output)
            for a, b in zip(drawn.env.data.train + drawn.env.data.test, fixed.env.data.train + fixed.env.data.test,
                            strict=True)]
    assert all(same)
    assert not np.array_equal(drawn.env.data.test[0].recording.output, other.env.data.test[0].recording.output)
    assert drawn.names.task == fixed.names.task == "msra_zerobias-dev0"  # one board: the draws pair on it
