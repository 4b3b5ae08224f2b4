"""Bandwidth kept: the -3 dB frequency of a whole processing pipeline, measured by injection.

A filter that removes noise also removes signal. To keep smoothing from passing for
compensation, every gyro result reports how much of a real rate input still reaches the
output: known sines are added to the recorded rate, the pipeline is run with and without them,
and the difference is fitted with the same sines (least squares over the record). The gain at
each frequency is the fitted amplitude over the injected one; the bandwidth kept is where the
gain first falls below 1/sqrt(2), interpolated in log frequency.

By default all frequencies go in together as one multi-sine with non-harmonic frequencies
(one extra run of the pipeline); ``multisine=False`` injects them one at a time, which is exact
for nonlinear pipelines at the price of one run per frequency.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

HALF_POWER = 1.0 / np.sqrt(2.0)


@dataclass(frozen=True)
class Bandwidth:
    """Gain of the pipeline at ``freqs_hz`` and the -3 dB frequency (``inf`` when the gain
    never falls below 1/sqrt(2) over the frequencies tried: at least ``freqs_hz[-1]``)."""

    freqs_hz: np.ndarray
    gain: np.ndarray
    f3db_hz: float

    def describe(self) -> str:
        if np.isinf(self.f3db_hz):
            return f">= {self.freqs_hz[-1]:.3g} Hz (gain never below -3 dB)"
        return f"{self.f3db_hz:.3g} Hz"


def default_freqs(duration_s: float, fs_hz: float, count: int = 16) -> np.ndarray:
    """Log-spaced test frequencies from 20 cycles per record to 0.4 fs, nudged off a common
    harmonic grid so a multi-sine's components do not share frequencies."""
    lo, hi = 20.0 / duration_s, 0.4 * fs_hz
    if not hi > lo:
        raise ValueError(f"record too short for a bandwidth test: {duration_s:g} s at {fs_hz:g} Hz")
    f = np.geomspace(lo, hi, count)
    return f * (1.0 + 0.013 * np.sin(np.arange(count) * 2.3))


def _fit_gain(t_s: np.ndarray, d: np.ndarray, freqs_hz: np.ndarray, amplitude: float) -> np.ndarray:
    phase = 2.0 * np.pi * np.outer(t_s, freqs_hz)
    design = np.hstack([np.sin(phase), np.cos(phase)])
    coef, *_ = np.linalg.lstsq(design, d, rcond=None)
    k = freqs_hz.size
    return np.hypot(coef[:k], coef[k:]) / amplitude


def bandwidth_kept(
    process: Callable[[np.ndarray], np.ndarray],
    t_s: np.ndarray,
    output: np.ndarray,
    *,
    amplitude: float = 1.0,
    freqs_hz: np.ndarray | None = None,
    multisine: bool = True,
) -> Bandwidth:
    """The -3 dB frequency of ``process`` (output array -> processed array of the same length)
    on the recording ``output`` sampled at ``t_s`` (s), with sines of ``amplitude`` (output unit,
    each; a multi-sine's total is larger) injected at ``freqs_hz`` (default: :func:`default_freqs`)."""
    t = np.asarray(t_s, dtype=float)
    y = np.asarray(output, dtype=float)
    if t.ndim != 1 or t.shape != y.shape:
        raise ValueError(f"t_s and output must be 1-D of one length, got {t.shape} and {y.shape}")
    if not amplitude > 0:
        raise ValueError(f"amplitude must be > 0, got {amplitude}")
    fs = (t.size - 1) / (t[-1] - t[0])
    f = default_freqs(t[-1] - t[0], fs) if freqs_hz is None else np.sort(np.asarray(freqs_hz, dtype=float))
    base = np.asarray(process(y), dtype=float)
    if base.shape != y.shape:
        raise ValueError(f"the pipeline returned shape {base.shape} for an input of shape {y.shape}")
    if multisine:
        inject = amplitude * np.sin(2.0 * np.pi * np.outer(t, f)).sum(axis=1)
        gain = _fit_gain(t, np.asarray(process(y + inject)) - base, f, amplitude)
    else:
        gain = np.array([
            _fit_gain(t, np.asarray(process(y + amplitude * np.sin(2.0 * np.pi * fi * t))) - base, np.array([fi]), amplitude)[0]
            for fi in f
        ])
    below = np.flatnonzero(gain < HALF_POWER)
    if below.size == 0:
        return Bandwidth(f, gain, float("inf"))
    i = int(below[0])
    if i == 0:
        return Bandwidth(f, gain, float(f[0]))
    # interpolate log f linearly in gain between the last point above and the first below
    g0, g1 = gain[i - 1], gain[i]
    w = (g0 - HALF_POWER) / (g0 - g1)
    return Bandwidth(f, gain, float(np.exp(np.log(f[i - 1]) + w * (np.log(f[i]) - np.log(f[i - 1])))))
