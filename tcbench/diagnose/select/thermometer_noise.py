"""The thermometer's own noise, carried into the output through the model's temperature slope.

A model driven by a noisy thermometer inherits its noise: after smoothing, what is left of it
is slow (correlated over the smoothing window) and, multiplied by the output's temperature
slope, can exceed the output's white noise at long averaging times. The diagnosis must not take
that for flicker. :func:`propagated_noise` draws one realisation of it (fixed seed, so a
diagnosis is repeatable) to widen the white-noise line of the Allan test.
"""

from __future__ import annotations

import numpy as np

from tcbench.diagnose.select.design import Designer, Model
from tcbench.diagnose.signals import lagged, smoothed_value


def thermometer_sigma(designer: Designer) -> float:
    """Per-sample noise of the thermometer reading (degC): spread about its smoothed value."""
    d = designer.data
    return float(np.std(d.temp_raw_c - d.temp_c))


def propagated_noise(designer: Designer, model: Model, beta: np.ndarray, seed: int = 0) -> np.ndarray:
    """One realisation of the thermometer noise as the fitted model sees it (output unit)."""
    d = designer.data
    rng = np.random.default_rng(seed)
    eps = smoothed_value(d.t_s, rng.standard_normal(d.n) * thermometer_sigma(designer), d.smooth_s)
    if model.lag_tau_s:
        eps = lagged(d.t_s, eps, model.lag_tau_s)
    return designer.temperature_slope(model, beta) * eps


def thermometer_variance(designer: Designer, model: Model, beta: np.ndarray, z: np.ndarray) -> float:
    """Variance of ``z' e`` for ``e`` the thermometer noise the fitted model inherits
    (``e = slope * lag(smooth(eps))``, eps white with the thermometer's sigma): the part of a
    regressor ``z``'s score that is not output noise. Exact for a linear smoother and lag:
    ``sigma_T^2 |smooth'(lag'(slope * z))|^2``, the transposes applied by reversing time."""
    d = designer.data
    sigma_t = thermometer_sigma(designer)
    if sigma_t == 0:
        return 0.0
    w = designer.temperature_slope(model, beta) * z
    if model.lag_tau_s:
        w = lagged(d.t_s, w[::-1], model.lag_tau_s)[::-1]
    w = smoothed_value(d.t_s, w, d.smooth_s)
    return float(sigma_t**2 * (w @ w))
