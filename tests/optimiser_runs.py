"""Driving an ask/tell optimiser to the end of its budget, checking the protocol on the way."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np


def make(cls: type, dim: int = 2, budget: int = 100, seed: int = 0, params: dict[str, Any] | None = None,
         lower: float = -5.12, upper: float = 5.12) -> Any:
    """An optimiser of class ``cls`` on the box ``[lower, upper]^dim``."""
    lo, hi = np.full(dim, lower), np.full(dim, upper)
    return cls(lo, hi, budget, np.random.default_rng(seed), params or {})


def run(cls: type, fn: Callable[[np.ndarray], np.ndarray], dim: int = 2, budget: int = 100, seed: int = 0,
        params: dict[str, Any] | None = None, lower: float = -5.12, upper: float = 5.12) -> tuple[Any, int]:
    """Ask/tell until done, asserting every ask fits the budget and the box; (optimiser, asked)."""
    opt = make(cls, dim, budget, seed, params, lower, upper)
    asked = 0
    while not opt.done:
        x = opt.ask()
        assert 0 < len(x) <= opt.remaining
        assert np.all(x >= opt.lower) and np.all(x <= opt.upper)
        asked += len(x)
        opt.tell(x, fn(x))
    return opt, asked


def drive(opt: Any, f: Callable[[np.ndarray], np.ndarray]) -> list[np.ndarray]:
    """Ask/tell ``opt`` on ``f`` until done; every batch it asked, in order."""
    asked = []
    while not opt.done:
        x = opt.ask()
        asked.append(x)
        opt.tell(x, f(x))
    return asked


def assert_initialises_bp(optimiser: str, searches: int = 60) -> None:
    """``optimiser`` searching BP's initial weights on MSRA full-temperature (X-BP): the best of
    ``searches`` starts beats one random start, and the result compensates."""
    from tcbench.runner.loop import run_compensation

    task, bp = {"name": "msra_fulltemp"}, {"name": "bp", "training": "lm", "epochs": 20}
    searched = run_compensation(task, bp, {"name": optimiser}, searches, 0)
    random = run_compensation(task, bp, {"name": "none"}, searches, 0)
    assert searched.search_evaluations == searches and random.search_evaluations == 1
    assert searched.init_loss < random.init_loss
    assert searched.score.summary()["bias_variation_ug"] < searched.score.summary()["raw_bias_variation_ug"]
