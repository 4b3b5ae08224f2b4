"""Terms of the static response beyond the minimal model: a cubic in temperature and a square
in the input."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from tcbench.diagnose.signals import DiagnosisData
from tcbench.diagnose.terms.base import Term, g3
from tcbench.sensors.effects import AccelNonlinearity, Effect, TemperatureCubic


class TemperatureCubicTerm(Term):
    """A cubic in temperature: the column is ``u^3``, ``u = (T - centre) / half range`` (the
    effect's cube on the scaled temperature)."""

    id = "temperature_cubic"
    effect = TemperatureCubic
    shape = "temperature_function"
    units = {"c3_per_c3": "{unit}/degC^3"}
    confirm_with = (
        "a finer grid of soaks over the same temperature range: the residual against temperature stays S-shaped "
        "and repeats at every visit of a temperature, in either direction and at any time")

    def unit_effect(self, value: float | None = None) -> Effect:
        return TemperatureCubic(c3_per_c3=1.0)

    def column(self, data: DiagnosisData, value: float | None, temp_c: np.ndarray, centre_c: float,
               half_range_c: float) -> np.ndarray:
        return self.effect_column(data, value, (temp_c - centre_c) / half_range_c)

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"The bias bends with temperature more than a quadratic allows (cubic coefficient "
            f"{g3(params['c3_per_c3'])} {unit}/degC^3): the residual against temperature is S-shaped. The "
            "temperature coefficients of the material and of the thermal stress are themselves "
            "temperature dependent, so a wide range needs a third-order term.")

    def params(self, coef: float, value: float | None, half_range_c: float) -> dict[str, float]:
        return {"c3_per_c3": coef / half_range_c**3}  # the column is u^3


class AccelNonlinearityTerm(Term):
    """A square in the input: the column is ``input^2``."""

    id = "accel_nonlinearity"
    effect = AccelNonlinearity
    shape = "input_function"
    units = {"k2_per_g2": "{unit}/g^2"}
    confirm_with = (
        "more input levels on both sides of zero (a multi-position tumble or a rate table): a square term puts "
        "the responses at +a and -a on the same side of the straight line through them, by an amount growing as a^2")

    def unit_effect(self, value: float | None = None) -> Effect:
        return AccelNonlinearity(k2_per_g2=1.0)

    def column(self, data: DiagnosisData, value: float | None, temp_c: np.ndarray, centre_c: float,
               half_range_c: float) -> np.ndarray:
        return self.effect_column(data, value, temp_c)

    def skip(self, data: DiagnosisData) -> str | None:
        if data.input_levels < 3:
            return (f"the input takes {data.input_levels} value(s); a square term needs at least three "
                    "(e.g. +1 g, 0 g, -1 g)")
        return None

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"The response to acceleration is not a straight line: a term {g3(params['k2_per_g2'])} {unit}/g^2 "
            "makes the +1 g and -1 g positions sit unevenly around 0 g. The resonators' frequency "
            "depends nonlinearly on axial force (k2 of about -K^2 / (2 f0)), and the two resonators do "
            "not cancel it exactly.")

    def params(self, coef: float, value: float | None, half_range_c: float) -> dict[str, float]:
        return {"k2_per_g2": coef}
