"""An optimisation job is prepared once (:mod:`tcbench.runner.optimisation_job`): checked into a
typed job whose env is built once per job in a process and reused by its plan check, its run and
the ask/tell loop (``builds``, the fixture of tests/conftest.py, counts ``gym.make``)."""

from __future__ import annotations

import pickle
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from hydra_plugins.tcbench_launcher.launcher import _run_one
from tcbench.cli.app import expand
from tcbench.cli.main import main
from tcbench.errors import ConfigError
from tcbench.runner.config import validate
from tcbench.runner.kinds import kind_of
from tcbench.runner.kinds.optimisation import ioh_folder
from tcbench.runner.loop import make_task, run_optimisation

RASTRIGIN, SPHERE = "tcbench/Rastrigin-v0", "tcbench/Sphere-v0"
QUICK = ["task=rastrigin", "optimiser=ifa", "budget=200", "tracking.enabled=false"]


def _job(*overrides: str) -> dict[str, Any]:
    ((_, c),) = expand([*overrides], "config")
    return c


def test_an_optimisation_job_builds_its_env_once(workdir: Path, builds: list[str]) -> None:
    """``tcbench run``: the plan check's env is the one the job and its loop run on; in a sweep
    run in this process, each job after the first builds one of its own."""
    assert main(["run", *QUICK]) == 0
    assert builds == [RASTRIGIN]
    builds.clear()
    assert main(["run", "-m", *QUICK, "seed=0,1,2"]) == 0
    assert builds == [RASTRIGIN] * 3


def test_a_sweep_worker_builds_one_env_per_job(builds: list[str]) -> None:
    """A worker process runs each job's config (``_run_one``) with no plan check of its own: one
    env per job, and the same run as one that builds its env in the loop."""
    results = [_run_one(_job(*QUICK, f"seed={s}")) for s in (0, 1)]
    assert builds == [RASTRIGIN] * 2
    assert all(ok for ok, _ in results)
    builds.clear()
    alone = run_optimisation({"name": "rastrigin", "dim": 2}, {"name": "ifa"}, 200, 1)
    assert builds == [RASTRIGIN]
    assert alone.trace == results[1][1].trace and alone.best_f == results[1][1].best_f


def test_the_prepared_job_is_what_the_kind_runs_records_and_names(builds: list[str], tmp_path: Path) -> None:
    c = _job(*QUICK, "seed=3", "+optimiser.label=IFA-x", "optimiser.population=8", "budget=40",
             f"tracking.ioh_dir={tmp_path / 'ioh'}")
    kind = kind_of(c)
    job = kind.job(c)
    assert builds == [RASTRIGIN]
    assert job.optimiser.name == "ifa" and job.optimiser.label == "IFA-x" and job.optimiser.params["population"] == 8
    assert job.optimiser_config == {"name": "ifa", **job.optimiser.params} and "label" not in job.optimiser_config
    assert (job.budget, job.seed, job.progress, job.plots) == (40, 3, False, None)
    assert job.names == kind.names(c) and job.names.run == "IFA-x-rastrigin-2d-s3"
    assert job.ioh_folder == ioh_folder(c) and job.ioh_folder is not None
    assert job.task_kwargs == {k: v for k, v in job.task.items() if k != "name"}
    assert job.env.budget == 40 and job.env.evaluations == 0 and job.env._np_random is None  # not yet reset
    result = kind.execute(job)
    assert builds == [RASTRIGIN] and job.env.evaluations == result.evaluations == 40  # ran on the prepared env
    assert kind.summary(result, job).startswith("IFA-x on rastrigin-2d seed 3: best ")
    assert any(job.ioh_folder.rglob("*.json"))  # its IOHprofiler log where the job said
    restored = pickle.loads(pickle.dumps(job))  # a prepared job can cross to a worker process
    assert restored.names == job.names and restored.optimiser == job.optimiser and restored.env_key == job.env_key


def test_run_optimisation_on_a_built_env_is_the_run_it_builds(builds: list[str]) -> None:
    """Other callers give ``run_optimisation`` only the configs; given the env it builds from
    them, it builds none and runs the same."""
    task, opt = {"name": "sphere", "dim": 3, "shift": True}, {"name": "pso"}
    built = run_optimisation(task, opt, 300, 5)
    env = make_task(task, 300)
    assert builds == [SPHERE] * 2
    given = run_optimisation(task, opt, 300, 5, env=env)
    assert builds == [SPHERE] * 2 and env.evaluations == 300
    assert given.trace == built.trace and np.array_equal(given.best_x, built.best_x)


def test_a_planned_env_serves_one_job_of_the_same_arguments_only(builds: list[str]) -> None:
    kind = kind_of(_job(*QUICK))
    kind.plan_check(_job(*QUICK))
    other = kind.job(_job(*QUICK, "budget=300"))  # other env arguments: its own env
    first, second = kind.job(_job(*QUICK, "seed=4", "optimiser=pso")), kind.job(_job(*QUICK))
    assert builds == [RASTRIGIN] * 3
    assert first.env.budget == 200 and other.env.budget == 300
    assert len({id(other.env), id(first.env), id(second.env)}) == 3
    builds.clear()
    kind.plan_check(_job(*QUICK))
    compensation = _job("task=msra_zerobias", "learner=poly", "optimiser=none", "tracking.enabled=false")
    kind_of(compensation).plan_check(compensation)  # one env is kept at most, of any kind
    kind.job(_job(*QUICK))
    assert builds == [RASTRIGIN, "tcbench/MSRA-ZeroBias-v0", RASTRIGIN]


@pytest.mark.parametrize(("overrides", "error"), [
    (["budget=5"], r"budget of 5 evaluations is smaller than one generation \(optimiser ifa: population 10\)"),
    (["task=zdt1"], r"optimiser ifa is single-objective; task zdt1 has 2 objectives"),
    (["task=zdt1", "optimiser=mopso", "tracking.ioh_dir=ioh"],
     r"tracking.ioh_dir: IOHprofiler logs are for one objective; task zdt1 has 2"),
    (["task=bbob", "task.dim=1"], r"task: dim must be an integer >= 2 \(ioh's BBOB problems start at 2-D\), got 1"),
    (["optimiser.population=0"], r"optimiser ifa: population must be >= 2, got 0"),
    (["learner=poly"], r"learner=poly: learners apply to compensation tasks \(msra_zerobias, .*\), not to task "
                       r"rastrigin"),
    (["seed=-1"], r"seed must be >= 0, got -1"),
])
def test_the_checks_stay_one_line_naming_the_key(builds: list[str], overrides: list[str], error: str) -> None:
    """The prepared job refuses what :func:`validate` refuses, with the same line."""
    c = _job(*QUICK, "budget=1000", *overrides)
    with pytest.raises(ConfigError, match=f"^{error}$") as by_validate:
        validate(c)
    with pytest.raises(ConfigError, match=f"^{error}$") as by_job:
        kind_of(c).job(c)
    assert str(by_job.value) == str(by_validate.value) and "\n" not in str(by_job.value)


def test_a_refused_job_exits_2_with_its_line(workdir: Path, builds: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", *QUICK, "budget=5"]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1] == (
        "tcbench: error: budget of 5 evaluations is smaller than one generation (optimiser ifa: population 10)")
    assert builds == [RASTRIGIN]
