"""Design matrices: the minimal model and each effect of the library as a regressor.

The minimal model (DESIGN.md "Diagnosis") is ``b(T) + input * k(T)``, with ``b`` and ``k``
quadratic in ``u = (T - centre_c) / half_range_c``; the ``input * k(T)`` columns are dropped
when the input never varies. ``T`` is the smoothed thermometer reading, or the die temperature
``lag(T, tau_s)`` once ``thermal_lag`` is part of the model. Every other effect adds columns
(PHYSICS.md §3); its nonlinear parameter (a time constant, a width) is searched on a grid:

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
deviation (:mod:`tcbench.diagnose.attribute`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np

from tcbench.diagnose.open_terms import kind_of, term_columns
from tcbench.diagnose.signals import DiagnosisData, hysteresis_state, lagged

DETERMINISTIC = (
    "thermal_lag", "temperature_rate", "hysteresis", "warmup", "aging_drift", "temperature_cubic",
    "accel_nonlinearity",
)
ALL_EFFECTS = (*DETERMINISTIC, "bias_instability")
GRIDS: dict[str, np.ndarray] = {  # the nonlinear parameter's search grid
    "thermal_lag": np.geomspace(20.0, 3600.0, 16),
    "hysteresis": np.geomspace(0.2, 8.0, 12),
    "warmup": np.geomspace(120.0, 7200.0, 14),
}
PARAM_NAME = {"thermal_lag": "tau_s", "hysteresis": "width_c", "warmup": "tau_s"}


@dataclass(frozen=True)
class Model:
    """A model of the output: the minimal model, an optional die lag, and added effect terms
    ``(effect_id, nonlinear parameter or None)``; an open-world term
    (:mod:`tcbench.diagnose.open_terms`) has a tuple of nonlinear parameters."""

    lag_tau_s: float | None = None
    terms: tuple[tuple[str, Any], ...] = ()

    @property
    def ids(self) -> tuple[str, ...]:
        return (("thermal_lag",) if self.lag_tau_s else ()) + tuple(e for e, _ in self.terms)

    def with_effect(self, effect: str, value: float | None) -> Model:
        """This model with ``effect`` added (or its parameter replaced)."""
        if effect == "thermal_lag":
            return replace(self, lag_tau_s=value)
        return replace(self, terms=(*[t for t in self.terms if t[0] != effect], (effect, value)))

    def without(self, effect: str) -> Model:
        if effect == "thermal_lag":
            return replace(self, lag_tau_s=None)
        return replace(self, terms=tuple(t for t in self.terms if t[0] != effect))

    @property
    def n_params(self) -> int:
        """Extra parameters over the minimal model: each term's coefficients and searched values."""
        return (1 if self.lag_tau_s else 0) + sum(
            kind.n_params() if (kind := kind_of(e)) else 1 + (v is not None) for e, v in self.terms)


@dataclass
class Designer:
    """Builds design matrices for one recording, caching temperature-dependent columns."""

    data: DiagnosisData
    _lag_cache: dict[float, np.ndarray] = field(default_factory=dict)
    _hyst_cache: dict[tuple[float, float | None], np.ndarray] = field(default_factory=dict)
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
        """Model temperature: the smoothed thermometer, or its lag of ``lag_tau_s``."""
        if not lag_tau_s:
            return self.data.temp_c
        if lag_tau_s not in self._lag_cache:
            self._lag_cache[lag_tau_s] = lagged(self.data.t_s, self.data.temp_c, lag_tau_s)
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

    def column(self, effect: str, value: float | None, temp_c: np.ndarray, lag_tau_s: float | None) -> np.ndarray:
        """The regressor of ``effect`` with nonlinear parameter ``value``."""
        d = self.data
        if effect == "temperature_rate":
            return d.rate_c_per_s
        if effect == "hysteresis":
            key = (float(value), lag_tau_s)  # type: ignore[arg-type]
            if key not in self._hyst_cache:
                self._hyst_cache[key] = hysteresis_state(d.t_s, temp_c, float(value))  # type: ignore[arg-type]
            return self._hyst_cache[key]
        if effect == "warmup":
            return np.exp(-d.t_s / float(value))  # type: ignore[arg-type]
        if effect == "aging_drift":
            return d.t_s / 3600.0
        if effect == "temperature_cubic":
            return ((temp_c - self.centre_c) / self.half_range_c) ** 3
        if effect == "accel_nonlinearity":
            return d.input**2
        raise ValueError(f"effect {effect!r} has no regressor")

    def columns(self, effect: str, value: Any, lag_tau_s: float | None) -> np.ndarray:
        """The column(s) (n, m) of ``effect`` at ``value`` on the model temperature of ``lag_tau_s``."""
        temp = self.temperature(lag_tau_s)
        if kind_of(effect) is None:
            return self.column(effect, value, temp, lag_tau_s)[:, None]
        key = (effect, value, lag_tau_s)
        if key not in self._open_cache:
            self._open_cache[key] = term_columns(self.data, effect, value, temp)
        return self._open_cache[key]

    def matrix(self, model: Model) -> np.ndarray:
        """Design matrix of ``model``: core columns, then each term's column(s) in order."""
        cols = [self.core(self.temperature(model.lag_tau_s))]
        cols += [self.columns(e, v, model.lag_tau_s) for e, v in model.terms]
        return np.hstack(cols)

    def why_not_identifiable(self, effect: str) -> str | None:
        """Why this recording cannot show ``effect`` at all, or None."""
        d = self.data
        rising = d.rate_c_per_s > 0.05 / 60.0
        falling = d.rate_c_per_s < -0.05 / 60.0
        if effect == "accel_nonlinearity" and d.input_levels < 3:
            return (f"the input takes {d.input_levels} value(s); a square term needs at least three "
                    "(e.g. +1 g, 0 g, -1 g)")
        if effect == "hysteresis" and not (rising.any() and falling.any()):
            return "the temperature only moves one way; hysteresis needs the same temperatures reached heating and cooling"
        if effect in ("temperature_rate", "thermal_lag") and not (rising | falling).any():
            return "the temperature never changes faster than 0.05 degC/min"
        return None


def grid_values(effect: str) -> list[float | None]:
    """Values of the nonlinear parameter searched for ``effect`` (``[None]`` if it has none)."""
    return list(GRIDS[effect]) if effect in GRIDS else [None]

