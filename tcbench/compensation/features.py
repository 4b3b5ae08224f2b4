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


def temperature_rate_c_per_s(t_s: np.ndarray, temp_c: np.ndarray, window_s: float = 120.0) -> np.ndarray:
    """Causal temperature rate (degC/s): at each sample, the least-squares slope of ``temp_c``
    against ``t_s`` over the trailing window ``t_i - window_s < t_j <= t_i``.

    Only past and present samples are used, so it can run online. Near the start the window
    holds fewer samples (the slope of what is available); with one sample the rate is 0. Times
    need not be uniform but must increase. Computed for all samples at once from cumulative
    sums of the times and temperatures relative to the first sample (a global centring would
    let later samples change earlier rates in the last bits), compensated so that a long
    record loses no precision (:func:`_prefix_sums`).
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
    tc, yc = t - t[0], y - y[0]
    stop = np.arange(1, t.size + 1)
    start = np.searchsorted(t, t - window_s, side="right")
    sums = []
    for values in (np.ones_like(tc), tc, yc, tc * tc, tc * yc):
        high, low = _prefix_sums(values)
        sums.append((high[stop] - high[start]) + (low[stop] - low[start]))
    n, st, sy, stt, sty = sums
    den = n * stt - st * st
    num = n * sty - st * sy
    ok = (n >= 2) & (den > 0)
    return np.where(ok, num / np.where(ok, den, 1.0), 0.0)


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
