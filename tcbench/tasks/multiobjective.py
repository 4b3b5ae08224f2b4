"""Multi-objective test problems (minimisation), vectorised over a batch of candidates.

Every function takes ``x`` of shape ``(n, d)`` in ``[0, 1]^d`` and returns ``(n, m)`` objective
vectors. Each problem is described by a :class:`MultiObjectiveProblem` record with its default
dimension, a sampler of its true Pareto front, a map back to Pareto-optimal decision vectors,
and the hypervolume reference point used by tcbench together with the hypervolume of the true
front against it (for normalising a run's hypervolume to [0, 1]).

Problems (Zitzler, Deb & Thiele 2000; Deb, Thiele, Laumanns & Zitzler 2002/2005):

- ZDT1, ZDT2, ZDT3: ``m = 2``, default ``n = 30``. ``f1 = x1``,
  ``g = 1 + 9 sum(x2..xn) / (n - 1)``, ``f2 = g h(f1, g)`` with ``h = 1 - sqrt(f1/g)`` (ZDT1,
  convex front ``f2 = 1 - sqrt(f1)``), ``h = 1 - (f1/g)^2`` (ZDT2, concave ``f2 = 1 - f1^2``),
  ``h = 1 - sqrt(f1/g) - (f1/g) sin(10 pi f1)`` (ZDT3). The Pareto set is ``x2..xn = 0``
  (``g = 1``). For ZDT3 the curve ``1 - sqrt(f1) - f1 sin(10 pi f1)`` is only partly
  non-dominated: the front is five disconnected pieces, found here numerically
  (:func:`zdt3_front_intervals`) by keeping the non-dominated points of a fine grid on
  ``f1 in [0, 1]`` and refining each piece's ends by bisection.
- DTLZ2: ``m = 3`` objectives, ``n = m + k - 1`` variables with ``k = 10`` (12 by default).
  ``g = sum((x_i - 0.5)^2)`` over the last ``k`` variables, ``f_1 = (1+g) prod cos(x_i pi/2)``,
  ... , ``f_m = (1+g) sin(x_1 pi/2)``. The Pareto set is ``x_m..x_n = 0.5`` (``g = 0``) and
  the front is the octant of the unit sphere, ``sum f_i^2 = 1``, ``f >= 0``.

Hypervolume reference points (the convention of this module; pass any other point to
:func:`tcbench.metrics.multiobjective.hypervolume` if a paper used one):

- ZDT1, ZDT2, ZDT3: ``(1.1, 1.1)``, the nadir ``(1, 1)`` of the ZDT1/ZDT2 fronts plus 10% of
  their unit range (ZDT3's nadir, ``(0.852, 1)``, lies inside it too). Some papers use
  ``(11, 11)`` instead; that point makes far-off points score and squeezes good fronts
  together near the 121 maximum, so tcbench does not use it. With ``(1.1, 1.1)`` a point
  scores only once ``f2 < 1.1``, i.e. near the front: early in a run the hypervolume is 0 and
  IGD is the informative indicator.
- DTLZ2: ``(1.1, 1.1, 1.1)``, the nadir ``(1, 1, 1)`` plus 10%.

Hypervolume of the true (continuous) front against these points, ``front_hypervolume``:

- ZDT1: ``1.1^2 - int_0^1 (1 - sqrt t) dt = 1.21 - 1/3 = 0.876666...``
- ZDT2: ``1.21 - int_0^1 (1 - t^2) dt = 1.21 - 2/3 = 0.543333...``
- ZDT3: ``1.21 - int_0^1.1 e(t) dt`` with ``e`` the lower envelope (running minimum) of the
  curve, integrated in closed form piece by piece between the numerically refined ends of
  the five pieces: 1.331762909... (:func:`zdt3_front_hypervolume`).
- DTLZ2: the box minus the unit-ball octant, ``1.1^3 - pi/6 = 0.807401224...``

The tests check each value against the exact hypervolume of a dense sample of the front.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from tcbench.errors import unknown_name

Array = np.ndarray

DTLZ_K = 10  # distance variables of DTLZ2 (Deb et al. recommend k = 10)


# -- ZDT -----------------------------------------------------------------------------------


def _zdt_parts(x: Array) -> tuple[Array, Array]:
    f1 = x[:, 0]
    g = 1.0 + 9.0 * np.mean(x[:, 1:], axis=1)
    return f1, g


def zdt1(x: Array) -> Array:
    """ZDT1: ``f2 = g (1 - sqrt(f1/g))``; convex front ``f2 = 1 - sqrt(f1)``."""
    f1, g = _zdt_parts(x)
    return np.stack([f1, g * (1.0 - np.sqrt(f1 / g))], axis=1)


def zdt2(x: Array) -> Array:
    """ZDT2: ``f2 = g (1 - (f1/g)^2)``; concave front ``f2 = 1 - f1^2``."""
    f1, g = _zdt_parts(x)
    return np.stack([f1, g * (1.0 - (f1 / g) ** 2)], axis=1)


def zdt3(x: Array) -> Array:
    """ZDT3: ``f2 = g (1 - sqrt(f1/g) - (f1/g) sin(10 pi f1))``; front in five pieces."""
    f1, g = _zdt_parts(x)
    r = f1 / g
    return np.stack([f1, g * (1.0 - np.sqrt(r) - r * np.sin(10.0 * np.pi * f1))], axis=1)


def _zdt1_curve(t: Array) -> Array:
    return 1.0 - np.sqrt(t)


def _zdt2_curve(t: Array) -> Array:
    return 1.0 - t * t


def _zdt3_curve(t):
    """``1 - sqrt(t) - t sin(10 pi t)``: ZDT3's f2 on ``g = 1`` (scalars or arrays)."""
    return 1.0 - np.sqrt(t) - t * np.sin(10.0 * np.pi * t)


def _zdt3_slope(t: float) -> float:
    c = 10.0 * math.pi
    return -0.5 / math.sqrt(t) - math.sin(c * t) - c * t * math.cos(c * t)


def _zdt3_antiderivative(t: float) -> float:
    c = 10.0 * math.pi
    return t - (2.0 / 3.0) * t**1.5 + t * math.cos(c * t) / c - math.sin(c * t) / c**2


def _bisect(fn: Callable[[float], float], lo: float, hi: float) -> float:
    """Root of ``fn`` in ``[lo, hi]`` (opposite signs at the ends) to full precision."""
    flo = fn(lo)
    if flo == 0.0:
        return lo
    if (flo > 0) == (fn(hi) > 0):
        raise ValueError(f"no sign change in [{lo}, {hi}]")
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        fm = fn(mid)
        if fm == 0.0:
            return mid
        if (fm > 0) == (flo > 0):
            lo, flo = mid, fm
        else:
            hi = mid
    return 0.5 * (lo + hi)


@lru_cache(maxsize=1)
def zdt3_front_intervals() -> tuple[tuple[float, float], ...]:
    """The ``f1`` intervals ``(a_i, b_i)`` of ZDT3's Pareto front, in increasing order.

    Found by keeping the non-dominated points of 200 001 grid points on ``[0, 1]`` (a point
    is non-dominated when its f2 is below that of every point to its left), then refining
    each piece's end ``b_i`` (a local minimum: root of the slope) and the next piece's start
    ``a_{i+1}`` (where the curve falls back to ``f2(b_i)``) by bisection. Every piece but the
    first is open at its start, since ``(a_{i+1}, f2(b_i))`` is dominated by ``(b_i, f2(b_i))``.
    Result: (0, 0.0830015), (0.1822287, 0.2577624), (0.4093137, 0.4538821),
    (0.6183968, 0.6525117), (0.8233318, 0.8518329).
    """
    t = np.linspace(0.0, 1.0, 200_001)
    h = _zdt3_curve(t)
    best_before = np.minimum.accumulate(np.concatenate([[np.inf], h[:-1]]))
    keep = h < best_before
    edges = np.diff(keep.astype(np.int8))
    starts = np.concatenate([[0], np.flatnonzero(edges == 1) + 1])
    ends = np.flatnonzero(edges == -1)
    if keep[-1]:
        ends = np.append(ends, t.size - 1)
    pieces: list[tuple[float, float]] = []
    for s, e in zip(starts, ends, strict=True):
        if e == t.size - 1:
            b = 1.0
        else:  # local minimum of the curve between the grid neighbours of the last kept point
            b = _bisect(_zdt3_slope, float(t[max(e - 1, 1)]), float(t[e + 1]))
        if s == 0:
            a = 0.0
        else:
            level = float(_zdt3_curve(pieces[-1][1]))
            a = _bisect(lambda u: float(_zdt3_curve(u)) - level, float(t[s - 1]), b)
        pieces.append((a, b))
    return tuple(pieces)


def zdt3_front_hypervolume(ref: tuple[float, float] = (1.1, 1.1)) -> float:
    """Hypervolume of ZDT3's true front against ``ref`` (``ref[0] >= b_5``, ``ref[1] > 1``),
    integrated in closed form over the pieces of :func:`zdt3_front_intervals`: between pieces
    and after the last one the dominated region's lower edge stays at the previous piece's
    lowest f2."""
    pieces = zdt3_front_intervals()
    if ref[0] < pieces[-1][1] or ref[1] <= 1.0:
        raise ValueError(f"ref {ref} must have ref[0] >= {pieces[-1][1]} and ref[1] > 1")
    area_below = 0.0  # integral of the lower envelope over [0, ref[0]]
    for i, (a, b) in enumerate(pieces):
        area_below += _zdt3_antiderivative(b) - _zdt3_antiderivative(a)
        nxt = pieces[i + 1][0] if i + 1 < len(pieces) else ref[0]
        area_below += (nxt - b) * float(_zdt3_curve(b))
    return ref[0] * ref[1] - area_below


def _zdt_front(curve: Callable[[Array], Array], n_points: int) -> Array:
    t = np.linspace(0.0, 1.0, n_points)
    return np.stack([t, curve(t)], axis=1)


def zdt1_front(n_points: int) -> Array:
    """``n_points`` points of ZDT1's front, ``f1`` evenly spaced on [0, 1] (both ends included)."""
    return _zdt_front(_zdt1_curve, n_points)


def zdt2_front(n_points: int) -> Array:
    """``n_points`` points of ZDT2's front, ``f1`` evenly spaced on [0, 1] (both ends included)."""
    return _zdt_front(_zdt2_curve, n_points)


def zdt3_front(n_points: int) -> Array:
    """``n_points`` points of ZDT3's disconnected front, ``f1`` evenly spaced over the union of
    the pieces of :func:`zdt3_front_intervals` (laid end to end). The first point is
    ``f1 = 0``, the last the end of the last piece; a point that falls on a junction is put at
    the end of the earlier piece (the start of the later one is dominated), so every point
    returned is non-dominated."""
    pieces = np.array(zdt3_front_intervals())
    lengths = pieces[:, 1] - pieces[:, 0]
    cum_end = np.cumsum(lengths)
    s = np.linspace(0.0, cum_end[-1], n_points)
    i = np.minimum(np.searchsorted(cum_end, s, side="left"), len(pieces) - 1)
    f1 = pieces[i, 0] + (s - (cum_end[i] - lengths[i]))
    f1 = np.minimum(f1, pieces[i, 1])
    return np.stack([f1, _zdt3_curve(f1)], axis=1)


def _zdt_set(front: Array, dim: int) -> Array:
    x = np.zeros((front.shape[0], dim))
    x[:, 0] = front[:, 0]
    return x


# -- DTLZ2 ---------------------------------------------------------------------------------


def dtlz2(x: Array, n_objectives: int = 3) -> Array:
    """DTLZ2 with ``n_objectives`` objectives; ``x`` has ``d >= n_objectives`` columns, the
    last ``k = d - n_objectives + 1`` are the distance variables."""
    m = n_objectives
    theta = 0.5 * np.pi * x[:, : m - 1]
    g = np.sum((x[:, m - 1 :] - 0.5) ** 2, axis=1)
    cos = np.cumprod(np.concatenate([np.ones((x.shape[0], 1)), np.cos(theta)], axis=1), axis=1)
    sin = np.concatenate([np.ones((x.shape[0], 1)), np.sin(theta[:, ::-1])], axis=1)
    # f_j = prod_{i <= m-j} cos(theta_i) * sin(theta_{m-j+1}), no sine factor for j = 1
    f = cos[:, ::-1] * sin
    return (1.0 + g)[:, None] * f


def dtlz2_front(n_points: int) -> Array:
    """``n_points`` points of DTLZ2's 3-objective front (the positive octant of the unit sphere),
    spread by a Fibonacci lattice: ``f3 = (i + 0.5) / n`` (equal-area in height, by Archimedes'
    hat-box theorem) and azimuth ``(pi/2) frac(i / golden ratio)``. Deterministic."""
    i = np.arange(n_points)
    z = (i + 0.5) / n_points
    phi = 0.5 * np.pi * np.mod(i * (math.sqrt(5.0) - 1.0) / 2.0, 1.0)
    rho = np.sqrt(1.0 - z * z)
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1)


def _dtlz2_set(front: Array, dim: int) -> Array:
    """Decision vectors of DTLZ2 front points: invert the spherical coordinates, ``x_m.. = 0.5``."""
    m = front.shape[1]
    x = np.full((front.shape[0], dim), 0.5)
    # r_j = ||(f_1..f_j)|| = prod_{i <= m-j} cos(theta_i); theta_{m-j+1} = atan2(f_j, r_{j-1}).
    r = np.sqrt(np.cumsum(front**2, axis=1))
    for j in range(2, m + 1):
        x[:, m - j] = np.arctan2(front[:, j - 1], r[:, j - 2]) / (0.5 * np.pi)
    return np.clip(x, 0.0, 1.0)


# -- registry ------------------------------------------------------------------------------


@dataclass(frozen=True)
class MultiObjectiveProblem:
    """A multi-objective test problem with its domain, true front and hypervolume reference.

    ``front_sampler(n_points)`` returns ``(p, m)`` points of the true Pareto front (``p`` =
    ``n_points``); ``set_map(front, dim)`` returns decision vectors whose images are those
    points. ``front_hypervolume`` is the hypervolume of the whole true front against
    ``ref_point`` (see the module docstring for how each was obtained).
    """

    key: str
    name: str  # as in the gymnasium id, e.g. "ZDT1"
    title: str
    fn: Callable[[Array], Array]
    n_objectives: int
    default_dim: int
    min_dim: int
    front_sampler: Callable[[int], Array]
    set_map: Callable[[Array, int], Array]
    ref_point: tuple[float, ...]
    front_hypervolume: float
    lower: float = 0.0
    upper: float = 1.0

    def evaluate(self, x: Array) -> Array:
        """Objective vectors ``(n, m)`` of ``x`` (``(n, d)``, or ``(d,)`` for one point)."""
        a = np.atleast_2d(np.asarray(x, dtype=np.float64))
        if a.ndim != 2 or a.shape[1] < self.min_dim:
            raise ValueError(
                f"{self.name} needs x of shape (n, d) with d >= {self.min_dim}, got {np.shape(x)}"
            )
        return self.fn(a)

    def true_front(self, n_points: int = 1000) -> Array:
        """``(n_points, m)`` points of the true Pareto front, all mutually non-dominated."""
        if int(n_points) != n_points or n_points < 1:
            raise ValueError(f"n_points must be a positive integer, got {n_points}")
        return self.front_sampler(int(n_points))

    def pareto_set(self, n_points: int = 1000, dim: int | None = None) -> Array:
        """``(n_points, dim)`` Pareto-optimal decision vectors, mapping onto
        :meth:`true_front` ``(n_points)`` point by point."""
        d = self.default_dim if dim is None else int(dim)
        if d < self.min_dim:
            raise ValueError(f"dim must be >= {self.min_dim} for {self.name}, got {d}")
        return self.set_map(self.true_front(n_points), d)


PROBLEMS: dict[str, MultiObjectiveProblem] = {
    p.key: p
    for p in (
        MultiObjectiveProblem(
            "zdt1", "ZDT1", "ZDT1 (convex front)", zdt1, 2, 30, 2, zdt1_front, _zdt_set,
            (1.1, 1.1), 1.21 - 1.0 / 3.0,
        ),
        MultiObjectiveProblem(
            "zdt2", "ZDT2", "ZDT2 (concave front)", zdt2, 2, 30, 2, zdt2_front, _zdt_set,
            (1.1, 1.1), 1.21 - 2.0 / 3.0,
        ),
        MultiObjectiveProblem(
            "zdt3", "ZDT3", "ZDT3 (disconnected front)", zdt3, 2, 30, 2, zdt3_front, _zdt_set,
            (1.1, 1.1), 1.3317629086570204,  # zdt3_front_hypervolume((1.1, 1.1)); checked in tests
        ),
        MultiObjectiveProblem(
            "dtlz2", "DTLZ2", "DTLZ2 (spherical front, 3 objectives)", dtlz2, 3, 3 + DTLZ_K - 1,
            3, dtlz2_front, _dtlz2_set, (1.1, 1.1, 1.1), 1.1**3 - math.pi / 6.0,
        ),
    )
}


def get_problem(key: str) -> MultiObjectiveProblem:
    """Look up a problem by key (case-insensitive: ``zdt1`` or ``ZDT1``); unknown keys raise
    ``KeyError`` naming the known ones."""
    try:
        return PROBLEMS[key.lower()]
    except (KeyError, AttributeError):
        raise KeyError(unknown_name("problem", key, sorted(PROBLEMS))) from None


__all__ = [
    "DTLZ_K",
    "PROBLEMS",
    "MultiObjectiveProblem",
    "dtlz2",
    "dtlz2_front",
    "get_problem",
    "zdt1",
    "zdt1_front",
    "zdt2",
    "zdt2_front",
    "zdt3",
    "zdt3_front",
    "zdt3_front_hypervolume",
    "zdt3_front_intervals",
]
