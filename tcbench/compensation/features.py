"""Input features a compensation model derives from a recording's thermometer."""

from __future__ import annotations

import numpy as np


def _prefix_sums(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Prefix sums ``P[k] = x[0] + ... + x[k-1]`` (``P[0] = 0``) as ``high + low``: ``high`` is
    the running float sum and ``low`` accumulates the rounding error of each of its additions,
    recovered exactly by the two-sum identity, so a window sum ``P[b] - P[a]`` keeps its
    precision however large ``P`` has grown."""
    high = np.cumsum(x)
    before = np.r_[0.0, high[:-1]]
    added = high - before
    error = (before - (high - added)) + (x - added)
    return np.r_[0.0, high], np.r_[0.0, np.cumsum(error)]


Moments = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]  # n, mean t, mean y, Stt, Sty


def _merged(a: Moments, b: Moments, gap_t: np.ndarray, gap_y: np.ndarray) -> Moments:
    """The centred moments of two groups of samples together: each group as ``(count, mean time,
    mean temperature, sum of squared time deviations, sum of time-temperature deviation
    products)``, its means relative to its own first sample; ``gap_t``, ``gap_y``: ``b``'s first
    sample minus ``a``'s. The result's means are relative to ``a``'s first sample. Every term is
    a deviation from a mean, so nothing cancels (the pairwise update of Chan, Golub and LeVeque)."""
    na, ta, ya, tta, tya = a
    nb, tb, yb, ttb, tyb = b
    n = na + nb
    share = nb / n
    dt = gap_t + (tb - ta)
    dy = gap_y + (yb - ya)
    return n, ta + dt * share, ya + dy * share, tta + ttb + dt * dt * na * share, tya + tyb + dt * dy * na * share


def temperature_rate_c_per_s(t_s: np.ndarray, temp_c: np.ndarray, window_s: float = 120.0) -> np.ndarray:
    """Causal temperature rate (degC/s): at each sample, the least-squares slope of ``temp_c``
    against ``t_s`` over the trailing window ``t_i - window_s < t_j <= t_i``.

    Only past and present samples are used, so it can run online. Near the start the window
    holds fewer samples (the slope of what is available); with one sample the rate is 0. Times
    need not be uniform but must increase. Each window's moments are centred on the window's own
    means, as a device computing it sample by sample does (the exported C: two passes over its
    ring of the window's samples); moments summed about a distant reference (say the record's
    first sample) and centred afterwards cancel, and lose most of their digits where a window
    holds a few close samples far from it. All windows at once: the centred moments of aligned
    blocks of 1, 2, 4, ... samples are merged pairwise (:func:`_merged`), and each window is
    merged from at most ``2 log2(w)`` of them, w the most samples a window holds (O(n log w)
    work). A window's rate depends on its own samples only, in the last bit too.
    """
    t = np.asarray(t_s, dtype=np.float64).reshape(-1)
    y = np.asarray(temp_c, dtype=np.float64).reshape(-1)
    if t.shape != y.shape:
        raise ValueError(f"t_s has {t.size} samples, temp_c {y.size}")
    if not window_s > 0:
        raise ValueError(f"window_s must be > 0, got {window_s}")
    if t.size == 0:
        return np.zeros(0)
    if np.any(np.diff(t) <= 0):
        raise ValueError("t_s must be strictly increasing")
    stop = np.arange(1, t.size + 1)
    start = np.searchsorted(t, t - window_s, side="right")
    top = int(np.frexp(int(np.max(stop - start)))[1] - 1)  # the largest block a window can take
    zero = np.zeros(t.size)
    levels: list[Moments] = [(np.ones(t.size), zero, zero, zero, zero)]  # level k: blocks [p 2^k, (p+1) 2^k)
    for k in range(top):
        lower = levels[-1]
        m = t.size >> (k + 1)
        first, second = np.arange(m) << (k + 1), (np.arange(m) << (k + 1)) + (1 << k)
        levels.append(_merged(tuple(v[0:2 * m:2] for v in lower), tuple(v[1:2 * m:2] for v in lower),  # type: ignore[arg-type]
                              t[second] - t[first], y[second] - y[first]))
    offsets = np.cumsum([0] + [lv[0].size for lv in levels])
    table = tuple(np.concatenate([lv[j] for lv in levels]) for j in range(5))
    acc: Moments = tuple(np.zeros(t.size) for _ in range(5))  # type: ignore[assignment]  # each window's so far, about its first sample
    left = start.copy()
    while (rows := np.flatnonzero(left < stop)).size:
        at = left[rows]
        lowest = np.where(at > 0, at & -at, 1 << 62)  # the largest aligned block starting at ``at``
        level = np.minimum(np.minimum(np.frexp(lowest)[1], np.frexp(stop[rows] - at)[1]) - 1, top)
        block = tuple(v[offsets[level] + (at >> level)] for v in table)
        here = tuple(v[rows] for v in acc)
        both = _merged(here, block, t[at] - t[start[rows]], y[at] - y[start[rows]])  # type: ignore[arg-type]
        for j in range(5):
            acc[j][rows] = both[j]
        left[rows] = at + (1 << level)
    n, _, _, stt, sty = acc
    ok = (n >= 2) & (stt > 0)
    return np.where(ok, sty / np.where(ok, stt, 1.0), 0.0)


def running_mean(x: np.ndarray, width: int) -> np.ndarray:
    """Means of every ``width`` consecutive values of ``x`` (``np.convolve(x, ones(width) / width,
    "valid")``, ``x.size - width + 1`` values) from compensated prefix sums (:func:`_prefix_sums`):
    O(n) whatever the width, and as precise as the direct sums."""
    v = np.asarray(x, dtype=np.float64).reshape(-1)
    if not 1 <= width <= v.size:
        raise ValueError(f"width must be 1..{v.size}, got {width}")
    high, low = _prefix_sums(v)
    return ((high[width:] - high[:-width]) + (low[width:] - low[:-width])) / width


def bin_means(t_s: np.ndarray, columns: np.ndarray, bin_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Means over consecutive time bins ``[t_0 + k bin_s, t_0 + (k+1) bin_s)`` of the samples at
    increasing times ``t_s``: the bins' mean times and the means of each column of ``columns``
    (n, c), one row per bin that holds a sample (an empty bin, a gap, gives no row). Every sample
    counts once, so the count-weighted mean of the bin means is the mean of the samples."""
    t = np.asarray(t_s, dtype=np.float64).reshape(-1)
    cols = np.asarray(columns, dtype=np.float64)
    cols = cols.reshape(t.size, -1)
    if not bin_s > 0:
        raise ValueError(f"bin_s must be > 0, got {bin_s}")
    if t.size == 0:
        return t.copy(), cols.copy()
    if np.any(np.diff(t) <= 0):
        raise ValueError("t_s must be strictly increasing")
    index = np.floor((t - t[0]) / bin_s).astype(np.int64)
    starts = np.flatnonzero(np.r_[True, index[1:] != index[:-1]])
    counts = np.diff(np.r_[starts, t.size]).astype(np.float64)
    t_mean_s = t[0] + np.add.reduceat(t - t[0], starts) / counts
    return t_mean_s, np.add.reduceat(cols, starts, axis=0) / counts[:, None]
