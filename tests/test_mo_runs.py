"""Multi-objective tasks through the runner, tracking and leaderboard."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pandas as pd
import pytest

import tcbench  # noqa: F401
from tcbench.leaderboard import optimisation as leaderboard
from tcbench.tracking import store as tracking
from tcbench.runner.config import ConfigError, validate
from tcbench.runner.job import run_job
from tcbench.runner.loop import run_optimisation

TRACK = {"enabled": True, "uri": None, "experiment": "mo", "sweep_id": "s", "plots": False, "resume": False}


def job(optimiser: str, seed: int, budget: int = 400) -> dict:
    return {"task": {"name": "zdt1", "dim": 5, "shift": False, "target_precision": 1e-8, "lower": None,
                     "upper": None},
            "optimiser": {"name": optimiser}, "seed": seed, "budget": budget, "progress": False,
            "tracking": dict(TRACK)}


def test_mo_envs_registered() -> None:
    env = gym.make("tcbench/DTLZ2-v0")
    assert env.unwrapped.n_objectives == 3


def test_runner_reports_hypervolume_and_igd() -> None:
    r = run_optimisation({"name": "zdt1", "dim": 5}, {"name": "mopso"}, 600, 0)
    assert r.n_objectives == 2 and r.front_f.shape[1] == 2
    assert 0 < r.hypervolume < 0.8767 and r.igd > 0
    assert r.best_f == pytest.approx(1 - r.hypervolume / (1.21 - 1 / 3))
    gaps = np.array(r.trace.best_f)
    assert np.all(np.diff(gaps) <= 1e-12)  # the hypervolume of everything seen never shrinks


def test_single_objective_optimiser_refused_on_mo_task() -> None:
    with pytest.raises(ConfigError, match="single-objective"):
        validate(job("ifa", 0) | {"optimiser": {"name": "ifa", "population": 10}})


@pytest.mark.figures
def test_mo_leaderboard_columns_and_front(workdir: Path, capfd: pytest.CaptureFixture[str]) -> None:
    for seed in range(2):
        assert run_job(job("mopso", seed)) is not None
    runs = leaderboard.load_runs(tracking.client(), ["mo"])
    (board,) = leaderboard.boards(runs)
    assert list(board.table.columns) == leaderboard.MO_COLUMNS
    assert board.table.loc[0, "median_hv"] > 0 and board.table.loc[0, "median_igd"] > 0
    capfd.readouterr()
    paths = leaderboard.write(board, workdir / "lb", tracking.client(), "test")
    assert "Downloading artifacts" not in capfd.readouterr().err  # the front is read without a progress bar
    assert paths["front"].stat().st_size > 5000
    assert "![front]" in paths["md"].read_text()
    assert pd.read_csv(paths["csv"])["seeds"].tolist() == [2]
