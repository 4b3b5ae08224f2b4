"""Terms of the temperature's dynamics: the die behind the thermometer, the ramp rate and
the play of the die attach."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tcbench.diagnose.settings import DEFAULTS
from tcbench.diagnose.signals import DiagnosisData, hysteresis_state, lagged
from tcbench.diagnose.terms.base import Term, g3
from tcbench.sensors.effects import Effect, Hysteresis, TemperatureRate, ThermalLag

# slower than this the temperature counts as still: the soak/ramp boundary the locator uses
# (``settings.locate.still_rate_c_per_min``, its default; a term sees the record, not the settings)
MIN_RATE_C_PER_S = DEFAULTS.locate.still_rate_c_per_min / 60.0


def _moves(data: DiagnosisData) -> tuple[np.ndarray, np.ndarray]:
    """Where the temperature rises and where it falls faster than :data:`MIN_RATE_C_PER_S`."""
    return data.rate_c_per_s > MIN_RATE_C_PER_S, data.rate_c_per_s < -MIN_RATE_C_PER_S


def _fastest_c_per_min(data: DiagnosisData) -> float:
    """The thermometer's fastest rate of change, either way (degC/min)."""
    return float(np.max(np.abs(data.rate_c_per_s), initial=0.0)) * 60.0


def _too_slow(data: DiagnosisData, effect: str) -> str:
    """Why ``effect`` cannot be told on a record whose temperature never moves faster than
    :data:`MIN_RATE_C_PER_S`: how fast it does move, and what the term needs."""
    return (f"the thermometer never moves faster than {_fastest_c_per_min(data):.2g} degC/min; {effect} needs "
            f"ramps of at least {MIN_RATE_C_PER_S * 60.0:g} degC/min")


def _still(data: DiagnosisData, effect: str) -> str | None:
    rising, falling = _moves(data)
    if not (rising | falling).any():
        return _too_slow(data, effect)
    return None


class ThermalLagTerm(Term):
    """The die lags the thermometer: the whole model moves to ``lag(T, tau_s)`` (no column)."""

    id = "thermal_lag"
    effect = ThermalLag
    shape = "temperature_dynamics"
    param = "tau_s"
    transforms_temperature = True
    # tau_s (s): 20 s (twenty steps of the 1 s filter clock, signals.GRID_S) to 1 h, 16 log-spaced (1.41x
    # apart; the selection's bounded search refines the best between its neighbours, not past 1 h): a slower
    # node behind the thermometer is the open-world second_node's (NODE_TAU_S, to 4 h)
    grid = np.geomspace(20.0, 3600.0, 16)
    confirm_with = (
        "heat and cool through the same temperatures at two ramp rates, each ramp followed by a soak of at least "
        "five time constants: a lagging die keeps drifting into the soak with that time constant and its error "
        "scales with the local temperature sensitivity; a second thermometer on the die or the mount shows the lag "
        "directly")
    confusable = {
        "temperature_rate": (
            "soaks of at least five die time constants after fast ramps: a lagging die keeps drifting "
            "into the soak, a thermal-gradient term stops with the ramp"),
    }

    def model_temperature(self, data: DiagnosisData, value: float) -> np.ndarray:
        return lagged(data.t_s, data.temp_c, value)

    def n_params(self, value: Any) -> int:
        return 1  # its time constant: no coefficient of its own

    def skip(self, data: DiagnosisData) -> str | None:
        return _still(data, "a thermal lag")

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"The output follows a temperature that trails the thermometer by about {g3(params['tau_s'] / 60)} min "
            "(a first-order lag). The die, where the temperature dependence lives, is not where the "
            "thermometer is: heat takes time to cross the package, so during a ramp the die is behind "
            "the reading and the output draws a loop against temperature; the error grows with the "
            "local temperature sensitivity and dies out during a soak with that time constant.")

    def params(self, coef: float, value: float | None, half_range_c: float) -> dict[str, float]:
        return {"tau_s": float(value)}  # type: ignore[arg-type]


class TemperatureRateTerm(Term):
    """A thermal-gradient term: the column is ``dT/dt``."""

    id = "temperature_rate"
    effect = TemperatureRate
    shape = "temperature_dynamics"
    units = {"coef_per_c_per_s": "{unit} per degC/s"}
    confirm_with = (
        "the same temperature swing at two ramp rates with soaks between: the term scales with the ramp rate, "
        "changes sign between heating and cooling and vanishes the moment a ramp stops")

    def unit_effect(self, value: float | None = None) -> Effect:
        return TemperatureRate(coef_per_c_per_s=1.0)

    def column(self, data: DiagnosisData, value: float | None, temp_c: np.ndarray, centre_c: float,
               half_range_c: float) -> np.ndarray:
        return self.effect_column(data, value, temp_c)

    def skip(self, data: DiagnosisData) -> str | None:
        return _still(data, "a temperature-rate term")

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        c = params["coef_per_c_per_s"]
        return (
            f"The output carries a term proportional to how fast the temperature changes, "
            f"{g3(c)} {unit} per degC/s ({g3(c / 60)} {unit} per degC/min). "
            "A temperature gradient across the structure while it heats or cools bends it or stresses it "
            "unevenly; the term vanishes as soon as the ramp stops and does not scale with the static "
            "temperature sensitivity, which is how it differs from a lagging die.")

    def params(self, coef: float, value: float | None, half_range_c: float) -> dict[str, float]:
        return {"coef_per_c_per_s": coef}


class HysteresisTerm(Term):
    """Play of the die attach: the column is the play-operator state of the model temperature
    in [-1, 1] (:func:`~tcbench.diagnose.signals.hysteresis_state`, on a <= 1 Hz grid as the
    simulator runs it)."""

    id = "hysteresis"
    effect = Hysteresis
    shape = "temperature_dynamics"
    param = "width_c"
    # width_c (degC): 0.2 to 8 degC, 12 log-spaced (1.40x apart; refined between neighbours by the selection's
    # bounded search, and past 8 degC up to half the temperature span, :meth:`past_grid`)
    grid = np.geomspace(0.2, 8.0, 12)
    cached = True
    units = {"amplitude": "{unit}"}
    confirm_with = (
        "soaks at one temperature approached from above and from below, each long enough to settle: the "
        "difference between the two persists through the soak, where a lag or a rate term dies out")
    confusable = {
        "thermal_lag": (
            "soaks at one temperature approached from above and from below, each long enough to settle: "
            "a lag dies out during the soak, hysteresis persists"),
        "temperature_rate": (
            "soaks at one temperature approached from above and from below: a gradient term is zero "
            "during a soak, hysteresis is not"),
    }

    def column(self, data: DiagnosisData, value: float | None, temp_c: np.ndarray, centre_c: float,
               half_range_c: float) -> np.ndarray:
        return hysteresis_state(data.t_s, temp_c, float(value))  # type: ignore[arg-type]

    def past_grid(self, data: DiagnosisData) -> float | None:
        return float(0.5 * np.ptp(data.temp_c))  # a play up to half the temperature span

    def skip(self, data: DiagnosisData) -> str | None:
        rising, falling = _moves(data)
        if not (rising | falling).any():  # heating and cooling too slowly to count, not one way
            return _too_slow(data, "hysteresis") + ", heating and cooling through the same temperatures"
        if not (rising.any() and falling.any()):
            return (f"the temperature only {'rises' if rising.any() else 'falls'} faster than "
                    f"{MIN_RATE_C_PER_S * 60.0:g} degC/min; hysteresis needs the same temperatures reached "
                    "heating and cooling")
        return None

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"At the same temperature the output differs by about {g3(2 * abs(params['amplitude']))} {unit} "
            f"depending on whether the part last heated or cooled (play width {g3(params['width_c'])} degC), "
            "and the difference persists through soaks. Stress in the die attach, the package or the "
            "solder relaxes differently in each direction (friction-like memory), so the bias remembers "
            "the thermal history.")

    def params(self, coef: float, value: float | None, half_range_c: float) -> dict[str, float]:
        return {"amplitude": coef, "width_c": float(value)}  # type: ignore[arg-type]
