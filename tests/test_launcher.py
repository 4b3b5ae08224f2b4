"""tcbench's sweeper and launcher (hydra_plugins/tcbench_launcher): one compose per combination
of non-seed values, every job run once with its own seed and folder, in one process or in
worker processes, and the per-run convergence PNG left to the leaderboard in a sweep."""

from __future__ import annotations

import logging
from pathlib import Path

import mlflow
import pytest
import yaml
from cli_here import tcbench
from hydra_plugins.tcbench_launcher import launcher
from test_parallel import check_runs


def test_jobs_are_grouped_by_everything_but_the_seed() -> None:
    jobs = [["optimiser=fa", "seed=0"], ["optimiser=ifa", "seed=0"], ["seed=1", "optimiser=fa"],
            ["optimiser=ifa", "seed=1"], ["optimiser=ga"]]
    assert launcher.groups(jobs) == {("optimiser=fa",): [0, 2], ("optimiser=ifa",): [1, 3], ("optimiser=ga",): [4]}
    assert launcher.split_seed(["a=1", "seed=7"]) == (("a=1",), "7")
    assert launcher.split_seed(["a=1"]) == (("a=1",), None)
    assert launcher.split_seed(["seed=${task.instance}"]) == (("seed=${task.instance}",), None)


def test_a_seed_from_an_interpolation_is_composed(workdir: Path) -> None:
    from tcbench.cli import main

    code = main(["run", "-m", "task=sphere", "task.dim=2", "budget=60", "optimiser=fa,ifa", "seed=${budget}",
                 "tracking.experiment=interp"])
    assert code == 0
    paths = sorted(workdir.glob("multirun/*/*/*/.hydra/config.yaml"))
    assert [yaml.safe_load(p.read_text())["seed"] for p in paths] == [60, 60]


def compose_counter(monkeypatch: pytest.MonkeyPatch) -> list[list[str]]:
    """Record every config Hydra composes for a sweep's jobs."""
    from hydra._internal.config_loader_impl import ConfigLoaderImpl

    calls: list[list[str]] = []
    original = ConfigLoaderImpl.load_sweep_config

    def counted(self, master_config, sweep_overrides):  # type: ignore[no-untyped-def]
        calls.append(list(sweep_overrides))
        return original(self, master_config, sweep_overrides)

    monkeypatch.setattr(ConfigLoaderImpl, "load_sweep_config", counted)
    return calls


@pytest.mark.parametrize("launcher_args, composes", [([], 2), (["hydra/sweeper=basic", "hydra/launcher=basic"], 12)])
def test_one_compose_per_group_and_every_job_once(workdir: Path, monkeypatch, launcher_args, composes) -> None:
    """6 jobs in 2 groups: the launcher composes one config per group (2; the sweeper leaves the
    check to it), where Hydra's basic pair composes each job twice (6 + 6); the runs are the same."""
    from tcbench.cli import main

    calls = compose_counter(monkeypatch)
    code = main(["run", "-m", "task=sphere", "task.dim=2", "budget=60", "optimiser=fa,ifa", "seed=range(3)",
                 "tracking.experiment=grouped", *launcher_args])
    assert code == 0
    assert len(calls) == composes
    check_runs(mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}"), "grouped",
               {(o, s) for o in ("fa", "ifa") for s in range(3)})
    configs = sorted(workdir.glob("multirun/*/*/*/.hydra/config.yaml"))
    assert len(configs) == 6
    seen = set()
    for path in configs:
        cfg = yaml.safe_load(path.read_text())
        overrides = yaml.safe_load(path.with_name("overrides.yaml").read_text())
        assert f"seed={cfg['seed']}" in overrides and f"optimiser={cfg['optimiser']['name']}" in overrides
        seen.add((cfg["optimiser"]["name"], cfg["seed"]))
    assert len(seen) == 6


def test_a_group_that_does_not_compose_stops_the_launch_before_any_job_folder(tmp_path: Path) -> None:
    """With no check by the sweeper ahead of it, the launcher composes every group before it writes a
    job folder: a config that does not compose leaves the sweep folder unmade."""
    from types import SimpleNamespace

    from hydra.errors import ConfigCompositionException
    from omegaconf import OmegaConf

    from hydra_plugins.tcbench_launcher.launcher import GroupedLauncher

    class Refusing:
        def load_sweep_config(self, master_config, sweep_overrides):  # type: ignore[no-untyped-def]
            raise ConfigCompositionException(f"cannot compose {sweep_overrides}")

    launcher = GroupedLauncher()
    launcher.config = OmegaConf.create({"hydra": {"sweep": {"dir": str(tmp_path / "multirun")}}})
    launcher.hydra_context = SimpleNamespace(config_loader=Refusing())  # type: ignore[assignment]
    with pytest.raises(ConfigCompositionException, match="optimiser=nope"):
        launcher.launch([["optimiser=nope", "seed=0"], ["optimiser=nope", "seed=1"]], 0)
    assert not (tmp_path / "multirun").exists()


def test_the_sweeper_checks_one_config_per_group_ahead_of_another_launcher_only() -> None:
    from types import SimpleNamespace

    from omegaconf import OmegaConf

    from hydra_plugins.tcbench_launcher.launcher import GroupedLauncher, GroupingSweeper

    checked: list[list[str]] = []
    loader = SimpleNamespace(
        load_sweep_config=lambda master_config, sweep_overrides: checked.append(sweep_overrides))
    sweeper = GroupingSweeper(max_batch_size=None)
    sweeper.config = OmegaConf.create({})
    sweeper.hydra_context = SimpleNamespace(config_loader=loader)  # type: ignore[assignment]
    batch = [["optimiser=fa", "seed=0"], ["optimiser=fa", "seed=1"], ["optimiser=ifa", "seed=0"]]
    sweeper.launcher = object()  # type: ignore[assignment]  # e.g. joblib's, composing in other processes
    sweeper.validate_batch_is_legal(batch)
    assert checked == [["optimiser=fa", "seed=0"], ["optimiser=ifa", "seed=0"]]
    sweeper.launcher = GroupedLauncher()
    sweeper.validate_batch_is_legal(batch)
    assert len(checked) == 2  # tcbench's launcher composes them itself before any job


@pytest.mark.slow  # the workers' crash and kill cases on two workers (tests/test_sweep_failures.py) stay in CI
def test_two_worker_processes_record_every_run_once(workdir: Path) -> None:
    """The launcher's fresh worker processes, started from this process (4 jobs on 2 workers)."""
    out = tcbench("run", "-m", "task=sphere", "task.dim=2", "budget=60", "optimiser=fa", "seed=range(4)",
                  "tracking.experiment=workers", "hydra.launcher.n_jobs=2", cwd=workdir)
    assert out.returncode == 0, out.stderr
    assert "on 2 worker processes" in out.stderr + out.stdout
    check_runs(mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}"), "workers", {("fa", s) for s in range(4)})


def test_an_untracked_job_that_raises_fails_the_sweep(workdir: Path, capsys) -> None:
    """Without tracking nothing records a failure: the other jobs still run, the command lists
    the failures and exits 1 (it used to end in Hydra's traceback)."""
    from test_tracking import Exploding

    from tcbench.cli import main
    from tcbench.optimisers import register

    register("exploding", Exploding)
    code = main(["run", "-m", "task=sphere", "task.dim=2", "budget=200", "seed=range(2)", "tracking.enabled=false",
                 "optimiser=fa", "optimiser.name=fa,exploding"])
    out = capsys.readouterr().out
    assert code == 1
    assert "2 of 4 jobs failed" in out and out.count("  FAILED exploding-sphere-2d") == 2


@pytest.mark.figures  # the one run's convergence figure drawn in this process
def test_sweeps_leave_the_convergence_png_to_the_leaderboard(workdir: Path) -> None:
    """``tracking.plots: null``: a single run logs its convergence PNG, the runs of a sweep do not
    (unless ``tracking.plots=true``)."""
    assert tcbench("run", "task=sphere", "task.dim=2", "budget=60", "tracking.experiment=one", cwd=workdir).returncode == 0
    assert tcbench("run", "-m", "task=sphere", "task.dim=2", "budget=60", "seed=range(2)", "tracking.experiment=many",
                   cwd=workdir).returncode == 0
    assert tcbench("run", "-m", "task=sphere", "task.dim=2", "budget=60", "seed=range(2)", "tracking.experiment=asked",
                   "tracking.plots=true", cwd=workdir).returncode == 0
    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")

    def pngs(experiment: str) -> list[int]:
        exp = client.get_experiment_by_name(experiment)
        return [sum(a.path.endswith(".png") for a in client.list_artifacts(r.info.run_id))
                for r in client.search_runs([exp.experiment_id])]

    assert pngs("one") == [1]
    assert pngs("many") == [0, 0]
    assert pngs("asked") == [1, 1]


def test_the_plan_counts_a_command_line_value_over_the_configs_params() -> None:
    """``experiment=optim_suite_mo`` sweeps 4 tasks x 4 optimisers x 15 seeds from its params;
    ``task=zdt1 seed='range(2)'`` on the command line replaces two of them, as Hydra does."""
    from tcbench.cli.app import plan

    assert plan(["-m", "experiment=optim_suite_mo", "task=zdt1", "seed=range(2)"]).jobs == 8
    assert plan(["-m", "experiment=optim_suite_mo"]).jobs == 4 * 4 * 15


def test_the_sweep_progress_counts_every_kind_of_job_and_its_failures(caplog: pytest.LogCaptureFixture) -> None:
    from hydra_plugins.tcbench_launcher.launcher import Progress

    progress = Progress(3)
    with caplog.at_level(logging.INFO, logger="hydra_plugins.tcbench_launcher.launcher"):
        for i, ok in enumerate((True, False, True)):
            progress(i, ok)
    lines = [r.getMessage() for r in caplog.records]
    assert [ln.split(" jobs done")[0] for ln in lines] == ["sweep: 1/3", "sweep: 2/3", "sweep: 3/3"]
    assert "(1 failed)" in lines[-1] and "about 0 s left" in lines[-1]
