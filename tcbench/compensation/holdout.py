"""Held-out scores of a calibration and how sure they are.

A method's held-out drift is the RMS, over every held-out sample, of its residual's centred
running mean over ``drift_window_s`` (computed inside each held-out part, so no window straddles
a fitted part). Its uncertainty comes from a moving-block bootstrap: the held-out parts are cut
into blocks of ``block_s`` (much longer than the drift window, so the blocks are nearly
independent although the samples are not), the blocks are drawn with replacement, and every
method is scored on the same draw — a ratio of two methods' drifts then carries the draws'
shared difficulty once, not twice.

The white-noise floor of the drift score (:func:`noise_sums`, :func:`floor_intervals`): what a
method would score if it left white noise alone, the raw residual's sample-to-sample variance
(from first differences, within the same blocks) over the samples in one drift window, with a
block bootstrap drawn within each held-out part, jointly with every method's drift, so that a
method is at the floor only when its ratio's interval reaches 1.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from tcbench.compensation.features import running_mean
from tcbench.sensors.segments import GAP_FACTOR

BLOCKS_MIN = 10  # the bootstrap needs some blocks: fewer held-out blocks than this shortens them
DRAWS = 2000
LEVEL = 0.95
OUTLIER_Z = 8.0  # a first difference this many robust sigmas out (a spike, a step) is not white noise


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
    part: np.ndarray | None = None  # the held-out part each block lies in (blocks in part order)

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
        edges = _block_edges(n, dt_s[k], block_s)
        counts.append(np.diff(np.append(edges, n)))
        for m, track in tracks.items():
            squares[m].append(np.add.reduceat(track ** 2, edges) if n else np.array([]))
    part = np.concatenate([np.full(c.size, k) for k, c in enumerate(counts)])
    return BlockSums({m: np.concatenate(v) for m, v in squares.items()}, np.concatenate(counts), float(block_s), part)


def _block_edges(track_size: int, dt_s: float, block_s: float) -> np.ndarray:
    """The first index of each block of a part's drift track (``track_size`` samples)."""
    return np.arange(0, track_size, max(1, int(round(block_s / dt_s))))


@dataclass(frozen=True)
class NoiseSums:
    """Per held-out block (those of a :class:`BlockSums`, same order): ``squares``, the sum of the
    squared first differences of the raw residual (centred on the block's mean difference; gaps
    and outliers left out) over twice the drift window's samples, and ``counts``, their degrees of
    freedom; ``sqrt(sum(squares) / sum(counts))`` is the drift score white noise alone would give."""

    squares: np.ndarray
    counts: np.ndarray

    @property
    def floor(self) -> float:
        n = self.counts.sum()
        return float(np.sqrt(self.squares.sum() / n)) if n > 0 else float("nan")


def noise_sums(raw: Sequence[np.ndarray], t_s: Sequence[np.ndarray], dt_s: Sequence[float], window_s: float,
               block_s: float) -> NoiseSums:
    """The white noise of the held-out parts' raw residual ``raw`` (part ``k`` at times ``t_s[k]``,
    sampled every ``dt_s[k]``) in the blocks :func:`block_sums` cuts with the same ``block_s``:
    the variance of one sample is half that of a first difference (a drift moves little from one
    sample to the next; each block's mean difference, its slope, is taken out). A difference
    across a gap (a step over :data:`~tcbench.sensors.segments.GAP_FACTOR` sample intervals) or
    beyond :data:`OUTLIER_Z` robust sigmas of all the parts' differences (a spike, a bias step) is
    left out. White noise's running mean over ``w`` samples has ``1 / w`` of its variance."""
    diffs, keeps = [], []
    for res, t, dt in zip(raw, t_s, dt_s, strict=True):
        d = np.diff(np.asarray(res, dtype=np.float64))
        diffs.append(d)
        keeps.append((np.diff(np.asarray(t, dtype=np.float64)) <= GAP_FACTOR * dt) & np.isfinite(d))
    kept = np.concatenate([d[k] for d, k in zip(diffs, keeps, strict=True)] or [np.array([])])
    if kept.size:
        centre = float(np.median(kept))
        scale = 1.4826 * float(np.median(np.abs(kept - centre))) or float(np.std(kept))
        if scale > 0:
            keeps = [k & (np.abs(d - centre) <= OUTLIER_Z * scale) for d, k in zip(diffs, keeps, strict=True)]
    squares, counts = [], []
    for res, d, keep, dt in zip(raw, diffs, keeps, dt_s, strict=True):
        n = res.size
        width = max(1, int(round(window_s / dt)))
        track = (n - width + 1 if n >= width else 1) if n else 0
        edges = _block_edges(track, dt, block_s)
        if not edges.size:
            continue
        w = np.append(keep, False).astype(np.float64)  # one padding sample: every edge indexes it
        x = np.append(np.where(keep, d, 0.0), 0.0)
        c = np.add.reduceat(w, edges)
        s1, s2 = np.add.reduceat(x, edges), np.add.reduceat(x ** 2, edges)
        with np.errstate(divide="ignore", invalid="ignore"):
            centred = np.where(c > 0, s2 - s1 ** 2 / np.where(c > 0, c, 1.0), 0.0)
        squares.append(np.clip(centred, 0.0, None) / (2.0 * width))
        counts.append(np.clip(c - 1.0, 0.0, None))
    return NoiseSums(np.concatenate(squares or [np.array([])]), np.concatenate(counts or [np.array([])]))


@dataclass(frozen=True)
class FloorIntervals:
    """The white-noise floor ``(point, lo, hi)``, each method's held-out drift (RMS over the parts)
    and its drift over the floor ``(point, lo, hi)``."""

    floor: tuple[float, float, float]
    drift: dict[str, float]
    x_floor: dict[str, tuple[float, float, float]]


def floor_intervals(sums: BlockSums, noise: NoiseSums, restarts: Mapping[str, Sequence[str]], seed: int = 0,
                    draws: int = DRAWS, level: float = LEVEL) -> FloorIntervals:
    """The white-noise floor and each method's held-out drift over it, with ``level`` intervals of
    a block bootstrap drawn within each held-out part (a part keeps its number of blocks; every
    method and the floor on the same draws). A method's drift is the RMS over the held-out parts
    of each part's drift, the median over its restarts (``restarts``: method -> its keys in
    ``sums.squares``), as a calibration's table scores a part. NaN bounds with one block."""
    part = sums.part if sums.part is not None else np.zeros(sums.counts.size, dtype=np.int64)
    nb = sums.counts.size
    if noise.counts.size != nb:
        raise ValueError(f"the noise has {noise.counts.size} blocks and the drift {nb}: cut them alike")
    starts = np.flatnonzero(np.r_[True, part[1:] != part[:-1]]) if nb else np.array([], dtype=np.int64)
    sizes = np.diff(np.r_[starts, nb])
    first, size = np.repeat(starts, sizes), np.repeat(sizes, sizes)
    rng = np.random.default_rng(seed)
    idx = np.vstack([np.arange(nb), first + rng.integers(0, size, size=(draws, nb))])  # row 0: the point
    with np.errstate(divide="ignore", invalid="ignore"):
        floor = np.sqrt(noise.squares[idx].sum(axis=1) / noise.counts[idx].sum(axis=1))
        n = np.add.reduceat(sums.counts[idx], starts, axis=1)
        drift = {}
        for m, keys in restarts.items():
            per_part = np.median([np.sqrt(np.add.reduceat(sums.squares[k][idx], starts, axis=1) / n) for k in keys],
                                 axis=0)
            drift[m] = np.sqrt(np.mean(per_part ** 2, axis=1))
    q = [(1 - level) / 2, (1 + level) / 2]

    def interval(x: np.ndarray) -> tuple[float, float, float]:
        if nb < 2 or not np.isfinite(x[1:]).any():
            return float(x[0]), float("nan"), float("nan")
        lo, hi = np.nanquantile(x[1:], q)
        return float(x[0]), float(lo), float(hi)

    return FloorIntervals(interval(floor), {m: float(d[0]) for m, d in drift.items()},
                          {m: interval(d / floor) for m, d in drift.items()})


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
