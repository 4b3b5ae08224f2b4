"""Pure, vectorised firefly movement shared by FA and IFA (seed 000 eq. 4-5).

In the reference firefly algorithm each firefly ``i`` visits every brighter firefly ``j`` in
turn and moves ``x_i <- x_i + beta_ij (x_j - x_i) + alpha (xi - 1/2)``: a chain of affine maps.
Taking every ``beta_ij`` from the distances at the start of the generation (eq. 4 with
``r_ij(n)``, as eq. 5 is written), the chain has a closed form, so a whole population moves in a
few array operations instead of a double loop over fireflies::

    x_i' = x_i prod_j c_ij + sum_j S_ij (beta_ij x_j + alpha u_ij)
    c_ij = 1 - beta_ij,   S_ij = prod_{l > j} c_il

with ``j`` running over the columns in order (the population is kept sorted, brightest first,
so the last pull is the dimmest brighter firefly's, as in a loop over a sorted population).
Because ``0 < beta <= beta0 <= 1`` each pull is a convex step and a crowd of brighter fireflies
cannot fling ``x_i`` past them, which a summed form of eq. 5 would do.
"""

from __future__ import annotations

import numpy as np


def squared_distances(x: np.ndarray) -> np.ndarray:
    """Pairwise squared Euclidean distances ``r_ij^2`` of the rows of ``x`` (n, d)."""
    sq = np.einsum("ij,ij->i", x, x)
    r2 = sq[:, None] + sq[None, :] - 2.0 * (x @ x.T)
    return np.maximum(r2, 0.0)


def attractiveness(
    r2: np.ndarray, beta0: float, gamma: float, beta_min: float = 0.0
) -> np.ndarray:
    """Eq. 4: ``beta = beta0 exp(-gamma r^2)``; with ``beta_min > 0`` Yang's floored form
    ``beta_min + (beta0 - beta_min) exp(-gamma r^2)``."""
    return beta_min + (beta0 - beta_min) * np.exp(-gamma * r2)


def move_towards(
    x: np.ndarray, coef: np.ndarray, step: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """Move every firefly along its chain of attractions (eq. 5, composed in closed form).

    Parameters
    ----------
    x: positions (n, d), sorted brightest first.
    coef: (n, n) attraction ``beta_ij`` of firefly i toward j; 0 where i does not move toward j.
    step: step size alpha, scalar or per-axis (d,), multiplying ``xi - 1/2`` with xi ~ U[0, 1].
    rng: source of the random steps.

    A firefly with no attraction at all takes one random step ``alpha (xi - 1/2)``.
    """
    n, d = x.shape
    moves = coef > 0.0
    keep = 1.0 - coef
    through = np.cumprod(keep[:, ::-1], axis=1)[:, ::-1]  # prod_{l >= j} c_il
    after = np.concatenate([through[:, 1:], np.ones((n, 1))], axis=1)  # prod_{l > j} c_il
    out = through[:, :1] * x + (after * coef) @ x
    # One random step per move actually made, drawn in (i, j) row-major order.
    rows, cols = np.nonzero(moves)
    if rows.size:
        noise = (rng.random((rows.size, d)) - 0.5) * step * after[rows, cols][:, None]
        starts = np.flatnonzero(np.r_[True, rows[1:] != rows[:-1]])
        out[rows[starts]] += np.add.reduceat(noise, starts, axis=0)
    lone = ~moves.any(axis=1)
    if lone.any():
        out[lone] = x[lone] + (rng.random((int(lone.sum()), d)) - 0.5) * step
    return out


def brighter_mask(f: np.ndarray) -> np.ndarray:
    """``mask[i, j]`` is true where firefly j is strictly brighter (lower f) than i."""
    return f[None, :] < f[:, None]
