"""A physics-agnostic reference: how much temperature structure a recording holds.

Ridge regression of the output on a generic library of temperature terms built from the
smoothed thermometer ``T`` (degC): powers of ``u = (T - centre) / half range`` up to the
third, ``T`` through first-order lags at several time constants (and their squares), dT/dt and
time. It names no physics; it is fitted under the *same* blocked folds as the diagnosis, and
its held-out RMSE says how far a model driven by the thermometer can go on this recording. A
final model far above it leaves deterministic structure in its residual.

The ridge penalty is chosen among :data:`ALPHAS` (relative to the mean diagonal of the Gram of
the standardised columns) by the held-out error itself, so the reference is slightly optimistic.
How many lags, the longest, and the ratio above which structure remains are
:class:`~tcbench.diagnose.settings.ReferenceSettings`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tcbench.diagnose.settings import DEFAULTS, ReferenceSettings
from tcbench.diagnose.signals import DiagnosisData, lagged

# ridge penalties tried (relative to the mean diagonal of the standardised Gram): from 1e-8, a plain least
# squares kept solvable, to 0.1, which shrinks every column; 15 log-spaced, two per decade
ALPHAS = np.geomspace(1e-8, 1e-1, 15)
DEGREE = 3  # powers of u up to this: the library's polynomial (temperature_cubic) and no further
MIN_HALF_RANGE_C = 1.0  # u's half range (degC) at least this: a record spanning less is not scaled up
# the shortest lag (s): half the smoothing window (a faster lag is what the smoothing already blurs), and at
# least this many sample intervals
MIN_LAG_WINDOWS = 0.5
MIN_LAG_SAMPLES = 2.0
MIN_LAG_RATIO = 2.0  # the longest lag at least this many times the shortest, on a short record


@dataclass(frozen=True)
class Reference:
    """The reference fit: held-out and fit RMSE (output unit), the terms and the ridge
    penalty chosen; ``heldout_residual`` per sample; ``structure_ratio`` the final / reference
    held-out RMSE above which structure remains."""

    rmse_heldout: float
    rmse_fit: float
    terms: list[str]
    alpha: float
    heldout_residual: np.ndarray
    structure_ratio: float = DEFAULTS.reference.structure_ratio

    def to_json(self) -> dict[str, object]:
        return {"rmse_heldout": self.rmse_heldout, "rmse_fit": self.rmse_fit, "terms": self.terms,
                "ridge_alpha": self.alpha}

    def structure_remains(self, final_rmse: float) -> bool:
        """Whether a model of held-out RMSE ``final_rmse`` leaves deterministic temperature
        structure: above :attr:`structure_ratio` times this reference's."""
        return final_rmse > self.structure_ratio * self.rmse_heldout


def lag_grid_s(data: DiagnosisData, settings: ReferenceSettings = DEFAULTS.reference) -> np.ndarray:
    """Time constants (s) of the reference's lags: from the smoothing window to ``max_lag_share``
    of the recording, ``n_lags`` log-spaced."""
    span = float(data.t_s[-1] - data.t_s[0])
    lo = max(data.smooth_s * MIN_LAG_WINDOWS, MIN_LAG_SAMPLES / data.sample_rate_hz)
    hi = max(settings.max_lag_share * span, MIN_LAG_RATIO * lo)
    return np.geomspace(lo, hi, settings.n_lags)


def reference_terms(data: DiagnosisData, settings: ReferenceSettings = DEFAULTS.reference
                    ) -> tuple[np.ndarray, list[str]]:
    """Columns (n, p) of the reference library (without the intercept) and their names."""
    temp = data.temp_c
    centre = 0.5 * (temp.min() + temp.max())
    half = max(0.5 * float(np.ptp(temp)), MIN_HALF_RANGE_C)
    cols, names = [], []
    u = (temp - centre) / half
    for p in range(1, DEGREE + 1):
        cols.append(u**p)
        names.append(f"u^{p}")
    for tau in lag_grid_s(data, settings):
        ul = (lagged(data.t_s, temp, float(tau)) - centre) / half
        cols += [ul, ul * ul]
        names += [f"lag(u, {tau:.0f} s)", f"lag(u, {tau:.0f} s)^2"]
    cols.append(data.rate_c_per_s)
    names.append("dT/dt")
    span = max(float(data.t_s[-1] - data.t_s[0]), 1e-12)
    cols.append((data.t_s - data.t_s[0]) / span)
    names.append("t")
    if data.input_levels >= 2:  # the scale factor, as the minimal model has it
        a = data.input
        cols += [a, a * u, a * u * u]
        names += ["input", "input u", "input u^2"]
    return np.column_stack(cols), names


@dataclass(frozen=True)
class _Gram:
    """What every penalty's fit shares: the design with its intercept column, its Gram and
    right-hand side, and each non-empty fold's samples with their own Gram, right-hand side and
    share of the samples (computed once, not once per penalty)."""

    x1: np.ndarray
    gram: np.ndarray
    rhs: np.ndarray
    folds: tuple[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float], ...]

    @classmethod
    def of(cls, xs: np.ndarray, y: np.ndarray, fold: np.ndarray, k: int) -> _Gram:
        x1 = np.column_stack([np.ones(xs.shape[0]), xs])
        folds = []
        for f in range(k):
            m = fold == f
            if m.any():
                xf = x1[m]
                folds.append((m, xf, xf.T @ xf, xf.T @ y[m], float(m.mean())))
        return cls(x1, x1.T @ x1, x1.T @ y, tuple(folds))


def _ridge_heldout(g: _Gram, y: np.ndarray, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """Held-out residual and in-sample residual of ridge (intercept unpenalised, columns
    already standardised) at relative penalty ``alpha``."""
    n, q = g.x1.shape
    pen = np.full(q, alpha * n)
    pen[0] = 0.0
    beta = np.linalg.solve(g.gram + np.diag(pen), g.rhs)
    heldout = np.empty_like(y)
    for m, xf, gram_f, rhs_f, share in g.folds:
        b = np.linalg.solve(g.gram - gram_f + np.diag(pen * (1.0 - share)), g.rhs - rhs_f)
        heldout[m] = y[m] - xf @ b
    return heldout, y - g.x1 @ beta


def reference_fit(data: DiagnosisData, fold: np.ndarray, k: int,
                  settings: ReferenceSettings = DEFAULTS.reference) -> Reference:
    """The reference fitted to ``data.output`` under the folds ``fold`` (``k`` of them)."""
    x, names = reference_terms(data, settings)
    mu, sd = x.mean(axis=0), x.std(axis=0)
    sd[sd == 0] = 1.0
    xs = (x - mu) / sd
    y = data.output
    gram = _Gram.of(xs, y, fold, k)
    best: tuple[float, float, np.ndarray, np.ndarray] | None = None
    for alpha in ALPHAS:
        heldout, resid = _ridge_heldout(gram, y, float(alpha))
        sse = float(heldout @ heldout)
        if best is None or sse < best[0]:
            best = (sse, float(alpha), heldout, resid)
    assert best is not None
    sse, alpha, heldout, resid = best
    n = y.size
    return Reference(float(np.sqrt(sse / n)), float(np.sqrt(resid @ resid / n)), names, alpha, heldout,
                     settings.structure_ratio)
