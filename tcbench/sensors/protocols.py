"""Test protocols: what the chamber, turntable and rate table do during an experiment.

A protocol yields a :class:`Profile`, the sampled conditions the sensor experiences: the
package temperature its thermometer reads, and the applied acceleration or rate. The chamber
set-point follows the protocol's segments at a limited ramp rate; the chamber air and the
package follow it with first-order lags (the die's own lag behind the thermometer is the
sensor's ``thermal_lag`` effect).

- ``msra_roomtemp``: seed 000 zero-bias test — 1.5 h at 1 Hz, 0 g, power-on self-heating and
  slow ambient wander.
- ``msra_fulltemp``: seed 000 full-temperature test — nodes -40..60 degC every 20 degC, 1 h
  soak, then +0 g, +1 g, -0 g, -1 g for 40 s each (10 s turntable moves between) at 1 Hz.
- ``gyro_oven``: seed 001 §4.1 — 1 h at room temperature, 60 degC for 1 h, then down in
  10 degC steps held 1 h each to -40 degC, at rest.
- ``gyro_static``: a long run at constant temperature, at rest (Allan variance).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from tcbench.sensors import kinds
from tcbench.sensors.thermal import Segment, first_order_lag, gauss_markov, segment_index, setpoint
from tcbench.sensors.timing import MIN_SOAK_S, Timing, current_timing

MAX_LEVELS = 1000  # temperature levels of an oven run
MAX_SAMPLES = 100_000_000  # a longer profile is refused before any array is made (8 bytes x columns each)
POSITIONS = {  # label: (acceleration along the sensitive axis, across it), in g
    "+0g": (0.0, 1.0),
    "+1g": (1.0, 0.0),
    "-0g": (0.0, -1.0),
    "-1g": (-1.0, 0.0),
}


@dataclass
class Profile:
    """Conditions per sample: time, package temperature, applied inputs, position labels."""

    name: str
    sensor: str
    sample_rate_hz: float
    t_s: np.ndarray
    temp_c: np.ndarray
    accel_g: np.ndarray
    cross_g: np.ndarray
    rate_dps: np.ndarray
    position: np.ndarray | None = None
    info: dict[str, float | str] = field(default_factory=dict)

    @property
    def dt_s(self) -> float:
        return 1.0 / self.sample_rate_hz

    @property
    def input(self) -> np.ndarray:
        """The recorded ``input`` column: the applied input its sensor kind measures
        (acceleration in g, or rate in deg/s)."""
        return getattr(self, kinds.get(self.sensor).input_field)


@dataclass(frozen=True)
class Chamber:
    """Chamber behaviour: ramp-rate limit and the lags of its air and of the sensor package."""

    ramp_c_per_min: float = 1.0
    air_tau_s: float = 60.0
    package_tau_s: float = 180.0


def check_length(duration_s: float, sample_rate_hz: float, thermal_dt_s: float | None = None) -> None:
    """Refuse a profile of fewer than two samples, or of more than :data:`MAX_SAMPLES` samples
    (or thermal steps of ``thermal_dt_s``), before anything is allocated."""
    n = duration_s * sample_rate_hz
    steps = duration_s / thermal_dt_s if thermal_dt_s else 0.0
    if not n >= 2:
        raise ValueError(f"protocol_params: {duration_s:g} s at {sample_rate_hz:g} Hz is {math.floor(n)} sample(s); "
                         "a recording needs at least two (raise duration_s or sample_rate_hz)")
    if max(n, steps) > MAX_SAMPLES:
        raise ValueError(f"protocol_params: {duration_s:g} s at {sample_rate_hz:g} Hz is {max(n, steps):.3g} samples, "
                         f"more than the {MAX_SAMPLES:.0e} a simulation makes (shorten it or lower sample_rate_hz)")


def programme_s(segments: list[Segment], start_c: float, ramp_c_per_min: float) -> float:
    """Length of a segment programme in s: its holds plus the ramps between them."""
    targets = np.array([start_c] + [s.target_c for s in segments])
    return float(np.abs(np.diff(targets)).sum() * 60.0 / ramp_c_per_min + sum(s.duration_s for s in segments))


def _from_segments(
    name: str,
    sensor: str,
    segments: list[Segment],
    start_c: float,
    sample_rate_hz: float,
    chamber: Chamber,
) -> Profile:
    """Sample a segment programme: set-point -> chamber air -> package, inputs per segment, as
    the current run's chamber runs it (:func:`as_run`)."""
    segments, start_c, chamber = as_run(segments, start_c, chamber, current_timing())
    thermal_dt = min(1.0, 1.0 / sample_rate_hz)
    check_length(programme_s(segments, start_c, chamber.ramp_c_per_min), sample_rate_hz, thermal_dt)
    t_th, sp = setpoint(segments, start_c, chamber.ramp_c_per_min, thermal_dt)
    air = first_order_lag(sp, thermal_dt, chamber.air_tau_s)
    package = first_order_lag(air, thermal_dt, chamber.package_tau_s)
    t = np.arange(0.0, t_th[-1], 1.0 / sample_rate_hz)
    temp = np.interp(t, t_th, package)
    seg = segment_index(segments, start_c, chamber.ramp_c_per_min, t)
    held = seg >= 0
    # During a ramp the unit already rests in the orientation of the segment it ramps to.
    upcoming = np.minimum.accumulate(np.where(held, seg, len(segments) - 1)[::-1])[::-1]
    table = np.array([[s.accel_g, s.cross_g, s.rate_dps] for s in segments])
    # An input the same in every segment is a read-only broadcast view, not a full array.
    accel, cross, rate = (
        np.broadcast_to(column[0], t.shape) if np.all(column == column[0]) else column[upcoming]
        for column in table.T
    )
    labels = None
    if any(s.position for s in segments):
        names = np.array([""] + [s.position for s in segments])
        labels = names[np.where(held, seg + 1, 0)]
    return Profile(
        name, sensor, sample_rate_hz, t, temp, accel, cross, rate, labels,
        {"chamber_ramp_c_per_min": chamber.ramp_c_per_min, "package_tau_s": chamber.package_tau_s},
    )


def as_run(segments: list[Segment], start_c: float, chamber: Chamber,
           timing: Timing) -> tuple[list[Segment], float, Chamber]:
    """A programme as one run runs it: the holds in reverse order (``timing.reverse``; a leading
    hold at the start temperature stays first), soaks of at least :data:`MIN_SOAK_S` scaled, the
    start point moved and the ramp rate scaled."""
    if timing.reverse:
        starts = [i for i, seg in enumerate(segments) if seg.duration_s >= MIN_SOAK_S] or [0]
        starts = [0] + [i for i in starts if i > 0]
        groups = [segments[a:b] for a, b in zip(starts, starts[1:] + [len(segments)], strict=True)]
        first = [groups.pop(0)] if groups[0][0].target_c == start_c and len(groups) > 1 else []
        segments = [seg for group in first + groups[::-1] for seg in group]
    durations = timing.soaks(np.array([seg.duration_s for seg in segments]))
    segments = [dataclasses.replace(seg, duration_s=float(d)) for seg, d in zip(segments, durations, strict=True)]
    chamber = dataclasses.replace(chamber, ramp_c_per_min=chamber.ramp_c_per_min * timing.ramp_scale)
    return segments, start_c + timing.start_offset_c, chamber


def four_position_nodes(
    name: str,
    sensor: str,
    nodes_c: tuple[float, ...],
    soak_s: float,
    position_s: float,
    move_s: float,
    start_c: float,
    sample_rate_hz: float,
    chamber: Chamber,
) -> Profile:
    """An accelerometer's multi-position test: at each temperature node a soak at +0g, then
    +0g, +1g, -0g, -1g for ``position_s`` each with ``move_s`` turntable moves between."""
    segments: list[Segment] = []
    for node in nodes_c:
        segments.append(Segment(node, soak_s, "", *POSITIONS["+0g"]))
        for label, (accel, cross) in POSITIONS.items():
            segments.append(Segment(node, move_s, "", accel, cross))
            segments.append(Segment(node, position_s, label, accel, cross))
    return _from_segments(name, sensor, segments, start_c, sample_rate_hz, chamber)


def msra_fulltemp(
    nodes_c: tuple[float, ...] = (-40.0, -20.0, 0.0, 20.0, 40.0, 60.0),
    soak_s: float = 3600.0,
    position_s: float = 40.0,
    move_s: float = 10.0,
    start_c: float = 25.0,
    sample_rate_hz: float = 1.0,
    chamber: Chamber = Chamber(),
) -> Profile:
    """Seed 000 full-temperature test: soak at each node, then the four positions."""
    return four_position_nodes("fulltemp", "msra", nodes_c, soak_s, position_s, move_s, start_c, sample_rate_hz,
                               chamber)


def msra_roomtemp(
    rng: np.random.Generator,
    duration_s: float = 5400.0,
    ambient_c: float = 23.0,
    self_heating_c: float = 1.1,
    self_heating_tau_s: float = 2400.0,
    wander_c: float = 0.05,
    wander_tau_s: float = 1800.0,
    sample_rate_hz: float = 1.0,
) -> Profile:
    """Seed 000 zero-bias test at room temperature: 0 g, power-on at t = 0.

    The package warms by ``self_heating_c`` with time constant ``self_heating_tau_s`` after
    power-on, on top of an ambient that wanders (Gauss-Markov, std ``wander_c``).
    """
    check_length(duration_s, sample_rate_hz)
    timing = current_timing()
    ambient_c += timing.ambient_offset_c
    self_heating_c *= timing.self_heating_scale
    t = np.arange(0.0, duration_s, 1.0 / sample_rate_hz)
    thermal_dt = max(1.0 / sample_rate_hz, 1.0)
    coarse_t = np.arange(0.0, duration_s + thermal_dt, thermal_dt)
    wander = gauss_markov(coarse_t.size, thermal_dt, wander_tau_s, wander_c, rng)
    temp = ambient_c + self_heating_c * (1.0 - np.exp(-t / self_heating_tau_s))
    temp = temp + np.interp(t, coarse_t, wander)
    zeros = np.zeros_like(t)
    return Profile(
        "roomtemp", "msra", sample_rate_hz, t, temp, zeros, np.ones_like(t), zeros.copy(),
        np.full(t.size, "+0g"), {"self_heating_c": self_heating_c, "wander_c": wander_c},
    )


def gyro_oven(
    room_c: float = 25.0,
    room_s: float = 3600.0,
    hot_c: float = 60.0,
    cold_c: float = -40.0,
    step_c: float = 10.0,
    hold_s: float = 3600.0,
    sample_rate_hz: float = 10.0,
    chamber: Chamber = Chamber(ramp_c_per_min=1.0),
) -> Profile:
    """Seed 001 §4.1 oven run: room temperature, 60 degC, then 10 degC steps down to -40 degC."""
    if (hot_c - cold_c) / step_c > MAX_LEVELS:
        raise ValueError(f"protocol_params.step_c: {step_c:g} degC makes more than {MAX_LEVELS} levels from "
                         f"{hot_c:g} to {cold_c:g} degC")
    levels = np.arange(hot_c, cold_c - 1e-9, -step_c)
    segments = [Segment(room_c, room_s, cross_g=0.0)]
    segments += [Segment(float(level), hold_s, cross_g=0.0) for level in levels]
    return _from_segments("oven", "gyro", segments, room_c, sample_rate_hz, chamber)


def gyro_static(
    duration_s: float = 86400.0, temp_c: float = 25.0, sample_rate_hz: float = 100.0
) -> Profile:
    """A long run at rest and constant temperature (for Allan variance). The constant columns
    are read-only broadcast views, so a 24 h run at 100 Hz holds one full-length array (time)."""
    check_length(duration_s, sample_rate_hz)
    temp_c += current_timing().start_offset_c
    t = np.arange(0.0, duration_s, 1.0 / sample_rate_hz)
    zeros = np.broadcast_to(np.float64(0.0), t.shape)
    return Profile("static", "gyro", sample_rate_hz, t, np.broadcast_to(np.float64(temp_c), t.shape), zeros, zeros, zeros)
