"""The lag-aware polynomial: the simplest compensator that models the die's lag behind the
thermometer.

The bias (and, where the input varies, the scale factor) is a polynomial of degree ``degree`` in
the thermometer reading passed through a first-order lag of time constant ``tau_s``::

    output = sum_j b_j u^j + input * sum_j k_j u^j,   u = (lag(T, tau_s) - centre_c) / half_range_c

Everything but ``tau_s`` and the degree is linear least squares; they are chosen from
:data:`TAUS_S` and :data:`DEGREES` by leave-one-recording-out error on the training recordings
(with one recording, by its training error, the degree then fixed at 2). A compensated output is the input solved from the model
(``inverse`` form, in the input unit) or the output minus the modelled bias (``bias`` form).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tcbench.sensors.recording import Recording
from tcbench.sensors.thermal import first_order_lag

TAUS_S = np.concatenate(([0.0], np.geomspace(30.0, 3000.0, 21)))  # 0: no lag
DEGREES = (1, 2, 3)


def lagged(t_s: np.ndarray, temp_c: np.ndarray, tau_s: float) -> np.ndarray:
    """``temp_c`` through a first-order lag of ``tau_s`` (settled at the first reading), on the
    record's median sample interval."""
    if tau_s <= 0.0:
        return np.asarray(temp_c, dtype=np.float64)
    dt = float(np.median(np.diff(t_s))) if t_s.size > 1 else 1.0
    return first_order_lag(temp_c, dt, tau_s)


@dataclass(frozen=True)
class LagPoly:
    """A fitted lag-aware polynomial (see the module docstring)."""

    tau_s: float
    centre_c: float
    half_range_c: float
    bias: np.ndarray
    scale: np.ndarray | None  # None: a bias-only model (the input never varied)

    def _powers(self, rec: Recording) -> np.ndarray:
        u = (lagged(rec.time_s, rec.temperature_c, self.tau_s) - self.centre_c) / self.half_range_c
        return np.vander(u, self.bias.size, increasing=True)

    def bias_of(self, rec: Recording) -> np.ndarray:
        return self._powers(rec) @ self.bias

    def inverse(self, rec: Recording, output: np.ndarray) -> np.ndarray:
        """The input solved from ``output`` (``inverse`` form)."""
        if self.scale is None:
            raise ValueError("a bias-only lag polynomial cannot solve for the input")
        powers = self._powers(rec)
        return (np.asarray(output, dtype=np.float64) - powers @ self.bias) / (powers @ self.scale)


def _design(rec: Recording, tau_s: float, centre_c: float, half_c: float, degree: int, with_input: bool) -> np.ndarray:
    u = (lagged(rec.time_s, rec.temperature_c, tau_s) - centre_c) / half_c
    powers = np.vander(u, degree + 1, increasing=True)
    return np.hstack([powers, rec.input[:, None] * powers]) if with_input else powers


def _solve(recs: Sequence[Recording], tau_s: float, centre_c: float, half_c: float, degree: int,
           with_input: bool) -> np.ndarray:
    x = np.vstack([_design(r, tau_s, centre_c, half_c, degree, with_input) for r in recs])
    y = np.concatenate([r.output for r in recs])
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    return coef


def fit_lag_poly(recs: Sequence[Recording], degrees: Sequence[int] = DEGREES,
                 taus_s: Sequence[float] = tuple(TAUS_S)) -> LagPoly:
    """The lag-aware polynomial of ``recs`` (their ``output`` against thermometer and ``input``)."""
    if not recs:
        raise ValueError("no training recording")
    temps = np.concatenate([r.temperature_c for r in recs])
    centre_c = float(0.5 * (temps.min() + temps.max()))
    half_c = float(max(0.5 * np.ptp(temps), 1.0))
    with_input = bool(np.ptp(np.concatenate([r.input for r in recs])) > 0)

    def held_out_sse(choice: tuple[float, int]) -> float:
        tau, degree = choice
        if len(recs) == 1:
            coef = _solve(recs, tau, centre_c, half_c, degree, with_input)
            return float(np.sum((recs[0].output - _design(recs[0], tau, centre_c, half_c, degree, with_input) @ coef) ** 2))
        sse = 0.0
        for k, held in enumerate(recs):
            coef = _solve([r for i, r in enumerate(recs) if i != k], tau, centre_c, half_c, degree, with_input)
            sse += float(np.sum((held.output - _design(held, tau, centre_c, half_c, degree, with_input) @ coef) ** 2))
        return sse

    tau, degree = min(((t, d) for t in taus_s for d in (degrees if len(recs) > 1 else (2,))), key=held_out_sse)
    coef = _solve(recs, tau, centre_c, half_c, degree, with_input)
    n = degree + 1
    return LagPoly(float(tau), centre_c, half_c, coef[:n], coef[n:] if with_input else None)
