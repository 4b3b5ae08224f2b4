"""The BBOB task (ioh's functions 1-24) and the IOHprofiler log of any single-objective run."""

from __future__ import annotations

import json
import subprocess
import warnings
from pathlib import Path

import gymnasium as gym
import ioh
import numpy as np
import pytest
from cli_here import tcbench as here
from gymnasium.utils.env_checker import check_env

import tcbench  # noqa: F401  (registers the envs)
from tcbench.cli import main
from tcbench.leaderboard.iohprofiler import (
    HEADER,
    IOHFormatError,
    RunLogger,
    merge,
    problem_meta,
    read_json,
    read_runs,
)
from tcbench.runner.loop import run_optimisation
from tcbench.tasks import BBOB_ID, FunctionEnv
from tcbench.tasks.bbob_env import BBOBEnv


def tcbench_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``tcbench ARGS`` run in this process (:mod:`cli_here`)."""
    return here(*args, cwd=cwd)


@pytest.mark.parametrize("function", [1, 8, 17, 24])
def test_check_env_passes(function: int) -> None:
    env = gym.make(BBOB_ID, function=function, dim=3, instance=2, budget=50)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(env.unwrapped)


@pytest.mark.parametrize("dim", [2, 5, 20])
def test_precision_is_zero_at_the_optimum_and_positive_elsewhere(dim: int) -> None:
    rng = np.random.default_rng(dim)
    for function in range(1, 25):
        for instance in (1, 7):
            env = BBOBEnv(function=function, dim=dim, instance=instance)
            problem = ioh.get_problem(function, instance, dim, ioh.ProblemClass.BBOB)
            np.testing.assert_array_equal(env.x_opt, problem.optimum.x)
            assert env.raw_f_opt == problem.optimum.y
            assert env.evaluate(env.x_opt[None, :])[0] == 0.0
            away = rng.uniform(-5, 5, (3, dim))
            assert np.all(env.evaluate(away) > 0.0)


def test_batch_equals_single_evaluations_and_info() -> None:
    rng = np.random.default_rng(0)
    x = rng.uniform(-5, 5, (9, 5))
    batch_env = BBOBEnv(function=21, dim=5, instance=3, budget=20)
    batch_env.reset(seed=0)
    f_batch, reward, terminated, truncated, info = batch_env.step(x)
    single_env = BBOBEnv(function=21, dim=5, instance=3, budget=20)
    single_env.reset(seed=0)
    f_single = np.array([single_env.step(row)[0][0] for row in x])
    np.testing.assert_array_equal(f_batch, f_single)
    np.testing.assert_array_equal(reward, -f_batch)
    raw = ioh.get_problem(21, 3, 5, ioh.ProblemClass.BBOB)
    np.testing.assert_allclose(f_batch, np.array([raw(list(r)) for r in x]) - raw.optimum.y, rtol=0, atol=1e-9)
    shared = FunctionEnv("sphere", dim=5).reset(seed=0)[1]
    assert set(shared) <= set(info) and {"raw_f_opt", "function", "instance"} <= set(info)
    assert info["f_opt"] == 0.0 and info["best_f"] == f_batch.min() and info["evaluations"] == 9
    np.testing.assert_array_equal(info["lower"], np.full(5, -5.0))
    np.testing.assert_array_equal(info["upper"], np.full(5, 5.0))
    assert not terminated and not truncated


def test_episode_ends_at_the_target_or_the_budget() -> None:
    env = BBOBEnv(function=1, dim=4, instance=1, budget=10)
    env.reset(seed=0)
    far = np.full((2, 4), 4.0)
    *_, terminated, truncated, _ = env.step(far)
    assert not terminated and not truncated
    x = np.vstack([far, env.x_opt, far])
    *_, terminated, truncated, info = env.step(x)
    assert terminated and not truncated and info["target_hit_at"] == 5
    keep = BBOBEnv(function=1, dim=4, instance=1, budget=4, stop_at_target=False)
    keep.reset(seed=0)
    *_, terminated, truncated, info = keep.step(np.vstack([keep.x_opt, far, far[:1]]))
    assert not terminated and truncated and info["target_hit_at"] == 1


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("task.function=0", "task: function must be an integer in 1..24 (the BBOB functions), got 0"),
        ("task.function=abc", "task.function"),
        ("task.dim=1", "task: dim must be an integer >= 2"),
        ("task.instance=0", "task: instance must be an integer >= 1, got 0"),
        ("task.shift=true", "task.shift: no such config key"),
    ],
)
def test_bad_bbob_config_is_one_line(override: str, message: str, workdir: Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "task=bbob", override]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], lines


def test_function_25_through_the_command_line(workdir: Path) -> None:
    out = tcbench_cli("run", "task=bbob", "task.function=25", cwd=workdir)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert lines == ["tcbench: error: task: function must be an integer in 1..24 (the BBOB functions), got 25"]
    assert not (workdir / "mlflow.db").exists()


def test_ioh_dir_is_refused_for_several_objectives(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "task=zdt1", "optimiser=ga", "tracking.ioh_dir=ioh"]) == 2
    assert "tracking.ioh_dir: IOHprofiler logs are for one objective" in capsys.readouterr().err


def test_logger_writes_what_ioh_analyzer_writes(tmp_path: Path) -> None:
    """Same evaluations, once logged by ioh's own Analyzer and once by tcbench: the same .dat,
    the same run summary."""
    rng = np.random.default_rng(3)
    for function in (1, 15, 21):
        env = BBOBEnv(function=function, dim=3, instance=2, budget=2000)
        env.reset(seed=0)
        analyzer = ioh.logger.Analyzer(root=str(tmp_path), folder_name=f"ioh{function}", algorithm_name="rs")
        env.problem.attach_logger(analyzer)
        ours = RunLogger(tmp_path / f"ours{function}", problem_meta(env, 0), "rs", seed=0)
        for k in range(25):  # random points closing in on the optimum: improvements of all sizes
            x = np.clip(env.x_opt + rng.normal(0.0, 5.0 * 0.5**k, (40, 3)), -5, 5)
            ours.record(x, env.step(x)[0])
        env.problem.reset()  # ioh writes a run's last line when it ends
        analyzer.close()
        ours.close()
        theirs_dat = next((tmp_path / f"ioh{function}").rglob("*.dat")).read_text()
        ours_dat = next((tmp_path / f"ours{function}").rglob("*.dat")).read_text()
        assert ours_dat == theirs_dat
        (theirs,) = read_json(next((tmp_path / f"ioh{function}").glob("*.json")))
        (mine,) = read_json(next((tmp_path / f"ours{function}").glob("*.json")))
        assert (mine.evals, mine.best_evals, mine.meta.instance) == (theirs.evals, theirs.best_evals, 2)
        assert mine.meta.function_id == theirs.meta.function_id == function
        assert mine.meta.function_name == theirs.meta.function_name
        assert mine.best_y == pytest.approx(theirs.best_y, abs=1e-9)


def _check_run_folder(folder: Path, function_id: int, name: str, dim: int, algorithm: str) -> np.ndarray:
    """Format checks of a one-run IOHprofiler folder; its rows [evaluations, raw_y]."""
    (meta_path,) = folder.glob("IOHprofiler_*.json")
    assert meta_path.name == f"IOHprofiler_f{function_id}_{name}.json"
    meta = json.loads(meta_path.read_text())
    assert meta["function_id"] == function_id and meta["function_name"] == name
    assert meta["maximization"] is False and meta["algorithm"]["name"] == algorithm
    assert meta["attributes"] == ["evaluations", "raw_y"] and meta["run_attributes"] == ["seed"]
    (scenario,) = meta["scenarios"]
    assert scenario["dimension"] == dim and scenario["path"] == f"data_f{function_id}_{name}/IOHprofiler_f{function_id}_DIM{dim}.dat"
    (run,) = scenario["runs"]
    lines = (folder / scenario["path"]).read_text().splitlines()
    assert lines[0] == HEADER and HEADER not in lines[1:]
    rows = np.array([[float(v) for v in line.split()] for line in lines[1:]])
    evals = rows[:, 0].astype(int)
    assert evals[0] == 1 and evals[-1] == run["evals"] and np.all(np.diff(evals) > 0)
    improving = rows[:-1, 1]
    assert np.all(np.diff(improving) < -1e-10)  # every row but the last improves on the one before
    assert run["best"]["evals"] in evals and len(run["best"]["x"]) == dim
    assert run["best"]["y"] == pytest.approx(improving.min(), abs=1e-10)
    return rows


def test_cli_run_of_bbob_writes_ioh_files_and_mlflow(workdir: Path) -> None:
    out = tcbench_cli("run", "task=bbob", "task.function=3", "task.instance=2", "optimiser=pso", "seed=4",
                      "budget=3000", "tracking.ioh_dir=ioh", "tracking.plots=false", cwd=workdir)
    assert out.returncode == 0, out.stderr
    (folder,) = (workdir / "ioh" / "pso").iterdir()
    assert folder.name.startswith("bbob-f03-5d-s4-")
    rows = _check_run_folder(folder, 3, "Rastrigin", 5, "pso")
    assert rows[-1, 0] == 3000  # PSO does not reach 1e-8 on f3: the whole budget
    (run,) = read_runs(workdir / "ioh")
    assert (run.meta.suite, run.meta.instance, run.seed, run.attributes) == ("BBOB", 2, 4, {"budget": "3000"})
    import mlflow

    client = mlflow.MlflowClient(f"sqlite:///{workdir / 'mlflow.db'}")
    (tracked,) = client.search_runs([client.get_experiment_by_name("tcbench").experiment_id])
    assert tracked.data.tags["tcbench.task"] == "bbob-f03-5d"
    assert tracked.data.metrics["final_error"] == pytest.approx(run.raw_y.min(), abs=1e-9)


def test_cli_run_of_rastrigin_writes_ioh_files_without_tracking(workdir: Path) -> None:
    out = tcbench_cli("run", "task=rastrigin", "task.dim=3", "task.shift=true", "optimiser=ga", "seed=2",
                      "budget=800", "tracking.enabled=false", "tracking.ioh_dir=ioh", cwd=workdir)
    assert out.returncode == 0, out.stderr
    assert not (workdir / "mlflow.db").exists()
    (folder,) = (workdir / "ioh" / "ga").iterdir()
    rows = _check_run_folder(folder, 102, "Rastrigin", 3, "ga")
    assert rows[-1, 0] == 800
    (run,) = read_runs(workdir / "ioh")
    assert run.meta.suite == "tcbench" and run.meta.instance == 2 and run.seed == 2
    again = run_optimisation({"name": "rastrigin", "dim": 3, "shift": True}, {"name": "ga"}, 800, 2)
    assert run.best_so_far()[-1] == pytest.approx(again.error, abs=1e-10)


def test_runs_merge_into_one_folder_per_algorithm(tmp_path: Path) -> None:
    for seed in (0, 1):  # one instance, two seeds: IOHanalyzer wants them in one file
        for dim in (2, 3):
            run_optimisation({"name": "bbob", "function": 2, "dim": dim, "instance": 1}, {"name": "pso"}, 300, seed,
                             ioh_folder=tmp_path / "runs" / f"d{dim}-s{seed}", algorithm="pso")
    written = merge(tmp_path / "runs", tmp_path / "merged")
    assert sorted(p.name for p in written) == ["IOHprofiler_f2_DIM2.dat", "IOHprofiler_f2_DIM3.dat",
                                               "IOHprofiler_f2_Ellipsoid.json"]
    (merged_json,) = (tmp_path / "merged" / "pso").glob("*.json")
    runs = read_json(merged_json)
    assert [(r.meta.dim, r.seed) for r in runs] == [(2, 0), (2, 1), (3, 0), (3, 1)]
    dat = (tmp_path / "merged" / "pso" / "data_f2_Ellipsoid" / "IOHprofiler_f2_DIM2.dat").read_text()
    assert dat.count(HEADER) == 2
    originals = {(r.meta.dim, r.seed): r for r in read_runs(tmp_path / "runs")}
    for r in runs:
        np.testing.assert_array_equal(r.raw_y, originals[(r.meta.dim, r.seed)].raw_y)


def test_a_broken_folder_is_named(tmp_path: Path) -> None:
    run_optimisation({"name": "bbob", "function": 1, "dim": 2, "instance": 1}, {"name": "pso"}, 100, 0,
                     ioh_folder=tmp_path / "run")
    dat = next((tmp_path / "run").rglob("*.dat"))
    dat.write_text(dat.read_text() + HEADER + "\n1 2.0\n")
    with pytest.raises(IOHFormatError, match="1 runs in dimension 2 but 2 blocks"):
        read_runs(tmp_path)


def test_cmaes_solves_f1_in_5d() -> None:
    pytest.importorskip("tcbench_peers")
    result = run_optimisation({"name": "bbob", "function": 1, "dim": 5, "instance": 1}, {"name": "cmaes"},
                              50_000, 0)
    assert result.error <= 1e-8 and result.target_hit_at is not None
    # Stopped at the target, as COCO does: the generation that reached it is the last one.
    assert result.target_hit_at <= result.evaluations < result.target_hit_at + 8 < 50_000


def test_leaderboard_pairs_bbob_runs_by_instance_and_seed() -> None:
    """Instances of one function share the seed in a plain sweep; the paired test pairs them
    by (instance, seed) instead of failing on repeated seeds."""
    import pandas as pd

    from tcbench.leaderboard.optimisation import summarise

    rng = np.random.default_rng(0)
    rows = [{"method": m, "status": "FINISHED", "seed": 0, "instance": i, "final_error": e,
             "final_best": e, "target_hit": False, "evaluations": 100, "budget": 100, "evals_to_target": np.nan}
            for m, shift in (("a", 0.0), ("b", 1.0)) for i, e in enumerate(rng.uniform(0, 1, 8) + shift, 1)]
    table = summarise(pd.DataFrame(rows))
    assert table["method"].tolist() == ["a", "b"] and table["seeds"].tolist() == [8, 8]
    assert table["p_vs_next"].iloc[0] < 0.05  # b is worse on every instance
