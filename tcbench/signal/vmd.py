"""Variational mode decomposition (VMD, Dragomiretskiy & Zosso 2014; seed paper §3.1, eq. 1-7).

The signal ``f`` (``n`` samples, any unit) is split into ``k`` modes ``u_k`` (same unit), each
compact around a centre frequency ``omega_k``, with ``sum_k u_k ~= f``. The constrained problem
(eq. 2) is solved by ADMM on the augmented Lagrangian (eq. 3) in the Fourier domain:

1. ``f`` is mirror-extended by half its length on each side (``n // 2`` samples on the left,
   ``n - n // 2`` on the right, so ``T = 2 n``) to soften the edges, and transformed with a real
   FFT. Only the one-sided spectrum is kept (the analytic signal of eq. 1): bins
   ``j = 0 .. T/2 - 1`` at ``omega_j = j / T`` cycles/sample; the Nyquist bin is left out.
2. Each iteration updates the modes in turn (Gauss-Seidel), each by the Wiener filter of the
   residual (eq. 4)::

       u_k(omega) = (f(omega) - sum_{i != k} u_i(omega) + lambda(omega) / 2)
                    / (1 + alpha (omega - omega_k)^2)

   then its centre frequency by the power-weighted mean frequency (eq. 5)::

       omega_k = sum_omega omega |u_k(omega)|^2 / sum_omega |u_k(omega)|^2

   then the dual variable by ascent (eq. 6) ``lambda += tau (f - sum_k u_k)`` (``tau = 0``: no
   update, the noise-slack variant).
3. It stops after the first iteration with (eq. 7)
   ``sum_k ||u_k^{n+1} - u_k^n||^2 / ||u_k^n||^2 < tol``, or after ``max_iter`` iterations.
4. Each mode's one-sided spectrum is made Hermitian, inverted, and the mirror parts are cut off.

Conventions follow the reference code (Zosso's MATLAB, ported as ``vmdpy.VMD``), so ``alpha`` and
the modes are interchangeable with it: frequencies are in cycles/sample and the Wiener
denominator is ``1 + alpha (omega - omega_k)^2`` (the paper's ``2 alpha`` with its ``alpha``
halved); the Hermitian completion copies the conjugate of the highest kept bin into the Nyquist
bin, as that code does. Differences from ``vmdpy``: the stopping rule is eq. 7 (relative) where
``vmdpy`` uses the absolute ``eps + sum_k ||u_k^{n+1} - u_k^n||^2 / T``; ``vmdpy`` returns the
second-to-last iterate (an off-by-one of the port) where this returns the last; an odd-length
signal keeps all its samples (``vmdpy`` drops the last); modes are sorted by centre frequency.

Cost: O(k T) per iteration plus one FFT of length ``T`` in and ``k`` out; memory holds the
current ``k`` one-sided mode spectra (``k n`` complex128) and a few length-``n`` buffers, with no
iteration history (the previous mode is kept only while it is being replaced).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

INITS = ("uniform", "random", "zero")


@dataclass(frozen=True, eq=False)
class VMDResult:
    """A variational mode decomposition.

    modes: ``(k, n)`` float64, in the unit of the signal, sorted by centre frequency ascending;
        their sum approximates the signal.
    centre_freqs: ``(k,)`` final centre frequencies in cycles/sample (0 .. 0.5), ascending;
        multiply by the sampling rate for Hz.
    iterations: ADMM iterations run.
    converged: True when the stopping rule (eq. 7) was met before ``max_iter``.

    Arrays are read-only.
    """

    modes: np.ndarray
    centre_freqs: np.ndarray
    iterations: int
    converged: bool


def _initial_freqs(
    k: int, init: str, n: int, rng: np.random.Generator | int | None
) -> np.ndarray:
    """Starting centre frequencies (cycles/sample): uniform ``0.5 i / k``, log-uniform random
    in ``[1 / n, 0.5)`` sorted, or all zero."""
    if init == "uniform":
        return 0.5 * np.arange(k) / k
    if init == "random":
        gen = np.random.default_rng(rng)
        lo = np.log(1.0 / n)
        return np.sort(np.exp(lo + (np.log(0.5) - lo) * gen.random(k)))
    return np.zeros(k)


def _check(signal: np.ndarray, k: int, alpha: float, tau: float, init: str, tol: float,
           max_iter: int) -> np.ndarray:
    """The signal as a 1-D float64 array, or ValueError naming the first bad argument."""
    x = np.asarray(signal)
    if x.ndim != 1:
        raise ValueError(f"signal must be 1-D, got shape {x.shape}")
    if not (np.issubdtype(x.dtype, np.number) and not np.issubdtype(x.dtype, np.complexfloating)):
        raise ValueError(f"signal must be real numbers, got dtype {x.dtype}")
    x = x.astype(np.float64, copy=False)
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ValueError(f"k must be an integer >= 1, got {k!r}")
    if x.size < max(4, 2 * k):
        raise ValueError(f"signal needs at least max(4, 2 k) = {max(4, 2 * k)} samples, got {x.size}")
    if not np.isfinite(x).all():
        i = int(np.flatnonzero(~np.isfinite(x))[0])
        raise ValueError(f"signal must be finite: signal[{i}] = {x[i]}")
    if not (np.isfinite(alpha) and alpha > 0.0):
        raise ValueError(f"alpha must be a finite number > 0, got {alpha!r}")
    if not (np.isfinite(tau) and tau >= 0.0):
        raise ValueError(f"tau must be a finite number >= 0, got {tau!r}")
    if init not in INITS:
        raise ValueError(f"init must be one of {', '.join(map(repr, INITS))}, got {init!r}")
    if not (np.isfinite(tol) and tol >= 0.0):
        raise ValueError(f"tol must be a finite number >= 0, got {tol!r}")
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise ValueError(f"max_iter must be an integer >= 1, got {max_iter!r}")
    return x


def vmd(
    signal: np.ndarray,
    k: int,
    alpha: float,
    *,
    tau: float = 0.0,
    dc: bool = False,
    init: Literal["uniform", "random", "zero"] = "uniform",
    tol: float = 1e-7,
    max_iter: int = 500,
    rng: np.random.Generator | int | None = None,
) -> VMDResult:
    """Variational mode decomposition of ``signal`` (1-D, any unit) into ``k`` modes.

    alpha: bandwidth penalty (> 0); larger gives narrower modes. Same scale as ``vmdpy``'s
        ``alpha`` (frequencies in cycles/sample, denominator ``1 + alpha (omega - omega_k)^2``).
    tau: dual-ascent step (>= 0); 0 drops the exact-reconstruction constraint (noise slack).
    dc: hold the first mode's centre frequency at 0 (a trend mode).
    init: starting centre frequencies: "uniform" (``0.5 i / k``, vmdpy ``init=1``), "random"
        (log-uniform in ``[1/n, 0.5)``, sorted, drawn from ``rng``; vmdpy ``init=2``) or "zero"
        (vmdpy ``init=0``).
    tol: stop when ``sum_k ||u_k^{n+1} - u_k^n||^2 / ||u_k^n||^2 < tol`` (eq. 7); 0 never stops
        early.
    max_iter: iteration limit (>= 1).
    rng: a ``numpy.random.Generator`` (or a seed for ``numpy.random.default_rng``) for
        ``init="random"``; ignored otherwise.

    Returns a :class:`VMDResult` with the modes sorted by final centre frequency.

    Raises ValueError for a non-1-D, non-real, non-finite or too short signal (fewer than
    ``max(4, 2 k)`` samples), ``k < 1``, ``alpha <= 0``, ``tau < 0``, ``tol < 0``,
    ``max_iter < 1`` or an unknown ``init``.
    """
    x = _check(signal, k, float(alpha), float(tau), init, float(tol), max_iter)
    alpha, tau, tol, k = float(alpha), float(tau), float(tol), int(k)
    n = x.size
    left = n // 2
    mirrored = np.concatenate((x[left - 1 :: -1], x, x[: left - 1 : -1]))
    t_len = mirrored.size  # 2 n
    m = t_len // 2  # one-sided bins 0 .. T/2 - 1 (the Nyquist bin is dropped)
    f_hat = np.fft.rfft(mirrored)[:m]
    del mirrored
    freqs = np.arange(m) / t_len  # cycles/sample
    # Per real/imaginary part, for |u|^2-weighted sums by einsum (not BLAS: a threaded ddot on
    # vectors this short stalls when the cores are busy).
    freqs2 = np.repeat(freqs, 2)

    omega = _initial_freqs(k, init, n, rng)
    if dc:
        omega[0] = 0.0
    u = [np.zeros(m, dtype=np.complex128) for _ in range(k)]  # current one-sided spectra
    energy = np.zeros(k)  # ||u_k||^2 of the current spectra
    total = np.zeros(m, dtype=np.complex128)  # sum_k u_k, kept up to date mode by mode
    lam = np.zeros(m, dtype=np.complex128) if tau > 0.0 else None
    target = f_hat if lam is None else np.empty(m, dtype=np.complex128)  # f + lambda/2
    new = np.empty(m, dtype=np.complex128)  # scratch: the next spectrum of the current mode
    new_re = new.view(np.float64).reshape(m, 2)
    den = np.empty((m, 1))
    sq = np.empty(2 * m)

    iterations, converged = 0, False
    while iterations < max_iter:
        if lam is not None:
            np.multiply(lam, 0.5, out=target)
            target += f_hat
        change = 0.0
        for i in range(k):
            old = u[i]
            # Wiener filter of the residual (eq. 4): (f - sum_{j != i} u_j + lambda/2) / den.
            np.subtract(target, total, out=new)
            new += old
            np.subtract(freqs[:, None], omega[i], out=den)
            np.square(den, out=den)
            den *= alpha
            den += 1.0
            new_re /= den
            # The step u_new - u_old (eq. 7), in the old buffer, updates the running sum; then
            # the buffers swap roles, so no iterate is ever copied.
            np.subtract(new, old, out=old)
            step = old.view(np.float64)
            step_energy = float(np.einsum("i,i->", step, step))
            if energy[i] > 0.0:
                change += step_energy / energy[i]
            elif step_energy > 0.0:
                change = np.inf  # a mode leaving zero has no relative change
            total += old
            u[i], new = new, old
            new_re = new.view(np.float64).reshape(m, 2)
            # Power-weighted mean frequency (eq. 5).
            np.square(u[i].view(np.float64), out=sq)
            energy[i] = float(sq.sum())
            if energy[i] > 0.0 and not (dc and i == 0):
                omega[i] = float(np.einsum("i,i->", freqs2, sq)) / energy[i]
        if lam is not None:  # dual ascent (eq. 6)
            np.subtract(f_hat, total, out=new)
            new *= tau
            lam += new
        iterations += 1
        if change < tol:
            converged = True
            break

    # Hermitian completion (Nyquist bin = conj of the highest kept bin, as the reference code),
    # inverse FFT of every mode at once, and the mirror parts cut off.
    full = np.empty((k, m + 1), dtype=np.complex128)
    for i in range(k):
        full[i, :m] = u[i]
    del u, total, lam, target, new, new_re
    full[:, m] = np.conj(full[:, m - 1])
    modes = np.fft.irfft(full, n=t_len, axis=1)[:, left : left + n]
    order = np.argsort(omega, kind="stable")
    modes = np.ascontiguousarray(modes[order])
    omega = omega[order]
    modes.setflags(write=False)
    omega.setflags(write=False)
    return VMDResult(modes=modes, centre_freqs=omega, iterations=iterations, converged=converged)
