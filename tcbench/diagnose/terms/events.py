"""Open-world terms of an event at one instant, found at the change points of the residual: a
bias step and a transient that decays after it."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tcbench.diagnose.settings import DEFAULTS, DetectorSettings
from tcbench.diagnose.signals import DiagnosisData
from tcbench.diagnose.terms.base import g3
from tcbench.diagnose.terms.detectors import why_no_steps
from tcbench.diagnose.terms.open_base import OpenTerm, Screen, Search, Value, search_log, step_range
from tcbench.sensors.effects import BiasStep, Effect, Transient

# time constants (s) proposed at each change point: 5 min to 4 h (which needs AFTER_TAUS x 4 h of record after
# its step), 8 log-spaced (1.74x apart: refine_tau moves each within TAU_FACTOR either way, so they cover the range)
TRANSIENT_TAU_S = np.geomspace(300.0, 4.0 * 3600.0, 8)
TAU_FACTOR = 1.6  # a time constant is refined within this factor of its grid value
AFTER_TAUS = 2.0  # a transient is proposed where the record holds this many time constants after its step


def why_no_step(t_s: np.ndarray, fold: np.ndarray | None, detectors: DetectorSettings = DEFAULTS.detectors
                ) -> str | None:
    """Why no step can be tested on a record sampled at ``t_s`` with cross-validation ``fold``:
    too few bins for the change points, or no time with two folds on each side."""
    why = why_no_steps(t_s, detectors)
    if why is None and fold is not None:
        lo, hi = step_range(t_s, fold)
        if not hi > lo:
            return "a step needs samples of two cross-validation folds on each side; this record has no such time"
    return why


class BiasStepTerm(OpenTerm):
    """A bias jump that stays: the column is ``1[t >= time_s]``. Proposed at the residual's change points."""

    id = "bias_step"
    effect = BiasStep
    shape = "step"
    value_names = ("time_s",)
    confirm_with = "a log of the events during the run (handling, power, firmware); a repeat run through the same profile"

    def unit_effects(self, value: Value) -> tuple[Effect, ...]:
        return (BiasStep(time_s=value[0], size=1.0),)

    def params(self, coef: Any, value: Any, half_range_c: float = 1.0) -> dict[str, float]:
        return {"time_s": value[0], "size": float(coef[0])}

    def located(self, params: Mapping[str, float]) -> dict[str, Any]:
        return {"time_s": params["time_s"]}

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"The bias jumps by {g3(params['size'])} {unit} at t = {g3(params['time_s'])} s "
            f"({g3(params['time_s'] / 3600)} h) and stays there, before and after flat at any temperature. A mode "
            "hop, a mechanical shock, a power cycle or restart of the part, or a firmware range switch does this.")

    def propose(self, search: Search) -> list[Value]:
        return [(t,) for t in search.steps]

    def skip(self, data: DiagnosisData, fold: np.ndarray | None = None,
             detectors: DetectorSettings = DEFAULTS.detectors) -> str | None:
        return why_no_step(data.t_s, fold, detectors)


class TransientTerm(OpenTerm):
    """A jump that decays back: the column is ``1[t >= t0] exp(-(t - t0) / tau_s)``. Proposed
    at the residual's change points, at each time constant of :data:`TRANSIENT_TAU_S`."""

    id = "transient"
    effect = Transient
    shape = "transient"
    value_names = ("time_s", "tau_s")
    confirm_with = "a log of handling and power events; a second power-on or a tap test during a soak"

    def unit_effects(self, value: Value) -> tuple[Effect, ...]:
        return (Transient(time_s=value[0], tau_s=value[1], amplitude=1.0),)

    def params(self, coef: Any, value: Any, half_range_c: float = 1.0) -> dict[str, float]:
        return {"time_s": value[0], "tau_s": value[1], "amplitude": float(coef[0])}

    def located(self, params: Mapping[str, float]) -> dict[str, Any]:
        return {"time_s": params["time_s"]}

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"At t = {g3(params['time_s'])} s ({g3(params['time_s'] / 3600)} h) the bias jumps by "
            f"{g3(params['amplitude'])} {unit} and decays back with a time constant of {g3(params['tau_s'] / 60)} min. "
            "Stress that settles after a handling event or a shock, or self-heating after a power-on, does this.")

    def propose(self, search: Search) -> list[Value]:
        end = search.data.t_s[-1]
        return [(t, tau) for t in search.steps for tau in TRANSIENT_TAU_S if tau < (end - t) / AFTER_TAUS]

    def refine(self, screen: Screen, value: Value) -> Value:
        return refine_tau(screen, self.id, value)

    def skip(self, data: DiagnosisData, fold: np.ndarray | None = None,
             detectors: DetectorSettings = DEFAULTS.detectors) -> str | None:
        """Why no transient can be proposed: no step can, or its shortest time constant needs
        :data:`AFTER_TAUS` times its length of record after a testable step."""
        why = why_no_step(data.t_s, fold, detectors)
        if why is not None or fold is None:
            return why
        t_s = data.t_s
        lo, hi = step_range(t_s, fold)
        after = float(t_s[-1]) - lo
        need = AFTER_TAUS * float(TRANSIENT_TAU_S[0])
        if after > need and hi > lo:
            return None
        return (f"a transient of time constant {TRANSIENT_TAU_S[0]:.0f} s needs {need:.0f} s of record after a "
                f"testable step; this record has {max(after, 0.0):.0f} s after the earliest one")


def refine_tau(screen: Screen, term_id: str, value: Value) -> Value:
    """``value`` with its last entry, a time constant, moved within :data:`TAU_FACTOR` of it to
    the largest in-sample drop."""
    k = len(value) - 1
    return search_log(screen, term_id, value, np.log(value[k] / TAU_FACTOR), np.log(value[k] * TAU_FACTOR),
                      lambda z: (*value[:k], float(np.exp(z))))
