"""Quality indicators of an approximation of a Pareto front (minimisation).

- :func:`hypervolume`: Lebesgue measure of the region dominated by a point set and bounded
  above by a reference point. Exact: a sort-and-sweep for 2 objectives (O(n log n)); for 3
  objectives a sweep along the third objective that keeps the 2-D staircase of the points
  passed and its area up to date (Beume et al. 2009, O(n log n)); for 4 or more objectives
  slabs along the last objective, each measured recursively one dimension down
  (O(n^(m-2) n log n), meant for small sets). Points that do not strictly dominate the
  reference point, and rows with a non-finite value, contribute nothing and are ignored.
- :func:`igd`: inverted generational distance, the mean over the points of a reference front of
  the Euclidean distance to the nearest obtained point (lower is better; 0 when every
  reference point was obtained).
- :func:`igd_plus`: IGD+ (Ishibuchi et al. 2015), the same mean with the dominance-compliant
  distance ``sqrt(sum(max(a_i - z_i, 0)^2))`` from reference point ``z`` to obtained ``a``.

Both distance indicators work in chunks of reference points so that memory stays bounded
(about ``chunk_elements`` floats per chunk) for large sets.
"""

from __future__ import annotations

from bisect import bisect_left

import numpy as np

Array = np.ndarray

#: Upper bound on the number of floats in one temporary distance matrix of IGD / IGD+.
CHUNK_ELEMENTS = 1 << 22


def _as_points(f: Array, m: int | None = None, name: str = "f") -> Array:
    """``f`` as a float ``(n, m)`` array; a 1-D input is one point, an empty one no points."""
    a = np.asarray(f, dtype=np.float64)
    if a.ndim == 1:
        a = a.reshape(1, -1) if a.size else np.empty((0, m or 0))
    if a.ndim != 2:
        raise ValueError(f"{name} must have shape (n, m), got {np.shape(f)}")
    if a.shape[0] == 0 and m is not None:
        a = np.empty((0, m))
    return a


def _hv2(f: Array, ref: Array) -> float:
    """2-D hypervolume of points that all strictly dominate ``ref``: sort by f1, sweep."""
    order = np.lexsort((f[:, 1], f[:, 0]))
    x, y = f[order, 0], f[order, 1]
    run_min = np.minimum.accumulate(y)
    widths = np.diff(np.append(x, ref[0]))
    return float(np.sum(widths * (ref[1] - run_min)))


def _hv3(f: Array, ref: Array) -> float:
    """3-D hypervolume of points that all strictly dominate ``ref`` (Beume et al.'s sweep).

    Points are taken in increasing f3; the 2-D staircase of those seen so far (f1 strictly
    increasing, f2 strictly decreasing, kept in sorted lists) and its area against
    ``ref[:2]`` are updated per point, and each slab between consecutive f3 values adds that
    area times its depth. A point weakly dominated in (f1, f2) by the staircase adds nothing;
    otherwise it replaces the staircase points it dominates and the area grows by the strip
    between them and the point. O(n log n) comparisons (list splices are memmoves).
    """
    r1, r2, r3 = (float(v) for v in ref)
    pts = f[np.argsort(f[:, 2], kind="stable")].tolist()
    xs: list[float] = []
    ys: list[float] = []
    area = volume = 0.0
    z_prev = pts[0][2]
    for x, y, z in pts:
        volume += area * (z - z_prev)
        z_prev = z
        i = bisect_left(xs, x)  # xs[:i] < x <= xs[i:]
        if (i > 0 and ys[i - 1] <= y) or (i < len(xs) and xs[i] == x and ys[i] <= y):
            continue
        cur_x, cur_h = x, (ys[i - 1] if i > 0 else r2)
        j = i
        while j < len(xs) and ys[j] >= y:  # staircase points the new one dominates
            area += (xs[j] - cur_x) * (cur_h - y)
            cur_x, cur_h = xs[j], ys[j]
            j += 1
        area += ((xs[j] if j < len(xs) else r1) - cur_x) * (cur_h - y)
        xs[i:j] = [x]
        ys[i:j] = [y]
    return volume + area * (r3 - z_prev)


def _hv_recursive(f: Array, ref: Array) -> float:
    m = f.shape[1]
    if f.shape[0] == 0:
        return 0.0
    if m == 1:
        return float(ref[0] - f[:, 0].min())
    if m == 2:
        return _hv2(f, ref)
    if m == 3:
        return _hv3(f, ref)
    order = np.argsort(f[:, -1], kind="stable")
    f = f[order]
    z = np.append(f[:, -1], ref[-1])
    total = 0.0
    for i in range(f.shape[0]):
        depth = z[i + 1] - z[i]
        if depth > 0:
            total += depth * _hv_recursive(f[: i + 1, :-1], ref[:-1])
    return total


def hypervolume(f: Array, ref: Array) -> float:
    """Exact hypervolume of ``f`` (``(n, m)``, minimisation) against reference point ``ref``.

    Only rows that are finite and strictly better than ``ref`` in every objective count;
    dominated and duplicate rows are allowed and add nothing. An empty set has volume 0.
    """
    r = np.asarray(ref, dtype=np.float64).reshape(-1)
    if r.size == 0 or not np.all(np.isfinite(r)):
        raise ValueError(f"ref must be a finite point, got {ref}")
    a = _as_points(f, r.size)
    if a.shape[1] != r.size:
        raise ValueError(f"f has {a.shape[1]} objectives but ref has {r.size}")
    keep = np.all(np.isfinite(a), axis=1) & np.all(a < r, axis=1)
    return _hv_recursive(a[keep], r)


def _nearest(
    reference: Array, f: Array, dist2, chunk_elements: int
) -> Array:
    """Distance from every reference point to its nearest row of ``f`` under ``dist2``."""
    out = np.empty(reference.shape[0])
    rows = max(1, chunk_elements // max(f.shape[0] * f.shape[1], 1))
    for start in range(0, reference.shape[0], rows):
        z = reference[start : start + rows]
        out[start : start + rows] = np.sqrt(dist2(z[:, None, :], f[None, :, :]).min(axis=1))
    return out


def _prepare(f: Array, reference_front: Array) -> tuple[Array, Array]:
    z = _as_points(reference_front, name="reference_front")
    if z.shape[0] == 0:
        raise ValueError("reference_front is empty")
    a = _as_points(f, z.shape[1])
    if a.shape[1] != z.shape[1]:
        raise ValueError(f"f has {a.shape[1]} objectives but reference_front has {z.shape[1]}")
    return a[np.all(np.isfinite(a), axis=1)], z


def igd(f: Array, reference_front: Array, chunk_elements: int = CHUNK_ELEMENTS) -> float:
    """Inverted generational distance of ``f`` (``(n, m)``) to ``reference_front`` (``(p, m)``).

    Mean over the reference points of the Euclidean distance to the nearest (finite) row of
    ``f``; ``inf`` if ``f`` has no finite row.
    """
    a, z = _prepare(f, reference_front)
    if a.shape[0] == 0:
        return float("inf")
    d = _nearest(z, a, lambda u, v: np.sum((v - u) ** 2, axis=2), int(chunk_elements))
    return float(d.mean())


def igd_plus(f: Array, reference_front: Array, chunk_elements: int = CHUNK_ELEMENTS) -> float:
    """IGD+ of ``f`` to ``reference_front``: like :func:`igd` but only the amounts by which an
    obtained point is worse than the reference point count, so it is weakly Pareto-compliant."""
    a, z = _prepare(f, reference_front)
    if a.shape[0] == 0:
        return float("inf")
    d = _nearest(
        z, a, lambda u, v: np.sum(np.maximum(v - u, 0.0) ** 2, axis=2), int(chunk_elements)
    )
    return float(d.mean())


__all__ = ["CHUNK_ELEMENTS", "hypervolume", "igd", "igd_plus"]
