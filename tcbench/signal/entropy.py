"""Sample, permutation and fuzzy entropy of a 1-D signal (paper §3.2; IMF classification).

All three are dimensionless and natural-log based; the signal ``x`` may be in any unit (the
tolerances ``r`` are fractions of ``std(x, ddof=0)``, so they carry the unit of ``x``).

Sample entropy (Richman & Moorman 2000), ``m`` the template length and ``tol = r std(x)``::

    SampEn = -ln(A / B)

over the ``N - m`` templates starting at ``0 .. N - m - 1``: ``B`` is the number of unordered
pairs whose first ``m`` values are all within ``tol`` (Chebyshev distance ``<= tol``; a template
never matches itself) and ``A`` the number of those pairs whose ``m + 1``-th values are within
``tol`` as well. This is ``antropy.sample_entropy(x, order=m, metric="chebyshev")``: its
KD-tree path (N >= 5000) counts ``<= tol``; its numba path (N < 5000) counts ``< tol``, which
differs only when some ``|x_i - x_j|`` equals ``tol`` exactly. Pairs are found by sorting the
templates on their first value and comparing, block by block, only templates whose first values
are within ``tol`` (memory is one block of ``_PAIR_BLOCK`` pairs).

Permutation entropy (Bandt & Pompe 2002; paper eqs. 16-20): the ordinal pattern of each
``x[i], x[i + delay], ..., x[i + (m - 1) delay]`` (ties ordered by position, as a stable
argsort does), ``H = -sum p ln p`` over the patterns' relative frequencies, divided by
``ln(m!)`` when normalised. Normalised, this is ``antropy.perm_entropy(x, order=m,
delay=delay, normalize=True)``; unnormalised it is in nats (antropy returns bits).

Fuzzy entropy (Chen et al. 2007; paper eqs. 8-15): the ``N - m`` templates of length ``m`` and
of length ``m + 1`` starting at ``0 .. N - m - 1``, each minus its own mean; ``d`` the Chebyshev
distance between two such templates and the membership ``exp(-d**n / tol)`` with
``tol = r std(x)``; ``Phi_m`` the mean membership over pairs ``p != q``, and
``FuzzEn = ln Phi_m - ln Phi_{m+1}``. This is EntropyHub's ``FuzzEn(x, m=m, tau=1,
r=(r * std(x), n), Fx="default")[0][m - 1]`` (its ``Fx="default"`` membership
``exp(-(d**r[1]) / r[0])``); note that the paper's eq. 11 writes ``exp(-(d / omega)**theta)``,
which equals this one for ``omega = tol**(1 / n)``. The O(N^2) pair sum runs over
``_FUZZY_TILE`` x ``_FUZZY_TILE`` tiles of the upper triangle.
"""

from __future__ import annotations

import math

import numpy as np

_PAIR_BLOCK = 1 << 16  # candidate pairs compared at once by sample_entropy (~0.5 MiB float64)
_FUZZY_TILE = 256  # rows (and columns) of one fuzzy-entropy tile: 64 Ki pairs, 0.5 MiB float64
_MAX_BINCOUNT_PATTERNS = 1 << 22  # m! above this: count patterns with np.unique instead


def _series(x: np.ndarray, min_size: int, what: str) -> np.ndarray:
    """``x`` as a finite 1-D float64 array of at least ``min_size`` samples."""
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ValueError(f"x must be a 1-D array of numbers: {err}") from None
    if arr.ndim != 1:
        raise ValueError(f"x must be 1-D, got shape {arr.shape}")
    if arr.size < min_size:
        raise ValueError(f"x needs at least {min_size} samples for {what}, got {arr.size}")
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(f"x must be finite: x[{i}] = {arr[i]}")
    return arr


def _positive_int(value: int, name: str, minimum: int) -> int:
    """``value`` as an int, or ValueError when it is not an integer >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _tolerance(x: np.ndarray, r: float, name: str = "r") -> float:
    """``r * std(x, ddof=0)`` (unit of ``x``), checked to be finite and > 0."""
    if isinstance(r, bool) or not isinstance(r, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number > 0, got {r!r}")  # noqa: TRY004 (bad input is a ValueError here)
    if not (math.isfinite(r) and r > 0):
        raise ValueError(f"{name} must be a finite number > 0, got {r!r}")
    std = float(np.std(x))
    if std == 0.0:
        raise ValueError("x is constant (std 0), so the tolerance r * std(x) is 0")
    return float(r) * std


def sample_entropy(x: np.ndarray, m: int = 2, r: float = 0.2) -> float:
    """Sample entropy of ``x`` (dimensionless, natural log) for templates of length ``m`` and
    tolerance ``r * std(x, ddof=0)`` (``r`` a fraction, > 0), Chebyshev distance, self-matches
    excluded (see the module docstring).

    Returns ``inf`` when no pair of length ``m + 1`` matches and ``nan`` when no pair of length
    ``m`` matches (the entropy is undefined), as antropy does.

    Raises ValueError for a non-1-D or non-finite ``x``, fewer than ``m + 2`` samples, ``m`` not
    an integer >= 1, ``r`` not > 0 or a constant ``x``.
    """
    m = _positive_int(m, "m", 1)
    x = _series(x, m + 2, f"sample entropy with m = {m}")
    tol = _tolerance(x, r)
    n_t = x.size - m  # templates of length m and of length m + 1 share these start points
    order = np.argsort(x[:n_t], kind="stable")
    cols = [x[k : k + n_t][order] for k in range(m + 1)]  # template k-th values, sorted on 0th
    first = cols[0]
    # Last sorted index whose first value can be within tol of row i's (a superset: the exact
    # test |a - b| <= tol is made on the pairs themselves).
    slack = tol + 4.0 * np.finfo(np.float64).eps * float(np.abs(first).max())
    hi = np.searchsorted(first, first + slack, side="right")
    width = max(1.0, float(np.mean(hi - np.arange(n_t))))
    rows = int(min(max(16, _PAIR_BLOCK // width), 4096))
    later = np.tri(rows, rows, 0, dtype=bool).T  # [a, t]: column i0 + 1 + t > row i0 + a
    n_match_m = 0
    n_match_m1 = 0
    diff = np.empty(_PAIR_BLOCK * 2)
    for i0 in range(0, n_t, rows):
        i1 = min(i0 + rows, n_t)
        c0, c1 = i0 + 1, int(hi[i1 - 1])
        if c1 <= c0:
            continue
        shape = (i1 - i0, c1 - c0)
        size = shape[0] * shape[1]
        if diff.size < size:
            diff = np.empty(size)
        d = diff[:size].reshape(shape)
        np.subtract(first[None, c0:c1], first[i0:i1, None], out=d)
        np.abs(d, out=d)
        match = d <= tol
        k = min(shape[0], shape[1])
        match[:, :k] &= later[: shape[0], :k]
        ok = np.empty(shape, dtype=bool)
        for col in cols[1:m]:
            np.subtract(col[None, c0:c1], col[i0:i1, None], out=d)
            np.abs(d, out=d)
            np.less_equal(d, tol, out=ok)
            match &= ok
        n_match_m += int(np.count_nonzero(match))
        last = cols[m]
        np.subtract(last[None, c0:c1], last[i0:i1, None], out=d)
        np.abs(d, out=d)
        np.less_equal(d, tol, out=ok)
        match &= ok
        n_match_m1 += int(np.count_nonzero(match))
    if n_match_m == 0:
        return float("nan")
    if n_match_m1 == 0:
        return float("inf")
    return -math.log(n_match_m1 / n_match_m)


def permutation_entropy(
    x: np.ndarray, m: int = 3, delay: int = 1, normalize: bool = True
) -> float:
    """Permutation entropy of ``x`` for ordinal patterns of ``m`` samples ``delay`` samples
    apart: in [0, 1] when ``normalize`` (divided by ``ln(m!)``), else in nats. Ties are ordered
    by position (as ``np.argsort(kind="stable")`` does).

    Raises ValueError for a non-1-D or non-finite ``x``, ``m`` not an integer >= 2, ``delay``
    not an integer >= 1, or fewer than ``(m - 1) delay + 1`` samples.
    """
    m = _positive_int(m, "m", 2)
    delay = _positive_int(delay, "delay", 1)
    x = _series(x, (m - 1) * delay + 1, f"permutation entropy with m = {m}, delay = {delay}")
    n_w = x.size - (m - 1) * delay
    cols = [x[k * delay : k * delay + n_w] for k in range(m)]
    n_patterns = math.factorial(m)
    code_dtype = np.uint16 if n_patterns <= np.iinfo(np.uint16).max else np.int64
    # Lehmer code: digit i counts the later values strictly smaller than value i (a later equal
    # value ranks after it), in mixed radix (m - i); codes run over 0 .. m! - 1.
    code = np.zeros(n_w, dtype=code_dtype)
    for i in range(m - 1):
        digit = np.zeros(n_w, dtype=np.uint8)
        for j in range(i + 1, m):
            digit += (cols[j] < cols[i]).view(np.uint8)
        code *= m - i
        code += digit
    if n_patterns <= _MAX_BINCOUNT_PATTERNS:
        counts = np.bincount(code, minlength=n_patterns)
        counts = counts[counts > 0]
    else:
        counts = np.unique(code, return_counts=True)[1]
    p = counts / n_w
    h = float(-np.dot(p, np.log(p)))
    if normalize:
        return min(max(h / math.log(n_patterns), 0.0), 1.0)
    return h


def _centred_templates(x: np.ndarray, length: int, n_t: int, scale: float) -> list[np.ndarray]:
    """Columns of the ``n_t`` templates of ``length`` values, each minus its mean, times
    ``scale``. For length 2 the two centred values are opposite, so one column suffices."""
    cols = [x[k : k + n_t] for k in range(length)]
    mean = np.add.reduce(cols) / length if length > 1 else cols[0]
    keep = 1 if length <= 2 else length
    return [(cols[k] - mean) * scale for k in range(keep)]


def _fuzzy_tile_sum(
    a: list[np.ndarray], b: list[np.ndarray], power: float, acc: np.ndarray, buf: np.ndarray
) -> float:
    """Sum of ``exp(-max_k |a_k[i] - b_k[j]|**power)`` over the tile rows ``a`` x columns ``b``
    (templates already divided by ``tol**(1 / power)``)."""
    shape = (a[0].size, b[0].size)
    size = shape[0] * shape[1]
    s = acc[:size].reshape(shape)
    t = buf[:size].reshape(shape)
    squared = power == 2.0
    for k, (ak, bk) in enumerate(zip(a, b)):
        out = s if k == 0 else t
        np.subtract(ak[:, None], bk[None, :], out=out)
        if squared:
            np.multiply(out, out, out=out)
        else:
            np.abs(out, out=out)
        if k:
            np.maximum(s, t, out=s)
    if not squared and power != 1.0:
        np.power(s, power, out=s)
    np.negative(s, out=s)
    np.exp(s, out=s)
    return float(s.sum())


def fuzzy_entropy(x: np.ndarray, m: int = 2, r: float = 0.2, n: float = 2) -> float:
    """Fuzzy entropy of ``x`` (dimensionless, natural log) for templates of length ``m``,
    membership ``exp(-d**n / (r std(x, ddof=0)))`` of the Chebyshev distance ``d`` between
    mean-removed templates (``r`` > 0 a fraction of the std, ``n`` > 0 the exponent); see the
    module docstring. Returns ``inf`` when the ``m + 1`` memberships all underflow to 0.

    Raises ValueError for a non-1-D or non-finite ``x``, fewer than ``m + 2`` samples, ``m`` not
    an integer >= 1, ``r`` or ``n`` not > 0 or a constant ``x``.
    """
    m = _positive_int(m, "m", 1)
    x = _series(x, m + 2, f"fuzzy entropy with m = {m}")
    tol = _tolerance(x, r)
    if isinstance(n, bool) or not isinstance(n, (int, float, np.integer, np.floating)):
        raise ValueError(f"n must be a number > 0, got {n!r}")  # noqa: TRY004
    if not (math.isfinite(n) and n > 0):
        raise ValueError(f"n must be a finite number > 0, got {n!r}")
    power = float(n)
    n_t = x.size - m
    scale = tol ** (-1.0 / power)  # d**n / tol == (d * scale)**n
    short = _centred_templates(x, m, n_t, scale)
    long = _centred_templates(x, m + 1, n_t, scale)
    tile = _FUZZY_TILE
    acc = np.empty(tile * tile * 4)
    buf = np.empty_like(acc)
    sums = [0.0, 0.0]
    for i0 in range(0, n_t, tile):
        i1 = min(i0 + tile, n_t)
        for which, cols in enumerate((short, long)):
            rows = [c[i0:i1] for c in cols]
            # Diagonal tile: symmetric with ones on the diagonal; keep the pairs i < j.
            diag = _fuzzy_tile_sum(rows, rows, power, acc, buf)
            total = 0.5 * (diag - (i1 - i0))
            for j0 in range(i1, n_t, 4 * tile):
                j1 = min(j0 + 4 * tile, n_t)
                total += _fuzzy_tile_sum(rows, [c[j0:j1] for c in cols], power, acc, buf)
            sums[which] += total
    if sums[1] == 0.0:
        return float("inf")
    return math.log(sums[0] / sums[1])
