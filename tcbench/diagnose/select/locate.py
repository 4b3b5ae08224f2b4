"""Where a model's residual departs from white noise (docs/concepts/diagnosis-report.md, the ``mismatch`` list).

:func:`locate` runs five families of tests on a residual ``r`` (any unit) sampled at times
``t_s`` with thermometer temperature ``temp_c``; the family-wise false-alarm probability
``false_alarm`` under white noise is split between the five families by Šidák's rule,
``a_f = 1 - (1 - false_alarm)^(1/5)``, and inside each family by Šidák (or Bonferroni) over its
number of tests:

- time spans: non-overlapping windows of ``window_s``; every run of consecutive windows
  ``i..j`` gets ``z = sum(r) / (sigma sqrt(n))`` (the mean times sqrt(n) / sigma); the threshold
  is two-sided over the ``K (K + 1) / 2`` runs of ``K`` windows. Runs are picked greedily by
  largest ``|z|`` among those not overlapping a run already picked, then adjacent picks of the
  same sign are merged into one span.
- temperature bands: the same scan over bins of ``band_c`` of temperature (empty bins skipped).
- heating vs cooling: dT/dt > +eps against dT/dt < -eps, the difference of mean residuals taken
  in each temperature bin where both occur and combined with inverse-variance weights (a
  Welch-type z, each group's variance over its effective sample count ``n (1 - rho)/(1 + rho)``,
  ``rho`` the residual's lag-1 autocorrelation).
- soak vs ramp: |dT/dt| < eps against |dT/dt| > eps, the same test.
- frequency band: overlapping Allan deviation of ``r`` at ``tau = m / fs`` (m = 10, 20, 40, ...,
  at most N / 10) against the white line ``sigma / sqrt(m)``; a tau is flagged when the Allan
  variance exceeds the line by more than the chi-square bound ``chi2.isf(a, edf) / edf`` with
  the white-FM equivalent degrees of freedom of the overlapping estimator
  ``edf = (3 (N - 1) / (2 m) - 2 (N - 2) / N) 4 m^2 / (4 m^2 + 5)``, Bonferroni over the taus.
  When sigma is estimated from the data, its own relative variance (about 7 / N for the MAD of
  first differences) widens the bound. A record with gaps (bursts, a logging gap, samples given
  zero weight) is tested inside its continuous segments: second differences never span a gap,
  they are pooled over the segments and the degrees of freedom summed, and the taus stop at what
  the longest segment holds.

``sigma`` (per-sample white-noise standard deviation, unit of ``r``) is ``white_sigma`` when given,
otherwise ``1.4826 MAD(diff(r)) / sqrt(2)``, which drift and steps barely move. The false-alarm
probability, windows, bins and rates are :class:`~tcbench.diagnose.settings.LocateSettings`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from scipy.stats import chi2, norm

from tcbench.diagnose.settings import DEFAULTS, LocateSettings
from tcbench.diagnose.signals import MAD_TO_SIGMA
from tcbench.sensors.segments import bounds, segments, within_rate_hz
from tcbench.signal.allan import allan_deviation

N_FAMILIES = 5  # time spans, temperature bands, heating/cooling, soak/ramp, frequency band
SIGMA2_REL_VAR = 7.0  # N * var(sigma_hat^2 / sigma^2) for the MAD of first differences (measured)
MAX_LAG1 = 0.99  # the residual's lag-1 autocorrelation is capped here: at 1 a group's effective count would vanish
# the longest Allan tau is the record (in samples) over this: at N / 10 the overlapping estimator keeps about 13
# degrees of freedom (``_edf``), enough for its chi-square bound
ALLAN_RECORD_TAUS = 10


@dataclass(frozen=True)
class Mismatch:
    """One departure from white noise between ``t_start_s`` and ``t_end_s`` (s, same clock as
    the input), described by ``what``; ``statistic`` exceeded ``threshold`` (|z| for the scans and
    the two-group tests, Allan deviation / white line for the frequency band)."""

    t_start_s: float
    t_end_s: float
    what: str
    statistic: float
    threshold: float

    def to_dict(self) -> dict[str, Any]:
        """Plain dict with the report's keys ``t_start_s``, ``t_end_s``, ``what`` and the test's
        ``statistic`` and ``threshold``."""
        return {k: (v if isinstance(v, str) else float(v)) for k, v in asdict(self).items()}


def _check(
    t_s: np.ndarray, temp_c: np.ndarray, residual: np.ndarray, white_sigma: float | None,
    false_alarm: float, min_samples: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    arrays = {}
    for name, a in (("t_s", t_s), ("temp_c", temp_c), ("residual", residual)):
        a = np.asarray(a, dtype=np.float64)
        if a.ndim != 1:
            raise ValueError(f"{name} must be 1-D, got shape {a.shape}")
        bad = ~np.isfinite(a)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(f"{name} must be finite: {name}[{i}] = {a[i]}")
        arrays[name] = a
    t, temp, r = arrays["t_s"], arrays["temp_c"], arrays["residual"]
    if not (t.size == temp.size == r.size):
        raise ValueError(
            f"t_s, temp_c and residual must have the same length, got {t.size}, {temp.size}, {r.size}"
        )
    if t.size < min_samples:
        raise ValueError(f"residual needs at least {min_samples} samples, got {t.size}")
    if not (np.diff(t) > 0).all():
        raise ValueError("t_s must be strictly increasing")
    if white_sigma is not None and not (np.isfinite(white_sigma) and white_sigma > 0):
        raise ValueError(f"white_sigma must be None or a finite number > 0, got {white_sigma}")
    if not (0.0 < false_alarm < 1.0):
        raise ValueError(f"false_alarm must be in (0, 1), got {false_alarm}")
    return t, temp, r


def robust_white_sigma(residual: np.ndarray) -> float:
    """Per-sample white-noise sigma from the MAD of first differences (unit of ``residual``)."""
    d = np.diff(np.asarray(residual, dtype=np.float64))
    return float(MAD_TO_SIGMA * np.median(np.abs(d - np.median(d))) / np.sqrt(2.0))


def _sidak(alpha: float, n_tests: int) -> float:
    """Per-test level so that ``n_tests`` independent tests have family-wise level ``alpha``."""
    return float(-np.expm1(np.log1p(-alpha) / max(n_tests, 1)))


def _scan(sums: np.ndarray, counts: np.ndarray, sigma: float, z_thr: float, max_findings: int
          ) -> list[tuple[int, int, float]]:
    """Runs ``[i, j)`` of consecutive bins with ``|z| > z_thr``, greedy by largest ``|z|`` without
    overlap, adjacent same-sign runs merged; returns ``(i, j, z)``."""
    s = np.r_[0.0, np.cumsum(sums)]
    c = np.r_[0.0, np.cumsum(counts)]
    k = sums.size
    i, j = np.triu_indices(k + 1, 1)
    z = (s[j] - s[i]) / (sigma * np.sqrt(c[j] - c[i]))
    absz = np.abs(z)
    picks: list[tuple[int, int, float]] = []
    used = np.zeros(k, dtype=np.int64)
    alive = absz > z_thr
    while alive.any() and len(picks) < max_findings:
        best = int(np.argmax(np.where(alive, absz, -np.inf)))
        a, b = int(i[best]), int(j[best])
        picks.append((a, b, float(z[best])))
        used[a:b] = 1
        u = np.r_[0, np.cumsum(used)]
        alive &= (u[j] - u[i]) == 0
    picks.sort()
    merged: list[tuple[int, int, float]] = []
    for a, b, zz in picks:
        if merged and merged[-1][1] == a and np.sign(merged[-1][2]) == np.sign(zz):
            a = merged.pop()[0]
            zz = float((s[b] - s[a]) / (sigma * np.sqrt(c[b] - c[a])))
        merged.append((a, b, zz))
    return merged


def _binned_scan(idx: np.ndarray, r: np.ndarray, sigma: float, alpha: float, max_findings: int
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, list[tuple[int, int, float]]]:
    """Residual summed per bin ``idx``; the non-empty bins, their counts and sums, the Šidák
    threshold over all runs of consecutive non-empty bins, and the runs that exceed it."""
    counts = np.bincount(idx).astype(np.float64)
    sums = np.bincount(idx, weights=r)
    keep = np.flatnonzero(counts > 0)
    k = keep.size
    z_thr = float(norm.isf(_sidak(alpha, k * (k + 1) // 2) / 2.0))
    return keep, counts, sums, z_thr, _scan(sums[keep], counts[keep], sigma, z_thr, max_findings)


def _time_spans(t: np.ndarray, r: np.ndarray, sigma: float, alpha: float, settings: LocateSettings
                ) -> list[Mismatch]:
    span_s = t[-1] - t[0]
    w = min(max(settings.window_s, span_s / settings.max_windows), span_s / settings.min_windows)
    idx = np.minimum(((t - t[0]) / w).astype(np.int64), int(np.ceil(span_s / w)) - 1)
    keep, counts, sums, z_thr, runs = _binned_scan(idx, r, sigma, alpha, settings.max_findings)
    out = []
    for a, b, z in runs:
        n = counts[keep[a] : keep[b - 1] + 1].sum()
        mean = sums[keep[a] : keep[b - 1] + 1].sum() / n
        t0 = t[0] + keep[a] * w
        t1 = min(t[0] + (keep[b - 1] + 1) * w, t[-1])
        out.append(Mismatch(float(t0), float(t1), f"time span: mean residual {mean:+.3g}", abs(z), z_thr))
    return out


def _temperature_bands(
    t: np.ndarray, temp: np.ndarray, r: np.ndarray, sigma: float, alpha: float, settings: LocateSettings
) -> list[Mismatch]:
    band_c = settings.band_c
    lo = np.floor(temp.min() / band_c) * band_c
    idx = ((temp - lo) / band_c).astype(np.int64)
    keep, _, _, z_thr, runs = _binned_scan(idx, r, sigma, alpha, settings.max_findings)
    out = []
    for a, b, z in runs:
        b_lo, b_hi = keep[a], keep[b - 1]
        inside = (idx >= b_lo) & (idx <= b_hi)
        times = t[inside]
        mean = r[inside].mean()
        t_lo, t_hi = lo + b_lo * band_c, lo + (b_hi + 1) * band_c
        what = f"temperature band {t_lo:g}..{t_hi:g} °C: mean residual {mean:+.3g}"
        out.append(Mismatch(float(times[0]), float(times[-1]), what, abs(z), z_thr))
    return out


def _rate_c_per_s(t: np.ndarray, temp: np.ndarray, rate_window_s: float) -> np.ndarray:
    """Centred difference of temperature over about ``rate_window_s`` (°C/s)."""
    n = t.size
    fs = (n - 1) / (t[-1] - t[0])
    h = max(1, round(rate_window_s * fs / 2.0))
    k = np.arange(n)
    hi, lo = np.minimum(k + h, n - 1), np.maximum(k - h, 0)
    return (temp[hi] - temp[lo]) / (t[hi] - t[lo])


def _two_group_z(
    temp: np.ndarray, r: np.ndarray, in_a: np.ndarray, in_b: np.ndarray, band_c: float, rho: float,
    min_group: int,
) -> tuple[float, np.ndarray] | None:
    """Welch-type z of mean(r | a) - mean(r | b) stratified by temperature bins; also the mask
    of samples in bins that entered. None when no bin has ``min_group`` samples of both."""
    lo = np.floor(temp.min() / band_c) * band_c
    idx = ((temp - lo) / band_c).astype(np.int64)
    nb = int(idx.max()) + 1
    stats = []
    for m in (in_a, in_b):
        n = np.bincount(idx[m], minlength=nb).astype(np.float64)
        s1 = np.bincount(idx[m], weights=r[m], minlength=nb)
        s2 = np.bincount(idx[m], weights=r[m] ** 2, minlength=nb)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = s1 / n
            var = (s2 - s1 * mean) / (n - 1)
        stats.append((n, mean, var))
    (na, ma, va), (nbb, mb, vb) = stats
    ok = (na >= min_group) & (nbb >= min_group)
    if not ok.any():
        return None
    shrink = (1.0 - rho) / (1.0 + rho)
    var_d = va[ok] / (na[ok] * shrink) + vb[ok] / (nbb[ok] * shrink)
    var_d = np.maximum(var_d, np.finfo(float).tiny)
    w = 1.0 / var_d
    est = float(np.sum(w * (ma[ok] - mb[ok])) / np.sum(w))
    z = est * float(np.sqrt(np.sum(w)))
    used = ok[idx] & (in_a | in_b)
    return z, used


def _lag1(r: np.ndarray) -> float:
    e = r - r.mean()
    rho = float(np.dot(e[1:], e[:-1]) / np.dot(e, e)) if np.dot(e, e) > 0 else 0.0
    return min(max(rho, 0.0), MAX_LAG1)


def _group_tests(
    t: np.ndarray, temp: np.ndarray, r: np.ndarray, alpha: float, settings: LocateSettings, inflation: float = 1.0,
) -> list[Mismatch]:
    """Heating vs cooling and soak vs ramp; ``inflation`` (>= 1) is the variance of a window
    mean over its white-noise value, from known coloured noise, when it exceeds lag-1's."""
    rate = _rate_c_per_s(t, temp, settings.rate_window_s)
    rate_eps_c_per_s = settings.still_rate_c_per_min / 60.0
    rho = _lag1(r)
    rho = max(rho, (inflation - 1.0) / (inflation + 1.0))  # (1 - rho) / (1 + rho) = 1 / inflation
    z_thr = float(norm.isf(alpha / 2.0))
    tests = (
        ("heating vs cooling", rate > rate_eps_c_per_s, rate < -rate_eps_c_per_s),
        ("soak vs ramp", np.abs(rate) < rate_eps_c_per_s, np.abs(rate) > rate_eps_c_per_s),
    )
    out = []
    for what, a, b in tests:
        res = _two_group_z(temp, r, a, b, settings.band_c, rho, settings.min_group_samples)
        if res is None or abs(res[0]) <= z_thr:
            continue
        z, used = res
        times = t[used]
        out.append(Mismatch(float(times[0]), float(times[-1]), what, abs(z), z_thr))
    return out


@dataclass(frozen=True)
class AllanExcess:
    """Overlapping Allan deviation of a residual against its white-noise line: ``adev`` and
    ``white`` (= sigma / sqrt(m)) at ``tau_s``, the flagging bound on ``adev / white`` and the
    index of the first tau above it (None: consistent with white noise)."""

    tau_s: np.ndarray
    adev: np.ndarray
    white: np.ndarray
    bound: np.ndarray
    first_over: int | None


def _longest_run(t: np.ndarray) -> tuple[int, int]:
    """Samples of the longest continuous segment of ``t`` and the number of gaps."""
    if t.size == 0:
        return 0, 0
    seg = segments(t)
    starts, stops = bounds(seg)
    return int(np.max(stops - starts)), int(seg[-1])


def why_no_allan(t: np.ndarray, min_samples: int = DEFAULTS.locate.min_allan_samples) -> str | None:
    """Why :func:`allan_excess` cannot test a residual sampled at ``t`` (its shortest tau
    ``min_samples`` samples, inside one continuous segment), or None."""
    n = t.size
    longest, gaps = _longest_run(t)
    if min(n // ALLAN_RECORD_TAUS, (longest - 1) // 2) >= min_samples:
        return None
    if gaps and (n - 1) // 2 >= min_samples and n // ALLAN_RECORD_TAUS >= min_samples:
        return (f"the Allan deviation needs clusters of {min_samples} samples inside a continuous segment; the "
                f"longest of this record's {gaps + 1} segments (gaps of more than five sample intervals: bursts, "
                f"or samples given zero weight) holds {longest}")
    return (f"the Allan deviation needs clusters of {min_samples} samples at a tenth of the record "
            f"({ALLAN_RECORD_TAUS * min_samples} samples); this record has {n}")


def _edf(n: np.ndarray | int, m: np.ndarray) -> np.ndarray:
    """White-FM equivalent degrees of freedom of the overlapping Allan variance of ``n`` samples at ``m``."""
    return (3.0 * (n - 1) / (2.0 * m) - 2.0 * (n - 2) / n) * 4.0 * m**2 / (4.0 * m**2 + 5.0)


def _pooled_allan(t: np.ndarray, r: np.ndarray, fs: float, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Allan deviation of ``r`` at ``m`` samples with the second differences taken inside each
    continuous segment of ``t`` and pooled over them (never across a gap), and its degrees of
    freedom (the segments' summed); a segment shorter than ``2 m + 1`` samples skips that ``m``."""
    starts, stops = bounds(segments(t))
    sums, terms, edf = np.zeros(m.size), np.zeros(m.size), np.zeros(m.size)
    for a, b in zip(starts, stops, strict=True):
        fits = np.flatnonzero(2 * m + 1 <= b - a)
        if fits.size == 0:
            continue
        ad = allan_deviation(r[a:b], fs, m[fits] / fs)
        sums[fits] += ad.adev**2 * 2.0 * ad.tau_s**2 * ad.n_terms
        terms[fits] += ad.n_terms
        edf[fits] += _edf(b - a, m[fits])
    tau_s = m / fs
    return np.sqrt(sums / (2.0 * tau_s**2 * terms)), edf


def allan_excess(
    t: np.ndarray, r: np.ndarray, sigma: float, alpha: float, estimated: bool,
    coloured: np.ndarray | None = None, min_samples: int = DEFAULTS.locate.min_allan_samples,
) -> AllanExcess | None:
    """The frequency-band test (module doc) at level ``alpha``; None when the residual is too
    short for tau >= ``min_samples`` samples at N / 10. A record with gaps (bursts, a logging
    gap, samples given zero weight) is tested inside its continuous segments, the second
    differences pooled over them (an Allan deviation across a gap means nothing), its taus up to
    what its longest segment holds. ``coloured`` is a known non-white noise (one
    realisation, per sample) whose Allan variance is added to the white line."""
    n = r.size
    if why_no_allan(t, min_samples) is not None:
        return None
    longest, gaps = _longest_run(t)
    m_max = min(n // ALLAN_RECORD_TAUS, (longest - 1) // 2)
    m = min_samples * 2 ** np.arange(int(np.log2(m_max / min_samples)) + 1)
    if gaps:
        fs = within_rate_hz(t)
        tau_s, (adev, edf) = m / fs, _pooled_allan(t, r, fs, m)
        coloured_adev = _pooled_allan(t, coloured, fs, m)[0] if coloured is not None else None
    else:
        fs = (n - 1) / (t[-1] - t[0])
        ad = allan_deviation(r, fs, m / fs)
        tau_s, adev = ad.tau_s, ad.adev
        m = np.round(ad.tau_s * fs)
        edf = _edf(n, m)
        coloured_adev = allan_deviation(coloured, fs, ad.tau_s).adev if coloured is not None else None
    a = alpha / m.size
    bound = chi2.isf(a, edf) / edf
    if estimated:
        bound = bound * np.exp(norm.isf(a) * np.sqrt(SIGMA2_REL_VAR / n))
    white = sigma / np.sqrt(m)
    if coloured_adev is not None:
        white = np.sqrt(white**2 + coloured_adev**2)
    over = np.flatnonzero(adev**2 / white**2 > bound)
    return AllanExcess(tau_s, adev, white, np.sqrt(bound), int(over[0]) if over.size else None)


def _frequency_band(
    t: np.ndarray, r: np.ndarray, sigma: float, alpha: float, estimated: bool, coloured: np.ndarray | None,
    min_samples: int,
) -> list[Mismatch]:
    ex = allan_excess(t, r, sigma, alpha, estimated, coloured, min_samples)
    if ex is None or ex.first_over is None:
        return []
    k = ex.first_over
    what = f"low-frequency excess (flicker or drift) from tau = {ex.tau_s[k]:.4g} s"
    return [Mismatch(float(t[0]), float(t[-1]), what, float(ex.adev[k] / ex.white[k]), float(ex.bound[k]))]


def locate(
    t_s: np.ndarray,
    temp_c: np.ndarray,
    residual: np.ndarray,
    white_sigma: float | None,
    settings: LocateSettings = DEFAULTS.locate,
    *,
    coloured: np.ndarray | None = None,
) -> list[Mismatch]:
    """Departures of ``residual`` (any unit) from white noise of per-sample sigma ``white_sigma``
    (same unit; None: estimated robustly), at time ``t_s`` (s) and temperature ``temp_c`` (°C).

    The probability of any finding on pure white noise is at most about ``settings.false_alarm``.
    ``settings.window_s`` is the time-scan window, ``band_c`` the temperature bin,
    ``still_rate_c_per_min`` (default 0.05 °C/min) the dT/dt that separates soak from ramp, dT/dt
    taken over ``rate_window_s``. Findings come in family order: time spans, temperature bands, heating vs
    cooling, soak vs ramp, frequency band. ``coloured`` is one realisation of a known non-white
    noise in the residual (e.g. a thermometer's, carried through the model): the scans widen
    sigma by its variance over a window, the frequency test adds its Allan variance. Raises ValueError for non-finite values, unequal
    lengths, fewer than ``settings.min_samples`` samples or non-increasing ``t_s``.
    """
    false_alarm, window_s = settings.false_alarm, settings.window_s
    t, temp, r = _check(t_s, temp_c, residual, white_sigma, false_alarm, settings.min_samples)
    estimated = white_sigma is None
    sigma = robust_white_sigma(r) if estimated else float(white_sigma)
    if not sigma > 0:
        raise ValueError("residual has zero white-noise sigma (constant first differences)")
    alpha = _sidak(false_alarm, N_FAMILIES)
    scan_sigma = sigma
    if coloured is not None:
        window = np.floor((t - t[0]) / window_s).astype(np.int64)
        sums, counts = np.bincount(window, coloured), np.bincount(window)
        scan_sigma = float(np.sqrt(sigma**2 + np.mean(sums**2) / np.mean(counts)))
    return [
        *_time_spans(t, r, scan_sigma, alpha, settings),
        *_temperature_bands(t, temp, r, scan_sigma, alpha, settings),
        *_group_tests(t, temp, r, alpha, settings, (scan_sigma / sigma) ** 2),
        *_frequency_band(t, r, sigma, alpha, estimated, coloured, settings.min_allan_samples),
    ]
