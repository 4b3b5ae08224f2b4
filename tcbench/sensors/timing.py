"""A chamber programme as one run ran it (docs/concepts/split-tiers.md): the timing the protocols read.

:func:`running` sets the :class:`Timing` of the run being built; the protocols
(:mod:`tcbench.sensors.protocols` and each kind's) read it with :func:`current_timing` when they
lay out their segments, so a protocol written for the nominal programme runs with a run's ramp
rate, soak lengths and start point without a parameter of its own.
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

RAMP_TOLERANCE = 0.10  # the chamber controller's ramp-rate tolerance (uniform within it)
SOAK_JITTER = 0.05  # soak lengths, relative (uniform within it)
START_JITTER_C = 0.3  # the chamber's start point, std
AMBIENT_JITTER_C = 1.0  # a room-temperature run's ambient on another day, std
SELF_HEATING_JITTER = 0.15  # its power-on self-heating, relative std
MIN_SOAK_S = 600.0  # shorter segments (turntable positions and moves) keep their programmed length


@dataclass(frozen=True)
class Timing:
    """How the chamber ran a programme this time: ramp rate and soak lengths scaled, the start
    point and ambient moved, the order of the holds reversed (a profile the training never saw).
    The default is the programme as written."""

    ramp_scale: float = 1.0
    soak_scale: tuple[float, ...] = ()
    start_offset_c: float = 0.0
    ambient_offset_c: float = 0.0
    self_heating_scale: float = 1.0
    reverse: bool = False

    def soaks(self, durations_s: np.ndarray) -> np.ndarray:
        """Segment durations as run: a soak (>= :data:`MIN_SOAK_S`) scaled by its factor (the
        factors repeat when there are more soaks than factors)."""
        d = np.asarray(durations_s, dtype=np.float64)
        if not self.soak_scale:
            return d
        factors = np.resize(np.asarray(self.soak_scale), d.size)
        return np.where(d >= MIN_SOAK_S, d * factors, d)


NOMINAL = Timing()
_timing: contextvars.ContextVar[Timing] = contextvars.ContextVar("tcbench_run_timing", default=NOMINAL)


def current_timing() -> Timing:
    """The timing of the run being built (:data:`NOMINAL` outside :func:`running`)."""
    return _timing.get()


@contextlib.contextmanager
def running(timing: Timing) -> Iterator[None]:
    """Build profiles inside this block with ``timing`` (read by the protocols)."""
    token = _timing.set(timing)
    try:
        yield
    finally:
        _timing.reset(token)


def draw_timing(rng: np.random.Generator, soaks: int = 32) -> Timing:
    """A chamber's timing for one run (``soaks`` factors, repeated over longer programmes)."""
    return Timing(
        ramp_scale=float(1.0 + rng.uniform(-RAMP_TOLERANCE, RAMP_TOLERANCE)),
        soak_scale=tuple(float(x) for x in 1.0 + rng.uniform(-SOAK_JITTER, SOAK_JITTER, soaks)),
        start_offset_c=float(rng.normal(0.0, START_JITTER_C)),
        ambient_offset_c=float(rng.normal(0.0, AMBIENT_JITTER_C)),
        self_heating_scale=float(max(0.0, 1.0 + rng.normal(0.0, SELF_HEATING_JITTER))),
    )
