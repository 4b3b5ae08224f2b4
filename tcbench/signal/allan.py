"""Overlapping Allan deviation of a rate signal and its IEEE Std 952 read-offs (docs/concepts/physics.md, metrics).

The rate ``y`` (any unit, e.g. deg/s) sampled at ``fs_hz`` is integrated to the angle
``theta = [0, cumsum(y - mean(y))] * tau0`` (``N + 1`` points for ``N`` samples; removing the mean
changes no second difference but keeps ``theta`` small, as allantools does) and, for
``tau = m tau0``::

    sigma^2(tau) = sum_k (theta[k+2m] - 2 theta[k+m] + theta[k])^2 / (2 tau^2 (N + 1 - 2m))

over the ``n_terms = N + 1 - 2m`` overlapping second differences (NIST SP 1065 eq. 11 with
``N + 1`` phase points), so ``m <= (N - 1) // 2`` keeps at least two terms. This is
``allantools.oadev(y, rate=fs_hz, data_type="freq")``. Each tau costs O(N) array operations,
done in cache-sized blocks (the lag-m first difference of a block, then its lag-m difference and
a dot product), with BLAS held to one thread: a second thread costs more than it gains on
blocks this size. Memory is ``theta`` plus a three-block buffer (1.5 MiB).

Read-offs (:func:`noise_parameters`) are in the units of the input rate: the angle random walk
``N`` (rate-unit·√s) and rate random walk ``K`` (rate-unit/√s) come from the slope −1/2 and
+1/2 lines, the bias instability ``B`` from the minimum divided by 0.664, all from the points
with tau <= T/10 by default (T the record length).
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

BIAS_INSTABILITY_FACTOR = 0.664  # flicker floor / B = sqrt(2 ln 2 / pi) (IEEE Std 952)
SLOPE_TOLERANCE = 0.25  # a fit region's local log-log slope is within this of the target
MIN_SPAN = 3.0  # a fit region must cover tau_last / tau_first >= this (about half a decade)
MIN_INTERVALS = 10.0  # read-offs use tau <= T / MIN_INTERVALS by default, T = N / fs_hz
ARW_TAU_S = 1.0  # the slope -1/2 line is read at tau = 1 s
RRW_TAU_S = 3.0  # the slope +1/2 line is read at tau = 3 s
_BLOCK = 1 << 16  # samples per block of the second-difference sum (512 KiB of float64)


@dataclass(frozen=True, eq=False)
class AllanDeviation:
    """Overlapping Allan deviation: ``adev`` (rate unit) at ``tau_s`` (s, increasing), with
    ``n_terms`` second differences summed at each tau, of ``n_samples`` samples at ``fs_hz``.
    Arrays are read-only."""

    tau_s: np.ndarray
    adev: np.ndarray
    n_terms: np.ndarray
    fs_hz: float
    n_samples: int


@dataclass(frozen=True)
class NoiseParameters:
    """IEEE Std 952 read-offs of an :class:`AllanDeviation`, in the input rate unit.

    angle_random_walk: ``N``, slope −1/2 line at tau = 1 s (rate-unit·√s; deg/s·√s = deg/√s).
    arw_tau_range_s: (first, last) tau of the points fitted for ``N``.
    bias_instability: ``B = adev_min / 0.664`` (rate unit).
    adev_min, tau_min_s: the minimum of the curve (the raw floor, not divided by 0.664) and
        its tau.
    min_is_interior: False when the minimum is at the first or last tau used: no floor was
        seen and ``B`` is only an upper bound.
    rate_random_walk: ``K``, slope +1/2 line at tau = 3 s (rate-unit/√s).
    rrw_tau_range_s: (first, last) tau of the points fitted for ``K``.
    tau_max_s: the longest tau the read-offs looked at.

    ``N`` and ``K`` (and their ranges) are NaN when the curve has no region of that slope; all
    read-offs are NaN when no tau is <= ``tau_max_s``.
    """

    angle_random_walk: float
    arw_tau_range_s: tuple[float, float]
    bias_instability: float
    adev_min: float
    tau_min_s: float
    min_is_interior: bool
    rate_random_walk: float
    rrw_tau_range_s: tuple[float, float]
    tau_max_s: float


def _averaging_factors(taus: np.ndarray | str, fs_hz: float, m_max: int) -> np.ndarray:
    """Integer ``m = tau fs`` for a tau keyword or an array of tau in seconds."""
    if isinstance(taus, str):
        if taus == "octave":
            return 2 ** np.arange(int(np.log2(m_max)) + 1)
        if taus == "decade":
            m = np.logspace(0.0, np.log10(m_max), int(10 * np.log10(m_max)) + 1)
            return np.unique(np.round(m).astype(np.int64))
        raise ValueError(f"taus must be 'octave', 'decade' or an array of seconds, got {taus!r}")
    tau_s = np.asarray(taus, dtype=np.float64)
    if tau_s.ndim != 1 or tau_s.size == 0:
        raise ValueError(f"taus must be a non-empty 1-D array of seconds, got shape {tau_s.shape}")
    m = np.round(tau_s * fs_hz)
    bad = ~np.isfinite(m) | (m < 1) | (m > m_max)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"tau {float(tau_s[i])!r} s (taus[{i}]) is out of range: tau * fs_hz must round to an integer "
            f"m in [1, {m_max}] (m <= (N - 1) // 2), i.e. tau in "
            f"[{1 / fs_hz:g}, {m_max / fs_hz:g}] s"
        )
    return np.unique(m.astype(np.int64))


def _angle(rate: np.ndarray, tau0_s: float) -> np.ndarray:
    """``[0, cumsum(rate - mean(rate))] * tau0``, built in one float64 array."""
    theta = np.empty(rate.size + 1)
    theta[0] = 0.0
    np.subtract(rate, rate.mean(), out=theta[1:])
    np.cumsum(theta[1:], out=theta[1:])
    theta[1:] *= tau0_s
    return theta


@functools.cache
def _blas_controller():  # type: ignore[no-untyped-def]
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


@contextlib.contextmanager
def _one_blas_thread() -> Iterator[None]:
    """BLAS limited to one thread inside the block (restored after)."""
    with _blas_controller().limit(limits=1, user_api="blas"):
        yield


def _second_difference_sum(theta: np.ndarray, m: int, buf: np.ndarray) -> float:
    """``sum_k (theta[k+2m] - 2 theta[k+m] + theta[k])^2``, block by block through ``buf`` (three
    blocks long): ``d[k] = theta[k+m] - theta[k]`` over the block and ``m`` beyond it, then
    ``d[k+m] - d[k]``; a lag longer than a block takes the three-term form."""
    n = theta.size - 2 * m
    block = buf.size // 3
    total = 0.0
    for start in range(0, n, block):
        stop = min(start + block, n)
        size = stop - start
        v = buf[:size]
        if m <= block:
            d = buf[block : block + size + m]
            np.subtract(theta[start + m : stop + 2 * m], theta[start : stop + m], out=d)
            np.subtract(d[m:], d[:size], out=v)
        else:
            np.subtract(theta[start + 2 * m : stop + 2 * m], theta[start + m : stop + m], out=v)
            np.subtract(v, theta[start + m : stop + m], out=v)
            np.add(v, theta[start:stop], out=v)
        total += float(np.dot(v, v))
    return total


def _checked_rate(rate: np.ndarray, fs_hz: float) -> tuple[np.ndarray, float]:
    """``rate`` as a 1-D finite float64 array of at least 3 samples and ``fs_hz`` > 0, or ValueError."""
    rate = np.asarray(rate, dtype=np.float64)
    if rate.ndim != 1:
        raise ValueError(f"rate must be 1-D, got shape {rate.shape}")
    if rate.size < 3:
        raise ValueError(f"rate needs at least 3 samples, got {rate.size}")
    if not np.isfinite(rate).all():
        i = int(np.flatnonzero(~np.isfinite(rate))[0])
        raise ValueError(f"rate must be finite: rate[{i}] = {rate[i]}")
    fs_hz = float(fs_hz)
    if not (np.isfinite(fs_hz) and fs_hz > 0.0):
        raise ValueError(f"fs_hz must be a finite number > 0, got {fs_hz}")
    return rate, fs_hz


def allan_deviation(
    rate: np.ndarray, fs_hz: float, taus: np.ndarray | str = "octave"
) -> AllanDeviation:
    """Overlapping Allan deviation of ``rate`` (1-D, any rate unit) sampled at ``fs_hz``.

    taus: "octave" (m = 1, 2, 4, ... <= (N - 1) // 2), "decade" (about 10 log-spaced integer m
        per decade from 1 to (N - 1) // 2), or tau values in seconds, each rounded to the
        nearest m = tau fs_hz; the result is sorted and m values that coincide are merged.

    Raises ValueError for a non-1-D, shorter than 3 or non-finite ``rate`` (naming the first bad
    index), a non-positive ``fs_hz`` or a tau outside [1, (N - 1) // 2] samples.
    """
    rate, fs_hz = _checked_rate(rate, fs_hz)
    m = _averaging_factors(taus, fs_hz, (rate.size - 1) // 2)
    theta = _angle(rate, 1.0 / fs_hz)
    buf = np.empty(3 * min(_BLOCK, theta.size))
    with _one_blas_thread():
        sums = np.array([_second_difference_sum(theta, int(mj), buf) for mj in m])
    n_terms = theta.size - 2 * m
    tau_s = m / fs_hz
    adev = np.sqrt(sums / (2.0 * tau_s**2 * n_terms))
    for a in (tau_s, adev, n_terms):
        a.setflags(write=False)
    return AllanDeviation(tau_s=tau_s, adev=adev, n_terms=n_terms, fs_hz=fs_hz, n_samples=rate.size)


def allan_deviation_segments(rate: np.ndarray, fs_hz: float, segment: np.ndarray) -> AllanDeviation:
    """Overlapping Allan deviation of a rate recorded in segments (bursts with gaps between them).

    ``segment`` numbers the segment of every sample (non-decreasing, as
    :func:`tcbench.sensors.segments.segments` gives). The second differences are taken inside each
    segment only, never across a gap, and pooled: at each tau ``sigma^2 = sum of all segments'
    squared second differences / (2 tau^2 total n_terms)``, the Allan variance averaged over the
    segments weighted by their number of terms. Octave taus run up to half the median segment
    length (m <= (N_median - 1) // 2); a segment shorter than 2m + 1 samples skips that tau.
    ``n_samples`` of the result is the total number of samples, so the read-offs' default limit
    T/10 counts the time inside the segments. With one segment this is :func:`allan_deviation`.
    """
    from tcbench.sensors.segments import bounds

    rate, fs_hz = _checked_rate(rate, fs_hz)
    segment = np.asarray(segment)
    if segment.shape != rate.shape:
        raise ValueError(f"segment must number every sample: shape {segment.shape} against rate {rate.shape}")
    starts, stops = bounds(segment)
    lengths = stops - starts
    m_max = (int(np.median(lengths)) - 1) // 2
    if m_max < 1:
        raise ValueError(f"segments of {int(np.median(lengths))} samples (median) are too short for an Allan "
                         "deviation: it needs at least 3 samples per segment")
    m = 2 ** np.arange(int(np.log2(m_max)) + 1)
    sums = np.zeros(m.size)
    n_terms = np.zeros(m.size, dtype=np.int64)
    buf = np.empty(3 * min(_BLOCK, int(lengths.max()) + 1))
    with _one_blas_thread():
        for start, stop in zip(starts, stops, strict=True):
            fits = m[m <= (stop - start - 1) // 2]  # a prefix of m
            theta = _angle(rate[start:stop], 1.0 / fs_hz)
            for j, mj in enumerate(fits):
                sums[j] += _second_difference_sum(theta, int(mj), buf)
                n_terms[j] += theta.size - 2 * mj
    tau_s = m / fs_hz
    adev = np.sqrt(sums / (2.0 * tau_s**2 * n_terms))
    for a in (tau_s, adev, n_terms):
        a.setflags(write=False)
    return AllanDeviation(tau_s=tau_s, adev=adev, n_terms=n_terms, fs_hz=fs_hz, n_samples=rate.size)


def _slope_fit(
    tau_s: np.ndarray, log_adev: np.ndarray, slope: float, tau_read_s: float
) -> tuple[float, tuple[float, float]]:
    """Value at ``tau_read_s`` of the least-squares line of fixed ``slope`` in log-log space,
    fitted over the widest (in log tau) run of segments whose slope is within
    ``SLOPE_TOLERANCE`` of ``slope``; NaN and a NaN range when no run spans ``MIN_SPAN``."""
    nan = (float("nan"), (float("nan"), float("nan")))
    if tau_s.size < 2:
        return nan
    log_tau = np.log(tau_s)
    with np.errstate(divide="ignore", invalid="ignore"):
        local = np.diff(log_adev) / np.diff(log_tau)
    ok = np.abs(local - slope) <= SLOPE_TOLERANCE  # False for NaN/inf (zero adev)
    if not ok.any():
        return nan
    # Runs of consecutive good segments: [first, last] segment indices.
    edges = np.diff(np.r_[0, ok.astype(np.int8), 0])
    first, last = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    span = log_tau[last + 1] - log_tau[first]
    widest = int(np.argmax(span))
    if span[widest] < np.log(MIN_SPAN) - 1e-9:
        return nan
    pts = slice(first[widest], last[widest] + 2)
    intercept = float(np.mean(log_adev[pts] - slope * log_tau[pts]))
    value = float(np.exp(intercept + slope * np.log(tau_read_s)))
    return value, (float(tau_s[pts][0]), float(tau_s[pts][-1]))


def noise_parameters(ad: AllanDeviation, tau_max_s: float | None = None) -> NoiseParameters:
    """IEEE Std 952 read-offs of ``ad`` in its rate unit (fields: :class:`NoiseParameters`).

    ``N`` (``K``) is the slope −1/2 (+1/2) line, fitted by least squares on log adev with the
    slope fixed, read at tau = 1 s (3 s). The fit uses the widest contiguous tau range where the
    local slope between neighbouring points is within ±0.25 of the target; a range covering
    less than a factor of 3 in tau, or none, gives NaN. ``B`` is the minimum divided by 0.664.

    Only points with tau <= ``tau_max_s`` are used, by default T/10 (T = N / fs_hz the record
    length): beyond it fewer than ten independent intervals remain, the curve wanders by tens
    of percent and shows chance slopes of any sign and chance minima.
    """
    if tau_max_s is None:
        tau_max_s = ad.n_samples / ad.fs_hz / MIN_INTERVALS
    used = ad.tau_s <= tau_max_s
    tau_s, adev = ad.tau_s[used], ad.adev[used]
    with np.errstate(divide="ignore"):
        log_adev = np.log(adev)
    arw, arw_range = _slope_fit(tau_s, log_adev, -0.5, ARW_TAU_S)
    rrw, rrw_range = _slope_fit(tau_s, log_adev, 0.5, RRW_TAU_S)
    i_min = int(np.argmin(adev)) if adev.size else -1
    adev_min = float(adev[i_min]) if adev.size else float("nan")
    return NoiseParameters(
        angle_random_walk=arw,
        arw_tau_range_s=arw_range,
        bias_instability=adev_min / BIAS_INSTABILITY_FACTOR,
        adev_min=adev_min,
        tau_min_s=float(tau_s[i_min]) if adev.size else float("nan"),
        min_is_interior=0 < i_min < adev.size - 1,
        rate_random_walk=rrw,
        rrw_tau_range_s=rrw_range,
        tau_max_s=float(tau_max_s),
    )


def to_deg_per_hour(x_dps: float | np.ndarray) -> float | np.ndarray:
    """deg/s to deg/h: multiply by 3600 (e.g. a bias instability ``B`` read in deg/s)."""
    return x_dps * 3600.0


def arw_to_deg_per_sqrt_hour(n_dps_sqrt_s: float | np.ndarray) -> float | np.ndarray:
    """Angle random walk deg/s·√s (= deg/√s) to deg/√h: multiply by 60, since
    1 deg/√s = 1 deg / √(1/3600 h) = 60 deg/√h; equivalently N[deg/√h] = sigma(1 s)[deg/h] / 60."""
    return n_dps_sqrt_s * 60.0
