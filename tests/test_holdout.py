"""The held-out ranking of a calibration: pooled drift over held-out parts and the moving-block
bootstrap of one method's drift over another's."""

from __future__ import annotations

import numpy as np

from tcbench.compensation.holdout import BLOCKS_MIN, block_sums, ratio_interval


def test_the_pooled_drift_is_the_rms_of_every_part_s_running_mean() -> None:
    rng = np.random.default_rng(1)
    parts = [rng.normal(size=900), rng.normal(size=400) + 0.3]
    sums = block_sums({"m": parts}, [2.0, 2.0], window_s=20.0)
    tracks = [np.convolve(p, np.ones(10) / 10, mode="valid") for p in parts]
    assert np.isclose(sums.drift("m"), np.sqrt(np.mean(np.concatenate(tracks) ** 2)))
    assert sums.counts.sum() == sum(t.size for t in tracks) and sums.counts.size >= BLOCKS_MIN


def test_the_ratio_interval_covers_the_truth_and_is_degenerate_for_a_tie() -> None:
    covered = 0
    for seed in range(40):
        rng = np.random.default_rng(seed)
        base = np.cumsum(rng.normal(size=6000)) * 0.01  # a slow drift both methods leave, scaled
        sums = block_sums({"half": [0.5 * base], "full": [base]}, [1.0], 60.0)
        point, lo, hi = ratio_interval(sums, "half", "full", seed=seed)
        assert np.isclose(point, 0.5) and np.isclose(lo, 0.5) and np.isclose(hi, 0.5)
        noisy = block_sums({"a": [rng.normal(size=6000)], "b": [2.0 * rng.normal(size=6000)]}, [1.0], 60.0)
        point, lo, hi = ratio_interval(noisy, "a", "b", seed=seed)
        covered += lo <= 0.5 <= hi
        assert lo <= point <= hi
    assert covered >= 34  # a nominal 95 % interval over only ten blocks covers 35 of these 40 (slightly narrow)
