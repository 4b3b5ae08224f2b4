"""Denoising baselines for the TFPF comparison: wavelet thresholding and EMD + wavelet threshold.

:func:`wavelet_denoise` is Donoho–Johnstone wavelet shrinkage through PyWavelets: the signal is
decomposed with ``pywt.wavedec`` (``symmetric`` extension), every detail band is shrunk with
``pywt.threshold`` (soft or hard) at the universal threshold ``sigma sqrt(2 ln n)``, where
``sigma = median(|d_1|) / 0.6745`` is the noise level estimated from the finest detail band
``d_1`` (or at a given absolute threshold, in the unit of the signal), the approximation band is
kept, and ``pywt.waverec`` rebuilds the signal, trimmed to the input length.

:func:`emd_imfs` is ``PyEMD.EMD().emd`` with its default sifting: the intrinsic mode functions,
highest frequency first, one per row, with the residue (the trend, possibly zero) always as the
last row, so the rows sum to the input. :func:`emd_wavelet_denoise` is the seed paper's rival
method (EMD + wavelet threshold): the first ``noise_imfs`` IMFs are taken as pure noise and
dropped, the next ``mixed_imfs`` are denoised by :func:`wavelet_denoise`, and the remaining IMFs
and the residue are kept unchanged; the result is their sum. All functions return the unit of
the input.
"""

from __future__ import annotations

import numpy as np
import pywt  # type: ignore[import-untyped]
from PyEMD import EMD  # type: ignore[import-untyped]

MAD_TO_SIGMA = 0.6745  # median(|N(0, 1)|)


def _check(x: np.ndarray, min_size: int = 2) -> np.ndarray:
    """Validated float64 array of ``x`` (a copy when ``x`` is read-only, as pandas' ``.values``
    may be: PyWavelets' compiled transforms refuse a read-only buffer); raises ValueError with
    a one-line message."""
    a = np.asarray(x, dtype=np.float64)
    if not a.flags.writeable:
        a = a.copy()
    if a.ndim != 1:
        raise ValueError(f"x must be a 1-D array, got shape {a.shape}")
    if a.size < min_size:
        raise ValueError(f"x needs at least {min_size} samples, got {a.size}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"x must be finite: {int(np.count_nonzero(~np.isfinite(a)))} NaN/inf samples")
    return a


def universal_threshold(x: np.ndarray, wavelet: str = "db4") -> float:
    """``sigma sqrt(2 ln n)`` with ``sigma = median(|finest detail|) / 0.6745`` (unit of ``x``)."""
    a = _check(x)
    d1 = pywt.dwt(a, wavelet, mode="symmetric")[1]
    sigma = float(np.median(np.abs(d1))) / MAD_TO_SIGMA
    return sigma * float(np.sqrt(2.0 * np.log(a.size)))


def wavelet_denoise(
    x: np.ndarray,
    wavelet: str = "db4",
    level: int | None = None,
    mode: str = "soft",
    threshold: str | float = "universal",
) -> np.ndarray:
    """Wavelet-shrinkage denoised ``x`` (same unit and length).

    ``level``: decomposition depth (``None``: ``pywt.dwt_max_level``); ``mode``: ``"soft"`` or
    ``"hard"`` thresholding; ``threshold``: ``"universal"`` or an absolute value in the unit of
    ``x``. Raises ValueError for bad input or parameters.
    """
    a = _check(x)
    if mode not in ("soft", "hard"):
        raise ValueError(f"mode must be 'soft' or 'hard', got {mode!r}")
    try:
        w = pywt.Wavelet(wavelet)
    except ValueError as exc:
        raise ValueError(f"unknown wavelet {wavelet!r}") from exc
    max_level = pywt.dwt_max_level(a.size, w.dec_len)
    if level is None:
        level = max(1, max_level)
    elif isinstance(level, bool) or not isinstance(level, (int, np.integer)) or not 1 <= level <= max(1, max_level):
        raise ValueError(f"level must be an integer in [1, {max(1, max_level)}] for n = {a.size}, got {level!r}")
    if isinstance(threshold, str):
        if threshold != "universal":
            raise ValueError(f"threshold must be 'universal' or a number, got {threshold!r}")
        lam = universal_threshold(a, w.name)
    else:
        lam = float(threshold)
        if not (np.isfinite(lam) and lam >= 0.0):
            raise ValueError(f"threshold must be a finite number >= 0, got {threshold!r}")
    coeffs = pywt.wavedec(a, w, mode="symmetric", level=level)
    coeffs[1:] = [pywt.threshold(d, lam, mode=mode) for d in coeffs[1:]]
    return pywt.waverec(coeffs, w, mode="symmetric")[: a.size]


def emd_imfs(x: np.ndarray, max_imf: int = -1) -> np.ndarray:
    """EMD of ``x``: array ``(k + 1, n)`` of the ``k`` IMFs (highest frequency first) and the
    residue as the last row; rows sum to ``x``. ``max_imf < 0`` extracts all IMFs."""
    a = _check(x, min_size=3)
    if isinstance(max_imf, bool) or not isinstance(max_imf, (int, np.integer)) or max_imf == 0:
        raise ValueError(f"max_imf must be a non-zero integer (negative: all IMFs), got {max_imf!r}")
    emd = EMD()
    emd.emd(a, max_imf=int(max_imf))
    imfs, residue = emd.get_imfs_and_residue()
    return np.vstack((np.reshape(imfs, (-1, a.size)), residue))


def emd_wavelet_denoise(
    x: np.ndarray,
    noise_imfs: int = 1,
    mixed_imfs: int = 2,
    *,
    wavelet: str = "db4",
    level: int | None = None,
    mode: str = "soft",
    max_imf: int = -1,
) -> np.ndarray:
    """EMD + wavelet-threshold denoised ``x`` (same unit and length).

    Drops the first ``noise_imfs`` IMFs, applies :func:`wavelet_denoise` (``wavelet``, ``level``,
    ``mode``, universal threshold) to the next ``mixed_imfs``, keeps the rest and the residue.
    Both counts are clipped to the IMFs available (the residue is never dropped). Raises
    ValueError for bad input or negative counts.
    """
    for name, value in (("noise_imfs", noise_imfs), ("mixed_imfs", mixed_imfs)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
            raise ValueError(f"{name} must be an integer >= 0, got {value!r}")
    rows = emd_imfs(x, max_imf=max_imf)
    n_imf = rows.shape[0] - 1
    drop = min(noise_imfs, n_imf)
    mixed = min(mixed_imfs, n_imf - drop)
    out = rows[drop + mixed :].sum(axis=0)
    for imf in rows[drop : drop + mixed]:
        out += wavelet_denoise(imf, wavelet=wavelet, level=level, mode=mode)
    return out
