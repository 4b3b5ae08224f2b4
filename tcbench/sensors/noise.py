"""Sensor noise processes, vectorised and seeded (docs/concepts/physics.md, metrics).

All amplitudes are in the sensor's output unit (Hz for the MSRA, deg/s for the gyroscope).
"""

from __future__ import annotations

import numpy as np

from tcbench.sensors.thermal import gauss_markov

# Per-process std of the Gauss-Markov bank, per unit of bias instability B, for two processes
# per decade; with it the Allan deviation floor is 0.664 B (checked in tests/test_noise.py).
FLICKER_SIGMA_PER_B = 0.605
_PER_DECADE = 2
_MAX_STEPS_PER_TC = 40  # a process slower than this many samples is drawn coarser, then interpolated
_CHUNK = 1 << 18  # samples interpolated at a time, so no full-length time axis is ever built


def white(n: int, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """White noise with per-sample standard deviation ``sigma``."""
    x = rng.standard_normal(n)
    x *= sigma
    return x


def random_walk(n: int, dt_s: float, k_per_sqrt_s: float, rng: np.random.Generator) -> np.ndarray:
    """Rate random walk: increments ``K sqrt(dt)`` (``K`` in output unit per sqrt(s))."""
    return np.cumsum(rng.standard_normal(n) * (k_per_sqrt_s * np.sqrt(dt_s)))


def flicker_bank(n: int, dt_s: float, b: float, tau_max_s: float | None = None) -> tuple[np.ndarray, float]:
    """The Gauss-Markov bank :func:`flicker` sums for ``n`` samples ``dt_s`` apart: the
    correlation times (s) and the std of each process (output unit)."""
    t_hi = 10.0 * (tau_max_s or n * dt_s)
    t_lo = max(1.0, 2.0 * dt_s)
    count = max(1, int(np.ceil(_PER_DECADE * np.log10(t_hi / t_lo))) + 1)
    return np.logspace(np.log10(t_lo), np.log10(t_hi), count), FLICKER_SIGMA_PER_B * b


def flicker_score_variance(z: np.ndarray, dt_s: float, b: float, tau_max_s: float | None = None) -> float:
    """``E[(z' f)^2]`` for ``f`` the flicker of :func:`flicker` (coefficient ``b``) on ``z.size``
    samples ``dt_s`` apart: the variance of a score ``z' f`` over infinitely many draws, exactly.
    Each process of the bank has covariance ``sigma^2 exp(-|i - j| dt_s / tc)``, whose quadratic
    form ``z' K z = 2 z' s - z' z`` takes one first-order recursion ``s_i = z_i + a s_(i-1)``,
    ``a = exp(-dt_s / tc)`` (O(n) per process). The draws' slow processes, drawn coarser and
    interpolated, have this covariance to within 1 %."""
    from scipy.signal import lfilter  # here: scipy.signal takes about a second to import

    z = np.asarray(z, dtype=float)
    tcs, sigma = flicker_bank(z.size, dt_s, b, tau_max_s)
    zz = float(z @ z)
    total = sum(2.0 * float(z @ lfilter([1.0], [1.0, -np.exp(-dt_s / tc)], z)) - zz for tc in tcs)
    return float(sigma**2 * total)


def flicker(
    n: int, dt_s: float, b: float, rng: np.random.Generator, tau_max_s: float | None = None
) -> np.ndarray:
    """Flicker (1/f) bias noise whose Allan deviation floor is ``0.664 b``.

    A bank of Gauss-Markov processes with correlation times log-spaced two per decade from
    ``max(1 s, 2 dt)`` to ten times ``tau_max_s`` (default: the record length). Slow processes
    are drawn on a coarser grid and linearly interpolated chunk by chunk into the output, which
    keeps 24 h at 100 Hz fast and its memory at one full-length array (the output) plus chunks.
    """
    tcs, sigma = flicker_bank(n, dt_s, b, tau_max_s)
    out = np.zeros(n)
    for tc in tcs:
        step = max(1, int(tc / dt_s / _MAX_STEPS_PER_TC))
        if step == 1:
            out += gauss_markov(n, dt_s, tc, sigma, rng)
        else:
            coarse_n = n // step + 2
            coarse = gauss_markov(coarse_n, dt_s * step, tc, sigma, rng)
            coarse_t = np.arange(coarse_n) * dt_s * step
            for start in range(0, n, _CHUNK):
                stop = min(start + _CHUNK, n)
                out[start:stop] += np.interp(np.arange(start, stop) * dt_s, coarse_t, coarse)
    return out


def quantise(x: np.ndarray, step: float, *, in_place: bool = False) -> np.ndarray:
    """Round to a multiple of ``step`` (counter or ADC resolution); ``step <= 0`` leaves x.
    ``in_place`` rounds ``x`` itself (no full-length temporary) and returns it."""
    if step <= 0:
        return x
    if not in_place:
        return np.round(x / step) * step
    x /= step
    np.round(x, out=x)
    x *= step
    return x
