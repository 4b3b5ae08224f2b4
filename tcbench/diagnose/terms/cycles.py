"""Open-world terms of a cycle, found at the spectral lines of the residual: a line over the whole
record, a cycle present only in part of it (with harmonics), and a load switched on and off."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tcbench.diagnose.settings import DEFAULTS, DetectorSettings
from tcbench.diagnose.signals import DiagnosisData
from tcbench.diagnose.terms.base import g3
from tcbench.diagnose.terms.detectors import MIN_PERIOD_BINS, bin_width, duty_phase, line_window, why_no_lines
from tcbench.diagnose.terms.open_base import OpenTerm, Screen, Search, Value, search_log
from tcbench.sensors.effects import DutyCycle, Effect, GatedPeriodic, Periodic

GATED_HARMONICS = 5  # a switched load (a compressor's duty cycle) is not a sinusoid: its level and harmonics
GATED_MIN_CYCLES = 4.0  # a line present in part of the run must hold this many cycles there: flicker makes one or two
GATED_MAX_PART = 0.8  # ... and be absent from more than this share of the span (else it is a periodic line)
DUTY_MIN_CYCLES = 3.0  # a switched load's square cycle is a sharper shape than a line's: flicker does not mimic three
PERIOD_BAND = (0.9, 1.1)  # a period is refined within these factors of the detected one
DUTY_BRACKET = 41  # a square cycle's drop has side maxima in the period: this grid (points) brackets the best first
EDGE_STEPS_PER_PERIOD = 16  # a gated span's edges are moved in steps of a period over this ...
EDGE_REACH_PERIODS = 1.5  # ... within this many periods: demodulation places an edge only to about a period
EDGE_GRID = 17  # points within one phase bin either way where a switched load's on and off instants are tried


def windows(search: Search) -> list[tuple[float, float, float]]:
    """``(period_s, start_s, end_s)`` of each line short enough to hold :data:`DUTY_MIN_CYCLES`
    inside :data:`GATED_MAX_PART` of the span, with where it is present
    (:func:`~tcbench.diagnose.terms.detectors.line_window`); once per round."""
    d, r, span = search.data, search.residual, search.span_s
    return search.shared("line_windows", lambda: [(p, *line_window(d.t_s, r, p, search.detectors))
                                                  for p in search.lines if DUTY_MIN_CYCLES * p < GATED_MAX_PART * span])


def _period_phase(data: DiagnosisData, period_s: float) -> np.ndarray:
    return 2.0 * np.pi * data.t_s / period_s


def _log_period(value: Value) -> tuple[float, float]:
    return np.log(value[0] * PERIOD_BAND[0]), np.log(value[0] * PERIOD_BAND[1])


def _why_no_part(t_s: np.ndarray, min_cycles: float, what: str, detectors: DetectorSettings) -> str | None:
    """Why no line present in part of the record (or switched load, ``min_cycles`` apart) can be
    tested: even the shortest period the periodogram resolves needs its cycles inside less than
    the whole record."""
    span = float(t_s[-1] - t_s[0])
    longest = GATED_MAX_PART * span / min_cycles
    shortest = MIN_PERIOD_BINS * bin_width(t_s, detectors.line_bins, detectors.min_bin_s)
    if longest >= shortest:
        return None
    return (f"{what} present in part of the record needs {min_cycles:g} cycles inside "
            f"{GATED_MAX_PART:.0%} of it: the longest testable period is {longest:.4g} s, below the shortest "
            f"the periodogram resolves ({shortest:.4g} s)")


def _refine_window(screen: Screen, term_id: str, value: Value, min_cycles: float) -> Value:
    """A gated line's value with each edge of its span (the last two entries) moved, on a grid
    of a 16th of the period within 1.5 periods (:data:`EDGE_STEPS_PER_PERIOD`,
    :data:`EDGE_REACH_PERIODS`), to the largest in-sample drop: the demodulated
    envelope places the edges only to about a period, and a switched load's level inside the
    span makes a misplaced edge costly. The span keeps ``min_cycles`` cycles."""
    period = value[0]
    reach = int(EDGE_REACH_PERIODS * EDGE_STEPS_PER_PERIOD)
    offsets = period * np.arange(-reach, reach + 1) / float(EDGE_STEPS_PER_PERIOD)
    for edge in (len(value) - 2, len(value) - 1):
        moved = [(*value[:edge], float(value[edge] + off), *value[edge + 1:]) for off in offsets]
        moved = [v for v in moved if v[-1] - v[-2] >= min_cycles * period]
        if moved:
            value = max(moved, key=lambda v: screen.drop(term_id, v))
    return value


class PeriodicTerm(OpenTerm):
    """A line over the whole record: the columns are ``sin, cos(2 pi t / period_s)``. Proposed
    at the peaks of the residual's periodogram; the two coefficients are the effect's amplitude
    and phase."""

    id = "periodic"
    effect = Periodic
    shape = "periodic"
    value_names = ("period_s",)
    n_coef = 2
    confirm_with = "the chamber's own log of compressor and heater cycles; a run with the chamber idle at constant temperature"

    def columns(self, data: DiagnosisData, value: Value, temp_c: np.ndarray) -> np.ndarray:
        phase = _period_phase(data, value[0])
        return np.column_stack([np.sin(phase), np.cos(phase)])

    def params(self, coef: Any, value: Any, half_range_c: float = 1.0) -> dict[str, float]:
        # a sin(wt) + b cos(wt) = A sin(wt + phi)
        return {"period_s": value[0], "amplitude": float(np.hypot(coef[0], coef[1])),
                "phase_rad": float(np.arctan2(coef[1], coef[0]))}

    def located(self, params: Mapping[str, float]) -> dict[str, Any]:
        return {"period_s": params["period_s"], "frequency_hz": 1.0 / params["period_s"]}

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"A line in the residual's spectrum: a sinusoid of {g3(params['amplitude'])} {unit} with a period of "
            f"{g3(params['period_s'] / 60)} min, unrelated to the temperature profile. Environmental cycling does "
            "this: a chamber compressor or fan, the building's HVAC, supply ripple, or a mechanical resonance "
            "aliased by the sampling.")

    def propose(self, search: Search) -> list[Value]:
        return [(p,) for p in search.lines]

    def refine(self, screen: Screen, value: Value) -> Value:
        return search_log(screen, self.id, value, *_log_period(value), lambda z: (float(np.exp(z)), *value[1:]))

    def skip(self, data: DiagnosisData, fold: np.ndarray | None = None,
             detectors: DetectorSettings = DEFAULTS.detectors) -> str | None:
        return why_no_lines(data.t_s, detectors)


class _CycleInPart(OpenTerm):
    """A cycle present from ``start_s`` to ``end_s`` only: located at its line and its span."""

    def located(self, params: Mapping[str, float]) -> dict[str, Any]:
        return {"period_s": params["period_s"], "frequency_hz": 1.0 / params["period_s"],
                "time_s": [params["start_s"], params["end_s"]]}


class GatedPeriodicTerm(_CycleInPart):
    """A cycle present in part of the record only: a level and sin, cos of the period and its
    harmonics to the 5th, inside ``[start_s, end_s)``. Proposed where a line of the periodogram is
    present (complex demodulation)."""

    id = "gated_periodic"
    effect = GatedPeriodic
    shape = "periodic"
    value_names = ("period_s", "start_s", "end_s")
    n_coef = 1 + 2 * GATED_HARMONICS
    confirm_with = (
        "the chamber's log of compressor and heater cycles over the run; a soak at the same temperature with the "
        "chamber's cooling switched off")

    def columns(self, data: DiagnosisData, value: Value, temp_c: np.ndarray) -> np.ndarray:
        # the effect's formula, one column per coefficient in one pass (the effect would evaluate every harmonic per column)
        inside = ((data.t_s >= value[1]) & (data.t_s < value[2])).astype(float)
        phase = _period_phase(data, value[0])
        waves = [inside * f(k * phase) for k in range(1, GATED_HARMONICS + 1) for f in (np.sin, np.cos)]
        return np.column_stack([inside, *waves])

    def params(self, coef: Any, value: Any, half_range_c: float = 1.0) -> dict[str, float]:
        out = {"period_s": value[0], "start_s": value[1], "end_s": value[2], "offset": float(coef[0])}
        for k in range(GATED_HARMONICS):
            out[f"sin{k + 1}"], out[f"cos{k + 1}"] = float(coef[1 + 2 * k]), float(coef[2 + 2 * k])
        out["amplitude"] = float(np.hypot(coef[1], coef[2]))
        return out

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"A line in the residual's spectrum, a cycle of {g3(params['period_s'] / 60)} min "
            f"({g3(params['amplitude'])} {unit} at the fundamental, with harmonics and a mean offset of "
            f"{g3(params['offset'])} {unit}), present only from t = {g3(params['start_s'] / 3600)} h to "
            f"{g3(params['end_s'] / 3600)} h. Something that cycles only in part of the run does this: a chamber "
            "compressor that runs below room temperature, a heater's duty cycle, a fan switched with the set-point.")

    def propose(self, search: Search) -> list[Value]:
        span = search.span_s
        return [(p, a, b) for p, a, b in windows(search) if GATED_MIN_CYCLES * p <= b - a < GATED_MAX_PART * span]

    def refine(self, screen: Screen, value: Value) -> Value:
        value = search_log(screen, self.id, value, *_log_period(value), lambda z: (float(np.exp(z)), *value[1:]))
        return _refine_window(screen, self.id, value, GATED_MIN_CYCLES)

    def skip(self, data: DiagnosisData, fold: np.ndarray | None = None,
             detectors: DetectorSettings = DEFAULTS.detectors) -> str | None:
        return why_no_lines(data.t_s, detectors) or _why_no_part(data.t_s, GATED_MIN_CYCLES, "a line", detectors)


class DutyCycleTerm(_CycleInPart):
    """A load switched on and off: a level and ``1[(t - on_s) mod period_s < duty period_s]``,
    inside ``[start_s, end_s)``. Proposed where a line is present, its phase and duty read from
    the residual folded on the line's period."""

    id = "duty_cycle"
    effect = DutyCycle
    shape = "periodic"
    value_names = ("period_s", "on_s", "duty", "start_s", "end_s")
    n_coef = 2
    # period, phase, duty and both edges searched: on 40 open-world controls (development seeds
    # 40 700 000 + i) its chance gain reached twice a line's (90th percentile 13.9 against 6.6 sigma^2)
    search_scale = 2.0
    confirm_with = (
        "the chamber's log of compressor and heater cycles over the run; the supply voltage logged beside the "
        "output; a soak at the same temperature with the chamber's cooling switched off")

    def unit_effects(self, value: Value) -> tuple[Effect, ...]:
        period, on_s, duty, start, end = value
        return tuple(DutyCycle(period_s=period, on_s=on_s, duty=duty, start_s=start, end_s=end, offset=offset,
                               size=size) for offset, size in ((1.0, 0.0), (0.0, 1.0)))

    def params(self, coef: Any, value: Any, half_range_c: float = 1.0) -> dict[str, float]:
        return {"period_s": value[0], "on_s": value[1], "duty": value[2], "start_s": value[3], "end_s": value[4],
                "offset": float(coef[0]), "size": float(coef[1])}

    def explanation(self, params: Mapping[str, float], unit: str) -> str:
        return (
            f"A load switched on and off: every {g3(params['period_s'] / 60)} min the bias jumps by "
            f"{g3(params['size'])} {unit} for {g3(100 * params['duty'])} % of the cycle, from "
            f"t = {g3(params['start_s'] / 3600)} h to {g3(params['end_s'] / 3600)} h only (a mean offset of "
            f"{g3(params['offset'])} {unit} there). A chamber compressor or heater on a thermostat loading the "
            "supply or shaking the mount does this, as does a pump or fan on a timer.")

    def propose(self, search: Search) -> list[Value]:
        d, r, span = search.data, search.residual, search.span_s
        return [(p, *duty_phase(d.t_s, r, p, a, b, search.detectors.duty_phases), a, b) for p, a, b in windows(search)
                if DUTY_MIN_CYCLES * p <= b - a < GATED_MAX_PART * span]

    def refine(self, screen: Screen, value: Value) -> Value:
        value = search_log(screen, self.id, value, *_log_period(value),
                           lambda z: _refold(screen, (float(np.exp(z)), *value[1:])), bracket=DUTY_BRACKET)
        return self._refine_edges(screen, _refold(screen, _refine_window(screen, self.id, value, DUTY_MIN_CYCLES)))

    def _refine_edges(self, screen: Screen, value: Value) -> Value:
        """The on and off instants moved within one phase bin of the fold, to the largest
        in-sample drop: a switching edge misplaced by a few samples leaves a spike at every
        cycle, which the Allan test would take for flicker."""
        period, on_s, duty, start, end = value
        step = period / screen.detectors.duty_phases
        grid = np.linspace(-step, step, EDGE_GRID)
        on_s = max((on_s + g for g in grid), key=lambda x: screen.drop(self.id, (period, x, duty, start, end)))
        off = on_s + duty * period
        off = max((off + g for g in grid if 0.0 < off + g - on_s < period),
                  key=lambda x: screen.drop(self.id, (period, on_s, (x - on_s) / period, start, end)))
        return period, float(on_s), float((off - on_s) / period), start, end

    def skip(self, data: DiagnosisData, fold: np.ndarray | None = None,
             detectors: DetectorSettings = DEFAULTS.detectors) -> str | None:
        return why_no_lines(data.t_s, detectors) or _why_no_part(data.t_s, DUTY_MIN_CYCLES, "a switched load", detectors)


def _refold(screen: Screen, value: Value) -> Value:
    """A switched load's ``(period_s, on_s, duty, start_s, end_s)`` with its phase and duty
    read again from the residual folded on its period and span."""
    period, _, _, start, end = value
    return (period, *duty_phase(screen.data.t_s, screen.residual, period, start, end, screen.detectors.duty_phases),
            start, end)
