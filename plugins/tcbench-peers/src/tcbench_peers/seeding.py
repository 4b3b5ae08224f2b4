"""Seeds for the peer libraries, drawn from the run's ``numpy.random.Generator``."""

from __future__ import annotations

import numpy as np


def library_seed(rng: np.random.Generator) -> int:
    """A 31-bit integer seed for a library that takes one (cma, nevergrad, optuna, scipy, pymoo)."""
    return int(rng.integers(1, 2**31 - 1))
