"""Model terms for structure outside the effect library (PHYSICS.md §8), as regressors.

Each term has an id (its key in ``model.yaml`` ``effects``, simulated by the effect of the same
id in :mod:`tcbench.sensors.effects`), a ``shape`` of the report contract, nonlinear parameters
``value`` (a tuple, located by a detector of :mod:`tcbench.diagnose.detectors`) and linear
coefficients fitted with the rest of the model:

====================  ======================================  ===================  =====================
id                    column(s)                               value                shape
====================  ======================================  ===================  =====================
``bias_step``         ``1[t >= time_s]``                      ``(time_s,)``        step
``periodic``          ``sin, cos(2 pi t / period_s)``         ``(period_s,)``      periodic
``gated_periodic``    a level, the same and its harmonics     ``(period_s,         periodic
                      to the 5th, inside ``[start_s, end_s)`` start_s, end_s)``
``duty_cycle``        a level and ``1[(t - on_s) mod period   ``(period_s, on_s,   periodic
                      < duty period]``, inside the span       duty, start_s,
                                                              end_s)``
``transient``         ``1[t >= t0] exp(-(t - t0) / tau_s)``   ``(t0, tau_s)``      transient
``temperature_bump``  ``exp(-((T - c) / w)^2 / 2)``           ``(c, w)``           temperature_function
``second_node``       ``lag(T, tau_s) - T``                   ``(tau_s,)``         temperature_dynamics
====================  ======================================  ===================  =====================

``T`` is the model temperature (the smoothed thermometer, or the die once ``thermal_lag`` is in
the model); ``t`` the recording's clock, taken as time since power-on as for ``warmup``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.signals import DiagnosisData, lagged
from tcbench.sensors.effects import MAX_REPEATS, effect_class

Value = tuple[float, ...]
GATED_HARMONICS = 5  # a switched load (a compressor's duty cycle) is not a sinusoid: its level and harmonics


@dataclass(frozen=True)
class TermKind:
    """One kind of open-world term: how to build its columns and report what was fitted."""

    id: str
    shape: str
    value_names: tuple[str, ...]
    n_coef: int
    columns: Callable[[DiagnosisData, Value, np.ndarray], np.ndarray]
    params: Callable[[Value, np.ndarray], dict[str, float]]
    where: Callable[[dict[str, float]], dict[str, Any]]
    explanation: Callable[[dict[str, float], str], str]
    confirm_with: str
    search_scale: float = 1.0  # its gain threshold over the open world's: a wider search finds more by chance

    def n_params(self) -> int:
        return self.n_coef + len(self.value_names)


def _g(x: float) -> str:
    return f"{x:.3g}"


def _step_columns(d: DiagnosisData, v: Value, temp_c: np.ndarray) -> np.ndarray:
    return (d.t_s >= v[0]).astype(float)[:, None]


def _periodic_columns(d: DiagnosisData, v: Value, temp_c: np.ndarray) -> np.ndarray:
    phase = 2.0 * np.pi * d.t_s / v[0]
    return np.column_stack([np.sin(phase), np.cos(phase)])


def _transient_columns(d: DiagnosisData, v: Value, temp_c: np.ndarray) -> np.ndarray:
    age = d.t_s - v[0]
    return np.where(age >= 0.0, np.exp(-np.maximum(age, 0.0) / v[1]), 0.0)[:, None]


def _bump_columns(d: DiagnosisData, v: Value, temp_c: np.ndarray) -> np.ndarray:
    return np.exp(-0.5 * ((temp_c - v[0]) / v[1]) ** 2)[:, None]


def _node_columns(d: DiagnosisData, v: Value, temp_c: np.ndarray) -> np.ndarray:
    return (lagged(d.t_s, temp_c, v[0]) - temp_c)[:, None]


def _gated_columns(d: DiagnosisData, v: Value, temp_c: np.ndarray) -> np.ndarray:
    inside = ((d.t_s >= v[1]) & (d.t_s < v[2])).astype(float)
    phase = 2.0 * np.pi * d.t_s / v[0]
    waves = [inside * f(k * phase) for k in range(1, GATED_HARMONICS + 1) for f in (np.sin, np.cos)]
    return np.column_stack([inside, *waves])


def _gated_params(v: Value, c: np.ndarray) -> dict[str, float]:
    out = {"period_s": v[0], "start_s": v[1], "end_s": v[2], "offset": float(c[0])}
    for k in range(GATED_HARMONICS):
        out[f"sin{k + 1}"], out[f"cos{k + 1}"] = float(c[1 + 2 * k]), float(c[2 + 2 * k])
    out["amplitude"] = float(np.hypot(c[1], c[2]))
    return out


def _duty_columns(d: DiagnosisData, v: Value, temp_c: np.ndarray) -> np.ndarray:
    period, on_s, duty, start, end = v
    inside = ((d.t_s >= start) & (d.t_s < end)).astype(float)
    return np.column_stack([inside, inside * (np.mod(d.t_s - on_s, period) < duty * period)])


def _periodic_params(v: Value, c: np.ndarray) -> dict[str, float]:
    # a sin(wt) + b cos(wt) = A sin(wt + phi)
    return {"period_s": v[0], "amplitude": float(np.hypot(c[0], c[1])), "phase_rad": float(np.arctan2(c[1], c[0]))}


TERMS: dict[str, TermKind] = {k.id: k for k in (
    TermKind(
        "bias_step", "step", ("time_s",), 1, _step_columns,
        lambda v, c: {"time_s": v[0], "size": float(c[0])},
        lambda p: {"time_s": p["time_s"]},
        lambda p, unit: (
            f"The bias jumps by {_g(p['size'])} {unit} at t = {_g(p['time_s'])} s ({_g(p['time_s'] / 3600)} h) and "
            "stays there, before and after flat at any temperature. A mode hop, a mechanical shock, a power cycle "
            "or restart of the part, or a firmware range switch does this."),
        "a log of the events during the run (handling, power, firmware); a repeat run through the same profile"),
    TermKind(
        "periodic", "periodic", ("period_s",), 2, _periodic_columns, _periodic_params,
        lambda p: {"period_s": p["period_s"], "frequency_hz": 1.0 / p["period_s"]},
        lambda p, unit: (
            f"A line in the residual's spectrum: a sinusoid of {_g(p['amplitude'])} {unit} with a period of "
            f"{_g(p['period_s'] / 60)} min, unrelated to the temperature profile. Environmental cycling does this: "
            "a chamber compressor or fan, the building's HVAC, supply ripple, or a mechanical resonance aliased "
            "by the sampling."),
        "the chamber's own log of compressor and heater cycles; a run with the chamber idle at constant temperature"),
    TermKind(
        "gated_periodic", "periodic", ("period_s", "start_s", "end_s"), 1 + 2 * GATED_HARMONICS, _gated_columns,
        _gated_params,
        lambda p: {"period_s": p["period_s"], "frequency_hz": 1.0 / p["period_s"], "time_s": [p["start_s"], p["end_s"]]},
        lambda p, unit: (
            f"A line in the residual's spectrum, a cycle of {_g(p['period_s'] / 60)} min ({_g(p['amplitude'])} {unit} "
            f"at the fundamental, with harmonics and a mean offset of {_g(p['offset'])} {unit}), present only from t = {_g(p['start_s'] / 3600)} h to "
            f"{_g(p['end_s'] / 3600)} h. Something that cycles only in part of the run does this: a chamber "
            "compressor that runs below room temperature, a heater's duty cycle, a fan switched with the set-point."),
        "the chamber's log of compressor and heater cycles over the run; a soak at the same temperature with the "
        "chamber's cooling switched off"),
    TermKind(
        "duty_cycle", "periodic", ("period_s", "on_s", "duty", "start_s", "end_s"), 2, _duty_columns,
        lambda v, c: {"period_s": v[0], "on_s": v[1], "duty": v[2], "start_s": v[3], "end_s": v[4],
                      "offset": float(c[0]), "size": float(c[1])},
        lambda p: {"period_s": p["period_s"], "frequency_hz": 1.0 / p["period_s"], "time_s": [p["start_s"], p["end_s"]]},
        lambda p, unit: (
            f"A load switched on and off: every {_g(p['period_s'] / 60)} min the bias jumps by {_g(p['size'])} {unit} "
            f"for {_g(100 * p['duty'])} % of the cycle, from t = {_g(p['start_s'] / 3600)} h to "
            f"{_g(p['end_s'] / 3600)} h only (a mean offset of {_g(p['offset'])} {unit} there). A chamber compressor "
            "or heater on a thermostat loading the supply or shaking the mount does this, as does a pump or fan on "
            "a timer."),
        "the chamber's log of compressor and heater cycles over the run; the supply voltage logged beside the "
        "output; a soak at the same temperature with the chamber's cooling switched off",
        # period, phase, duty and both edges searched: on 40 open-world controls (development seeds
        # 40 700 000 + i) its chance gain reached twice a line's (90th percentile 13.9 against 6.6 sigma^2)
        search_scale=2.0),
    TermKind(
        "transient", "transient", ("time_s", "tau_s"), 1, _transient_columns,
        lambda v, c: {"time_s": v[0], "tau_s": v[1], "amplitude": float(c[0])},
        lambda p: {"time_s": p["time_s"]},
        lambda p, unit: (
            f"At t = {_g(p['time_s'])} s ({_g(p['time_s'] / 3600)} h) the bias jumps by {_g(p['amplitude'])} {unit} "
            f"and decays back with a time constant of {_g(p['tau_s'] / 60)} min. Stress that settles after a "
            "handling event or a shock, or self-heating after a power-on, does this."),
        "a log of handling and power events; a second power-on or a tap test during a soak"),
    TermKind(
        "temperature_bump", "temperature_function", ("centre_c", "width_c"), 1, _bump_columns,
        lambda v, c: {"centre_c": v[0], "width_c": v[1], "amplitude": float(c[0])},
        lambda p: {"temperature_c": [p["centre_c"] - 2.0 * p["width_c"], p["centre_c"] + 2.0 * p["width_c"]]},
        lambda p, unit: (
            f"A bump of {_g(p['amplitude'])} {unit} in the bias around {_g(p['centre_c'])} degC, "
            f"{_g(p['width_c'])} degC wide, that no low-order polynomial of temperature follows, heating or "
            "cooling alike. A coupling of the resonant mode to another mode that crosses it at that temperature "
            "(an activity dip), or a material transition of the die attach, does this."),
        "a finer temperature grid of soaks through the band, approached heating and cooling"),
    TermKind(
        "second_node", "temperature_dynamics", ("tau_s",), 1, _node_columns,
        lambda v, c: {"tau_s": v[0], "coef_per_c": float(c[0])},
        lambda p: {},
        lambda p, unit: (
            f"The output depends on a second temperature that trails the model temperature with a time constant "
            f"of {_g(p['tau_s'] / 60)} min ({_g(p['coef_per_c'])} {unit} per degC of lag). A mount, board or "
            "housing with its own heat capacity sets up a gradient across the package while the temperature "
            "moves, which the thermometer does not see."),
        "heat and cool through the same temperatures at two ramp rates, with soaks long enough to settle; a "
        "second thermometer on the mount"),
)}


def kind_of(term_id: str) -> TermKind | None:
    """The open-world term kind of ``term_id`` (``bias_step``, or a further instance such as
    ``bias_step_2``: a second step in the same record), None for any other id."""
    cls = effect_class(term_id)
    return TERMS.get(cls.id) if cls is not None else None


def is_open(term_id: str) -> bool:
    """Whether ``term_id`` is an open-world term (or a further instance of one)."""
    return kind_of(term_id) is not None


def free_id(term: str, ids: tuple[str, ...]) -> str | None:
    """The id a new instance of ``term`` takes beside ``ids`` (``term``, ``term_2``, ...), or
    None once :data:`~tcbench.sensors.effects.MAX_REPEATS` are in."""
    taken = set(ids)
    return next((i for i in (term, *(f"{term}_{k}" for k in range(2, MAX_REPEATS + 1))) if i not in taken), None)


def term_threshold(term_id: str, open_threshold: float) -> float:
    """The held-out gain open-world term ``term_id`` must exceed, for the open world's ``open_threshold``."""
    return open_threshold * _kind(term_id).search_scale


def term_columns(d: DiagnosisData, term_id: str, value: Value, temp_c: np.ndarray) -> np.ndarray:
    """The columns (n, m) of open-world term ``term_id`` at ``value``."""
    return _kind(term_id).columns(d, value, temp_c)


def _kind(term_id: str) -> TermKind:
    kind = kind_of(term_id)
    if kind is None:
        raise KeyError(f"not an open-world term: {term_id!r}")
    return kind


def open_finding(term_id: str, params: dict[str, float], evidence: dict[str, Any], unit: str) -> dict[str, Any]:
    """The report.json ``effects`` entry of a kept open-world term (the contract of
    :mod:`tcbench.diagnose.findings`)."""
    kind = _kind(term_id)
    return Finding(term_id, kind.shape, False, dict(params), kind.where(params), evidence,
                   kind.explanation(params, unit), kind.confirm_with).to_json()
