"""Held-out scores of a calibration and how sure they are.

A method's held-out drift is the RMS, over every held-out sample, of its residual's centred
running mean over ``drift_window_s`` (computed inside each held-out part, so no window straddles
a fitted part). Its uncertainty comes from a moving-block bootstrap: the held-out parts are cut
into blocks of ``block_s`` (much longer than the drift window, so the blocks are nearly
independent although the samples are not), the blocks are drawn with replacement, and every
method is scored on the same draw — a ratio of two methods' drifts then carries the draws'
shared difficulty once, not twice.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from tcbench.compensation.features import running_mean

BLOCKS_MIN = 10  # the bootstrap needs some blocks: fewer held-out blocks than this shortens them
DRAWS = 2000
LEVEL = 0.95


def drift_track(res: np.ndarray, dt_s: float, window_s: float) -> np.ndarray:
    """The running mean of ``res`` over ``window_s`` (its valid part; the mean of the whole part
    when it is shorter than a window), as the drift score reads it."""
    width = max(1, int(round(window_s / dt_s)))
    if res.size < width:
        return np.array([res.mean()]) if res.size else np.array([])
    return running_mean(res, width)


@dataclass(frozen=True)
class BlockSums:
    """Per method, the sum of squared running means in each held-out block, and each block's
    count of running-mean samples (shared by the methods)."""

    squares: dict[str, np.ndarray]
    counts: np.ndarray
    block_s: float

    def drift(self, method: str) -> float:
        return float(np.sqrt(self.squares[method].sum() / self.counts.sum()))


def block_sums(residuals: Mapping[str, Sequence[np.ndarray]], dt_s: Sequence[float], window_s: float,
               block_s: float | None = None) -> BlockSums:
    """Each method's held-out residual parts (the same parts for every method, part ``k``
    sampled every ``dt_s[k]``) cut into blocks: ``block_s`` defaults to ten drift windows,
    shortened so that there are at least :data:`BLOCKS_MIN` blocks, but never below one window."""
    first = next(iter(residuals.values()))
    total_s = sum(p.size * d for p, d in zip(first, dt_s, strict=True))
    block_s = block_s or max(window_s, min(10.0 * window_s, total_s / BLOCKS_MIN))
    squares: dict[str, list[np.ndarray]] = {m: [] for m in residuals}
    counts: list[np.ndarray] = []
    for k in range(len(first)):
        tracks = {m: drift_track(parts[k], dt_s[k], window_s) for m, parts in residuals.items()}
        n = next(iter(tracks.values())).size
        per = max(1, int(round(block_s / dt_s[k])))
        edges = np.arange(0, n, per)
        counts.append(np.diff(np.append(edges, n)))
        for m, track in tracks.items():
            squares[m].append(np.add.reduceat(track ** 2, edges) if n else np.array([]))
    return BlockSums({m: np.concatenate(v) for m, v in squares.items()}, np.concatenate(counts), float(block_s))


def ratio_interval(sums: BlockSums, a: str, b: str, seed: int = 0, draws: int = DRAWS,
                   level: float = LEVEL) -> tuple[float, float, float]:
    """``drift(a) / drift(b)`` and its ``level`` bootstrap interval over blocks (both methods on
    the same draws); NaN bounds with fewer than two blocks. The draws are those of
    ``scipy.stats.bootstrap(paired=True)`` with the same seed; this is kept for its NaN-free
    quantiles and 2.2-3.3x less time (benchmarks/RESULTS.md)."""
    point = sums.drift(a) / sums.drift(b) if sums.drift(b) > 0 else float("nan")
    nb = sums.counts.size
    if nb < 2:
        return point, float("nan"), float("nan")
    idx = np.random.default_rng(seed).integers(0, nb, size=(draws, nb))
    n = sums.counts[idx].sum(axis=1)
    da = np.sqrt(sums.squares[a][idx].sum(axis=1) / n)
    db = np.sqrt(sums.squares[b][idx].sum(axis=1) / n)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = da / db
    lo, hi = np.nanquantile(r, [(1 - level) / 2, (1 + level) / 2])
    return point, float(lo), float(hi)
