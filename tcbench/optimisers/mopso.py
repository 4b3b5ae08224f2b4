"""Multi-objective particle swarm optimisation (MOPSO), seed 001 §3.2 steps A-E, eq. 21-23
(Coello Coello, Pulido & Lechuga 2004, the paper's ref. [24]/[28]).

A swarm of ``population`` particles flies in decision space; an external archive (the paper's
"save set") of at most ``archive_size`` (NR) mutually non-dominated solutions is kept in an
adaptive hypergrid over objective space and supplies the global leaders.

- **B. Initialisation.** Positions uniform in the bounds, velocities zero, ``pbest = x``; the
  non-dominated finite points of the first population form the archive.
- **C(1). Adaptive grid.** Objective space is cut into ``grid_divisions`` equal intervals per
  objective between the archive's minimum and maximum of that objective, widened by
  ``grid_inflation`` times the range on each side (:func:`grid_bounds`, :func:`grid_index`).
  The grid is rebuilt from the archive every time it is used (Coello rebuilds it lazily, when a
  new member falls outside it; rebuilding always keeps it tight around the current archive).
  An objective on which all members agree has a single cell. Density = members per cell.
- **C(2). Leaders and personal bests.** For each particle a cell is drawn by roulette with
  probability proportional to ``count ** -leader_pressure`` (Coello: fitness ``x / count`` with
  ``x > 1``; ``x`` cancels in the roulette, ``leader_pressure = 1`` is exactly his rule), then a
  member of that cell uniformly (:func:`select_leaders`). The personal best is replaced when the
  new point dominates it, kept when it dominates the new point, and otherwise replaced with
  probability 1/2 (:func:`pbest_replace`); identical values count as "neither dominates".
- **C(3). Move.** Eq. 21 ``v <- mu (w v + c1 R1 (P - x) + c2 R2 (G - x))`` with ``R1, R2 ~ U[0, 1]``
  drawn independently per particle and per coordinate (:func:`velocity`), eq. 22 ``x <- x + v``.
  A coordinate that leaves the box is clamped to the violated bound and its velocity component
  is set to zero (``bound_velocity="zero"``, the default) or reversed (Coello: "multiplied by
  -1"; ``"reverse"``) (:func:`confine`). Zero is the default because Coello's rule fails where
  the Pareto set lies on a bound: on ZDT1 (d = 30, 10^4 evaluations, 30 seeds) the hypervolume
  ratio of everything evaluated is 0.953 (0.934-0.965) with zero against 0.829 (0.810-0.839,
  10 seeds) with reverse, because a reversed particle leaves the bound each time it reaches it
  (``benchmarks/RESULTS.md``, MOPSO section). Seed 001 inherits Coello's rule; set
  ``bound_velocity=reverse`` to reproduce it to the letter. Then Coello's mutation (:func:`mutate`): each particle is
  mutated with probability ``pm = (1 - t/T) ** (5 / mutation_rate)`` (``t`` the generation,
  ``T`` the planned number of generations) by redrawing one random coordinate uniformly in
  ``x +- pm * (upper - lower)`` clipped to the box; the velocity is left as it is. Early on
  every particle is mutated over the whole range, the share and the range then shrink quickly
  (with rate 0.5 the exponent is 10). ``mutation_rate = 0`` disables mutation.
- **Archive update (end of C).** The non-dominated finite points of the new generation are
  merged into the archive and only the non-dominated members of the union are kept (of
  identical values only the older member). Rows with a NaN/inf objective never enter it.
- **D. Truncation, eq. 23.** If the archive holds ``A > NR`` members, a grid is built over it and
  from every cell ``k`` with more than one member ``ND = Int(|A - NR| / A * Grid[k] + 0.5)``
  members are deleted at random (:func:`truncation_counts`), where ``N̄`` of eq. 23 is read as
  the maximum archive size NR and ``Grid[k, 2]`` as the member count of cell ``k``. Two
  completions where the printed rule is silent: ``ND`` is capped at ``Grid[k] - 1`` so a cell is
  never emptied (this only binds when ``(A - NR) / A > 3/4``, impossible while
  ``population <= archive_size``), and because rounding can leave more than NR members, the
  excess is then removed one at a time from the currently most crowded cell (Coello's own rule;
  ties at random). Rounding up can also remove a few more than ``A - NR``: eq. 23 as printed.
- **E. Stopping.** The budget (the last generation may evaluate only its first particles; the
  others keep their position, velocity and personal best) or ``max_generations`` (the paper's M).

Defaults are the paper's (§4: Np = NR = 40, W = 0.4, c1 = c2 = 1.5) except M = 10 generations,
which is replaced by budget-based stopping (``max_generations=None``). Where the paper is silent:
``mu = 1`` (eq. 21 without contraction is Coello's update), 10 grid divisions per objective
(Coello used 30 with archives of 100-250; with 40 members 10 per objective still separates
crowded from sparse regions), ``grid_inflation = 0`` (the grid spans the archive exactly, as
Coello's), ``mutation_rate = 0.5`` (Coello's). ``T`` of the mutation is the number of generations
the budget allows after the initial population (rounded up: the last may be partial), or
``max_generations`` if that is smaller, so the mutation has faded by the end of the run.

``archive`` is this algorithm's bounded, grid-truncated set; the base class's ``front`` is every
non-dominated point told during the run (unbounded), and so is never worse than the archive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.optimisers.protocol import Optimiser, OptimiserParams, ParetoSet
from tcbench.pareto import nondominated

BOUND_VELOCITY = ("reverse", "zero")


@dataclass(frozen=True)
class MOPSOParams(OptimiserParams):
    """MOPSO parameters; defaults from seed 001 §4 (Np = NR = 40, W = 0.4, c1 = c2 = 1.5).

    population: number of particles Np, >= 2.
    archive_size: maximum size NR of the external archive (save set), >= 1.
    w: inertia weight W of eq. 21, >= 0.
    c1, c2: cognitive and social learning factors of eq. 21, >= 0.
    mu: contraction factor of eq. 21, > 0 (the paper gives no value; 1 is Coello's update).
    grid_divisions: intervals per objective of the adaptive hypergrid, >= 1.
    grid_inflation: the grid spans the archive's range widened by this fraction of it on each
        side, >= 0.
    leader_pressure: exponent ``b`` of the leader roulette, cell probability ``~ count ** -b``,
        >= 0 (1 is Coello's ``x / count``; 0 picks cells uniformly).
    mutation_rate: Coello's mutation rate in [0, 1]; 0 disables mutation.
    bound_velocity: what happens to the velocity component of a clamped coordinate,
        ``"zero"`` (default; see the module docstring) or ``"reverse"`` (Coello).
    max_generations: stop after this many moves of the swarm (the paper's M = 10); None runs
        until the budget is spent.
    """

    population: int = 40
    archive_size: int = 40
    w: float = 0.4
    c1: float = 1.5
    c2: float = 1.5
    mu: float = 1.0
    grid_divisions: int = 10
    grid_inflation: float = 0.0
    leader_pressure: float = 1.0
    mutation_rate: float = 0.5
    bound_velocity: str = "zero"
    max_generations: int | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.archive_size < 1:
            raise ValueError(f"archive_size must be >= 1, got {self.archive_size}")
        for key in ("w", "c1", "c2", "grid_inflation", "leader_pressure"):
            value = getattr(self, key)
            if not (value >= 0 and math.isfinite(value)):
                raise ValueError(f"{key} must be a finite number >= 0, got {value}")
        if not (self.mu > 0 and math.isfinite(self.mu)):
            raise ValueError(f"mu must be a finite number > 0, got {self.mu}")
        if self.grid_divisions < 1:
            raise ValueError(f"grid_divisions must be >= 1, got {self.grid_divisions}")
        if not 0 <= self.mutation_rate <= 1:
            raise ValueError(f"mutation_rate must be in [0, 1], got {self.mutation_rate}")
        if self.bound_velocity not in BOUND_VELOCITY:
            raise ValueError(
                f"bound_velocity must be one of {', '.join(BOUND_VELOCITY)}, got {self.bound_velocity!r}"
            )
        if self.max_generations is not None and self.max_generations < 1:
            raise ValueError(f"max_generations must be >= 1, got {self.max_generations}")


# -- adaptive grid (step C(1)) -------------------------------------------------------------
def grid_bounds(f: np.ndarray, inflation: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Per-objective grid limits: the range of ``f`` (n, m) widened by ``inflation`` times it on
    each side."""
    lo, hi = f.min(axis=0), f.max(axis=0)
    pad = inflation * (hi - lo)
    return lo - pad, hi + pad


def grid_index(f: np.ndarray, lo: np.ndarray, hi: np.ndarray, divisions: int) -> np.ndarray:
    """Integer cell coordinates (n, m) of the rows of ``f`` in a grid of ``divisions`` equal
    intervals per objective on ``[lo, hi]``; values on the upper limit (or beyond) fall in the
    last cell, below ``lo`` in the first; an objective with ``hi == lo`` has one cell."""
    width = hi - lo
    safe = np.where(width > 0, width, 1.0)
    idx = np.floor((f - lo) / safe * divisions)
    idx = np.where(width > 0, idx, 0.0)
    return np.clip(idx, 0, divisions - 1).astype(np.int64)


def cell_census(idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cell number of every row of ``idx`` (n, m), numbered over the occupied cells only, and
    the member count of each occupied cell (the density of step C(1))."""
    _, cell, counts = np.unique(idx, axis=0, return_inverse=True, return_counts=True)
    return cell.reshape(-1), counts


def archive_cells(f: np.ndarray, divisions: int, inflation: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """:func:`cell_census` of ``f`` in the adaptive grid built over ``f`` itself."""
    lo, hi = grid_bounds(f, inflation)
    return cell_census(grid_index(f, lo, hi, divisions))


# -- leaders and personal bests (step C(2)) --------------------------------------------------
def leader_probabilities(counts: np.ndarray, pressure: float = 1.0) -> np.ndarray:
    """Roulette probability of each occupied cell, proportional to ``count ** -pressure``."""
    weight = counts.astype(np.float64) ** -pressure
    return weight / weight.sum()


def select_leaders(
    cell: np.ndarray, counts: np.ndarray, n: int, pressure: float, rng: np.random.Generator
) -> np.ndarray:
    """Archive rows of ``n`` leaders: a cell by density roulette, then one of its members
    uniformly; ``cell``/``counts`` as returned by :func:`cell_census`."""
    chosen = rng.choice(counts.size, size=n, p=leader_probabilities(counts, pressure))
    members = np.argsort(cell, kind="stable")  # archive rows grouped by cell
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    offset = np.minimum((rng.random(n) * counts[chosen]).astype(np.int64), counts[chosen] - 1)
    return members[starts[chosen] + offset]


def rowwise_dominates(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``out[i]``: row ``a[i]`` dominates row ``b[i]`` (minimisation)."""
    return np.all(a <= b, axis=1) & np.any(a < b, axis=1)


def pbest_replace(pbest_f: np.ndarray, f: np.ndarray, coin: np.ndarray) -> np.ndarray:
    """Step C(2): which personal bests the new values ``f`` replace: when ``f`` dominates, not
    when the personal best dominates, otherwise where ``coin`` (a fair random draw) is True."""
    return rowwise_dominates(f, pbest_f) | (~rowwise_dominates(pbest_f, f) & coin)


# -- move (step C(3)) ------------------------------------------------------------------------
def velocity(
    v: np.ndarray,
    x: np.ndarray,
    pbest: np.ndarray,
    leader: np.ndarray,
    w: float,
    c1: float,
    c2: float,
    mu: float,
    r1: np.ndarray,
    r2: np.ndarray,
) -> np.ndarray:
    """Eq. 21: ``mu (w v + c1 R1 (P - x) + c2 R2 (G - x))``."""
    return mu * (w * v + c1 * r1 * (pbest - x) + c2 * r2 * (leader - x))


def confine(
    x: np.ndarray, v: np.ndarray, lower: np.ndarray, upper: np.ndarray, mode: str = "reverse"
) -> tuple[np.ndarray, np.ndarray]:
    """Clamp ``x`` to the box; the velocity component of each clamped coordinate is reversed
    (``"reverse"``) or zeroed (``"zero"``)."""
    out = (x < lower) | (x > upper)
    factor = -1.0 if mode == "reverse" else 0.0
    return np.clip(x, lower, upper), np.where(out, factor * v, v)


def mutation_probability(t: int, horizon: int, rate: float) -> float:
    """Coello's share of mutated particles and relative mutation range at generation ``t`` of
    ``horizon``: ``(1 - t/horizon) ** (5 / rate)``; 0 when ``rate`` is 0 or ``t >= horizon``."""
    if rate <= 0 or t >= horizon:
        return 0.0
    return (1.0 - t / horizon) ** (5.0 / rate)


def mutate(
    x: np.ndarray, lower: np.ndarray, upper: np.ndarray, pm: float, rng: np.random.Generator
) -> np.ndarray:
    """Coello's mutation: each row with probability ``pm`` has one random coordinate redrawn
    uniformly in ``x +- pm (upper - lower)`` intersected with the box."""
    n, d = x.shape
    hit = rng.random(n) < pm
    dim = rng.integers(0, d, size=n)
    u = rng.random(n)
    rows = np.flatnonzero(hit)
    cols = dim[rows]
    reach = pm * (upper[cols] - lower[cols])
    lo = np.maximum(x[rows, cols] - reach, lower[cols])
    hi = np.minimum(x[rows, cols] + reach, upper[cols])
    out = x.copy()
    out[rows, cols] = np.clip(lo + u[rows] * (hi - lo), lower[cols], upper[cols])
    return out


# -- archive (steps C end and D) -------------------------------------------------------------
def truncation_counts(counts: np.ndarray, size: int, capacity: int) -> np.ndarray:
    """Eq. 23: members to delete from each cell, ``Int(|A - NR| / A * Grid[k] + 0.5)`` for cells
    with more than one member (``A = size``, ``NR = capacity``), at most ``Grid[k] - 1``.
    Computed in integers, ``floor((2 |A - NR| Grid[k] + A) / (2 A))``, so halves round up exactly."""
    excess = abs(size - capacity)
    nd = (2 * excess * counts + size) // (2 * size)
    return np.where(counts > 1, np.minimum(nd, counts - 1), 0).astype(np.int64)


def truncate(
    f: np.ndarray, capacity: int, divisions: int, inflation: float, rng: np.random.Generator
) -> np.ndarray:
    """Step D: boolean mask of the archive rows ``f`` kept after eq. 23 (random deletions from
    crowded cells of a grid over ``f``), then, while more than ``capacity`` remain, deletion of
    a random member of the most crowded cell (ties at random)."""
    n = f.shape[0]
    keep = np.ones(n, dtype=bool)
    if n <= capacity:
        return keep
    cell, counts = archive_cells(f, divisions, inflation)
    nd = truncation_counts(counts, n, capacity)
    # random rank of each member inside its cell; delete the nd lowest-ranked
    order = np.lexsort((rng.random(n), cell))
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    rank = np.empty(n, dtype=np.int64)
    rank[order] = np.arange(n) - np.repeat(starts, counts)
    keep &= rank >= nd[cell]
    left = np.bincount(cell[keep], minlength=counts.size)
    while keep.sum() > capacity:
        crowded = np.flatnonzero(left == left.max())
        k = crowded[rng.integers(crowded.size)]
        victims = np.flatnonzero(keep & (cell == k))
        keep[victims[rng.integers(victims.size)]] = False
        left[k] -= 1
    return keep


def update_archive(
    ax: np.ndarray,
    af: np.ndarray,
    x: np.ndarray,
    f: np.ndarray,
    capacity: int,
    divisions: int,
    inflation: float,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """Merge the finite rows of ``(x, f)`` into the archive ``(ax, af)``, keep the non-dominated
    members (older first among identical values) and truncate to ``capacity`` (step D)."""
    finite = np.isfinite(f).all(axis=1)
    xs = np.concatenate([ax, x[finite]])
    fs = np.concatenate([af, f[finite]])
    nd = nondominated(fs)
    xs, fs = xs[nd], fs[nd]
    keep = truncate(fs, capacity, divisions, inflation, rng)
    return xs[keep], fs[keep]


class MOPSO(Optimiser):
    """Coello's multi-objective PSO with adaptive grid, density-based leaders and eq. 23
    archive truncation, population-vectorised ask/tell (seed 001 §3.2)."""

    name = "mopso"
    Params = MOPSOParams
    params: MOPSOParams
    single_objective = False
    multi_objective = True

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        p = self.params
        after_init = self.budget - p.population
        self.horizon = max(1, math.ceil(after_init / p.population))  # T of the mutation
        if p.max_generations is not None:
            self.horizon = min(self.horizon, p.max_generations)
        m = self.n_objectives
        self.x = np.empty((0, self.dim))
        self.v = np.empty((0, self.dim))
        self.fitness = np.empty((0, m))
        self.pbest_x = np.empty((0, self.dim))
        self.pbest_f = np.empty((0, m))
        self._archive_x = np.empty((0, self.dim))
        self._archive_f = np.empty((0, m))
        self._next_v: np.ndarray | None = None

    @property
    def archive(self) -> ParetoSet:
        """The external archive (save set): at most ``archive_size`` non-dominated points, as
        truncated by eq. 23. ``front`` is everything non-dominated told, unbounded."""
        return ParetoSet(self._archive_x.copy(), self._archive_f.copy())

    def _stopped(self) -> bool:
        limit = self.params.max_generations
        return limit is not None and self.generation >= limit

    def leaders(self) -> np.ndarray:
        """Step C(2): one global leader position per particle from the archive by density
        roulette; while the archive is empty (every value so far non-finite) a random
        particle's personal best instead."""
        n = self.x.shape[0]
        if self._archive_f.shape[0] == 0:
            return self.pbest_x[self.rng.integers(0, n, size=n)]
        p = self.params
        cell, counts = archive_cells(self._archive_f, p.grid_divisions, p.grid_inflation)
        return self._archive_x[select_leaders(cell, counts, n, p.leader_pressure, self.rng)]

    def _ask(self) -> np.ndarray:
        p = self.params
        if self.x.shape[0] == 0:
            return self.uniform(p.population)
        g = self.leaders()
        r1 = self.rng.random(self.x.shape)
        r2 = self.rng.random(self.x.shape)
        v = velocity(self.v, self.x, self.pbest_x, g, p.w, p.c1, p.c2, p.mu, r1, r2)  # eq. 21
        x, v = confine(self.x + v, v, self.lower, self.upper, p.bound_velocity)  # eq. 22
        pm = mutation_probability(self.generation, self.horizon, p.mutation_rate)
        x = mutate(x, self.lower, self.upper, pm, self.rng)
        self._next_v = v
        return x[: self.remaining]

    def _tell(self, x: np.ndarray, f: np.ndarray) -> None:
        p = self.params
        k = x.shape[0]
        if self.x.shape[0] == 0:  # step B
            self.x, self.v, self.fitness = x.copy(), np.zeros_like(x), f.copy()
            self.pbest_x, self.pbest_f = x.copy(), f.copy()
        else:
            assert self._next_v is not None
            self.x[:k], self.v[:k], self.fitness[:k] = x, self._next_v[:k], f
            replace = pbest_replace(self.pbest_f[:k], f, self.rng.random(k) < 0.5)
            self.pbest_x[:k][replace] = x[replace]
            self.pbest_f[:k][replace] = f[replace]
            self._next_v = None
            self.generation += 1
        self._archive_x, self._archive_f = update_archive(
            self._archive_x, self._archive_f, x, f,
            p.archive_size, p.grid_divisions, p.grid_inflation, self.rng,
        )
