"""Optimiser-initialised training (X-BP): any registered optimiser searches a learner's initial
weights, one batched evaluation per generation; learners come from plugins like optimisers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from cli_here import install_here
from cli_here import tcbench as here

from tcbench.learners import available
from tcbench.learners.bp import BPNetwork
from tcbench.runner.loop import run_compensation

TASK = {"name": "msra_fulltemp"}


def test_builtin_learners_come_from_entry_points() -> None:
    found = available()
    assert {"bp", "elman", "poly"} <= set(found) and found["bp"].package == "tcbench"
    assert found["bp"].cls.searchable and not found["poly"].cls.searchable


def test_population_is_evaluated_in_one_batch_per_generation(monkeypatch) -> None:
    calls: list[int] = []
    original = BPNetwork.loss_batch

    def counting(self, params, inputs, targets):  # type: ignore[no-untyped-def]
        calls.append(len(np.atleast_2d(params)))
        return original(self, params, inputs, targets)

    monkeypatch.setattr(BPNetwork, "loss_batch", counting)
    result = run_compensation(TASK, {"name": "bp", "epochs": 5}, {"name": "fa", "population": 10}, 110, 0)
    assert calls == [10] * 11 and result.search_evaluations == 110
    assert len(result.trace.best_f) == 11
    assert result.init_loss == pytest.approx(min(result.trace.best_f))
    calls.clear()  # IFA asks twice per generation: the perturbed best (eq. 9), then the others
    run_compensation(TASK, {"name": "bp", "epochs": 5}, {"name": "ifa", "population": 10}, 110, 0)
    assert calls == [10] + [1, 9] * 10


@pytest.mark.parametrize("optimiser", ["fa", "ifa", "bas", "ga", "pso", "sa"])
def test_every_single_objective_optimiser_initialises_bp(optimiser: str) -> None:
    result = run_compensation(TASK, {"name": "bp", "training": "lm", "epochs": 20}, {"name": optimiser}, 200, 1)
    assert result.search_evaluations <= 200 and np.isfinite(result.init_loss)
    assert result.history is not None and result.history.loss[0] == pytest.approx(result.init_loss)
    assert result.score.summary()["bias_variation_ug"] < result.score.summary()["raw_bias_variation_ug"]


def test_search_beats_random_starts_on_the_training_error() -> None:
    searched = run_compensation(TASK, {"name": "bp", "epochs": 1}, {"name": "pso"}, 400, 2)
    random = [run_compensation(TASK, {"name": "bp", "epochs": 1}, {"name": "none"}, 400, s).init_loss for s in range(5)]
    assert searched.init_loss < min(random)


def test_same_seed_same_result() -> None:
    a = run_compensation(TASK, {"name": "bp", "epochs": 30}, {"name": "ifa"}, 60, 4).score.summary()
    b = run_compensation(TASK, {"name": "bp", "epochs": 30}, {"name": "ifa"}, 60, 4).score.summary()
    c = run_compensation(TASK, {"name": "bp", "epochs": 30}, {"name": "ifa"}, 60, 5).score.summary()
    assert a == b and a != c


def test_bas_initialises_elman() -> None:
    result = run_compensation({"name": "msra_zerobias"}, {"name": "elman", "epochs": 5}, {"name": "bas"}, 40, 0)
    s = result.score.summary()
    assert result.search_evaluations == 40 and s["zb_zero_start_ug"] < s["raw_zb_zero_start_ug"]


LINEAR_PLUGIN = '''
import numpy as np
from dataclasses import dataclass
from tcbench.learners import Learner, LearnerParams, FitHistory

class Linear(Learner):
    """Least-squares linear model: a learner from another package."""
    name = "linear"
    searchable = False

    def __init__(self, n_inputs, params=None, rng=None):
        super().__init__(n_inputs, params, rng)
        self._w = np.zeros(n_inputs + 1)

    @property
    def n_params(self):
        return self._w.size

    def get_params(self):
        return self._w.copy()

    def set_params(self, params):
        self._w = self._check_vector(params)

    def fit(self, inputs, targets, init=None):
        a = np.column_stack([inputs, np.ones(len(inputs))])
        self._w = np.linalg.lstsq(a, targets, rcond=None)[0]
        return FitHistory(loss=[0.0], iterations=1, stopped="closed_form")

    def predict(self, inputs):
        return np.column_stack([inputs, np.ones(len(inputs))]) @ self._w
'''


def test_learner_plugin_from_another_package(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The plugin installed here (:func:`cli_here.install_here`, as ``PYTHONPATH`` would): listed,
    and a run of it (``tcbench list`` with plugins in a process of its own: tests/test_plugins.py)."""
    site = tmp_path / "site"
    info = site / "linear_plugin-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: linear-plugin\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[tcbench.learners]\nlinear = linear_mod:Linear\n")
    (site / "linear_mod.py").write_text(LINEAR_PLUGIN)
    install_here(monkeypatch, site)
    listed = here("list", cwd=tmp_path)
    assert "linear     linear_mod.Linear  (from linear-plugin; closed form)" in listed.stdout
    run = here("run", "task=msra_fulltemp", "learner=raw", "learner.name=linear", "optimiser=none", cwd=tmp_path,
               env={"MLFLOW_TRACKING_URI": None})
    assert run.returncode == 0, run.stderr
    assert "1 finished, 0 failed" in run.stdout
