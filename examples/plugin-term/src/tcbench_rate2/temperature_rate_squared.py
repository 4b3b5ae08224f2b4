"""A thermal-gradient stress the output carries in the square of the temperature rate: the effect
the simulator runs and the term the diagnosis fits, reports and explains, in one file."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from tcbench.diagnose.signals import DiagnosisData
from tcbench.diagnose.terms import Term
from tcbench.diagnose.terms.base import g3
from tcbench.sensors.effects import Effect, Signals


@dataclass(frozen=True)
class TemperatureRateSquared(Effect):
    """Thermal-gradient stress ``coef * (dT_meas/dt in degC/min)^2`` (output unit per (degC/min)^2):
    the same sign heating and cooling, zero at rest."""

    id: ClassVar[str] = "temperature_rate_squared"
    coef_per_c2_per_min2: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        rate_c_per_min = 60.0 * s.temp_rate_c_per_s
        return self.coef_per_c2_per_min2 * rate_c_per_min * rate_c_per_min

MIN_RATE_C_PER_S = 0.05 / 60.0  # slower than this the temperature counts as still


class TemperatureRateSquaredTerm(Term):
    """Thermal-gradient stress: the column is (dT/dt)^2 in (degC/min)^2."""

    id = "temperature_rate_squared"
    effect = TemperatureRateSquared
    shape = "temperature_dynamics"
    confirm_with = (
        "the same temperature swing at two ramp rates with soaks between: the term grows with the square of the "
        "ramp rate, has the same sign heating and cooling and vanishes the moment a ramp stops")
    confusable = {
        "temperature_rate": (
            "ramps up and down at the same rate: a rate term changes sign with the ramp's direction, a "
            "squared-rate term does not"),
    }

    def unit_effect(self, value: float | None = None) -> Effect:
        return TemperatureRateSquared(coef_per_c2_per_min2=1.0)

    def column(self, data: DiagnosisData, value: float | None, temp_c: np.ndarray, centre_c: float,
               half_range_c: float) -> np.ndarray:
        return self.effect_column(data, value, temp_c)

    def skip(self, data: DiagnosisData) -> str | None:
        if not (np.abs(data.rate_c_per_s) > MIN_RATE_C_PER_S).any():
            return "the temperature never changes faster than 0.05 degC/min"
        return None

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        c = params["coef_per_c2_per_min2"]
        return (
            f"The output moves by {g3(c)} {unit} per (degC/min)^2 of the temperature rate, the same way whether the "
            "part heats or cools. A ramp sets up a temperature gradient across the package; the stress it causes "
            "grows with the gradient in either direction and bends the structure, and it relaxes as soon as the "
            "ramp stops.")

    def params(self, coef: float, value: float | None, half_range_c: float) -> dict[str, float]:
        return {"coef_per_c2_per_min2": coef}
