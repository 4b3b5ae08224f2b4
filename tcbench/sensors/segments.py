"""Continuous segments of a recording's clock: a logger's bursts with gaps between them.

A new segment starts after a gap of more than :data:`GAP_FACTOR` median sample intervals. The
within-segment sample rate is one over the median interval inside the segments; the gaps never
count as samples. Import, metrics and diagnosis share these definitions.
"""

from __future__ import annotations

import numpy as np

GAP_FACTOR = 5.0  # a step longer than this many median sample intervals starts a new segment


def segments(t_s: np.ndarray) -> np.ndarray:
    """Segment number per sample (0, 1, ...): a new segment starts after a gap of more than
    five median sample intervals (a logger's bursts)."""
    t_s = np.asarray(t_s, dtype=np.float64)
    if t_s.size < 2:
        return np.zeros(t_s.size, dtype=np.int64)
    dt = np.diff(t_s)
    return np.concatenate(([0], np.cumsum(dt > GAP_FACTOR * np.median(dt))))


def bounds(segment: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(starts, stops)``: segment ``k`` is the samples ``starts[k]:stops[k]`` of a
    non-decreasing segment number per sample (as :func:`segments` gives)."""
    segment = np.asarray(segment)
    starts = np.flatnonzero(np.diff(segment, prepend=segment[:1] - 1)) if segment.size else np.zeros(0, np.int64)
    return starts, np.append(starts[1:], segment.size)


def within_rate_hz(t_s: np.ndarray, segment: np.ndarray | None = None) -> float:
    """One over the median sample interval inside the segments (gaps excluded), in Hz."""
    t_s = np.asarray(t_s, dtype=np.float64)
    if t_s.size < 2:
        raise ValueError("a sample rate needs at least two samples")
    segment = segments(t_s) if segment is None else np.asarray(segment)
    inside = np.diff(segment) == 0
    dt = np.diff(t_s)[inside] if inside.any() else np.diff(t_s)
    return 1.0 / float(np.median(dt))
