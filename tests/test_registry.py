"""The entry-point registry."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.optimisers import (
    Optimiser,
    UnknownOptimiserError,
    available,
    get,
    register,
)
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


def test_asking_for_one_optimiser_imports_no_other_plugin() -> None:
    """A run of FA must not pay for importing cma, nevergrad or optuna (about 2 s): the registry
    imports an entry point when its name is asked for. The peers plugin is installed in the test
    environment, so those modules would be loaded by an eager registry."""
    import subprocess
    import sys

    code = ("import sys\nfrom tcbench.optimisers import registry\nregistry.get('fa')\n"
            "assert 'ifa' in registry.REGISTRY.names()\n"
            "print(sorted({m.split('.')[0] for m in sys.modules} & {'cma', 'nevergrad', 'optuna', 'pymoo', 'tcbench_peers'}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_a_broken_entry_point_is_named_when_asked_for(monkeypatch: pytest.MonkeyPatch) -> None:
    from importlib.metadata import EntryPoint

    from tcbench.optimisers.registry import REGISTRY

    broken = EntryPoint("broken-test", "no_such_module_xyz:Thing", "tcbench.optimisers")
    monkeypatch.setattr(REGISTRY, "_points", {**REGISTRY._entry_points(), "broken-test": broken})
    with pytest.raises(UnknownOptimiserError, match="'broken-test' .plugin failed to load: ModuleNotFoundError"):
        get("broken-test")
    assert "broken-test" in REGISTRY.broken()
    assert "broken-test" not in available()
    monkeypatch.setattr(REGISTRY, "_broken", {k: v for k, v in REGISTRY._broken.items() if k != "broken-test"})
