"""The library's noise judged by the diagnosis: flicker bias noise (bias instability)."""

from __future__ import annotations

from collections.abc import Mapping

from tcbench.diagnose.terms.base import Term, g3
from tcbench.sensors.effects import BiasInstability


class BiasInstabilityTerm(Term):
    """Flicker bias noise: not a column of the design, judged from the residual's Allan
    deviation (:mod:`tcbench.diagnose.select.locate`); ``b`` in output units."""

    id = "bias_instability"
    effect = BiasInstability
    shape = "noise"
    deterministic = False
    units = {"b": "{unit} (flicker coefficient)"}
    gain_name = "Allan ratio"
    gain_label = "Allan deviation / white line at the first τ over the bound (not a σ² gain)"
    confirm_with = (
        "a longer record at constant temperature after every deterministic term is modelled: flicker keeps the "
        "Allan deviation flat over decades of tau and does not repeat between runs, where a warm-up repeats "
        "after every power-on and ageing keeps its sign")

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"After every deterministic term, the residual's Allan deviation stops falling as 1/sqrt(tau) "
            f"and flattens: flicker (1/f) bias noise with a floor of about {g3(0.664 * params['b'])} {unit}. "
            "Defects and charge trapping in the electronics and the structure make the bias wander "
            "slowly and randomly; it is noise, so it sets a limit on compensation rather than a term to "
            "subtract.")

    def params(self, coef: float, value: float | None, half_range_c: float) -> dict[str, float]:
        return {"b": coef}
