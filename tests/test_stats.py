"""Bootstrap intervals and paired tests behind the leaderboard ranks."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from tcbench.leaderboard.optimisation import summarise
from tcbench.stats import bootstrap_median_ci, paired_p_value


def test_bootstrap_interval_covers_and_shrinks() -> None:
    rng = np.random.default_rng(0)
    small = rng.normal(5.0, 1.0, 15)
    large = rng.normal(5.0, 1.0, 400)
    lo_s, hi_s = bootstrap_median_ci(small)
    lo_l, hi_l = bootstrap_median_ci(large)
    assert lo_s < np.median(small) < hi_s and lo_l < 5.0 < hi_l
    assert hi_l - lo_l < hi_s - lo_s
    assert bootstrap_median_ci(small) == (lo_s, hi_s)  # reproducible
    assert np.isnan(bootstrap_median_ci(np.array([1.0]))[0])


def test_coverage_of_the_median_interval() -> None:
    rng = np.random.default_rng(1)
    covered = 0
    for i in range(200):
        x = rng.exponential(1.0, 30)
        lo, hi = bootstrap_median_ci(x, n_boot=500, seed=i)
        covered += lo <= np.log(2) <= hi
    assert 0.88 <= covered / 200 <= 0.99


def test_paired_p_value() -> None:
    seeds = np.arange(15)
    a = pd.Series(np.linspace(1, 2, 15), index=seeds)
    assert paired_p_value(a, a + 0.5) < 0.001
    noise = pd.Series(np.random.default_rng(2).normal(0, 1, 15), index=seeds)
    assert 0.0 <= paired_p_value(a, a + noise) <= 1.0
    assert paired_p_value(a, a) == 1.0
    assert np.isnan(paired_p_value(a.iloc[:5], a.iloc[:5] + 1))
    # pairing is by seed, not by position
    shuffled = (a + 0.5).sample(frac=1.0, random_state=0)
    assert paired_p_value(a, shuffled) < 0.001


def test_leaderboard_columns_from_runs() -> None:
    rows = []
    rng = np.random.default_rng(3)
    for method, shift in (("good", 0.0), ("twin", 0.0), ("bad", 5.0)):
        for seed in range(12):
            e = 1.0 + 0.1 * seed + shift + (rng.normal(0, 0.01) if method == "twin" else 0.0)
            rows.append({"method": method, "status": "FINISHED", "seed": seed, "final_error": e,
                         "final_best": e, "target_hit": False, "evaluations": 100.0,
                         "evals_to_target": np.nan, "budget": 100})
    table = summarise(pd.DataFrame(rows)).set_index("method")
    assert table.loc["bad", "rank"] == 3
    assert table.loc["bad", "ci95_low"] > table.loc["good", "ci95_high"]
    second = table[table["rank"] == 2].iloc[0]
    assert second["p_vs_next"] < 0.01  # rank 2 against "bad"
    assert np.isnan(table.loc["bad", "p_vs_next"])  # last row has no next
    first = table[table["rank"] == 1].iloc[0]
    assert first["p_vs_next"] == pytest.approx(first["p_vs_next"]) and 0 <= first["p_vs_next"] <= 1


def test_bootstrap_interval_ignores_the_order_of_the_values() -> None:
    values = np.random.default_rng(3).lognormal(size=30)
    for seed in range(10):  # an order-dependent resampling differs on several of these
        assert bootstrap_median_ci(values) == bootstrap_median_ci(np.random.default_rng(seed).permutation(values))
