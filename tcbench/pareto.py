"""Pareto dominance for minimisation, vectorised over a population: a leaf module (numpy only) that
the optimisers, the multi-objective tasks and the optimiser checks share."""

from __future__ import annotations

import numpy as np


def dominates(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``out[i, j]``: row ``a[i]`` dominates row ``b[j]`` (no worse in all, better in one).

    Loops over the (few) objectives with 2-D comparisons, which is much faster than one
    reduction over a trailing axis of length m."""
    le = np.ones((a.shape[0], b.shape[0]), dtype=bool)
    lt = np.zeros_like(le)
    for j in range(a.shape[1]):
        aj, bj = a[:, j, None], b[None, :, j]
        le &= aj <= bj
        lt |= aj < bj
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


def merge_front(
    front_x: np.ndarray, front_f: np.ndarray, x: np.ndarray, f: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Non-dominated set of a non-dominated ``front`` plus new points, comparing the new points
    with each other and with the front only (O(k a + k^2), not O((a + k)^2)). A new point equal
    to one already in the front is dropped."""
    new = nondominated(f)
    x, f = x[new], f[new]
    if front_f.shape[0] == 0 or f.shape[0] == 0:
        return (np.concatenate([front_x, x]), np.concatenate([front_f, f]))
    beaten_new = dominates(front_f, f).any(axis=0)
    same = np.ones((front_f.shape[0], f.shape[0]), dtype=bool)
    for j in range(f.shape[1]):
        same &= front_f[:, j, None] == f[None, :, j]
    keep_new = ~beaten_new & ~same.any(axis=0)
    beaten_old = dominates(f[keep_new], front_f).any(axis=0)
    return (
        np.concatenate([front_x[~beaten_old], x[keep_new]]),
        np.concatenate([front_f[~beaten_old], f[keep_new]]),
    )
