"""The oracle: temperature compensation at the physical limit of a simulated recording.

A compensation method sees the output and the thermometer; the oracle also sees the simulator's
deterministic truth (:class:`tcbench.sensors.truth.Truth`): the noise-free output at the true
die temperature and the true input. Its compensated output differs from the ideal one by the
sensor's noise (white, flicker, random walk, quantisation) alone. That noise is drawn
independently of temperature and of everything a method can observe, so no method, however it
models temperature, can remove it without knowing the noise itself: the oracle's metrics are the
floor every method's metrics are compared with.

With ``thermometer=True`` each oracle knows the same model but reads only the thermometer
(``Truth.output_det_thermometer``: the model fed the recorded, smoothed thermometer reading): the
limit of a compensator that knows the physics exactly and reads what a real one reads. The gap
between the two oracles is what the thermometer's noise and resolution cost; a method's gap to the
thermometer-limited one is what better modelling could still win.
"""

from __future__ import annotations

import numpy as np

from tcbench.sensors.truth import Truth


def _checked(output: np.ndarray, truth: Truth) -> np.ndarray:
    y = np.asarray(output, dtype=np.float64).reshape(-1)
    if y.shape != truth.output_det.shape:
        raise ValueError(f"oracle: output has {y.size} samples, the truth {truth.output_det.size}")
    return y


def _det(truth: Truth, thermometer: bool) -> np.ndarray:
    return truth.output_det_thermometer if thermometer else truth.output_det


def oracle_inverse(output: np.ndarray, truth: Truth, thermometer: bool = False) -> np.ndarray:
    """Applied input estimated from ``output`` (g for the MSRA): ``input + (output -
    output_det) / sensitivity``.

    This is the simulator's own deterministic model, with the true die temperature, inverted at
    the true input: all temperature dependence (bias, scale factor, lag, nonlinearity) is
    removed exactly, and the residual ``a_hat - input`` is the output noise divided by the
    local scale factor, which no compensation of temperature can beat.
    """
    y = _checked(output, truth)
    return truth.input + (y - _det(truth, thermometer)) / truth.sensitivity_per_input


def oracle_bias(output: np.ndarray, truth: Truth, thermometer: bool = False) -> np.ndarray:
    """Compensated output (output unit, Hz for the MSRA): ``output - output_det +
    mean(output_det)``.

    The whole deterministic output (temperature bias, warm-up, lag) is removed and its mean put
    back, so what varies is the noise alone plus a constant: the zero-bias stability no method
    can beat.
    """
    y = _checked(output, truth)
    det = _det(truth, thermometer)
    return y - det + float(np.mean(det))
