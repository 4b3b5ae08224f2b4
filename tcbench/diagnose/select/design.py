"""Design matrices: the minimal model and each effect of the library as a regressor.

The minimal model (docs/concepts/diagnosis-report.md) is ``b(T) + input * k(T)``, with ``b`` and ``k``
quadratic in ``u = (T - centre_c) / half_range_c``; the ``input * k(T)`` columns are dropped
when the input never varies. ``T`` is the smoothed thermometer reading, or what the term that
transforms it gives once that term is part of the model
(:func:`~tcbench.diagnose.terms.temperature_transform`: the die temperature ``lag(T, tau_s)`` of
``thermal_lag``). Every other effect adds the
column(s) of its term (:mod:`tcbench.diagnose.terms`, docs/concepts/physics.md, the effect library); its nonlinear parameter
(a time constant, a width) is searched on the term's grid:

=====================  ===============================  =====================
effect                 column(s)                        searched
=====================  ===============================  =====================
``thermal_lag``        the whole model at ``lag(T)``    ``tau_s``
``temperature_rate``   dT/dt                            --
``hysteresis``         play state of ``T``              ``width_c``
``warmup``             ``exp(-t / tau_s)``              ``tau_s``
``aging_drift``        ``t`` (h)                        --
``temperature_cubic``  ``u^3``                          --
``accel_nonlinearity`` ``input^2``                      --
=====================  ===============================  =====================

``bias_instability`` is noise, not a regressor; it is judged from the residual's Allan
deviation (:mod:`tcbench.diagnose.select.attribute`). An open-world term
(:class:`~tcbench.diagnose.terms.OpenTerm`) adds its columns at a tuple of nonlinear
parameters found by :mod:`tcbench.diagnose.select.discover`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np

from tcbench.diagnose.signals import DiagnosisData
from tcbench.diagnose.terms import is_open, open_term, temperature_transform, term, terms

DELTA_C = 0.01  # step of the numerical temperature slope (degC)


def deterministic() -> tuple[str, ...]:
    """The forward selection's candidates, in order: the deterministic library terms registered
    now (read at each call, so a term installed later in the process is among them)."""
    return tuple(t.id for t in terms() if t.deterministic)


@dataclass(frozen=True)
class Model:
    """A model of the output: the minimal model, an optional input transform of its temperature
    (``lag_tau_s``: the value of :func:`~tcbench.diagnose.terms.temperature_transform`, the die
    lag's time constant), and added effect terms ``(effect_id, nonlinear parameter or None)``; an
    open-world term (:class:`~tcbench.diagnose.terms.OpenTerm`) has a tuple of nonlinear parameters."""

    lag_tau_s: float | None = None
    terms: tuple[tuple[str, Any], ...] = ()

    @property
    def ids(self) -> tuple[str, ...]:
        return ((temperature_transform().id,) if self.lag_tau_s else ()) + tuple(e for e, _ in self.terms)

    def with_effect(self, effect: str, value: float | None) -> Model:
        """This model with ``effect`` added (or its parameter replaced)."""
        if term(effect).transforms_temperature:
            return replace(self, lag_tau_s=value)
        return replace(self, terms=(*[t for t in self.terms if t[0] != effect], (effect, value)))

    def without(self, effect: str) -> Model:
        if term(effect).transforms_temperature:
            return replace(self, lag_tau_s=None)
        return replace(self, terms=tuple(t for t in self.terms if t[0] != effect))

    @property
    def n_params(self) -> int:
        """Extra parameters over the minimal model: each term's coefficients and searched values."""
        lag = temperature_transform().n_params(self.lag_tau_s) if self.lag_tau_s else 0
        return lag + sum(term(e).n_params(v) for e, v in self.terms)


@dataclass
class Designer:
    """Builds design matrices for one recording, caching temperature-dependent columns."""

    data: DiagnosisData
    _lag_cache: dict[float, np.ndarray] = field(default_factory=dict)
    _term_cache: dict[tuple[str, float | None, float | None], np.ndarray] = field(default_factory=dict)
    _open_cache: dict[tuple[str, Any, float | None], np.ndarray] = field(default_factory=dict)

    @cached_property
    def centre_c(self) -> float:
        return float(0.5 * (self.data.temp_c.min() + self.data.temp_c.max()))

    @cached_property
    def half_range_c(self) -> float:
        return float(max(0.5 * np.ptp(self.data.temp_c), 1.0))

    @property
    def has_input(self) -> bool:
        return self.data.input_levels >= 2

    def temperature(self, lag_tau_s: float | None) -> np.ndarray:
        """Model temperature: the smoothed thermometer, or its transform at ``lag_tau_s`` (its lag)."""
        if not lag_tau_s:
            return self.data.temp_c
        if lag_tau_s not in self._lag_cache:
            self._lag_cache[lag_tau_s] = temperature_transform().model_temperature(self.data, lag_tau_s)
        return self._lag_cache[lag_tau_s]

    def core_names(self) -> list[str]:
        names = ["b0", "b1", "b2"]
        return names + (["k0", "k1", "k2"] if self.has_input else [])

    def core(self, temp_c: np.ndarray) -> np.ndarray:
        u = (temp_c - self.centre_c) / self.half_range_c
        cols = [np.ones_like(u), u, u * u]
        if self.has_input:
            a = self.data.input
            cols += [a, a * u, a * u * u]
        return np.column_stack(cols)

    def temperature_slope(self, model: Model, beta: np.ndarray) -> np.ndarray:
        """d(output)/dT of the core fitted as ``beta`` (``model``'s coefficients) at its model
        temperature, per sample (unit per degC): a central difference of ``DELTA_C``."""
        temp = self.temperature(model.lag_tau_s)
        core = beta[: len(self.core_names())]
        up, down = self.core(temp + DELTA_C) @ core, self.core(temp - DELTA_C) @ core
        return (up - down) / (2.0 * DELTA_C)

    def column(self, effect: str, value: float | None, temp_c: np.ndarray, lag_tau_s: float | None) -> np.ndarray:
        """The regressor of ``effect`` with nonlinear parameter ``value`` (its term's column)."""
        t = term(effect)
        if not t.cached:
            return t.column(self.data, value, temp_c, self.centre_c, self.half_range_c)
        key = (effect, float(value) if value is not None else None, lag_tau_s)
        if key not in self._term_cache:
            self._term_cache[key] = t.column(self.data, value, temp_c, self.centre_c, self.half_range_c)
        return self._term_cache[key]

    def columns(self, effect: str, value: Any, lag_tau_s: float | None) -> np.ndarray:
        """The column(s) (n, m) of ``effect`` at ``value`` on the model temperature of ``lag_tau_s``."""
        temp = self.temperature(lag_tau_s)
        if not is_open(effect):
            return self.column(effect, value, temp, lag_tau_s)[:, None]
        key = (effect, value, lag_tau_s)
        if key not in self._open_cache:
            self._open_cache[key] = open_term(effect).columns(self.data, value, temp)
        return self._open_cache[key]

    def matrix(self, model: Model) -> np.ndarray:
        """Design matrix of ``model``: core columns, then each term's column(s) in order."""
        cols = [self.core(self.temperature(model.lag_tau_s))]
        cols += [self.columns(e, v, model.lag_tau_s) for e, v in model.terms]
        return np.hstack(cols)
