"""``check_optimizer``: the ask/tell contract checker for optimiser authors.

In the spirit of gymnasium's ``check_env``: given an optimiser class it runs it on small
problems through its public API only (so it also catches a subclass that overrides ``ask`` or
``tell``) and verifies that

- every asked batch has shape (k, d) with 0 < k <= the evaluations left, and lies inside the
  bounds;
- the run ends (``done``) without ever exceeding the budget, and uses it up unless the optimiser
  stops itself;
- the same seed gives the same points and the same result;
- NaN and inf objective values are survived and never become the best;
- ``best`` (single objective) is the best finite value told, at a point that was asked;
  ``front`` (several objectives) is non-dominated and made of told points and values.

Plugin authors call it in their own tests::

    from tcbench import check_optimizer
    check_optimizer(MyOptimiser)
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.optimisers.protocol import Optimiser
from tcbench.pareto import nondominated


class OptimizerContractError(AssertionError):
    """An optimiser broke the ask/tell contract; the message names it and the case."""


@dataclass(frozen=True)
class Case:
    """One contract run: bounds, budget, seed, objectives, and whether values may be NaN/inf."""

    lower: np.ndarray
    upper: np.ndarray
    budget: int
    seed: int
    n_objectives: int = 1
    nasty: bool = False
    params: dict[str, Any] | None = None

    def describe(self) -> str:
        return (f"d={self.lower.size}, budget={self.budget}, seed={self.seed}, "
                f"objectives={self.n_objectives}, nonfinite={self.nasty}")


def _objective(case: Case) -> Callable[[np.ndarray], np.ndarray]:
    """A shifted sphere (or m of them), with NaN/inf sprinkled in when ``case.nasty``."""
    centre = case.lower + 0.3 * (case.upper - case.lower)
    m = case.n_objectives

    def f(x: np.ndarray) -> np.ndarray:
        values = np.stack([np.sum((x - centre - 0.1 * j) ** 2, axis=1) for j in range(m)], axis=1)
        if case.nasty:
            row_hash = np.floor(np.abs(x[:, 0]) * 1e6).astype(np.int64) % 7
            values[row_hash == 0] = np.nan
            values[row_hash == 1, 0] = np.inf
            values[row_hash == 2, -1] = -np.inf
        return values[:, 0] if m == 1 else values

    return f


def _run(cls: type[Optimiser], case: Case) -> tuple[list[np.ndarray], list[np.ndarray], Optimiser]:
    """Drive one run, checking every step; return what was asked and told."""
    name = getattr(cls, "name", cls.__name__) or cls.__name__

    def fail(message: str) -> OptimizerContractError:
        return OptimizerContractError(f"optimiser {name!r} ({case.describe()}): {message}")

    opt = cls(case.lower, case.upper, case.budget, np.random.default_rng(case.seed), case.params,
              n_objectives=case.n_objectives)
    objective = _objective(case)
    asked: list[np.ndarray] = []
    told: list[np.ndarray] = []
    used = 0
    for _ in range(case.budget + 1):
        if opt.done:
            break
        try:
            x = np.asarray(opt.ask())
        except Exception as exc:
            raise fail(f"ask() raised {type(exc).__name__}: {exc}") from exc
        left = case.budget - used
        if x.ndim != 2 or x.shape[1] != case.lower.size or not 0 < x.shape[0] <= left:
            raise fail(f"ask() returned shape {x.shape}; expected (k, {case.lower.size}) with 0 < k <= {left}")
        if not np.all(np.isfinite(x)) or np.any(x < case.lower) or np.any(x > case.upper):
            raise fail("ask() returned points outside the bounds")
        f = objective(x)
        try:
            opt.tell(x, f)
        except Exception as exc:
            raise fail(f"tell() raised {type(exc).__name__}: {exc}") from exc
        used += x.shape[0]
        asked.append(x)
        told.append(f)
    else:
        raise fail(f"not done after {case.budget + 1} ask/tell rounds")
    if used > case.budget:
        raise fail(f"used {used} evaluations, budget {case.budget}")
    return asked, told, opt


def _check_best(name: str, case: Case, asked: list[np.ndarray], told: list[np.ndarray], opt: Optimiser) -> None:
    x = np.concatenate(asked)
    f = np.concatenate(told)
    where = f"optimiser {name!r} ({case.describe()})"
    if case.n_objectives == 1:
        finite = np.isfinite(f)
        best = opt.best
        if not finite.any():
            return
        if not np.isfinite(best.f) or best.f != f[finite].min():
            raise OptimizerContractError(f"{where}: best.f = {best.f} but the best finite value told is {f[finite].min()}")
        matches = np.all(x == best.x, axis=1) & (f == best.f)
        if not matches.any():
            raise OptimizerContractError(f"{where}: best.x was never asked with value best.f")
        return
    front = opt.front
    if front.f.shape[0] and not np.all(nondominated(front.f)):
        raise OptimizerContractError(f"{where}: front holds dominated points")
    finite = np.isfinite(f).all(axis=1)
    for xi, fi in zip(front.x, front.f, strict=True):
        if not np.any(np.all(x[finite] == xi, axis=1) & np.all(f[finite] == fi, axis=1)):
            raise OptimizerContractError(f"{where}: front holds a point that was not told")


def check_optimizer(
    cls: type[Optimiser],
    dims: Sequence[int] = (1, 3),
    budgets: Sequence[int] = (60, 257),
    seeds: Sequence[int] = (0, 1),
    params: dict[str, Any] | None = None,
) -> int:
    """Check the ask/tell contract of ``cls``; raise :class:`OptimizerContractError` on the
    first breach. Returns the number of runs checked. Budgets the optimiser rejects at
    construction (``ValueError``, e.g. smaller than its generation) are skipped."""
    if not (isinstance(cls, type) and issubclass(cls, Optimiser)):
        raise TypeError(f"{cls!r} is not a tcbench Optimiser subclass")
    name = getattr(cls, "name", "") or cls.__name__
    objectives = ([1] if cls.single_objective else []) + ([2] if cls.multi_objective else [])
    runs = skipped = 0
    for m in objectives:
        for d in dims:
            for budget in budgets:
                for seed in seeds:
                    lower = np.linspace(-2.0, -1.0, d)
                    upper = lower + np.linspace(3.0, 7.0, d)
                    case = Case(lower, upper, budget, seed, m, nasty=bool(seed % 2), params=params)
                    try:
                        asked, told, opt = _run(cls, case)
                    except ValueError as exc:
                        if "budget" not in str(exc):
                            raise
                        skipped += 1
                        continue
                    again, _, _ = _run(cls, case)
                    same = len(again) == len(asked) and all(
                        np.array_equal(a, b) for a, b in zip(asked, again, strict=True))
                    if not same:
                        raise OptimizerContractError(
                            f"optimiser {name!r} ({case.describe()}): the same seed asked different points")
                    _check_best(name, case, asked, told, opt)
                    runs += 1
    if runs == 0:
        raise OptimizerContractError(f"optimiser {name!r} rejected all {skipped} budgets tried ({list(budgets)})")
    return runs
