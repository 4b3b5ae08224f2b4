"""Generic detectors of shape: where in a residual an open-world term would go.

Each detector reads the in-sample residual of the current model and proposes a few values of
the nonlinear parameters of open-world terms (:mod:`tcbench.diagnose.terms`, each term's
``propose``); the held-out
scoring of :mod:`tcbench.diagnose.select.discover` decides. They work on the residual averaged in
time bins (:func:`binned`: a few thousand bins however long or fast the record, gaps left
empty), so a 24 h record at 100 Hz costs what a 1 Hz one does.

- **steps** (:func:`step_times`): change points of the binned residual's mean by binary
  segmentation (``ruptures.Binseg``, l2 cost), each refined to the sample by the two-sample
  mean statistic within a bin of it; the first sample after every long gap (a restart) too.
- **spectral lines** (:func:`line_periods`): Lomb-Scargle periodogram of the binned residual
  (gapped and burst records included) on at most ``line_bins`` bins, the highest peaks
  with periods between three bins and two thirds of the span.
  :func:`line_window` locates where a line is present (a cycle in part of the run) by complex
  demodulation.
- **temperature bumps** (:func:`bump_centres`): a matched filter of Gaussian bumps of several
  widths against the residual averaged in 0.1 degC bins of the model temperature, each bump
  taken orthogonal to the quadratic in temperature the model already holds.

Their numbers (bins, how many of each they propose, the bump widths ...) are
:class:`~tcbench.diagnose.settings.DetectorSettings`.
"""

from __future__ import annotations

import numpy as np
import ruptures
from scipy.signal import find_peaks, lombscargle

from tcbench.diagnose.settings import DEFAULTS, DetectorSettings

DETECTORS = DEFAULTS.detectors

# the detectors' own numbers, not settings: how finely they search, not what counts as found (the held-out
# scoring decides that)
MIN_SEGMENT_BINS = 2  # a change point leaves at least this many bins on either side (a single bin is an outlier)
BINS_PER_CHANGE = 4  # at most one change point per this many bins of a short record
MIN_PERIOD_BINS = 3.0  # the shortest period searched spans this many time bins (two is the bins' Nyquist limit)
FREQS_PER_FOURIER_BIN = 2.0  # the periodogram's frequency step, per 1 / span: the scorer refines the period
PEAK_DISTANCE = 4  # periodogram peaks (and the low edge against its neighbours) this many steps apart: 2 Fourier bins
ENVELOPE_PERIODS = 2.0  # a line's demodulated amplitude is averaged over this many periods
PRESENT_SHARE = 0.5  # a line is present where that amplitude is above this share of its peak
BUMP_STEPS_PER_WIDTH = 8.0  # bump centres are tried a width over this apart (or one temperature bin, if wider)


def binned(t_s: np.ndarray, r: np.ndarray, max_bins: int = DETECTORS.max_bins, min_bin_s: float = DETECTORS.min_bin_s
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """``(centre_s, mean, count, width_s)`` of ``r`` in time bins of ``width_s`` (at least
    ``min_bin_s``, at most ``max_bins`` of them); empty bins left out."""
    width = bin_width(t_s, max_bins, min_bin_s)
    idx = ((t_s - t_s[0]) / width).astype(np.int64)
    count = np.bincount(idx).astype(float)
    total = np.bincount(idx, weights=r)
    keep = count > 0
    centre = np.bincount(idx, weights=t_s)[keep] / count[keep]
    return centre, total[keep] / count[keep], count[keep], width


def bin_width(t_s: np.ndarray, max_bins: int = DETECTORS.max_bins, min_bin_s: float = DETECTORS.min_bin_s) -> float:
    """The width (s) of :func:`binned`'s time bins."""
    span = float(t_s[-1] - t_s[0])
    return max(min_bin_s, span / max_bins, float(np.median(np.diff(t_s))))


def _refine_step(t_s: np.ndarray, cum: np.ndarray, around_s: float, half_s: float) -> int:
    """Index of the first sample after the jump: the split of the whole record within
    ``around_s +- half_s`` with the largest two-sample mean statistic."""
    n = t_s.size
    lo = max(int(np.searchsorted(t_s, around_s - half_s)), 1)
    hi = min(int(np.searchsorted(t_s, around_s + half_s)), n - 1)
    if hi <= lo:
        return min(max(lo, 1), n - 1)
    k = np.arange(lo, hi + 1)
    stat = (cum[k] - k / n * cum[n]) ** 2 / (k * (n - k) / n)
    return int(k[np.argmax(stat)])


def step_times(t_s: np.ndarray, r: np.ndarray, settings: DetectorSettings = DETECTORS) -> list[float]:
    """Candidate step times (s): the first sample after each of the ``n_changes`` change points
    of the mean of ``r``, and after each of the ``max_gaps`` longest gaps."""
    centre, mean, _, width = binned(t_s, r, settings.max_bins, settings.min_bin_s)
    out: list[float] = []
    cum = np.concatenate(([0.0], np.cumsum(r)))
    if mean.size >= settings.min_step_bins:
        n_bkps = min(settings.n_changes, mean.size // BINS_PER_CHANGE)
        algo = ruptures.Binseg(model="l2", min_size=MIN_SEGMENT_BINS).fit(mean)
        for b in algo.predict(n_bkps=n_bkps)[:-1]:
            around = 0.5 * (centre[b - 1] + centre[b])
            out.append(float(t_s[_refine_step(t_s, cum, around, width)]))
    dt = np.diff(t_s)
    gaps = np.flatnonzero(dt > settings.gap_factor * np.median(dt))
    for g in gaps[np.argsort(-dt[gaps])][:settings.max_gaps]:
        out.append(float(t_s[g + 1]))
    return sorted(set(out))


def line_periods(t_s: np.ndarray, r: np.ndarray, settings: DetectorSettings = DETECTORS) -> list[float]:
    """Periods (s) of the ``n_lines`` highest Lomb-Scargle peaks of ``r``, between three bins
    and the span over ``line_cycles``."""
    centre, mean, count, width = binned(t_s, r, settings.line_bins, settings.min_bin_s)
    span = float(t_s[-1] - t_s[0])
    if mean.size < settings.min_line_bins:
        return []
    f_lo, f_hi = settings.line_cycles / span, 1.0 / (MIN_PERIOD_BINS * width)
    if f_hi <= f_lo:
        return []
    df = 1.0 / (FREQS_PER_FOURIER_BIN * span)
    freq = np.arange(f_lo, f_hi, df)
    power = lombscargle(centre - centre[0], mean - np.average(mean, weights=count), 2.0 * np.pi * freq,
                        normalize=False)
    peaks, _ = find_peaks(power, distance=PEAK_DISTANCE)
    best = list(peaks[np.argsort(-power[peaks])][:settings.n_lines])
    # a slow line (under two cycles) peaks at the low edge
    if power.size > PEAK_DISTANCE and power[0] > power[1:PEAK_DISTANCE + 1].max():
        best.append(0)
    return [float(1.0 / freq[i]) for i in best]


def line_window(t_s: np.ndarray, r: np.ndarray, period_s: float, settings: DetectorSettings = DETECTORS
                ) -> tuple[float, float]:
    """``(start_s, end_s)`` where a line of ``period_s`` is present in ``r``: the contiguous span
    around its strongest part where the complex-demodulated amplitude, averaged over
    :data:`ENVELOPE_PERIODS` periods, stays above :data:`PRESENT_SHARE` of its peak."""
    centre, mean, count, width = binned(t_s, r, settings.line_bins, settings.min_bin_s)
    z = mean * count * np.exp(-2j * np.pi * centre / period_s)
    m = min(max(int(round(ENVELOPE_PERIODS * period_s / width)), 1), centre.size)  # 'same' would return the longer
    kernel = np.ones(m)
    envelope = np.abs(np.convolve(z, kernel, "same")) / np.maximum(np.convolve(count, kernel, "same"), 1.0)
    peak = int(np.argmax(envelope))
    above = envelope >= PRESENT_SHARE * envelope[peak]
    lo = peak - int(np.argmin(above[peak::-1])) if not above[: peak + 1].all() else 0
    hi = peak + int(np.argmin(above[peak:])) if not above[peak:].all() else centre.size
    start = float(t_s[0]) if lo == 0 else float(centre[lo] + 0.5 * width)
    end = float(t_s[-1]) + 1.0 if hi >= centre.size else float(centre[hi] - 0.5 * width)
    return start, end


def duty_phase(t_s: np.ndarray, r: np.ndarray, period_s: float, start_s: float, end_s: float,
               n_phases: int = DETECTORS.duty_phases) -> tuple[float, float]:
    """``(on_s, duty)`` of a load switched on for a share ``duty`` of every ``period_s`` inside
    ``[start_s, end_s)``: ``r`` folded on the period into ``n_phases`` phase bins, and the
    contiguous arc of bins (wrapping) whose mean differs most from the rest's, by the
    between-group sum of squares; ``on_s`` is the arc's first instant (mod the period)."""
    inside = (t_s >= start_s) & (t_s < end_s)
    k = (np.mod(t_s[inside], period_s) / period_s * n_phases).astype(np.int64) % n_phases
    count = np.bincount(k, minlength=n_phases).astype(float)
    total = np.bincount(k, weights=r[inside], minlength=n_phases)
    n_all, s_all = count.sum(), total.sum()
    # every arc [i, i + length) on the circle, by cumulative sums of the doubled sequence
    cc, cs = np.concatenate([[0.0], np.cumsum(np.tile(count, 2))]), np.concatenate([[0.0], np.cumsum(np.tile(total, 2))])
    i, length = np.meshgrid(np.arange(n_phases), np.arange(1, n_phases), indexing="ij")
    n_on, s_on = cc[i + length] - cc[i], cs[i + length] - cs[i]
    n_off = n_all - n_on
    ok = (n_on > 0) & (n_off > 0)
    between = np.where(ok, (s_on / np.where(ok, n_on, 1.0) - (s_all - s_on) / np.where(ok, n_off, 1.0)) ** 2
                       * n_on * n_off / n_all, -np.inf)
    best = np.unravel_index(int(np.argmax(between)), between.shape)
    return float(best[0] * period_s / n_phases), float((best[1] + 1) / n_phases)


def bump_centres(temp_c: np.ndarray, r: np.ndarray, settings: DetectorSettings = DETECTORS
                 ) -> list[tuple[float, float]]:
    """``(centre_c, width_c)`` of the ``n_bumps`` Gaussian bumps in temperature that best match
    ``r``, each bump orthogonal to ``1, T, T^2`` (sample-weighted)."""
    bin_c = settings.temp_bin_c
    lo, hi = float(temp_c.min()), float(temp_c.max())
    span = hi - lo
    idx = ((temp_c - lo) / bin_c).astype(np.int64)
    count = np.bincount(idx).astype(float)
    total = np.bincount(idx, weights=r)
    tb = lo + (np.arange(count.size) + 0.5) * bin_c
    u = (tb - 0.5 * (lo + hi)) / max(0.5 * span, 1e-9)
    core = np.column_stack([np.ones_like(u), u, u * u])
    gram = core.T @ (core * count[:, None])
    found: list[tuple[float, float, float]] = []
    for w in (w for w in settings.bump_widths_c if settings.bump_spans * w <= span):
        centres = np.arange(lo + w, hi - w + 1e-9, max(bin_c, w / BUMP_STEPS_PER_WIDTH))
        if centres.size == 0:
            continue
        g = np.exp(-0.5 * ((tb[:, None] - centres[None, :]) / w) ** 2)  # (bins, centres)
        coef = np.linalg.solve(gram, core.T @ (g * count[:, None]))
        g_perp = g - core @ coef
        norm2 = np.einsum("bc,bc,b->c", g_perp, g_perp, count)
        score = (total @ g_perp) ** 2 / np.maximum(norm2, 1e-300)
        i = int(np.argmax(score))
        found.append((float(score[i]), float(centres[i]), float(w)))
    found.sort(reverse=True)
    return [(c, w) for _, c, w in found[:settings.n_bumps]]


def _bins(t_s: np.ndarray, max_bins: int, min_bin_s: float) -> int:
    """How many non-empty bins :func:`binned` makes of ``t_s``."""
    width = bin_width(t_s, max_bins, min_bin_s)
    return int(np.unique(((t_s - t_s[0]) / width).astype(np.int64)).size)


def why_no_steps(t_s: np.ndarray, settings: DetectorSettings = DETECTORS) -> str | None:
    """Why :func:`step_times` cannot search change points on a record sampled at ``t_s``, or None."""
    n = _bins(t_s, settings.max_bins, settings.min_bin_s)
    if n >= settings.min_step_bins:
        return None
    return (f"change points need at least {settings.min_step_bins} bins of "
            f"{bin_width(t_s, settings.max_bins, settings.min_bin_s):.4g} s of the residual; this record has {n}")


def why_no_lines(t_s: np.ndarray, settings: DetectorSettings = DETECTORS) -> str | None:
    """Why :func:`line_periods` cannot search spectral lines on ``t_s``, or None."""
    n, width = _bins(t_s, settings.line_bins, settings.min_bin_s), bin_width(t_s, settings.line_bins, settings.min_bin_s)
    if n < settings.min_line_bins:
        return (f"spectral lines need at least {settings.min_line_bins} bins of {width:.4g} s of the residual; "
                f"this record has {n}")
    longest, shortest = float(t_s[-1] - t_s[0]) / settings.line_cycles, MIN_PERIOD_BINS * width
    if longest <= shortest:
        return (f"a line needs {settings.line_cycles:g} cycles inside the record and {MIN_PERIOD_BINS:g} bins per "
                f"cycle: the longest testable period ({longest:.4g} s) is below the shortest ({shortest:.4g} s)")
    return None


def why_no_bumps(temp_c: np.ndarray, settings: DetectorSettings = DETECTORS) -> str | None:
    """Why :func:`bump_centres` cannot search temperature bumps on ``temp_c``, or None."""
    span, w = float(np.ptp(temp_c)), min(settings.bump_widths_c)
    if settings.bump_spans * w <= span:
        return None
    return (f"a temperature bump of width {w:g} degC needs a temperature span of {settings.bump_spans * w:g} degC; "
            f"this record spans {span:.3g} degC")
