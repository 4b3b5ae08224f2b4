"""Gyroscope metrics of seed 001: Allan read-offs in the paper's units and the temperature drift.

- ARW ``N`` in deg/sqrt(h). Seed 001 prints "deg/h/sqrt(Hz)" beside 0.531, a value that only fits
  its bias stability if read as deg/sqrt(h); tcbench reports deg/sqrt(h) and says so.
- bias instability ``B`` in deg/h (Allan minimum / 0.664; the raw minimum is reported too).
- rate random walk ``K`` in deg/h/sqrt(h).
- drift: mean output over the last ``window_s`` of the hot soak minus that of the cold soak
  (deg/s); the soaks are the last stretch at which the thermometer stays within ``tol_c`` of
  the set-point.
"""

from __future__ import annotations

import numpy as np

from tcbench.signal.allan import AllanDeviation, allan_deviation, noise_parameters


def allan_summary(output_dps: np.ndarray, fs_hz: float) -> tuple[AllanDeviation, dict[str, float]]:
    """Allan deviation (octave taus) and its read-offs in deg/sqrt(h), deg/h, deg/h/sqrt(h)."""
    ad = allan_deviation(output_dps, fs_hz, "octave")
    p = noise_parameters(ad)
    return ad, {
        "arw_deg_per_sqrt_h": p.angle_random_walk * 60.0,
        "bias_instability_dph": p.bias_instability * 3600.0,
        "allan_min_dph": p.adev_min * 3600.0,
        "allan_min_tau_s": p.tau_min_s,
        "rrw_dph_per_sqrt_h": p.rate_random_walk * 3600.0 * 60.0,
    }


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
