"""The held-out ranking of a calibration: pooled drift over held-out parts and the moving-block
bootstrap of one method's drift over another's; the white-noise floor of the drift score as a
limit with its interval."""

from __future__ import annotations

import numpy as np

import pytest

from tcbench.compensation.holdout import (BLOCKS_MIN, FloorIntervals, block_sums, floor_intervals, noise_sums,
                                         ratio_interval)


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


def _floor(parts: dict[str, list[np.ndarray]], raw: list[np.ndarray], t: list[np.ndarray], window_s: float,
           seed: int = 0) -> FloorIntervals:
    dt = [float(np.median(np.diff(x))) for x in t]
    sums = block_sums(parts, dt, window_s)
    noise = noise_sums(raw, t, dt, window_s, sums.block_s)
    assert noise.counts.size == sums.counts.size  # the same blocks
    return floor_intervals(sums, noise, {m: [m] for m in parts}, seed=seed)


def test_the_floor_is_white_noise_s_drift_score_with_an_interval_that_covers_it() -> None:
    sigma, window_s = 0.3, 60.0
    covered = at_floor = 0
    for seed in range(30):
        rng = np.random.default_rng(seed)
        t = [np.arange(3000.0), np.arange(3000.0, 5000.0)]
        noise = [rng.normal(0.0, sigma, x.size) for x in t]
        raw = [n + 0.002 * x for n, x in zip(noise, t)]  # a slope the differences do not see
        drift = [n + 3.0 * sigma / np.sqrt(window_s) * np.sin(x / 400.0) for n, x in zip(noise, t)]
        got = _floor({"white": noise, "drift": drift, "raw": raw}, raw, t, window_s, seed)
        point, lo, hi = got.floor
        assert lo < point < hi
        covered += lo <= sigma / np.sqrt(window_s) <= hi
        # noise alone is at the floor (its interval reaches 1) but for the bootstrap's misses; a
        # drift of three floors never is
        at_floor += got.x_floor["white"][1] <= 1.0 <= got.x_floor["white"][2]
        assert got.x_floor["drift"][1] > 1.5
        # the drift is the RMS over the parts of each part's drift, the point of the ratio
        tracks = [np.convolve(d, np.ones(60) / 60, mode="valid") for d in drift]
        over_parts = np.sqrt(np.mean([np.mean(x ** 2) for x in tracks]))
        assert got.drift["drift"] == pytest.approx(over_parts)
        assert got.x_floor["drift"][0] == pytest.approx(over_parts / point)
    # the floor's interval covers the truth 28 times in 30; noise alone's ratio interval reaches 1
    # 25 times (ten blocks of overlapping running means: a bootstrap interval narrower than nominal)
    assert covered >= 25 and at_floor >= 23


def test_the_floor_leaves_out_gaps_and_spikes() -> None:
    rng = np.random.default_rng(7)
    bursts = [np.arange(250) * 0.02 + k * 300.0 for k in range(8)]  # 5-s bursts at 50 Hz, 5 min apart
    t = [np.concatenate(bursts)]
    clean = rng.normal(0.0, 0.01, t[0].size)
    stepped = clean + np.repeat(np.arange(8) * 0.5, 250)  # the level jumps between bursts
    stepped[100] += 5.0  # and one spike
    one, other = (_floor({"m": [x]}, [x], t, 5.0).floor for x in (clean, stepped))
    assert other[0] == pytest.approx(one[0], rel=0.02)
    assert one[0] == pytest.approx(0.01 / np.sqrt(250), rel=0.1)


def test_the_floor_needs_the_drift_s_blocks() -> None:
    rng = np.random.default_rng(0)
    t = [np.arange(2000.0)]
    x = [rng.normal(size=2000)]
    sums = block_sums({"m": x}, [1.0], 60.0)
    with pytest.raises(ValueError, match="cut them alike"):
        floor_intervals(sums, noise_sums(x, t, [1.0], 60.0, sums.block_s / 2), {"m": ["m"]})
