"""The entry-point registry."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.optimisers import Optimiser, UnknownOptimiserError, available, get, register
from tcbench.optimisers.fa import FireflyAlgorithm
from tcbench.optimisers.ifa import ImprovedFireflyAlgorithm


def test_builtins_come_from_entry_points() -> None:
    found = available()
    assert found["fa"].cls is FireflyAlgorithm and found["fa"].package == "tcbench"
    assert found["ifa"].cls is ImprovedFireflyAlgorithm


def test_unknown_name_lists_known() -> None:
    with pytest.raises(UnknownOptimiserError, match="unknown optimiser 'nope'; known: .*fa.*ifa"):
        get("nope")


def test_register_rejects_non_optimisers() -> None:
    with pytest.raises(TypeError, match="Optimiser subclass"):
        register("bad", dict)  # type: ignore[arg-type]


def test_register_in_process() -> None:
    class Random(Optimiser):
        name = "random-test"

        def _ask(self):
            return self.uniform(min(self.params.population, self.remaining))

        def _tell(self, x, f):
            self.generation += 1

    register("random-test", Random)
    opt = get("random-test")(np.zeros(2), np.ones(2), 25, np.random.default_rng(0))
    while not opt.done:
        x = opt.ask()
        opt.tell(x, x.sum(axis=1))
    assert opt.evaluations == 25 and 0 <= opt.best.f <= 2
