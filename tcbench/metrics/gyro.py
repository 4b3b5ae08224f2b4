"""Gyroscope metrics of seed 001: Allan read-offs in the paper's units and the temperature drift.

- ARW ``N`` in deg/sqrt(h). Seed 001 prints "deg/h/sqrt(Hz)" beside 0.531, a value that only fits
  its bias stability if read as deg/sqrt(h); tcbench reports deg/sqrt(h) and says so.
- bias instability ``B`` in deg/h (Allan minimum / 0.664; the raw minimum is reported too).
- rate random walk ``K`` in deg/h/sqrt(h).
- drift: mean output over the last ``window_s`` of the hot soak minus that of the cold soak
  (deg/s); the soaks are the last stretch at which the thermometer stays within ``tol_c`` of
  the set-point.
- rate against temperature: a straight line through the mean output at several temperatures,
  with its slope (deg/s per degC), the slope's standard error and the correlation ``r``. A
  recording of short bursts (segments) gives one point per segment, the segment's mean output
  at its mean temperature; a continuous one gives the means in equal-width temperature bins.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from tcbench.sensors.segments import bounds
from tcbench.signal.allan import (
    AllanDeviation,
    NoiseParameters,
    allan_deviation,
    allan_deviation_segments,
    noise_parameters,
)

TEMPERATURE_BINS = 20  # bins of a continuous recording's temperature range
MIN_FIT_POINTS = 3  # a line with a standard error needs three points
MIN_FIT_SPAN_C = 0.5  # ... spread over at least this much temperature
BURST_SPAN_FRACTION = 0.1  # segments are bursts when each spans less than this of the range


class AllanSummary(NamedTuple):
    """An Allan deviation, its read-offs in the input's units and as metrics (see :func:`allan_summary`)."""

    ad: AllanDeviation
    params: NoiseParameters
    metrics: dict[str, float]


def allan_summary(output_dps: np.ndarray, fs_hz: float, segment: np.ndarray | None = None) -> AllanSummary:
    """Allan deviation (octave taus) and its read-offs in deg/sqrt(h), deg/h, deg/h/sqrt(h).

    With ``segment`` (segment number per sample) the Allan variance is taken within the
    segments and averaged over them (:func:`~tcbench.signal.allan.allan_deviation_segments`)."""
    if segment is None:
        ad = allan_deviation(output_dps, fs_hz, "octave")
    else:
        ad = allan_deviation_segments(output_dps, fs_hz, segment)
    p = noise_parameters(ad)
    return AllanSummary(ad, p, {
        "arw_deg_per_sqrt_h": p.angle_random_walk * 60.0,
        "bias_instability_dph": p.bias_instability * 3600.0,
        "allan_min_dph": p.adev_min * 3600.0,
        "allan_min_tau_s": p.tau_min_s,
        "allan_min_is_interior": float(p.min_is_interior),
        "rrw_dph_per_sqrt_h": p.rate_random_walk * 3600.0 * 60.0,
    })


def soak_mean(
    t_s: np.ndarray,
    temperature_c: np.ndarray,
    output: np.ndarray,
    target_c: float,
    window_s: float = 600.0,
    tol_c: float = 0.5,
) -> float:
    """Mean output over the last ``window_s`` of the last soak within ``tol_c`` of ``target_c``.

    A soak is a run of samples within the tolerance lasting at least ``window_s`` (a noisy
    thermometer flickers in and out of the band while a ramp crosses it; those runs are skipped).
    """
    near = np.abs(temperature_c - target_c) <= tol_c
    edges = np.flatnonzero(np.diff(np.r_[0, near.astype(np.int8), 0]))
    starts, stops = edges[::2], edges[1::2]  # runs near[start:stop]
    long_enough = t_s[stops - 1] - t_s[starts] >= window_s
    if not long_enough.any():
        raise ValueError(
            f"the recording never stays within {tol_c} degC of {target_c:g} degC for {window_s:g} s"
        )
    start, stop = starts[long_enough][-1], stops[long_enough][-1]
    recent = t_s[start:stop] >= t_s[stop - 1] - window_s
    return float(np.mean(output[start:stop][recent]))


def drift_dps(
    t_s: np.ndarray,
    temperature_c: np.ndarray,
    output_dps: np.ndarray,
    hot_c: float = 60.0,
    cold_c: float = -40.0,
    window_s: float = 600.0,
) -> float:
    """Output at the end of the hot soak minus output at the end of the cold soak (deg/s)."""
    hot = soak_mean(t_s, temperature_c, output_dps, hot_c, window_s)
    cold = soak_mean(t_s, temperature_c, output_dps, cold_c, window_s)
    return hot - cold


@dataclass(frozen=True)
class RateTemperatureFit:
    """Mean output (deg/s) at ``temperature_c`` points and the least-squares line through them.

    ``method`` is ``"segment means"`` or ``"temperature bins"``; ``samples`` counts the samples
    behind each point; ``intercept_dps`` is the line's value at 0 degC."""

    method: str
    temperature_c: np.ndarray
    output_dps: np.ndarray
    samples: np.ndarray
    slope_dps_per_c: float
    slope_stderr_dps_per_c: float
    intercept_dps: float
    r: float

    def metrics(self) -> dict[str, float]:
        """The scalars a report prints."""
        return {"rate_temp_slope_dps_per_c": self.slope_dps_per_c,
                "rate_temp_slope_se_dps_per_c": self.slope_stderr_dps_per_c,
                "rate_temp_r": self.r, "rate_temp_points": float(self.temperature_c.size)}

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready description: method, fit and points."""
        return {"method": self.method, "slope_dps_per_c": self.slope_dps_per_c,
                "slope_stderr_dps_per_c": self.slope_stderr_dps_per_c, "intercept_dps": self.intercept_dps,
                "r": self.r, "points": {"temperature_c": self.temperature_c.tolist(),
                                        "output_dps": self.output_dps.tolist(), "samples": self.samples.tolist()}}


def line_fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float]:
    """Least-squares line ``y = slope x + intercept``: ``(slope, slope standard error, intercept,
    r)``, the standard error from the residual variance with ``n - 2`` degrees of freedom."""
    n = x.size
    dx, dy = x - x.mean(), y - y.mean()
    sxx, syy, sxy = float(dx @ dx), float(dy @ dy), float(dx @ dy)
    slope = sxy / sxx
    r = sxy / np.sqrt(sxx * syy) if syy > 0 else float("nan")  # a constant y has no correlation
    residual = max(syy - slope * sxy, 0.0)
    return slope, float(np.sqrt(residual / (n - 2) / sxx)), float(y.mean() - slope * x.mean()), float(r)


def rate_vs_temperature(temperature_c: np.ndarray, output_dps: np.ndarray,
                        segment: np.ndarray | None = None) -> RateTemperatureFit | None:
    """Output against temperature: points and a straight line through them, or ``None`` when
    fewer than three points span at least 0.5 degC.

    With ``segment`` (segment number per sample) and at least three segments that are bursts
    (each spanning less than a tenth of the temperature range, median over segments), each
    segment gives its mean output at its mean temperature; otherwise the samples are binned in
    20 equal-width temperature bins and each non-empty bin gives its means.
    """
    temperature_c = np.asarray(temperature_c, dtype=np.float64)
    output_dps = np.asarray(output_dps, dtype=np.float64)
    span_c = float(np.ptp(temperature_c)) if temperature_c.size else 0.0
    if span_c < MIN_FIT_SPAN_C:
        return None
    method, group = "temperature bins", None
    if segment is not None:
        starts, stops = bounds(segment)
        if starts.size >= MIN_FIT_POINTS:
            seg_span = np.maximum.reduceat(temperature_c, starts) - np.minimum.reduceat(temperature_c, starts)
            if float(np.median(seg_span)) < BURST_SPAN_FRACTION * span_c:
                method, group = "segment means", np.repeat(np.arange(starts.size), stops - starts)
    if group is None:
        edges = np.linspace(temperature_c.min(), temperature_c.max(), TEMPERATURE_BINS + 1)
        group = np.clip(np.searchsorted(edges, temperature_c, "right") - 1, 0, TEMPERATURE_BINS - 1)
    samples = np.bincount(group)
    used = samples > 0
    t_mean = np.bincount(group, temperature_c)[used] / samples[used]
    y_mean = np.bincount(group, output_dps)[used] / samples[used]
    if t_mean.size < MIN_FIT_POINTS or np.ptp(t_mean) < MIN_FIT_SPAN_C:
        return None
    slope, stderr, intercept, r = line_fit(t_mean, y_mean)
    return RateTemperatureFit(method, t_mean, y_mean, samples[used], slope, stderr, intercept, r)
