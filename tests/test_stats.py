"""Bootstrap intervals and paired tests behind the leaderboard ranks."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tcbench.leaderboard.optimisation import summarise
from tcbench.stats import BOOTSTRAP_SEED, bootstrap_median_ci, paired_p_value, percentiles, with_failures


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


_board_values = st.integers(2, 40).flatmap(lambda n: st.tuples(
    st.lists(st.one_of(st.floats(-1e6, 1e6), st.sampled_from([0.0, 1.0, 1.5])), min_size=n, max_size=n),
    st.integers(0, n), st.booleans()))


@settings(max_examples=150, deadline=None)
@given(_board_values)
def test_the_median_interval_is_scipys_percentile_bootstrap_up_to_the_quantile_rule(case: tuple[list[float], int, bool]) -> None:
    """Same seed, same resampled medians as ``scipy.stats.bootstrap(method="percentile")``, so
    the interval is ``percentiles`` of scipy's bootstrap distribution, bit for bit, ties and
    failed runs (±inf) included. scipy's own interval is not used: its quantile rule differs in
    the last bits and has no ±inf rule (benchmarks/RESULTS.md, bootstrap_vs_scipy.py)."""
    pytest.importorskip("scipy", minversion="1.15")  # the rng argument
    from scipy import stats

    finished, failed, higher_is_better = case
    x = with_failures(np.array(finished), failed, higher_is_better)
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    sample = np.sort(x)
    with warnings.catch_warnings():  # ±inf: scipy warns about its own interval and spread
        warnings.simplefilter("ignore")
        res = stats.bootstrap((sample,), np.median, method="percentile", n_resamples=2000, rng=rng, vectorized=True)
    tail = 100.0 * (1.0 - 0.95) / 2.0  # as bootstrap_median_ci computes it (2.5000000000000022)
    assert bootstrap_median_ci(x) == tuple(percentiles(res.bootstrap_distribution, [tail, 100.0 - tail]).tolist())
