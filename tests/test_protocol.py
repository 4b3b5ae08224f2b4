"""The ask/tell bookkeeping of the optimiser base class, on a scripted optimiser."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from tcbench.optimisers import ProtocolError
from tcbench.optimisers.protocol import Optimiser


class Scripted(Optimiser):
    """Asks exactly the points it is given; records what it is told."""

    name = "scripted"
    multi_objective = True

    def __init__(self, *args: Any, points: np.ndarray, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.points = points
        self.told: list[np.ndarray] = []

    def _ask(self) -> np.ndarray:
        return self.points

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        self.told.append(f)


def scripted(lower, upper, points, n_objectives: int = 1) -> Scripted:
    return Scripted(np.asarray(lower, float), np.asarray(upper, float), 100,
                    np.random.default_rng(0), n_objectives=n_objectives,
                    points=np.asarray(points, float))


@pytest.mark.parametrize(
    ("lower", "upper", "point", "inside"),
    [
        ([0, 0], [1, 1], [0.0, 1.0], True),  # the bounds themselves are inside
        ([0, 0], [1, 1], [0.5, 1.5], False),
        ([0, 0], [1, 1], [-1e-12, 0.5], False),
        ([0, 0], [1, 1], [np.nan, 0.5], False),
        ([0, 0], [1, 2], [0.5, 1.5], True),  # per-axis bounds: 1.5 is inside on axis 1 only
        ([0, 0], [1, 2], [1.5, 0.5], False),
        ([0, 0], [1, 2], [0.5, np.nan], False),
        ([-np.inf, 0], [np.inf, 1], [1e300, 0.5], True),
        ([-np.inf, 0], [np.inf, 1], [np.inf, 0.5], False),
        ([-np.inf, -np.inf], [np.inf, np.inf], [-np.inf, 0.0], False),
        ([-np.inf, -np.inf], [np.inf, np.inf], [np.nan, 0.0], False),
    ],
)
def test_ask_checks_the_bounds(lower, upper, point, inside) -> None:
    opt = scripted(lower, upper, [[0.5, 0.5], point])  # every row is checked, not just the first
    if inside:
        np.testing.assert_array_equal(opt.ask()[1], point)
    else:
        with pytest.raises(ProtocolError, match="outside the bounds"):
            opt.ask()


@pytest.mark.parametrize("upper", [[1.0, 1.0, 1.0], [1.0, 2.0, 3.0]])
def test_clip_clamps_each_axis(upper) -> None:
    opt = scripted([0, 0, 0], upper, [[0.5, 0.5, 0.5]])
    x = np.array([[-1.0, 0.5, 9.0], [0.2, 2.5, -0.0], [np.nan, 1.5, 2.5]])
    np.testing.assert_array_equal(opt.clip(x), np.clip(x, [0, 0, 0], upper))


def test_tell_hands_the_optimiser_its_own_values() -> None:
    opt = scripted([0, 0], [1, 1], [[0.1, 0.2], [0.3, 0.4]])
    x = opt.ask()
    f = np.array([2.0, 1.0])
    opt.tell(x, f)
    f[:] = -5.0  # the caller reuses its buffer
    np.testing.assert_array_equal(opt.told[0], [2.0, 1.0])
    assert opt.best.f == 1.0
    np.testing.assert_array_equal(opt.best.x, [0.3, 0.4])


def test_tell_counts_nonfinite_values_as_worst() -> None:
    opt = scripted([0, 0], [1, 1], [[0.1, 0.2]] * 4)
    x = opt.ask()
    opt.tell(x, np.array([np.nan, 3.0, -np.inf, np.inf]))
    assert opt.nonfinite == 3 and opt.best.f == 3.0
    np.testing.assert_array_equal(opt.told[0], [np.inf, 3.0, np.inf, np.inf])


def test_tell_counts_a_multiobjective_row_once() -> None:
    opt = scripted([0, 0], [1, 1], [[0.1, 0.2]] * 3, n_objectives=2)
    x = opt.ask()
    opt.tell(x, np.array([[np.nan, np.inf], [1.0, 2.0], [3.0, np.nan]]))
    assert opt.nonfinite == 2
    np.testing.assert_array_equal(opt.told[0], [[np.inf, np.inf], [1.0, 2.0], [np.inf, np.inf]])
