"""experiments/accel_chamber/devices.py: the best method per device and the rows the board's paired
test ties with it."""

from __future__ import annotations

import numpy as np
import pandas as pd
from script_module import load

devices = load("experiments/accel_chamber/devices.py", "accel_devices")


def board(rows: list[tuple[str, float]]) -> pd.DataFrame:
    """A board of (method, p_vs_next) rows in rank order."""
    return pd.DataFrame({"rank": range(1, len(rows) + 1), "method": [m for m, _ in rows],
                         "p_vs_next": [p for _, p in rows]}).set_index("method")


def test_ties_follow_the_paired_test_down_to_the_first_difference() -> None:
    b = board([("oracle", 1e-9), ("oracle_thermometer", 1e-9), ("diagnosed", 0.98), ("poly3_rate", 0.3),
               ("lagpoly", 0.01), ("poly3", np.nan)])
    assert devices.tied(b, "diagnosed") == ["poly3_rate", "lagpoly"]
    assert devices.tied(b, "lagpoly") == []


def test_no_tie_across_a_limit_or_a_missing_test() -> None:
    b = board([("poly3_rate", 0.5), ("oracle_thermometer", 0.5), ("poly3", 0.9)])
    assert devices.tied(b, "poly3_rate") == []
    assert devices.tied(board([("lagpoly", np.nan), ("poly3", 0.9)]), "lagpoly") == []


pairs = load("experiments/accel_chamber/pairs.py", "accel_pairs")


def test_pairs_compare_draw_by_draw_as_the_board() -> None:
    """Two rows paired on their draws: the count below, and the board's p-value (none under 6 pairs)."""
    rng = np.random.default_rng(0)
    base = rng.uniform(100, 200, 10)
    runs = pd.DataFrame({"task": "accel_chamber-dev3", "method": ["a"] * 10 + ["b"] * 10,
                         "draw": list(range(10)) * 2, "seed": list(range(10)) * 2,
                         "drift_ug": np.concatenate([base, base * 1.1])})
    line = pairs.compare(runs, 3, "a", "b")
    assert line.startswith("device 3: a below b on 10 of 10 draws, Wilcoxon p = 0.002"), line
    assert pairs.compare(runs[runs["draw"] < 5], 3, "a", "b").endswith("p = nan")
    assert pairs.compare(runs, 3, "a", "c") == "device 3: no runs of c"
