"""Time-frequency peak filtering (TFPF) of a noisy signal (seed paper §3.3, Boashash & Mesbah).

The samples ``x`` (any unit) at ``fs_hz`` are encoded as the instantaneous frequency of a
unit-amplitude analytic signal::

    f[k] = fs (c + mu' (x[k] - x_mid)),   z[k] = exp(j phi[k]),   phi = 2 pi cumtrapz(f) / fs

with ``c = 1/4`` and ``mu' = mu / fs``, so that the encoded frequency stays in
``[0.05, 0.45] fs`` (``mu = None`` takes the largest such ``mu``, the usual TFPF scaling). The
pseudo Wigner–Ville distribution with a rectangular lag window ``h`` of ``window = 2K + 1``
samples is, for every sample ``k``::

    PW(k, nu) = sum_{|tau| <= K} h(tau) z[k + tau] z*[k - tau] exp(-j 2 pi nu tau)

The lag product oscillates at ``nu = 2 f / fs``, so the peak ``nu_peak(k)`` of ``PW`` over
``nu`` gives ``f_peak = nu_peak fs / 2`` and the estimate ``x_hat = (f_peak - c fs) / mu +
x_mid`` in the unit of ``x``. ``PW`` is real (the lag product is Hermitian in ``tau``); it is
evaluated on a zero-padded FFT grid of ``nfft >= 4 (K + 1)`` points, and the grid peak is
refined by parabolic interpolation then two Newton steps on ``dPW/dnu = 0``. The trapezoidal
phase makes ``phi[k + tau] - phi[k - tau]`` exact for a linear ``x``, so a ramp is recovered to
rounding; the window length trades noise reduction (longer) against bandwidth (shorter: less
lag/attenuation of fast components).

The record is extended by ``K`` samples at each end by point reflection (``2 x[0] - x[K:0:-1]``,
as ``scipy.signal.filtfilt(padtype="odd")``), which keeps linear trends. Rows of the
``(n, nfft)`` lag-product matrix are built and transformed in chunks of about
``2**20`` complex values (16 MiB); beyond that block, memory is a few O(n) vectors.
"""

from __future__ import annotations

import numpy as np

CENTRE = 0.25  # encoded centre frequency / fs
HALF_BAND = 0.2  # encoded frequency stays in CENTRE +- HALF_BAND (times fs): [0.05, 0.45] fs
_NEWTON_STEPS = 2  # refinement of the parabolic peak estimate
_CHUNK_VALUES = 1 << 20  # complex values per chunk of the lag-product matrix (16 MiB)


def _check(x: np.ndarray, window: int, fs_hz: float, mu: float | None) -> np.ndarray:
    """Validated float64 copy of ``x``; raises ValueError with a one-line message."""
    a = np.asarray(x, dtype=np.float64)
    if a.ndim != 1:
        raise ValueError(f"x must be a 1-D array, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"x must be finite: {int(np.count_nonzero(~np.isfinite(a)))} NaN/inf samples")
    is_int = isinstance(window, (int, np.integer)) and not isinstance(window, bool)
    if not is_int or window < 3 or window > a.size or window % 2 == 0:
        raise ValueError(f"window must be an odd integer in [3, n = {a.size}] samples, got {window!r}")
    if not (np.isfinite(fs_hz) and fs_hz > 0):
        raise ValueError(f"fs_hz must be a positive finite number, got {fs_hz!r}")
    if mu is not None and not (np.isfinite(mu) and mu > 0):
        raise ValueError(f"mu must be a positive finite number of Hz per signal unit, got {mu!r}")
    return a


def _odd_extension(x: np.ndarray, half: int) -> np.ndarray:
    """``x`` with ``half`` samples point-reflected about each end (keeps a linear trend)."""
    left = 2.0 * x[0] - x[half:0:-1]
    right = 2.0 * x[-1] - x[-2 : -half - 2 : -1]
    return np.concatenate((left, x, right))


def _peak_nu(z: np.ndarray, half: int, n: int, nfft: int) -> np.ndarray:
    """Peak (cycles/sample, in [0, 1)) of the PWVD over ``nu`` for rows ``half .. half + n - 1``
    of the padded analytic signal ``z``, by chunks of rows."""
    taus = np.arange(half + 1)
    rows = max(1, _CHUNK_VALUES // nfft)
    out = np.empty(n)
    buf = np.zeros((min(rows, n), nfft), dtype=np.complex128)
    for start in range(0, n, rows):
        stop = min(start + rows, n)
        centre = np.arange(start, stop)[:, None] + half
        g = buf[: stop - start]
        # one-sided lag product (h = 1); tau = 0 halved so PW = 2 Re FFT
        np.multiply(z[centre + taus], np.conj(z[centre - taus]), out=g[:, : half + 1])
        g[:, 0] *= 0.5
        spec = np.fft.fft(g, axis=1).real
        k = np.argmax(spec, axis=1)
        r = np.arange(stop - start)
        a, b, c = spec[r, k - 1], spec[r, k], spec[r, (k + 1) % nfft]
        den = a - 2.0 * b + c
        delta = np.where(den < 0.0, 0.5 * (a - c) / np.where(den < 0.0, den, 1.0), 0.0)
        out[start:stop] = _newton(g[:, : half + 1], (k + delta) / nfft, 1.0 / nfft)
    return out % 1.0


def _newton(g: np.ndarray, nu: np.ndarray, max_step: float) -> np.ndarray:
    """Refine the peaks ``nu`` of ``PW(nu) = 2 Re sum_tau g[:, tau] exp(-j 2 pi nu tau)`` by
    Newton steps on ``PW'(nu) = 0`` (steps kept only where ``PW'' < 0`` and ``|step| <= max_step``)."""
    w = 2.0 * np.pi * np.arange(g.shape[1])
    for _ in range(_NEWTON_STEPS):
        powers = np.empty(g.shape, dtype=np.complex128)
        powers[:, 0] = 1.0
        powers[:, 1:] = np.exp(-2j * np.pi * nu)[:, None]
        e = g * np.cumprod(powers, axis=1)  # g exp(-j nu w), by powers of one rotation
        d1 = (e @ w).imag  # PW' / 2 = Re sum -j w e = Im sum w e
        d2 = -(e @ (w * w)).real  # PW'' / 2
        ok = d2 < 0.0
        step = np.where(ok, -d1 / np.where(ok, d2, -1.0), 0.0)
        nu = nu + np.clip(step, -max_step, max_step)
    return nu


def tfpf(x: np.ndarray, window: int = 31, *, fs_hz: float = 1.0, mu: float | None = None) -> np.ndarray:
    """Time-frequency peak filtered ``x`` (same unit and length).

    ``window`` is the PWVD lag-window length in samples (odd, 3 <= window <= len(x)); ``fs_hz``
    the sampling rate (Hz); ``mu`` the frequency-modulation index in Hz per unit of ``x``
    (``None``: map the padded record's range onto [0.05, 0.45] fs_hz). Raises ValueError for
    non-finite or non-1-D input, a bad window, or a ``mu`` whose encoding leaves that band.
    """
    a = _check(x, window, fs_hz, mu)
    half = (window - 1) // 2
    xp = _odd_extension(a, half)
    lo, hi = float(xp.min()), float(xp.max())
    span = hi - lo
    if span == 0.0:
        return a.copy()
    mid = 0.5 * (lo + hi)
    mu_max = 2.0 * HALF_BAND * fs_hz / span
    if mu is None:
        mu = mu_max
    elif mu > mu_max * (1.0 + 1e-12):
        raise ValueError(
            f"mu = {mu:g} Hz/unit encodes the signal range {span:g} beyond [0.05, 0.45] fs_hz; "
            f"use mu <= {mu_max:g}"
        )
    f_norm = CENTRE + (mu / fs_hz) * (xp - mid)  # encoded frequency / fs, cycles per sample
    phase = np.empty_like(f_norm)
    phase[0] = 0.0
    np.cumsum(0.5 * (f_norm[1:] + f_norm[:-1]), out=phase[1:])
    phase %= 1.0
    z = np.exp(2j * np.pi * phase)
    nfft = max(64, 1 << int(np.ceil(np.log2(4 * (half + 1)))))
    nu = _peak_nu(z, half, a.size, nfft)
    return (0.5 * nu - CENTRE) * (fs_hz / mu) + mid
