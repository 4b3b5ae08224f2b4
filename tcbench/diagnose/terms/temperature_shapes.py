"""Open-world terms of the temperature: a bump at one temperature and a second thermal node."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tcbench.diagnose.settings import DEFAULTS, DetectorSettings
from tcbench.diagnose.signals import DiagnosisData, lagged
from tcbench.diagnose.terms.base import g3, term
from tcbench.diagnose.terms.detectors import bump_centres, why_no_bumps
from tcbench.diagnose.terms.events import refine_tau
from tcbench.diagnose.terms.open_base import OpenTerm, Screen, Search, Value
from tcbench.sensors.effects import Effect, SecondNode, TemperatureBump

# time constants (s) of a second node proposed: 10 min (faster is the thermal lag's grid, up to 1 h) to 4 h,
# 9 log-spaced (1.49x apart: refine_tau moves each within events.TAU_FACTOR either way)
NODE_TAU_S = np.geomspace(600.0, 4.0 * 3600.0, 9)
NODE_SPANS = 4.0  # a second node's time constant is searched below the span over this
BUMP_EXTENT_WIDTHS = 2.0  # a bump's report ``where``: its centre +- this many widths (95 % of a Gaussian's area)


class TemperatureBumpTerm(OpenTerm):
    """A bump in temperature: the column is ``exp(-((T - centre_c) / width_c)^2 / 2)``. Proposed
    at the Gaussians that best match the residual against the model temperature."""

    id = "temperature_bump"
    effect = TemperatureBump
    shape = "temperature_function"
    value_names = ("centre_c", "width_c")
    confirm_with = "a finer temperature grid of soaks through the band, approached heating and cooling"

    def unit_effects(self, value: Value) -> tuple[Effect, ...]:
        return (TemperatureBump(centre_c=value[0], width_c=value[1], amplitude=1.0),)

    def params(self, coef: Any, value: Any, half_range_c: float = 1.0) -> dict[str, float]:
        return {"centre_c": value[0], "width_c": value[1], "amplitude": float(coef[0])}

    def located(self, params: Mapping[str, float]) -> dict[str, Any]:
        return {"temperature_c": [params["centre_c"] - BUMP_EXTENT_WIDTHS * params["width_c"],
                                  params["centre_c"] + BUMP_EXTENT_WIDTHS * params["width_c"]]}

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"A bump of {g3(params['amplitude'])} {unit} in the bias around {g3(params['centre_c'])} degC, "
            f"{g3(params['width_c'])} degC wide, that no low-order polynomial of temperature follows, heating or "
            "cooling alike. A coupling of the resonant mode to another mode that crosses it at that temperature "
            "(an activity dip), or a material transition of the die attach, does this.")

    def propose(self, search: Search) -> list[Value]:
        return [(c, w) for c, w in bump_centres(search.temp_c, search.residual, search.detectors)]

    def skip(self, data: DiagnosisData, fold: np.ndarray | None = None,
             detectors: DetectorSettings = DEFAULTS.detectors) -> str | None:
        return why_no_bumps(data.temp_c, detectors)


class SecondNodeTerm(OpenTerm):
    """A second thermal node: the column is ``lag(T, tau_s) - T``. Proposed at each time
    constant of :data:`NODE_TAU_S` below the span over :data:`NODE_SPANS`; the lag runs on the
    diagnosis's time grid, gaps included (the effect lags at the mean sample interval)."""

    id = "second_node"
    effect = SecondNode
    shape = "temperature_dynamics"
    value_names = ("tau_s",)
    confirm_with = (
        "heat and cool through the same temperatures at two ramp rates, with soaks long enough to settle; a "
        "second thermometer on the mount")

    def columns(self, data: DiagnosisData, value: Value, temp_c: np.ndarray) -> np.ndarray:
        return (lagged(data.t_s, temp_c, value[0]) - temp_c)[:, None]

    def params(self, coef: Any, value: Any, half_range_c: float = 1.0) -> dict[str, float]:
        return {"tau_s": value[0], "coef_per_c": float(coef[0])}

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"The output depends on a second temperature that trails the model temperature with a time constant "
            f"of {g3(params['tau_s'] / 60)} min ({g3(params['coef_per_c'])} {unit} per degC of lag). A mount, board "
            "or housing with its own heat capacity sets up a gradient across the package while the temperature "
            "moves, which the thermometer does not see.")

    def propose(self, search: Search) -> list[Value]:
        if term("thermal_lag").skip(search.data) is not None:  # a second node needs what thermal lag needs
            return []
        return [(float(tau),) for tau in NODE_TAU_S if tau < search.span_s / NODE_SPANS]

    def refine(self, screen: Screen, value: Value) -> Value:
        return refine_tau(screen, self.id, value)

    def skip(self, data: DiagnosisData, fold: np.ndarray | None = None,
             detectors: DetectorSettings = DEFAULTS.detectors) -> str | None:
        """Why no second thermal node can be proposed: thermal lag not identifiable, or a record
        shorter than :data:`NODE_SPANS` times the shortest time constant."""
        why = term("thermal_lag").skip(data)
        if why is not None:
            return f"a second thermal node needs what thermal lag needs: {why}"
        span, need = float(data.t_s[-1] - data.t_s[0]), NODE_SPANS * float(NODE_TAU_S[0])
        if span > need:
            return None
        return (f"a second thermal node of time constant {NODE_TAU_S[0]:.0f} s needs a record of more than "
                f"{need:.0f} s; this record spans {span:.0f} s")
