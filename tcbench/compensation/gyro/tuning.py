"""Multi-objective tuning of VMD's ``[k, alpha]`` (seed 001 §3.2 and §4.2, the "MOVMD" step).

Seed 001 searches ``k`` in [4, 12] and ``alpha`` in [1000, 10000] with MOPSO (Np = NR = 40,
M = 10, W = 0.4, c1 = c2 = 1.5) against two fitness functions, fuzzy entropy (FE, eq. 8-15) and
permutation entropy (PE, eq. 16-20), both to be minimised ("when the fitness values are smaller,
the corresponding VMD decomposition parameters are better"), and reports ``[8, 9755]``. It does
not say which signal the entropies are taken of, nor how one point of the Pareto set is chosen.
tcbench states its reading:

- **signal**: a contiguous window of ``samples`` samples (default 2048) from the middle of the
  training record, at its own sample rate (``alpha`` is in cycles/sample, so a value tuned on
  the window applies to the whole record at that rate); the O(N^2) fuzzy entropy keeps the
  window short;
- **objectives**: the mean over the ``k`` modes of their fuzzy entropy (m = 2, r = 0.2 std,
  n = 2) and the mean of their normalised permutation entropy (order 3, delay 1): a low value of
  both means each mode is a regular, narrow-band component (no mode mixing);
- **k** is the candidate's first coordinate rounded to the nearest integer;
- **choice**: the Pareto point nearest the ideal point (each objective's minimum over the set)
  after scaling each objective to [0, 1] over the set; ties go to the smaller ``k``.
"""

from __future__ import annotations

import numpy as np

from tcbench.signal.entropy import fuzzy_entropy, permutation_entropy
from tcbench.signal.vmd import vmd

K_RANGE = (4.0, 12.0)
ALPHA_RANGE = (1000.0, 10000.0)
PAPER_BEST = (8, 9755.0)  # seed 001 §4.2
OBJECTIVES = ("mean fuzzy entropy of the modes", "mean permutation entropy of the modes")
REF_POINT = (2.5, 1.0)  # hypervolume reference: above white noise's FE (~2.2) and PE's maximum 1


def tuning_window(y: np.ndarray, samples: int = 2048) -> np.ndarray:
    """The contiguous ``samples``-long window from the middle of ``y`` (all of ``y`` if shorter)."""
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 64:
        raise ValueError(f"tuning_samples must be an integer >= 64, got {samples!r}")
    y = np.asarray(y, dtype=np.float64)
    start = max(0, (y.size - samples) // 2)
    return y[start:start + samples].copy()


def decode(x: np.ndarray) -> tuple[int, float]:
    """``(k, alpha)`` of a candidate ``[k, alpha]`` (k rounded to the nearest integer)."""
    return int(np.rint(x[0])), float(x[1])


def vmd_objectives(signal: np.ndarray, k: int, alpha: float) -> np.ndarray:
    """``[mean FE, mean PE]`` of the VMD modes of ``signal`` for ``k`` modes and ``alpha``."""
    modes = vmd(signal, k, alpha).modes
    fe = [fuzzy_entropy(u) if np.std(u) > 0 else 0.0 for u in modes]
    pe = [permutation_entropy(u) for u in modes]
    return np.array([np.mean(fe), np.mean(pe)])


def compromise(front_x: np.ndarray, front_f: np.ndarray) -> int:
    """Index of the Pareto point nearest the ideal point in objectives scaled to [0, 1]."""
    f = np.asarray(front_f, dtype=np.float64)
    if f.ndim != 2 or f.shape[0] == 0:
        raise ValueError("the Pareto set is empty")
    span = np.ptp(f, axis=0)
    scaled = (f - f.min(axis=0)) / np.where(span > 0, span, 1.0)
    dist = np.hypot(scaled[:, 0], scaled[:, 1])
    order = np.lexsort((np.rint(np.asarray(front_x)[:, 0]), dist))
    return int(order[0])
