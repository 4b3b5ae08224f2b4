"""COCO-style runtime ECDFs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tcbench.leaderboard import optimisation as leaderboard
from tcbench.tracking import store as tracking
from tcbench.leaderboard.ecdf import TARGETS, ecdf_curves, hitting_evaluations, write_ecdf_plots
from tcbench.runner.job import run_job


def test_hitting_evaluations_by_hand() -> None:
    steps = np.array([10.0, 20.0, 30.0])
    errors = np.array([50.0, 0.5, 1e-9])
    hits = hitting_evaluations(steps, errors, np.array([100.0, 1.0, 1e-3, 1e-10]))
    np.testing.assert_array_equal(hits, [10.0, 20.0, 30.0, np.inf])
    assert len(TARGETS) == 51 and TARGETS[0] == 100.0 and np.isclose(TARGETS[-1], 1e-8)


def test_ecdf_fractions() -> None:
    table = pd.DataFrame({
        "method": ["a"] * 4 + ["b"] * 4, "dim": [2] * 8, "task": ["t"] * 8, "seed": [0] * 8,
        "target": [1, 2, 3, 4] * 2, "evaluations": [5, 10, np.inf, np.inf, 1, 1, 1, 100],
        "budget": [100] * 8,
    })
    curves = ecdf_curves(table, np.array([1, 5, 10, 100]))
    np.testing.assert_allclose(curves[2]["a"], [0, 0.25, 0.5, 0.5])
    np.testing.assert_allclose(curves[2]["b"], [0.75, 0.75, 0.75, 1.0])


@pytest.mark.figures
def test_ecdf_plots_from_runs(workdir: Path) -> None:
    base = {"task": {"name": "sphere", "dim": 2, "shift": True, "target_precision": 1e-8, "lower": None,
                     "upper": None}, "budget": 300, "progress": False,
            "tracking": {"enabled": True, "uri": None, "experiment": "e", "sweep_id": "s", "plots": False,
                         "resume": False}}
    for opt in ("fa", "ga"):
        for seed in range(2):
            run_job(base | {"optimiser": {"name": opt}, "seed": seed})
    runs = leaderboard.load_runs(tracking.client(), ["e"])
    (path,) = write_ecdf_plots(tracking.client(), runs, workdir)
    assert path.name == "ecdf_2d.png" and path.stat().st_size > 5000


def test_ecdf_line_styles_are_distinct_beyond_ten_methods() -> None:
    from tcbench.plots import line_styles

    styles = line_styles(13)  # the BBOB and optimiser-suite boards have 13 methods
    assert len({(s["color"], s["ls"]) for s in styles}) == 13
