"""Test protocols: what the chamber, turntable and rate table do during an experiment.

A protocol yields a :class:`Profile`, the sampled conditions the sensor experiences: the
package temperature its thermometer reads, and the applied acceleration or rate. The chamber
set-point follows the protocol's segments at a limited ramp rate; the chamber air and the
package follow it with first-order lags (the die's own lag behind the thermometer is the
sensor's ``thermal_lag`` effect).

Each sensor kind's protocols are in its module of :mod:`tcbench.sensors.kinds`; this module holds
what they are built from.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from tcbench.sensors.thermal import Segment, first_order_lag, segment_index, setpoint
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
