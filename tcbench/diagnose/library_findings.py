"""Effects of the library (PHYSICS.md §3) as findings of the report contract
(:mod:`tcbench.diagnose.findings`).

Each library effect has the shape its signature takes in a residual (PHYSICS.md §8):

==================== ======================== =====================================
effect               shape                    where
==================== ======================== =====================================
thermal_lag          temperature_dynamics     the recording's temperature band
temperature_rate     temperature_dynamics     the recording's temperature band
hysteresis           temperature_dynamics     the recording's temperature band
temperature_cubic    temperature_function     the recording's temperature band
warmup               transient                ``time_s`` 0 (power-on)
aging_drift          trend                    - (the whole record)
accel_nonlinearity   input_function           - (the input levels)
bias_instability     noise                    - (the Allan tau is in the evidence)
==================== ======================== =====================================

The explanation is :func:`~tcbench.diagnose.explain.explain`'s; ``confirm_with`` names the
measurement or test profile that would confirm the effect and, when the recording cannot tell
it from another effect, the test of :data:`~tcbench.diagnose.attribute.CONFUSABLE` that would
separate the two.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.diagnose.attribute import CONFUSABLE
from tcbench.diagnose.explain import explain
from tcbench.diagnose.findings import Finding
from tcbench.diagnose.signals import DiagnosisData

SHAPE = {
    "thermal_lag": "temperature_dynamics",
    "temperature_rate": "temperature_dynamics",
    "hysteresis": "temperature_dynamics",
    "temperature_cubic": "temperature_function",
    "warmup": "transient",
    "aging_drift": "trend",
    "accel_nonlinearity": "input_function",
    "bias_instability": "noise",
}
TEMPERATURE_TERMS = ("thermal_lag", "temperature_rate", "hysteresis", "temperature_cubic")
CONFIRM_WITH = {
    "thermal_lag": (
        "heat and cool through the same temperatures at two ramp rates, each ramp followed by a soak of at least "
        "five time constants: a lagging die keeps drifting into the soak with that time constant and its error "
        "scales with the local temperature sensitivity; a second thermometer on the die or the mount shows the lag "
        "directly"),
    "temperature_rate": (
        "the same temperature swing at two ramp rates with soaks between: the term scales with the ramp rate, "
        "changes sign between heating and cooling and vanishes the moment a ramp stops"),
    "hysteresis": (
        "soaks at one temperature approached from above and from below, each long enough to settle: the "
        "difference between the two persists through the soak, where a lag or a rate term dies out"),
    "temperature_cubic": (
        "a finer grid of soaks over the same temperature range: the residual against temperature stays S-shaped "
        "and repeats at every visit of a temperature, in either direction and at any time"),
    "warmup": (
        "a second power-on, ideally at constant temperature: a warm-up repeats after every power-on with the same "
        "time constant, and a longer run shows it settled"),
    "aging_drift": (
        "a long soak at constant temperature, or a profile that revisits the same temperatures hours apart: "
        "ageing follows time and keeps its sign, a temperature term follows temperature"),
    "accel_nonlinearity": (
        "more input levels on both sides of zero (a multi-position tumble or a rate table): a square term puts "
        "the responses at +a and -a on the same side of the straight line through them, by an amount growing as a^2"),
    "bias_instability": (
        "a longer record at constant temperature after every deterministic term is modelled: flicker keeps the "
        "Allan deviation flat over decades of tau and does not repeat between runs, where a warm-up repeats "
        "after every power-on and ageing keeps its sign"),
}


@dataclass(frozen=True)
class Extent:
    """What a library finding needs from the recording: its time span (s), its temperature
    band (degC, smoothed thermometer) and the output unit."""

    t_start_s: float
    t_end_s: float
    temp_low_c: float
    temp_high_c: float
    unit: str

    @classmethod
    def of(cls, data: DiagnosisData) -> Extent:
        """The extent of prepared ``data``."""
        return cls(float(data.t_s[0]), float(data.t_s[-1]), float(np.min(data.temp_c)), float(np.max(data.temp_c)),
                   data.unit)


def where_of(effect: str, extent: Extent) -> dict[str, Any]:
    """Where ``effect`` shows in a recording of ``extent`` (see the module table)."""
    if effect in TEMPERATURE_TERMS:
        return {"temperature_c": [round(extent.temp_low_c, 3), round(extent.temp_high_c, 3)]}
    if effect == "warmup":
        return {"time_s": 0.0}  # the warm-up regressor decays from t = 0, the power-on
    return {}


def confirm_with(effect: str, confusable_with: Sequence[str] = ()) -> str:
    """The measurement that would confirm ``effect``; for each effect it ``confusable_with``,
    the test that would separate the two."""
    text = CONFIRM_WITH[effect]
    for other in confusable_with:
        test = CONFUSABLE.get(frozenset({effect, other}))
        if test:
            text += f"; to tell it from {other}: {test}"
    return text


def library_finding(
    effect: str,
    params: Mapping[str, float],
    evidence: Mapping[str, Any],
    extent: Extent,
    confusable_with: Sequence[str] = (),
) -> Finding:
    """The report finding of a kept library ``effect`` with its fitted ``params`` and the
    ``evidence`` that kept it, on a recording of ``extent``; ``confusable_with`` (the effects
    this recording cannot tell it from) rides along as an extra key when not empty."""
    if effect not in SHAPE:
        raise ValueError(f"{effect!r} is not an effect of the library; known: {', '.join(SHAPE)}")
    return Finding(
        id=effect, shape=SHAPE[effect], library=True, params=dict(params), where=where_of(effect, extent),
        evidence=dict(evidence), explanation=explain(effect, params, extent.unit),
        confirm_with=confirm_with(effect, confusable_with),
        extra={"confusable_with": list(confusable_with)} if confusable_with else {},
    )
