"""Temperature profiles: chamber set-point programmes, chamber and package dynamics, lags.

A protocol is a list of :class:`Segment` (hold or ramp the chamber to a set-point, optionally
recording a turntable position). :func:`setpoint` turns it into a set-point trace with the
chamber's ramp-rate limit; :func:`first_order_lag` models anything that follows another
temperature with a time constant (chamber air, the package thermometer, the die).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Segment:
    """Hold the chamber at ``target_c`` for ``duration_s`` (ramping there first if needed).

    ``position``: turntable position recorded during the segment (MSRA four-position test),
    ``""`` when no labelled data are taken; ``accel_g`` / ``cross_g``: acceleration along the
    sensitive axis and across it in that position; ``rate_dps``: applied rotation rate.
    """

    target_c: float
    duration_s: float
    position: str = ""
    accel_g: float = 0.0
    cross_g: float = 1.0
    rate_dps: float = 0.0


def first_order_lag(x: np.ndarray, dt_s: float, tau_s: float, y0: float | None = None) -> np.ndarray:
    """Exact discretisation of ``dy/dt = (x - y)/tau`` for a sampled input (zero-order hold)."""
    if tau_s <= 0:
        return np.asarray(x, dtype=float).copy()
    from scipy.signal import lfilter  # here: scipy.signal takes about a second to import

    a = np.exp(-dt_s / tau_s)
    start = float(x[0]) if y0 is None else float(y0)
    y, _ = lfilter([1.0 - a], [1.0, -a], x, zi=[a * start])
    return y


def setpoint(
    segments: list[Segment], start_c: float, ramp_c_per_min: float, dt_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """Chamber set-point sampled every ``dt_s``: a ramp at ``ramp_c_per_min`` to each segment's
    target, then a hold for its duration. Returns ``(t_s, setpoint_c)`` and, per sample, the
    index of the segment (``-1`` while ramping) via :func:`segment_index`."""
    times, temps = [0.0], [start_c]
    for seg in segments:
        ramp_s = abs(seg.target_c - temps[-1]) / (ramp_c_per_min / 60.0)
        if ramp_s > 0:
            times.append(times[-1] + ramp_s)
            temps.append(seg.target_c)
        times.append(times[-1] + seg.duration_s)
        temps.append(seg.target_c)
    t = np.arange(0.0, times[-1], dt_s)
    return t, np.interp(t, times, temps)


def segment_index(
    segments: list[Segment], start_c: float, ramp_c_per_min: float, t_s: np.ndarray
) -> np.ndarray:
    """For each time, the index of the hold segment it falls in, or ``-1`` during ramps."""
    edges, labels, now, temp = [0.0], [-1], 0.0, start_c
    for i, seg in enumerate(segments):
        ramp_s = abs(seg.target_c - temp) / (ramp_c_per_min / 60.0)
        now += ramp_s
        edges.append(now)
        labels.append(i)
        now += seg.duration_s
        edges.append(now)
        labels.append(-1)
        temp = seg.target_c
    idx = np.searchsorted(np.asarray(edges), t_s, side="right") - 1
    return np.asarray(labels)[np.clip(idx, 0, len(labels) - 1)]


def gauss_markov(
    n: int, dt_s: float, tau_s: float, sigma: float, rng: np.random.Generator
) -> np.ndarray:
    """Stationary first-order Gauss-Markov process (std ``sigma``, correlation time ``tau_s``)."""
    from scipy.signal import lfilter  # here: scipy.signal takes about a second to import

    a = np.exp(-dt_s / tau_s)
    drive = rng.standard_normal(n)
    drive *= sigma
    drive *= np.sqrt(1.0 - a * a)
    x0 = rng.standard_normal() * sigma
    y, _ = lfilter([1.0], [1.0, -a], drive, zi=[a * x0])
    return y
