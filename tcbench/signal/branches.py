"""Temperature branches of a chamber record: the stretches over which the temperature goes one
way (cooling or heating), split at its turning points.

A calibration is fitted on some branches and scored on others (a heating branch against the
cooling branch before it shows what a model of the thermometer alone misses: a lag, a
hysteresis). A turning point is a maximum or minimum of the smoothed temperature that stands out
by at least ``min_swing_c`` from the extremes on both sides of it (its prominence), so a soak's
noise or a small overshoot does not split a branch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import median_filter


@dataclass(frozen=True)
class Branch:
    """Samples ``start:stop`` of a record, over which the smoothed temperature goes from
    ``from_c`` to ``to_c``."""

    start: int
    stop: int
    from_c: float
    to_c: float

    @property
    def direction(self) -> str:
        return "heating" if self.to_c > self.from_c else "cooling"

    @property
    def span_c(self) -> float:
        return abs(self.to_c - self.from_c)


def _alternating(smooth: np.ndarray, maxima: np.ndarray, minima: np.ndarray) -> np.ndarray:
    """The turning points as alternating maxima and minima: of two of a kind in a row (equal
    readings of one soak both count as prominent), the more extreme one, the earlier on a tie.
    A loop over the few turning points, not over samples."""
    kind = dict.fromkeys(maxima.tolist(), 1.0) | dict.fromkeys(minima.tolist(), -1.0)
    kept: list[int] = []
    for i in sorted(kind):
        if kept and kind[kept[-1]] == kind[i]:
            if kind[i] * smooth[i] > kind[i] * smooth[kept[-1]]:
                kept[-1] = i
        else:
            kept.append(i)
    return np.asarray(kept, dtype=np.int64)


def temperature_branches(t_s: np.ndarray, temp_c: np.ndarray, min_swing_c: float = 5.0,
                         smooth_s: float = 60.0) -> list[Branch]:
    """The branches of a record, in time order, covering every sample; a record whose
    temperature never swings by ``min_swing_c`` is one branch. The temperature is smoothed by a
    running median over ``smooth_s`` (the thermometer's noise and quantisation steps)."""
    t = np.asarray(t_s, dtype=np.float64)
    temp = np.asarray(temp_c, dtype=np.float64)
    if t.shape != temp.shape or t.ndim != 1 or t.size < 2:
        raise ValueError("need matching 1-D time and temperature arrays of at least two samples")
    if not (np.isfinite(t).all() and np.isfinite(temp).all()) or np.any(np.diff(t) <= 0):
        raise ValueError("time must increase strictly and both arrays be finite")
    if not min_swing_c > 0 or not smooth_s >= 0:
        raise ValueError("min_swing_c must be > 0 and smooth_s >= 0")
    from scipy.signal import find_peaks  # here: scipy.signal takes about a second to import

    width = max(1, int(round(smooth_s / float(np.median(np.diff(t))))) | 1)
    smooth = median_filter(temp, size=min(width, temp.size - (temp.size % 2 == 0)), mode="nearest")
    maxima, _ = find_peaks(smooth, prominence=min_swing_c)
    minima, _ = find_peaks(-smooth, prominence=min_swing_c)
    edges = np.concatenate([[0], _alternating(smooth, maxima, minima), [temp.size - 1]])
    out = []
    for k, (a, b) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        stop = int(b) + 1 if k == len(edges) - 2 else int(b)
        out.append(Branch(int(a), stop, float(smooth[a]), float(smooth[b])))
    return out


def time_blocks(t_s: np.ndarray, temp_c: np.ndarray, blocks: int) -> list[Branch]:
    """The record cut into ``blocks`` parts of equal duration, in time order (a record with one
    temperature branch, such as a single cooling, is then fitted on some blocks and scored on
    the others); each part's ``from_c``/``to_c`` are its first and last temperatures."""
    t = np.asarray(t_s, dtype=np.float64)
    if not 1 <= blocks <= t.size:
        raise ValueError(f"blocks must be 1..{t.size} (the samples), got {blocks}")
    cuts = np.searchsorted(t, np.linspace(t[0], t[-1], blocks + 1)[1:-1])
    edges = np.concatenate([[0], cuts, [t.size]]).astype(int)
    if np.any(np.diff(edges) == 0):
        raise ValueError(f"{blocks} blocks of equal duration leave one without samples; use fewer")
    return [Branch(int(a), int(b), float(temp_c[a]), float(temp_c[b - 1])) for a, b in zip(edges[:-1], edges[1:],
                                                                                           strict=True)]
