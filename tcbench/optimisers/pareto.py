"""Pareto dominance for minimisation, vectorised over a population."""

from __future__ import annotations

import numpy as np


def dominates(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``out[i, j]``: row ``a[i]`` dominates row ``b[j]`` (no worse in all, better in one)."""
    le = np.all(a[:, None, :] <= b[None, :, :], axis=2)
    lt = np.any(a[:, None, :] < b[None, :, :], axis=2)
    return le & lt


def nondominated(f: np.ndarray) -> np.ndarray:
    """Boolean mask of the rows of ``f`` (n, m) that no other row dominates; of identical rows
    only the first is kept."""
    if f.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    dominated = dominates(f, f).any(axis=0)
    _, first = np.unique(f, axis=0, return_index=True)
    unique = np.zeros(f.shape[0], dtype=bool)
    unique[first] = True
    return ~dominated & unique
