"""Continuous segments of a recording's clock: a logger's bursts with gaps between them.

A new segment starts after a gap of more than :data:`GAP_FACTOR` median sample intervals. The
within-segment sample rate is one over the median interval inside the segments; the gaps never
count as samples. Import, metrics and diagnosis share these definitions.
"""

from __future__ import annotations

import numpy as np

GAP_FACTOR = 5.0  # a step longer than this many median sample intervals starts a new segment


def gaps(t_s: np.ndarray) -> np.ndarray:
    """One flag per step of the clock (``t_s.size - 1``): True where the step is a gap of more
    than five median sample intervals, so that a new segment starts after it."""
    t_s = np.asarray(t_s, dtype=np.float64)
    if t_s.size < 2:
        return np.zeros(max(t_s.size - 1, 0), dtype=bool)
    gap_s = GAP_FACTOR * np.median(np.diff(t_s), overwrite_input=True)  # one interval array at a time
    return np.diff(t_s) > gap_s


def segments(t_s: np.ndarray) -> np.ndarray:
    """Segment number per sample (0, 1, ...): a new segment starts after a gap of more than
    five median sample intervals (a logger's bursts)."""
    t_s = np.asarray(t_s, dtype=np.float64)
    out = np.zeros(t_s.size, dtype=np.int64)
    if t_s.size >= 2:
        np.cumsum(gaps(t_s), out=out[1:])
    return out


def bounds(segment: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(starts, stops)``: segment ``k`` is the samples ``starts[k]:stops[k]`` of a
    non-decreasing segment number per sample (as :func:`segments` gives)."""
    segment = np.asarray(segment)
    starts = np.flatnonzero(np.diff(segment, prepend=segment[:1] - 1)) if segment.size else np.zeros(0, np.int64)
    return starts, np.append(starts[1:], segment.size)


def gap_bounds(gap: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`bounds` of the segments that the step flags ``gap`` (as :func:`gaps` gives) make
    of ``gap.size + 1`` samples."""
    starts = np.concatenate((np.zeros(1, np.int64), np.flatnonzero(gap) + 1))
    return starts, np.append(starts[1:], gap.size + 1)


def within_rate_hz(t_s: np.ndarray, segment: np.ndarray | None = None, gap: np.ndarray | None = None) -> float:
    """One over the median sample interval inside the segments (gaps excluded), in Hz; the
    segments given by ``segment`` (as :func:`segments` gives) or ``gap`` (as :func:`gaps`), else
    found here."""
    t_s = np.asarray(t_s, dtype=np.float64)
    if t_s.size < 2:
        raise ValueError("a sample rate needs at least two samples")
    if gap is not None:
        inside = ~np.asarray(gap, dtype=bool)
    else:
        segment = segments(t_s) if segment is None else np.asarray(segment)
        inside = segment[1:] == segment[:-1]
    dt = np.diff(t_s)
    if inside.any() and not inside.all():
        dt = dt[inside]
    return 1.0 / float(np.median(dt, overwrite_input=True))
