"""Statistics for fair comparisons over seeds: bootstrap confidence intervals and paired tests."""

from __future__ import annotations

import numpy as np
import pandas as pd

BOOTSTRAP_SEED = 20221  # fixed, so a leaderboard is reproducible from the same runs


def with_failures(values: np.ndarray, failed: int = 0, higher_is_better: bool = False) -> np.ndarray:
    """The finished runs' values (NaN left out) and one worst value per failed run: ``+inf``, or
    ``-inf`` where higher is better. Every order statistic of a board is taken over these, so a
    failed run ranks below every finished one instead of leaving the sample."""
    x = np.asarray(values, dtype=float)
    worst = -np.inf if higher_is_better else np.inf
    return np.concatenate([x[~np.isnan(x)], np.full(int(failed), worst)])


def failure_tie_break(values: np.ndarray, failed: int = 0, higher_is_better: bool = False) -> dict[str, float]:
    """Sort keys (lower ranks higher) that order methods whose median counting failures ties,
    typically at ``±inf``: a method without any finished run last, then the smaller share of
    failed runs, then the better median of the finished runs."""
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    runs = x.size + int(failed)
    median = float(np.median(x)) if x.size else np.inf
    return {
        "_no_finished": float(x.size == 0),
        "_failed_share": int(failed) / runs if runs else 1.0,
        "_finished_median": -median if higher_is_better and x.size else median,
    }


TIE_BREAK_KEYS = ["_failed_share", "_finished_median"]


def percentiles(values: np.ndarray, q: list[float]) -> np.ndarray:
    """``np.percentile`` (linear) of values that may hold ``±inf`` (failed runs): a percentile
    that falls on, or between a finite value and, an infinite one is that infinity."""
    x = np.asarray(values, dtype=float)
    finite = x[np.isfinite(x)]
    if finite.size == x.size:
        return np.percentile(x, q)
    if finite.size == 0:
        return np.full(len(q), x[0])
    lo, hi = float(finite.min()), float(finite.max())
    pad = max(1.0, hi - lo)
    stand_in = np.where(x == np.inf, hi + pad, np.where(x == -np.inf, lo - pad, x))
    p = np.percentile(stand_in, q)
    return np.where(p > hi, np.inf, np.where(p < lo, -np.inf, p))


def bootstrap_median_ci(
    values: np.ndarray, level: float = 0.95, n_boot: int = 2000, seed: int = BOOTSTRAP_SEED
) -> tuple[float, float]:
    """Percentile-bootstrap confidence interval of the median (NaN for fewer than 2 values; NaN
    values are left out, ``±inf`` — failed runs, :func:`with_failures` — kept, so an end of the
    interval may be infinite); the same for the same values in any order (runs come back from
    MLflow in the order they ran). The resamples are ``scipy.stats.bootstrap``'s (percentile
    method, same seed), but the interval is :func:`percentiles` of them, not scipy's: that is kept
    for its rule at ``±inf``, its last bits and 1.4-2.6x less time (benchmarks/RESULTS.md)."""
    x = np.sort(np.asarray(values, dtype=float))
    x = x[~np.isnan(x)]
    if x.size < 2:
        return float("nan"), float("nan")
    rng = np.random.default_rng(seed)
    medians = np.median(x[rng.integers(0, x.size, size=(n_boot, x.size))], axis=1)
    tail = 100.0 * (1.0 - level) / 2.0
    low, high = percentiles(medians, [tail, 100.0 - tail])
    return float(low), float(high)


def median_counting_failures(values: np.ndarray, failed: int, higher_is_better: bool = False) -> float:
    """Median of ``values`` with ``failed`` more runs counted as worse than any finished one
    (:func:`with_failures`): a method that failed on half its runs or more has an infinite
    median ("failed"), and cannot rank on the few it finished (NaN when there are no runs)."""
    x = with_failures(values, failed, higher_is_better)
    return float(np.median(x)) if x.size else float("nan")


def paired_p_value(a: pd.Series, b: pd.Series) -> float:
    """Two-sided Wilcoxon signed-rank p-value of ``a - b`` over the seeds (index) both have.

    NaN when fewer than 6 seeds are shared (no difference could reach p < 0.05); 1.0 when all
    shared differences are zero."""
    both = pd.concat([a, b], axis=1, join="inner").dropna()
    if len(both) < 6:
        return float("nan")
    diff = both.iloc[:, 0].to_numpy() - both.iloc[:, 1].to_numpy()
    if np.all(diff == 0):
        return 1.0
    from scipy.stats import wilcoxon  # scipy.stats costs ~0.5 s to import: only when a test is made

    return float(wilcoxon(diff, zero_method="zsplit").pvalue)
