"""One paragraph in plain words per effect found: what the data showed and what physics does that."""

from __future__ import annotations

from collections.abc import Mapping


def _g(x: float) -> str:
    return f"{x:.3g}"


def explain(effect: str, params: Mapping[str, float], unit: str) -> str:
    """The physical explanation of ``effect`` with its fitted ``params`` (output ``unit``)."""
    p = params
    if effect == "thermal_lag":
        return (
            f"The output follows a temperature that trails the thermometer by about {_g(p['tau_s'] / 60)} min "
            "(a first-order lag). The die, where the temperature dependence lives, is not where the "
            "thermometer is: heat takes time to cross the package, so during a ramp the die is behind "
            "the reading and the output draws a loop against temperature; the error grows with the "
            "local temperature sensitivity and dies out during a soak with that time constant.")
    if effect == "temperature_rate":
        return (
            f"The output carries a term proportional to how fast the temperature changes, "
            f"{_g(p['coef_per_c_per_s'])} {unit} per degC/s ({_g(p['coef_per_c_per_s'] / 60)} {unit} per degC/min). "
            "A temperature gradient across the structure while it heats or cools bends it or stresses it "
            "unevenly; the term vanishes as soon as the ramp stops and does not scale with the static "
            "temperature sensitivity, which is how it differs from a lagging die.")
    if effect == "hysteresis":
        return (
            f"At the same temperature the output differs by about {_g(2 * abs(p['amplitude']))} {unit} "
            f"depending on whether the part last heated or cooled (play width {_g(p['width_c'])} degC), "
            "and the difference persists through soaks. Stress in the die attach, the package or the "
            "solder relaxes differently in each direction (friction-like memory), so the bias remembers "
            "the thermal history.")
    if effect == "warmup":
        return (
            f"After power-on the output settles by {_g(p['amplitude'])} {unit} with a time constant of "
            f"{_g(p['tau_s'] / 60)} min, independent of the chamber temperature. Self-heating of the "
            "electronics and settling of the drive loop and of mechanical stress after switch-on do this; "
            "it follows time since power-on, not temperature.")
    if effect == "aging_drift":
        return (
            f"The output drifts steadily with time, {_g(p['rate_per_h'])} {unit} per hour, at any temperature. "
            "Slow stress relaxation in the package, charging of dielectrics or outgassing change the "
            "resonator or the bias over hours and days; it follows time, not temperature.")
    if effect == "temperature_cubic":
        return (
            f"The bias bends with temperature more than a quadratic allows (cubic coefficient "
            f"{_g(p['c3_per_c3'])} {unit}/degC^3): the residual against temperature is S-shaped. The "
            "temperature coefficients of the material and of the thermal stress are themselves "
            "temperature dependent, so a wide range needs a third-order term.")
    if effect == "accel_nonlinearity":
        return (
            f"The response to acceleration is not a straight line: a term {_g(p['k2_per_g2'])} {unit}/g^2 "
            "makes the +1 g and -1 g positions sit unevenly around 0 g. The resonators' frequency "
            "depends nonlinearly on axial force (k2 of about -K^2 / (2 f0)), and the two resonators do "
            "not cancel it exactly.")
    if effect == "bias_instability":
        return (
            f"After every deterministic term, the residual's Allan deviation stops falling as 1/sqrt(tau) "
            f"and flattens: flicker (1/f) bias noise with a floor of about {_g(0.664 * p['b'])} {unit}. "
            "Defects and charge trapping in the electronics and the structure make the bias wander "
            "slowly and randomly; it is noise, so it sets a limit on compensation rather than a term to "
            "subtract.")
    raise ValueError(f"no explanation for effect {effect!r}")
