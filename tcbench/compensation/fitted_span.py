"""Which temperature branches a calibration fits by default: those whose temperatures span what
the held-out branches need, so that the held-out score judges interpolation, not what each model
guesses beyond the fitted range.

Among the runs of consecutive branches that leave at least one branch held out, the default is
one with the smallest share of held-out samples beyond its temperature range (within
:data:`SHARE_TOLERANCE`: a few samples at a turning point do not cost a branch of held-out data):
of those, the fewest branches, then the smallest share, the widest range, the earliest. A record
of an oven heating to its hottest level and then stepping down to its coldest is fitted on the
long cooling, not on the first warm-up.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

SHARE_TOLERANCE = 0.01  # shares of held-out samples beyond the fitted range this close count as equal


@dataclass(frozen=True)
class SpanChoice:
    """The fitted parts (indices, in time order), their temperature range and the share of the
    held-out samples beyond it."""

    train: list[int]
    fitted_c: tuple[float, float]
    beyond_share: float


def beyond_share(temp_c: np.ndarray, parts: Sequence[Any], train: Sequence[int]) -> float:
    """The share of the samples outside ``train`` whose temperature lies beyond the range of the
    samples inside it (``parts``: slices with ``start``/``stop`` covering the record)."""
    temp = np.asarray(temp_c, dtype=np.float64)
    inside = np.zeros(temp.size, dtype=bool)
    for k in train:
        inside[parts[k].start:parts[k].stop] = True
    if inside.all() or not inside.any():
        return 0.0
    lo, hi = temp[inside].min(), temp[inside].max()
    held = temp[~inside]
    return float(np.mean((held < lo) | (held > hi)))


def spanning_parts(temp_c: np.ndarray, parts: Sequence[Any]) -> SpanChoice:
    """The run of consecutive ``parts`` to fit (at least one part left out) whose temperature
    range leaves the smallest share of the held-out samples beyond it, within
    :data:`SHARE_TOLERANCE`; of those the fewest parts, then the smallest share, the widest range,
    the earliest. ``parts`` cover the record in time order without overlap (its branches)."""
    temp = np.asarray(temp_c, dtype=np.float64)
    n = len(parts)
    if n < 2:
        raise ValueError("a record of one part holds nothing out: cut it into time blocks")
    lo = np.array([temp[p.start:p.stop].min() for p in parts])
    hi = np.array([temp[p.start:p.stop].max() for p in parts])
    rows = np.array([p.stop - p.start for p in parts])
    ordered = np.sort(temp)
    first, length, share, span = [], [], [], []
    for i in range(n):  # a loop over parts (a handful), each run's range by a running min/max
        run_lo, run_hi = np.minimum.accumulate(lo[i:]), np.maximum.accumulate(hi[i:])
        held = temp.size - np.cumsum(rows[i:])
        beyond = np.searchsorted(ordered, run_lo, "left") + temp.size - np.searchsorted(ordered, run_hi, "right")
        ok = held > 0
        first.append(np.full(ok.sum(), i))
        length.append(np.arange(1, n - i + 1)[ok])
        share.append(beyond[ok] / held[ok])
        span.append((run_hi - run_lo)[ok])
    first_, length_, share_, span_ = (np.concatenate(a) for a in (first, length, share, span))
    near = np.flatnonzero(share_ <= share_.min() + SHARE_TOLERANCE)
    best = near[np.lexsort((first_[near], -span_[near], share_[near], length_[near]))[0]]
    i, m = int(first_[best]), int(length_[best])
    train = list(range(i, i + m))
    return SpanChoice(train, (float(lo[i:i + m].min()), float(hi[i:i + m].max())), float(share_[best]))
