"""The effect as the simulator runs it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

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
