"""The Lomb-Scargle periodogram with memory bounded by a budget, not by samples x frequencies.

``scipy.signal.lombscargle`` builds several (samples x frequencies) arrays at once: 3000
frequencies of a 465 000-sample record ask for 10 GiB. Each frequency's power depends on that
frequency alone, so :func:`lombscargle_chunked` evaluates the frequencies in chunks of at most
:data:`MAX_ELEMENTS` samples x frequencies and returns the same numbers.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lombscargle

MAX_ELEMENTS = 1 << 22  # samples x frequencies per chunk: about 32 MiB per float64 array scipy builds


def chunk_size(n_samples: int, max_elements: int = MAX_ELEMENTS) -> int:
    """Frequencies evaluated together for ``n_samples`` samples (at least one)."""
    return max(1, max_elements // max(n_samples, 1))


def lombscargle_chunked(t_s: np.ndarray, x: np.ndarray, angular_hz: np.ndarray,
                        max_elements: int = MAX_ELEMENTS) -> np.ndarray:
    """``scipy.signal.lombscargle(t_s, x, angular_hz)`` (default normalisation), evaluated
    :func:`chunk_size` frequencies at a time."""
    w = np.asarray(angular_hz, dtype=np.float64)
    step = chunk_size(np.size(t_s), max_elements)
    return np.concatenate([lombscargle(t_s, x, w[i:i + step]) for i in range(0, w.size, step)]) if w.size else \
        np.zeros(0)
