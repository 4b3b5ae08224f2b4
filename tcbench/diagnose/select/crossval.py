"""Least squares scored on held-out time blocks.

The recording is cut into blocks of ``block_s`` of time; block ``b`` belongs to fold
``b mod k``, so every fold samples the whole run (early warm-up, every soak) while the samples
it predicts are never neighbours of the samples it was fitted on, except at its ``2 / block``
edges. Each fold is predicted by the model fitted on the other ``k - 1``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tcbench.diagnose.settings import DEFAULTS

RIDGE = 1e-10  # relative to the Gram's mean diagonal, for numerically rank-deficient designs


@dataclass(frozen=True)
class Fit:
    """Coefficients fitted on all samples, with the fit and held-out sums of squared residuals
    and the held-out residual per sample (each sample predicted by the fold that left it out)."""

    beta: np.ndarray
    sse_fit: float
    sse_heldout: float
    residual: np.ndarray
    heldout_residual: np.ndarray


def block_folds(t_s: np.ndarray, block_s: float, k: int) -> np.ndarray:
    """Fold index per sample: ``floor((t - t0) / block_s) mod k``."""
    if k < 2:
        raise ValueError(f"need at least 2 folds, got {k}")
    return (np.floor((t_s - t_s[0]) / block_s).astype(np.int64) % k).astype(np.int64)


def _solve(gram: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    ridge = RIDGE * max(float(np.trace(gram)) / gram.shape[0], 1e-300)
    return np.linalg.solve(gram + ridge * np.eye(gram.shape[0]), rhs)


def fit_cv(x: np.ndarray, y: np.ndarray, fold: np.ndarray, k: int) -> Fit:
    """Least squares of ``y`` on the columns of ``x`` (n, p), fitted on all samples and by
    blocked cross-validation over the ``k`` folds of ``fold``."""
    scale = np.sqrt(np.mean(x * x, axis=0))
    scale[scale == 0] = 1.0
    xs = x / scale
    gram, rhs = xs.T @ xs, xs.T @ y
    beta = _solve(gram, rhs)
    resid_fit = y - xs @ beta
    heldout = np.empty_like(y)
    for f in range(k):
        mask = fold == f
        if not mask.any():
            continue
        xf, yf = xs[mask], y[mask]
        b = _solve(gram - xf.T @ xf, rhs - xf.T @ yf)
        heldout[mask] = yf - xf @ b
    return Fit(beta / scale, float(resid_fit @ resid_fit), float(heldout @ heldout), resid_fit, heldout)


def robust_wald(base: Fit, model: Fit, cluster: np.ndarray, lags: int = DEFAULTS.selection.wald_lags) -> float:
    """Wald statistic of what ``model`` adds to the nested ``base``, with a variance robust to
    slow noise: ``z = r_base - r_model`` is the added fitted signal, ``s_c = z_c' e_c`` its
    score per cluster ``c`` (contiguous time spans, ``e`` the model's held-out residual), and

        W = (z' r_base)^2 / (sum_c s_c^2 + 2 sum_{l=1..L} (1 - l / (L + 1)) sum_c s_c s_{c+l})

    (Bartlett-weighted covariances of neighbouring clusters, L = ``lags``, by default
    ``settings.selection.wald_lags``). Under white noise it is about chi-square(1); noise that is
    correlated over minutes to hours (flicker, a smoothed thermometer) inflates the denominator
    as much as the numerator, where a white-noise test would call it significant."""
    z = base.residual - model.residual
    num = float(z @ base.residual) ** 2
    score = np.bincount(cluster, weights=z * model.heldout_residual)
    den = float(score @ score)
    for lag in range(1, min(lags, score.size - 1) + 1):
        den += 2.0 * (1.0 - lag / (lags + 1.0)) * float(score[:-lag] @ score[lag:])
    return num / den if den > 0 else float("inf")
