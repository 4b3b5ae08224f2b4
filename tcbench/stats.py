"""Statistics for fair comparisons over seeds: bootstrap confidence intervals and paired tests."""

from __future__ import annotations

import numpy as np
import pandas as pd

BOOTSTRAP_SEED = 20221  # fixed, so a leaderboard is reproducible from the same runs


def bootstrap_median_ci(
    values: np.ndarray, level: float = 0.95, n_boot: int = 2000, seed: int = BOOTSTRAP_SEED
) -> tuple[float, float]:
    """Percentile-bootstrap confidence interval of the median (NaN for fewer than 2 values); the
    same for the same values in any order (runs come back from MLflow in the order they ran)."""
    x = np.sort(np.asarray(values, dtype=float))
    x = x[np.isfinite(x)]
    if x.size < 2:
        return float("nan"), float("nan")
    rng = np.random.default_rng(seed)
    medians = np.median(x[rng.integers(0, x.size, size=(n_boot, x.size))], axis=1)
    tail = 100.0 * (1.0 - level) / 2.0
    low, high = np.percentile(medians, [tail, 100.0 - tail])
    return float(low), float(high)


def median_counting_failures(values: np.ndarray, failed: int) -> float:
    """Median of ``values`` with ``failed`` more runs counted as infinitely bad: a method that
    crashed on most seeds cannot rank on the few it finished (NaN when there are no runs)."""
    x = np.concatenate([np.asarray(values, dtype=float), np.full(int(failed), np.inf)])
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
