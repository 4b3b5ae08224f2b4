"""The default fitted branches (:mod:`tcbench.compensation.fitted_span`): the run of consecutive
branches whose temperatures span the held-out ones, a few samples at a turning point not costing
a branch of held-out data."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.compensation.fitted_span import beyond_share, spanning_parts
from tcbench.signal.branches import Branch


def record(*legs: tuple[float, float, int]) -> tuple[np.ndarray, list[Branch]]:
    """Temperature legs (from, to, samples) one after the other, each a branch."""
    temp = np.concatenate([np.linspace(a, b, n) for a, b, n in legs])
    stops = np.cumsum([n for *_, n in legs])
    starts = np.r_[0, stops[:-1]]
    return temp, [Branch(int(a), int(b), float(temp[a]), float(temp[b - 1])) for a, b in zip(starts, stops, strict=True)]


def test_the_branch_spanning_the_others_is_fitted() -> None:
    temp, parts = record((25, 60, 300), (60, -40, 900))  # an oven: warm-up, then down to the coldest
    assert beyond_share(temp, parts, [0]) > 0.6
    choice = spanning_parts(temp, parts)
    assert choice.train == [1] and choice.beyond_share == 0.0 and choice.fitted_c == (-40.0, 60.0)


def test_a_few_samples_at_a_turning_point_do_not_cost_a_branch() -> None:
    temp, parts = record((50, -17, 300), (-17, 73.9, 400), (74.0, 36, 300))  # the tofupilot cycle's shape
    assert 0 < beyond_share(temp, parts, [1]) < 0.01 and beyond_share(temp, parts, [1, 2]) == 0.0
    assert spanning_parts(temp, parts).train == [1]


def test_when_no_branch_spans_alone_consecutive_ones_do() -> None:
    temp, parts = record((20, 40, 200), (40, 0, 200), (0, 60, 200), (60, 20, 200))
    choice = spanning_parts(temp, parts)
    assert choice.beyond_share == 0.0 and choice.train == [2]  # 0..60 holds 20..40, 40..0 and 60..20
    temp, parts = record((20, 60, 200), (60, 40, 200), (40, 0, 200), (0, 30, 200))
    choice = spanning_parts(temp, parts)
    assert choice.train == [1, 2] and choice.beyond_share == 0.0  # 60..0 across two branches
    with pytest.raises(ValueError, match="one part"):
        spanning_parts(*record((20, 60, 100)))
