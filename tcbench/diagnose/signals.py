"""The arrays a diagnosis works on, taken from one recording.

The thermometer reading is smoothed by a local linear fit over ``smooth_s`` of time (its
quantisation and noise would otherwise act as an error in the regressor), and dT/dt is that
fit's slope. Both use time windows rather than sample counts, so a recording made of bursts
with gaps between them (a logger that wakes up every few minutes) is handled like a continuous
one. Filters that need a uniform clock (the first-order lag, the play operator) run on a grid of
at most 1 s and are read back at the sample times.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter, oaconvolve, savgol_coeffs, savgol_filter

from tcbench.diagnose.settings import DEFAULTS
from tcbench.sensors import kinds
from tcbench.sensors.effects import play_operator
from tcbench.sensors.recording import Recording
from tcbench.sensors.segments import segments

MAD_TO_SIGMA = 1.4826  # standard deviation of a normal sample from its median absolute deviation
GRID_S = 1.0  # clock of the lag filter and the play operator
MAX_GRID_SAMPLES = 5_000_000  # that clock over the recording: 58 days at 1 s
MIN_NOISE_DIFFS = 10  # first differences at constant input a white sigma is measured from, at least
INPUT_CHANGE_TOL = 1e-9  # relative to the largest |input| (or 1): a smaller change is float rounding, not a new level


class DiagnosisDataError(ValueError):
    """A recording that cannot be diagnosed (too short, constant temperature, ...)."""


def local_linear(t_s: np.ndarray, x: np.ndarray, window_s: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Value and slope (per s) of a least-squares line through ``x`` over ``t ± window_s / 2``
    at every sample (``window_s`` one for all, or one per sample), by cumulative sums (O(n)); a
    window holding one sample keeps it."""
    t0 = t_s - t_s.mean()
    lo = np.searchsorted(t_s, t_s - 0.5 * window_s, side="left")
    hi = np.searchsorted(t_s, t_s + 0.5 * window_s, side="right")

    def window_sum(v: np.ndarray) -> np.ndarray:
        c = np.concatenate(([0.0], np.cumsum(v)))
        return c[hi] - c[lo]

    n = (hi - lo).astype(float)
    st, sx = window_sum(t0), window_sum(x)
    stt, stx = window_sum(t0 * t0), window_sum(t0 * x)
    var = stt - st * st / n
    ok = var > 1e-9 * np.maximum(n, 1.0)
    slope = np.where(ok, (stx - st * sx / n) / np.where(ok, var, 1.0), 0.0)
    value = sx / n + slope * (t0 - st / n)
    return value, slope


MIN_WINDOW_SAMPLES = 10  # a fitted smoothing window never holds fewer samples than this
MIN_SAVGOL_SAMPLES = 5  # the local quadratic needs this many samples in its window: three would interpolate them
SPARSE_SPACINGS = 3.0  # a sparse segment's local line spans this many of its own spacings, to reach its neighbours
NOISE_SEED = 0  # the white noise that measures a window's noise share: fixed, so a diagnosis is repeatable
FFT_WINDOW = 255  # longer Savitzky-Golay windows convolve by FFT (a 120 s window at 100 Hz holds 12001 samples)


def savgol(x: np.ndarray, window: int, deriv: int = 0, delta_s: float = 1.0) -> np.ndarray:
    """``savgol_filter(x, window, 2, deriv, delta_s, mode="interp")``, in O(n log n) for a long
    window: the interior by overlap-add convolution with the same coefficients, the first and
    last ``window // 2`` samples from a quadratic fitted to the first and last ``window``."""
    if window <= FFT_WINDOW:
        return savgol_filter(x, window, 2, deriv=deriv, delta=delta_s, mode="interp")
    y = oaconvolve(x, savgol_coeffs(window, 2, deriv=deriv, delta=delta_s, use="conv"), mode="same")
    half, pos = window // 2, np.arange(window, dtype=float)
    for sl, keep in ((slice(0, window), slice(0, half)), (slice(x.size - window, x.size), slice(window - half, window))):
        poly = np.polyder(np.polyfit(pos, x[sl], 2), deriv) if deriv else np.polyfit(pos, x[sl], 2)
        edge = np.polyval(poly, pos[keep]) / delta_s**deriv
        y[sl][keep] = edge
    return y


def smooth_temperature(t_s: np.ndarray, temp_c: np.ndarray, window_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Smoothed thermometer and its rate (degC/s).

    Inside a continuous segment at least ``window_s`` long: a local quadratic (Savitzky-Golay)
    over ``window_s``, whose value has no bias where the profile bends (a local line would lag
    by about T'' W^2 / 24 at every corner of a ramp). A shorter segment (a burst) holding at
    least :data:`MIN_WINDOW_SAMPLES` samples takes the local quadratic over its own samples: a
    line reaching across gaps of minutes misses the profile's bends between bursts by degrees
    (2 degC RMS on an 8 h staircase sampled 100 s of every 10 min), far more than the noise
    averaging gains. Sparser segments take the local line over ``window_s`` or, if wider, three
    times their own spacing, which reaches across the gaps to their neighbours: the span from the
    segment's first sample to its last plus the wider of the gaps on either side (on a regularly
    sparse record, the interval between segment starts). A few samples between two gaps of a
    continuous record (kept samples between clipped ones) are so bridged over their own gaps, not
    over the record's mean segment spacing (hours, where a line through an oven ramp misses by
    degrees).
    """
    value, rate = _smoothed(t_s, temp_c, window_s, with_rate=True)
    assert rate is not None
    return value, rate


def smoothed_value(t_s: np.ndarray, x: np.ndarray, window_s: float) -> np.ndarray:
    """The value of :func:`smooth_temperature` alone (the same numbers, without computing the
    rate), for the noise propagation that smooths many series."""
    return _smoothed(t_s, x, window_s, with_rate=False)[0]


def _smoothed(t_s: np.ndarray, temp_c: np.ndarray, window_s: float,
              with_rate: bool) -> tuple[np.ndarray, np.ndarray | None]:
    seg = segments(t_s)
    value = np.empty_like(temp_c)
    rate = np.empty_like(temp_c) if with_rate else None
    starts = np.flatnonzero(np.diff(np.concatenate(([-1], seg))))
    bounds = np.append(starts, t_s.size)
    first, n = bounds[:-1], np.diff(bounds)
    fs = (n - 1) / np.maximum(t_s[bounds[1:] - 1] - t_s[first], 1e-12)
    w = np.round(window_s * fs).astype(np.int64) | 1
    burst = (MIN_WINDOW_SAMPLES <= n) & (n < w)  # a burst: its own samples, not a line across the gaps
    w = np.where(burst, n - (n % 2 == 0), w)
    quadratic = (n >= w) & (w >= MIN_SAVGOL_SAMPLES)
    for size, window in {(int(a), int(b)) for a, b in zip(n[quadratic], w[quadratic], strict=True)}:
        members = np.flatnonzero(quadratic & (n == size) & (w == window))
        _savgol_segments(temp_c, first[members], size, window, fs[members], value, rate)
    if not quadratic.all():  # the sparse segments: the local line
        line = np.repeat(~quadratic, n)
        wide = local_linear(t_s, temp_c, _sparse_window_s(t_s, bounds, window_s))
        value[line] = wide[0][line]
        if rate is not None:
            rate[line] = wide[1][line]
    return value, rate


def _savgol_segments(x: np.ndarray, first: np.ndarray, size: int, window: int, fs: np.ndarray,
                     value: np.ndarray, rate: np.ndarray | None) -> None:
    """:func:`savgol` of the segments of ``size`` samples starting at ``first`` (sampled at
    ``fs``, Hz) into ``value`` and ``rate``: many short ones (a clipped record's thousands of
    kept runs) as the rows of one array, a long or lone one alone."""
    if first.size == 1 or window > FFT_WINDOW:
        for a, f in zip(first, fs, strict=True):
            value[a:a + size] = savgol(x[a:a + size], window)
            if rate is not None:
                rate[a:a + size] = savgol(x[a:a + size], window, deriv=1, delta_s=1.0 / f)
        return
    rows = first[:, None] + np.arange(size)
    value[rows] = savgol_filter(x[rows], window, 2, mode="interp", axis=1)
    if rate is not None:
        rate[rows] = savgol_filter(x[rows], window, 2, deriv=1, mode="interp", axis=1) * fs[:, None]


def _sparse_window_s(t_s: np.ndarray, bounds: np.ndarray, window_s: float) -> np.ndarray:
    """Per sample, the local line's window of a sparse segment (see :func:`smooth_temperature`):
    ``window_s`` or, if wider, three times the segment's own spacing (its span plus the wider of
    the gaps on either side); ``window_s`` for a record of one segment."""
    first, last = t_s[bounds[:-1]], t_s[bounds[1:] - 1]
    if first.size < 2:
        return np.full(t_s.size, float(window_s))
    gap = first[1:] - last[:-1]
    wider = np.maximum(np.concatenate(([gap[0]], gap)), np.concatenate((gap, [gap[-1]])))
    per_segment = np.maximum(window_s, SPARSE_SPACINGS * (last - first + wider))
    return np.repeat(per_segment, np.diff(bounds))


def fitted_window_s(t_s: np.ndarray, temp_c: np.ndarray, window_s: float,
                    bias_to_noise: float = DEFAULTS.smoothing.bias_to_noise) -> float:
    """The thermometer smoothing window fitted to the profile's time scales: ``window_s`` halved
    while the bias it puts on the smoothed temperature exceeds ``bias_to_noise`` of the
    thermometer noise it leaves (a deterministic error, e.g. at the corners of a fast ramp
    through a short package lag, is read by the output's temperature and acceleration terms as
    structure; the noise is accounted for by :mod:`tcbench.diagnose.select.thermometer_noise`). A quadratic
    smoother's bias scales as W^4, so halving takes it down 16x: the bias of ``W`` is estimated
    from the difference between the readings smoothed over ``W`` and ``W/2``, less that
    difference's noise share; the noise of each, from the same smoothing of white noise with the
    reading's per-sample spread (fixed seed, so a diagnosis is repeatable). A slow profile keeps
    ``window_s``; a fast one, or a high sample rate (many samples per window, so little noise),
    gets a shorter window; never below :data:`MIN_WINDOW_SAMPLES` samples. In bursts the halving
    starts from the longest burst (each is smoothed over at most its own samples), so a burst
    through a fast bend is also smoothed over less than its whole length."""
    if t_s.size < 2 * MIN_WINDOW_SAMPLES:
        return window_s
    rate_hz = 1.0 / max(float(np.median(np.diff(t_s))), 1e-12)  # within bursts, not over the gaps
    seg = segments(t_s)
    starts = np.flatnonzero(np.diff(np.concatenate(([-1], seg))))
    ends = np.append(starts[1:], t_s.size) - 1
    longest_s = float(np.max(t_s[ends] - t_s[starts]))  # a burst shorter than the window is smoothed whole
    rng = np.random.default_rng(NOISE_SEED)
    white = rng.standard_normal(t_s.size)
    w = float(min(window_s, longest_s)) if longest_s * rate_hz >= 2 * MIN_WINDOW_SAMPLES else float(window_s)
    while w / 2.0 * rate_hz >= MIN_WINDOW_SAMPLES:
        wide, narrow = smooth_temperature(t_s, temp_c, w)[0], smooth_temperature(t_s, temp_c, w / 2.0)[0]
        sigma_c = float(np.std(temp_c - narrow))
        noise_wide = sigma_c * smooth_temperature(t_s, white, w)[0]
        noise_narrow = sigma_c * smooth_temperature(t_s, white, w / 2.0)[0]
        bias2 = np.mean((wide - narrow) ** 2) - np.mean((noise_wide - noise_narrow) ** 2)
        if bias2 <= (bias_to_noise * (15.0 / 16.0)) ** 2 * np.mean(noise_wide**2):
            break
        w /= 2.0
    return w


def check_grid(t_s: np.ndarray, grid_s: float = GRID_S) -> None:
    """Refuse a recording whose span on a uniform clock of ``grid_s`` would exceed
    :data:`MAX_GRID_SAMPLES`, before anything is allocated."""
    n = (float(t_s[-1]) - float(t_s[0])) / grid_s if t_s.size else 0.0
    if not n <= MAX_GRID_SAMPLES:
        raise DiagnosisDataError(
            f"the recording spans {n * grid_s:.3g} s: its {grid_s:g} s filter clock would hold {n:.3g} samples, more "
            f"than the {MAX_GRID_SAMPLES:.0e} a diagnosis allocates (split it into shorter recordings)")


def on_grid(t_s: np.ndarray, x: np.ndarray, fn, grid_s: float = GRID_S) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Apply ``fn(x_grid, grid_s)`` to ``x`` resampled on a uniform clock, read back at ``t_s``."""
    check_grid(t_s, grid_s)
    grid = np.arange(t_s[0], t_s[-1] + grid_s, grid_s)
    return np.interp(t_s, grid, fn(np.interp(grid, t_s, x), grid_s))


def lagged(t_s: np.ndarray, temp_c: np.ndarray, tau_s: float) -> np.ndarray:
    """``temp_c`` through a first-order lag of ``tau_s`` (starting settled)."""

    def lag(x: np.ndarray, dt: float) -> np.ndarray:
        a = np.exp(-dt / tau_s)
        return lfilter([1.0 - a], [1.0, -a], x, zi=[a * x[0]])[0]

    return on_grid(t_s, temp_c, lag)


def hysteresis_state(t_s: np.ndarray, temp_c: np.ndarray, width_c: float) -> np.ndarray:
    """The play-operator state ``(T - play(T)) / width`` in [-1, 1]: +1 after heating, -1
    after cooling (the regressor of the ``hysteresis`` effect)."""
    return on_grid(t_s, temp_c, lambda x, dt: (x - play_operator(x, width_c)) / width_c)


@dataclass(frozen=True)
class DiagnosisData:
    """One recording prepared for diagnosis (all arrays per sample).

    ``temp_c`` the smoothed thermometer reading, ``rate_c_per_s`` its slope, ``input`` the
    applied acceleration (g) or rate (deg/s), ``output`` in ``unit``; ``run_id`` numbers the runs
    of constant input within a continuous segment; ``white_sigma`` the per-sample white-noise
    standard deviation of the output from first differences inside those runs.
    """

    sensor: str
    unit: str
    t_s: np.ndarray
    temp_raw_c: np.ndarray
    temp_c: np.ndarray
    rate_c_per_s: np.ndarray
    input: np.ndarray
    output: np.ndarray
    run_id: np.ndarray
    white_sigma: float
    sample_rate_hz: float
    smooth_s: float

    @property
    def n(self) -> int:
        return int(self.t_s.size)

    @property
    def input_levels(self) -> int:
        """How many distinct input values the recording holds (to 1e-6 of the largest)."""
        scale = max(float(np.max(np.abs(self.input))), 1e-12)
        return int(np.unique(np.round(self.input / scale, 6)).size)


def prepare(
    rec: Recording,
    sensor: str | None = None,
    *,
    smooth_s: float = DEFAULTS.smoothing.default_window_s,
    min_duration_s: float = 0.0,
    min_span_c: float = DEFAULTS.data.min_span_c,
    min_samples: int = DEFAULTS.data.min_samples,
) -> DiagnosisData:
    """Arrays for diagnosing ``rec``; ``sensor`` overrides the sidecar's kind.

    Raises :class:`DiagnosisDataError` (one line) when the recording is shorter than
    ``min_duration_s`` (``diagnose`` asks :func:`tcbench.diagnose.select.plan.min_full_duration_s`) or
    ``min_samples``, its temperature spans less than ``min_span_c``, or
    its output has no noise to measure.
    """
    kind = sensor or rec.meta.sensor
    if not kinds.known(kind):
        raise DiagnosisDataError(f"unknown sensor {kind!r}; give sensor=" + "|".join(kinds.names()))
    t, temp, u, y = rec.time_s, rec.temperature_c, rec.input, rec.output
    if t.size < min_samples or t[-1] - t[0] < min_duration_s:
        raise DiagnosisDataError(
            f"recording too short to identify anything: {t.size} samples over {t[-1] - t[0]:.0f} s "
            f"(need at least {min_samples} samples over {min_duration_s:.0f} s)")
    check_grid(t)
    span = float(np.ptp(temp))
    if span < min_span_c:
        raise DiagnosisDataError(
            f"temperature varies by only {span:.3g} degC (need at least {min_span_c:g} degC): "
            "a temperature model cannot be identified at constant temperature")
    gap = np.diff(segments(t)) > 0
    changed = np.abs(np.diff(u)) > INPUT_CHANGE_TOL * max(1.0, float(np.max(np.abs(u))))
    run_id = np.concatenate(([0], np.cumsum(gap | changed)))
    same = ~(gap | changed)
    d = np.diff(y)[same]
    if d.size < MIN_NOISE_DIFFS:
        raise DiagnosisDataError("too few consecutive samples at constant input to measure the noise")
    sigma = float(MAD_TO_SIGMA * np.median(np.abs(d - np.median(d))) / np.sqrt(2.0))
    if not sigma > 0:  # most steps zero: an output on a coarse grid; the RMS of the steps still measures it
        sigma = float(np.sqrt(np.mean(d * d) / 2.0))
    if not sigma > 0:
        raise DiagnosisDataError("the output has no sample-to-sample noise: it is constant at constant input")
    smooth, rate = smooth_temperature(t, temp, smooth_s)
    units = rec.meta.units or {}
    return DiagnosisData(
        sensor=kind, unit=str(units.get("output", kinds.get(str(kind)).output_unit)), t_s=t,
        temp_raw_c=temp, temp_c=smooth, rate_c_per_s=rate, input=u, output=y, run_id=run_id,
        white_sigma=sigma,
        sample_rate_hz=float(rec.meta.sample_rate_hz or 1.0 / np.median(np.diff(t))), smooth_s=smooth_s,
    )
