"""Terms that follow the time since power-on, not temperature: warm-up and ageing."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tcbench.diagnose.signals import DiagnosisData
from tcbench.diagnose.terms.base import Extent, Term, g3
from tcbench.sensors.effects import AgingDrift, Effect, Warmup


class WarmupTerm(Term):
    """Settling after power-on: the column is ``exp(-t / tau_s)``."""

    id = "warmup"
    effect = Warmup
    shape = "transient"
    param = "tau_s"
    # tau_s (s): 2 min to 2 h, 14 log-spaced (1.37x apart; the selection's bounded search refines the best
    # between its neighbours): a faster settling is over in the first minutes of a record, and a warm-up
    # settles within the hour after power-on, so a slower decay is ageing's trend
    grid = np.geomspace(120.0, 7200.0, 14)
    flicker_mimics = True
    units = {"amplitude": "{unit}"}
    confirm_with = (
        "a second power-on, ideally at constant temperature: a warm-up repeats after every power-on with the same "
        "time constant, and a longer run shows it settled")
    confusable = {
        "aging_drift": "a longer run or a power cycle: warm-up settles within the hour after power-on, ageing keeps going",
    }

    def unit_effect(self, value: float | None = None) -> Effect:
        return Warmup(amplitude=1.0, tau_s=float(value))  # type: ignore[arg-type]

    def column(self, data: DiagnosisData, value: float | None, temp_c: np.ndarray, centre_c: float,
               half_range_c: float) -> np.ndarray:
        return self.effect_column(data, value, temp_c)

    def where(self, extent: Extent) -> dict[str, Any]:
        return {"time_s": 0.0}  # the column decays from t = 0, the power-on

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"After power-on the output settles by {g3(params['amplitude'])} {unit} with a time constant of "
            f"{g3(params['tau_s'] / 60)} min, independent of the chamber temperature. Self-heating of the "
            "electronics and settling of the drive loop and of mechanical stress after switch-on do this; "
            "it follows time since power-on, not temperature.")

    def params(self, coef: float, value: float | None, half_range_c: float) -> dict[str, float]:
        return {"amplitude": coef, "tau_s": float(value)}  # type: ignore[arg-type]


class AgingDriftTerm(Term):
    """Drift with time: the column is ``t`` in hours (the effect's linear part)."""

    id = "aging_drift"
    effect = AgingDrift
    shape = "trend"
    flicker_mimics = True
    units = {"rate_per_h": "{unit}/h"}
    confirm_with = (
        "a long soak at constant temperature, or a profile that revisits the same temperatures hours apart: "
        "ageing follows time and keeps its sign, a temperature term follows temperature")
    confusable = {
        "temperature_cubic": (
            "a profile that revisits the same temperatures hours apart: ageing follows time, a cubic follows "
            "temperature"),
    }

    def unit_effect(self, value: float | None = None) -> Effect:
        return AgingDrift(rate_per_h=1.0)

    def column(self, data: DiagnosisData, value: float | None, temp_c: np.ndarray, centre_c: float,
               half_range_c: float) -> np.ndarray:
        return self.effect_column(data, value, temp_c)

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"The output drifts steadily with time, {g3(params['rate_per_h'])} {unit} per hour, at any temperature. "
            "Slow stress relaxation in the package, charging of dielectrics or outgassing change the "
            "resonator or the bias over hours and days; it follows time, not temperature.")

    def params(self, coef: float, value: float | None, half_range_c: float) -> dict[str, float]:
        return {"rate_per_h": coef}
