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

from functools import lru_cache
from typing import NamedTuple

import numpy as np


def squared_distances(x: np.ndarray) -> np.ndarray:
    """Pairwise squared Euclidean distances ``r_ij^2`` of the rows of ``x`` (n, d), as
    ``|x_i|^2 + |x_j|^2 - 2 x_i.x_j`` floored at 0."""
    sq = np.einsum("ij,ij->i", x, x)
    r2 = np.add.outer(sq, sq)
    gram = x @ x.T
    gram *= 2.0
    r2 -= gram
    return np.maximum(r2, 0.0, out=r2)


def attractiveness(
    r2: np.ndarray, beta0: float, gamma: float, beta_min: float = 0.0
) -> np.ndarray:
    """Eq. 4: ``beta = beta0 exp(-gamma r^2)``; with ``beta_min > 0`` Yang's floored form
    ``beta_min + (beta0 - beta_min) exp(-gamma r^2)``. ``r2`` is left unchanged."""
    beta = np.multiply(r2, -gamma)
    np.exp(beta, out=beta)
    if beta0 - beta_min != 1.0:  # multiplying by 1 and adding 0 would change nothing
        beta *= beta0 - beta_min
    if beta_min != 0.0:
        beta += beta_min
    return beta


class PullLayout(NamedTuple):
    """Where the random steps of one round of moves go (see :func:`pull_layout`).

    pulls: number of moves made, one random step each, drawn in (i, j) row-major order.
    starts: index of the first step of each firefly that moves, in row order.
    moving, lone: the rows that move toward somebody and those that move toward nobody, as
        slices when they are contiguous (the brightest fireflies first), else as masks.
    n_lone: number of lone rows, each taking one random step after the pulls' steps.
    """

    pulls: int
    starts: np.ndarray
    moving: slice | np.ndarray
    lone: slice | np.ndarray
    n_lone: int


@lru_cache(maxsize=16)
def _everyone_brighter(n: int) -> tuple[np.ndarray, PullLayout]:
    """The strictly lower triangle (firefly i pulled by every j < i, the FA case with distinct
    values) and its layout, built once per population size."""
    mask = np.tri(n, k=-1, dtype=bool)
    starts = np.cumsum(np.arange(n - 1))
    for array in (mask, starts):
        array.setflags(write=False)
    return mask, PullLayout(n * (n - 1) // 2, starts, slice(1, None), slice(None, 1), 1)


def pull_layout(moves: np.ndarray) -> PullLayout:
    """The layout of the random steps for the (n, n) mask ``moves[i, j]``: i moves toward j."""
    n = len(moves)
    triangle, layout = _everyone_brighter(n)
    if (moves == triangle).all():
        return layout
    per_row = moves.sum(axis=1)
    ends = np.cumsum(per_row)
    movers = per_row > 0
    n_lone = n - int(np.count_nonzero(movers))
    if movers[n_lone:].all():
        moving, lone = slice(n_lone, None), slice(None, n_lone)
    else:
        moving, lone = movers, ~movers
    return PullLayout(int(ends[-1]), (ends - per_row)[moving], moving, lone, n_lone)


def move_towards(
    x: np.ndarray, coef: np.ndarray, step: np.ndarray | float, rng: np.random.Generator
) -> np.ndarray:
    """Move every firefly along its chain of attractions (eq. 5, composed in closed form).

    Parameters
    ----------
    x: positions (n, d), sorted brightest first.
    coef: (n, n) attraction ``beta_ij`` of firefly i toward j; 0 where i does not move toward j.
    step: step size alpha, scalar or per-axis (d,), multiplying ``xi - 1/2`` with xi ~ U[0, 1].
    rng: source of the random steps.

    A firefly with no attraction at all takes one random step ``alpha (xi - 1/2)``. Returns a new
    (n, d) array; ``x`` and ``coef`` are left unchanged.
    """
    n, d = x.shape
    moves = coef > 0.0
    # chain[:, j] = prod_{l >= j} c_il for j < n and chain[:, n] = 1 (the empty product), so
    # chain[:, 0] is prod_j c_ij and chain[:, 1:] holds S_ij.
    chain = np.empty((n, n + 1))
    chain[:, n] = 1.0
    np.subtract(1.0, coef, out=chain[:, :n])
    np.multiply.accumulate(chain[:, ::-1], axis=1, out=chain[:, ::-1])
    after = chain[:, 1:]
    out = chain[:, :1] * x + (after * coef) @ x
    # One random step per move actually made, in (i, j) row-major order, then one for each
    # firefly that moves toward nobody, all from a single draw.
    layout = pull_layout(moves)
    noise = rng.random((layout.pulls + layout.n_lone, d))
    noise -= 0.5
    noise *= step
    if layout.pulls:
        steps = noise[: layout.pulls]
        steps *= after[moves][:, None]  # S_ij alpha (xi - 1/2), then summed per firefly
        out[layout.moving] += np.add.reduceat(steps, layout.starts, axis=0)
    if layout.n_lone:
        out[layout.lone] = x[layout.lone] + noise[layout.pulls :]
    return out


def brighter_mask(f: np.ndarray) -> np.ndarray:
    """``mask[i, j]`` is true where firefly j is strictly brighter (lower f) than i."""
    return f[None, :] < f[:, None]
