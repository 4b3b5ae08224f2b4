"""Standard errors of least-squares coefficients when the noise is slow: from the residual's spectrum.

A coefficient ``b = x'y / x'x`` of a column ``x`` already made orthogonal to the fit's other
columns errs by ``x'n / x'x``. For stationary noise of spectrum ``S`` its variance is

    V = (2 / N^2) sum_k |X_k|^2 S_k / (x'x)^2        (X_k the DFT of x, k = 1 .. N/2)

A temperature ramp or a level step puts nearly all of ``|X_k|^2`` on the lowest few frequencies,
where flicker and drift put their power: the white-noise formula ``sigma^2 / x'x`` then counts
100 000 correlated samples as independent ones, and so, for flicker, does Newey-West (its
kernel reads the spectrum at frequency zero from the fast lags). Here ``S_k`` is the residual's
periodogram averaged in octave bands (the two lowest ordinates, the next four, ...), ``V`` is
divided by ``1 - 2 sum_k h_k^2``, ``h_k = |X_k|^2 / (N x'x)`` (the residual lacks the part of
the noise the coefficient took: exact for white noise), and the few bands that carry ``V`` give
its degrees of freedom (Satterthwaite), so intervals and p-values use Student's t.

On 200 s at 500 Hz with a 5 degC ramp and no slope, the 1 % test of a temperature slope
rejected, over 300 records each: white noise 1.7 %, AR(1) of time constant 2 s 1.3 % and 10 s
3.7 %, white plus flicker 2.0-3.3 % (prewhitened Newey-West: 0.7 %, 0.7 %, 4.3 %, 62-87 %).
A random walk is not stationary: along a one-way ramp it is a drift in time, which no test on
one record tells from a temperature slope (22 %).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import t as student_t

FIRST_BAND = 2  # ordinates in the lowest band; each band after it is twice as wide


@dataclass(frozen=True)
class SpectralError:
    """A coefficient's standard error from the residual's spectrum (``se``), its degrees of
    freedom, the white-noise formula's ``se_white`` and the effective sample count
    ``n (se_white / se)^2`` (at most n)."""

    se: float
    dof: float
    se_white: float
    n_effective: float

    def quantile(self, alpha: float) -> float:
        """The two-sided ``1 - alpha`` quantile of Student's t at :attr:`dof`."""
        return float(student_t.isf(alpha / 2.0, self.dof))

    def p_value(self, value: float) -> float:
        """Two-sided p-value of ``value`` against zero."""
        if not self.se > 0:
            return 0.0 if value != 0 else 1.0
        return float(2.0 * student_t.sf(abs(value) / self.se, self.dof))


def octave_bands(k_max: int) -> np.ndarray:
    """Band edges over the ordinates ``1 .. k_max``: ``[1, 3, 7, 15, ...]`` ending at ``k_max + 1``."""
    edges = [1]
    width = FIRST_BAND
    while edges[-1] <= k_max:
        edges.append(min(k_max + 1, edges[-1] + width))
        width *= 2
    return np.asarray(edges)


def spectral_error(x: np.ndarray, residual: np.ndarray) -> SpectralError:
    """The standard error of the coefficient of ``x`` (orthogonal to the fit's other columns,
    the intercept included) from the fit's ``residual`` (module doc)."""
    n = x.size
    sxx = float(x @ x)
    x2 = np.abs(np.fft.rfft(x)[1:]) ** 2
    power = np.abs(np.fft.rfft(residual)[1:]) ** 2
    edges = octave_bands(x2.size)
    width = np.diff(edges)
    spectrum = np.add.reduceat(power, edges[:-1] - 1) / width
    share = np.add.reduceat(x2, edges[:-1] - 1) * spectrum
    h = x2 / (n * sxx)
    var = 2.0 / n**2 * float(share.sum()) / sxx**2 / max(1.0 - 2.0 * float(h @ h), 1e-12)
    dof = 2.0 * float(share.sum()) ** 2 / float(np.sum(share**2 / width)) if share.sum() > 0 else float(n)
    se = float(np.sqrt(var))
    u = x * residual
    se_white = float(np.sqrt(u @ u)) / sxx
    return SpectralError(se, dof, se_white, min(n * (se_white / se) ** 2, float(n)) if se > 0 else float(n))
