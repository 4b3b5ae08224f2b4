"""Job tracking: failed runs recorded and counted, NaN objectives reported, leaderboard maths."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tcbench.leaderboard import optimisation as leaderboard
from tcbench.tracking import store as tracking
from tcbench.runner.job import JobFailure, run_job
from tcbench.optimisers import register
from tcbench.optimisers.fa import FireflyAlgorithm
from tcbench.tasks.function_env import FunctionEnv

BASE = {
    "task": {"name": "sphere", "dim": 2, "shift": False, "target_precision": 1e-2, "lower": None, "upper": None},
    "optimiser": {"name": "fa", "population": 10},
    "seed": 0,
    "budget": 100,
    "progress": False,
    "tracking": {"enabled": True, "uri": None, "experiment": "t", "sweep_id": "s1", "plots": False},
}


def cfg(**changes) -> dict:
    c = copy.deepcopy(BASE)
    for key, value in changes.items():
        section, _, field = key.partition("__")
        if field:
            c[section][field] = value
        else:
            c[section] = value
    return c


class Exploding(FireflyAlgorithm):
    name = "exploding"

    def _tell(self, x, f):
        super()._tell(x, f)
        if self.generation == 2:
            raise RuntimeError("boom in generation 2")


def test_failed_job_is_recorded_and_counted(workdir: Path) -> None:
    register("exploding", Exploding)
    assert run_job(cfg(seed=0)) is not None
    assert isinstance(run_job(cfg(optimiser={"name": "exploding"}, seed=0)), JobFailure)
    assert isinstance(run_job(cfg(optimiser={"name": "exploding"}, seed=1)), JobFailure)
    client = tracking.client()
    runs = leaderboard.load_runs(client, ["t"], "s1")
    assert sorted(runs["status"]) == ["FAILED", "FAILED", "FINISHED"]
    failed = runs[runs["status"] == "FAILED"]
    assert (failed["error_message"] == "RuntimeError: boom in generation 2").all()
    (board,) = leaderboard.boards(runs)
    row = board.table.set_index("method").loc["exploding"]
    assert row["seeds"] == 2 and row["failed"] == 2 and row["success_rate"] == 0
    paths = leaderboard.write(board, workdir / "lb", client, "test")
    assert "exploding seed 1: FAILED RuntimeError: boom" in paths["md"].read_text()


def test_nonfinite_objective_reported(workdir: Path, monkeypatch) -> None:
    real = FunctionEnv.evaluate

    def sometimes_nan(self, x):
        f = real(self, x)
        f[::4] = np.nan  # 3 of every batch of 10
        return f

    monkeypatch.setattr(FunctionEnv, "evaluate", sometimes_nan)
    result = run_job(cfg())
    assert result is not None and result.nonfinite == 30 and np.isfinite(result.best_f)
    (run,) = tracking.client().search_runs([tracking.client().get_experiment_by_name("t").experiment_id])
    assert run.data.metrics["nonfinite_evaluations"] == 30
    assert run.data.tags["tcbench.warning"] == "30 NaN/inf evaluations"


def test_same_seed_same_result_untracked() -> None:
    a = run_job(cfg(tracking__enabled=False, task__shift=True, seed=4))
    b = run_job(cfg(tracking__enabled=False, task__shift=True, seed=4))
    c = run_job(cfg(tracking__enabled=False, task__shift=True, seed=5))
    assert a.best_f == b.best_f and a.trace.mean_f == b.trace.mean_f
    assert a.best_f != c.best_f


def test_tracking_uri_precedence(workdir: Path, monkeypatch) -> None:
    assert tracking.tracking_uri() == f"sqlite:///{workdir / 'mlflow.db'}"
    monkeypatch.setenv("MLFLOW_TRACKING_URI", "sqlite:////tmp/elsewhere.db")
    assert tracking.tracking_uri() == "sqlite:////tmp/elsewhere.db"
    assert tracking.tracking_uri("http://127.0.0.1:5000") == "http://127.0.0.1:5000"


def test_flatten_and_hash() -> None:
    flat = tracking.flatten({"a": {"b": 1, "c": [1, 2]}, "d": None})
    assert flat == {"a.b": "1", "a.c": "[1, 2]", "d": "None"}
    assert tracking.config_hash(cfg(seed=1)) == tracking.config_hash(cfg(seed=2))
    assert tracking.config_hash(cfg()) != tracking.config_hash(cfg(budget=200))


def test_expected_running_time_by_hand() -> None:
    # three runs: hits after 40 and 60 evaluations, one miss that spent 100 -> (40+60+100)/2
    ert = leaderboard.expected_running_time(
        np.array([100, 100, 100]), np.array([40, 60, np.nan]), np.array([True, True, False])
    )
    assert ert == 100.0
    assert leaderboard.expected_running_time(np.array([5.0]), np.array([np.nan]), np.array([False])) == np.inf


def test_summarise_ranks_and_statistics() -> None:
    rows = []
    for method, errors, hits in [("a", [1.0, 2.0, 3.0, 4.0], [0, 0, 0, 0]), ("b", [0.0, 0.0, 5.0, 9.0], [1, 1, 0, 0])]:
        for seed, (e, h) in enumerate(zip(errors, hits)):
            rows.append({
                "method": method, "seed": seed, "status": "FINISHED", "final_error": e, "final_best": e - 1.0,
                "target_hit": bool(h),
                "evaluations": 100.0, "evals_to_target": 50.0 if h else np.nan, "budget": 100,
            })
    table = leaderboard.summarise(pd.DataFrame(rows)).set_index("method")
    assert table.loc["b", "rank"] == 1 and table.loc["a", "rank"] == 2  # success rate first
    assert table.loc["a", "median_best"] == 1.5
    assert table.loc["a", "median_error"] == 2.5 and table.loc["a", "iqr_error"] == pytest.approx(1.5)
    assert table.loc["b", "success_rate"] == 0.5 and table.loc["b", "ert_evals"] == 150.0
    assert table.loc["a", "ert_evals"] == np.inf


def test_a_method_that_crashes_on_most_seeds_does_not_rank_first() -> None:
    """A method that failed on 7 of 12 seeds was ranked above FA (0 failed) on the median of the
    5 it finished: a failed run is a failure to reach the target, in the rank and in the median
    it shows ("failed": more than half its runs failed)."""
    rows = []
    for method, errors, failed in [("fa", [5.0] * 12, 0), ("crashy", [3.0] * 12, 7)]:
        for seed, e in enumerate(errors):
            ok = seed >= failed
            rows.append({"method": method, "seed": seed, "status": "FINISHED" if ok else "FAILED",
                         "final_error": e if ok else np.nan, "final_best": e if ok else np.nan,
                         "target_hit": False, "evaluations": 100.0 if ok else np.nan,
                         "evals_to_target": np.nan, "budget": 100})
    table = leaderboard.summarise(pd.DataFrame(rows)).set_index("method")
    assert table.loc["fa", "rank"] == 1 and table.loc["crashy", "rank"] == 2
    assert table.loc["crashy", "failed"] == 7 and np.isinf(table.loc["crashy", "median_error"])


def test_a_compensation_method_that_crashes_on_most_restarts_does_not_rank_first() -> None:
    from tcbench.leaderboard.compensation import summarise
    from tcbench.compensation.scoring import METRIC_NAMES as METRICS
    from tcbench.compensation.scoring import PRIMARY

    protocol = "fulltemp"
    primary = PRIMARY[protocol]
    rows = []
    for method, value, failed in [("steady", 5.0, 0), ("crashy", 3.0, 7)]:
        for seed in range(12):
            ok = seed >= failed
            rows.append({"method": method, "seed": seed, "status": "FINISHED" if ok else "FAILED",
                         **{m: (value if ok else np.nan) for m in METRICS[protocol]},
                         f"raw_{primary}": 50.0})
    table = summarise(pd.DataFrame(rows), protocol).set_index("method")
    assert table.loc["steady", "rank"] == 1 and table.loc["crashy", "rank"] == 2


def test_sweep_goes_on_after_a_failing_job(workdir: Path, capsys) -> None:
    """A multirun in which some jobs raise: they are FAILED in MLflow, the others finish,
    and the command lists the failures and exits 1."""
    from tcbench.cli import main

    register("exploding", Exploding)
    code = main([
        "run", "-m", "task=sphere", "budget=60", "seed=range(2)", "tracking.experiment=sweep",
        "optimiser=fa", "+optimiser.label=x", "optimiser.name=fa,exploding",
    ])
    out = capsys.readouterr().out
    assert code == 1
    assert "4 jobs recorded" in out and "2 finished, 2 failed" in out
    assert out.count("FAILED x on sphere-2d seed") == 2 and "boom in generation 2" in out


def test_resume_skips_finished_jobs(workdir: Path) -> None:
    register("exploding", Exploding)
    first = [run_job(cfg(seed=s)) for s in range(2)] + [run_job(cfg(optimiser={"name": "exploding"}, seed=0))]
    assert first[0] is not None and isinstance(first[2], JobFailure)
    again = [run_job(cfg(seed=s, tracking__resume=True, tracking__sweep_id="s2")) for s in range(3)]
    assert again[0] is None and again[1] is None and again[2] is not None  # only seed 2 ran
    redo = run_job(cfg(optimiser={"name": "exploding"}, seed=0, tracking__resume=True, tracking__sweep_id="s2"))
    assert isinstance(redo, JobFailure)  # FAILED before, so it was tried again (and failed again)
    runs = leaderboard.load_runs(tracking.client(), ["t"])
    assert len(runs) == 5  # 3 first attempts, 1 new seed, 1 retried failure
    (board,) = leaderboard.boards(runs)
    table = board.table.set_index("method")
    assert table.loc["fa", "seeds"] == 3 and table.loc["exploding", "seeds"] == 1


def test_repeated_job_counted_once(workdir: Path) -> None:
    run_job(cfg(seed=0))
    run_job(cfg(seed=0))
    (board,) = leaderboard.boards(leaderboard.load_runs(tracking.client(), ["t"]))
    assert board.table.loc[0, "seeds"] == 1
