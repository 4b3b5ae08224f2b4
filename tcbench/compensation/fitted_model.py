"""A fitted sensor model (what ``tcbench diagnose`` writes as ``model.yaml``) used as the
compensator: its deterministic output for a record's own thermometer, clock and input.

The model is run as the simulator runs it (:meth:`~tcbench.sensors.models.SensorModel.simulate`:
its thermal lag, hysteresis, warm-up, steps, bumps and polynomial core), without its stochastic
effects (white noise, flicker, random walk, quantisation), its outliers and its spectral lines
(:data:`RIG_EFFECTS`), on a uniform grid over the record at the rate inside its segments, then
read at the record's samples. The thermometer goes in as read (a flight controller has no future
samples to smooth with); the time is the record's own clock, as the diagnosis fitted it.

**Explained is not compensated.** A compensator that ships maps the temperature history it reads
(and at most the time since its own power-on) to a correction; it cannot know where the
calibration run's clock stood. So the compensating model (:func:`compensator`) drops every term
keyed to that clock (:data:`CLOCK_EFFECTS`): a bias step at a time of the calibration run, a
transient after a handling event, a warm-up or an ageing drift counted from the record's first
sample. Run on a later part of the same power-on they would carry what happened in the
calibration run into the test — information no shipped compensator has (on the tofupilot gyro
x, fitted on the cooling and heating branches, a step at 1447 s and a transient took the second
cooling's drift from 0.325 to 0.199 deg/s). The diagnosis still reports them: they explain the
record; they are not compensated.

A line (``periodic``, ``gated_periodic``, ``duty_cycle``) is what a chamber's compressor, a fan
or a supply does to the test (docs/concepts/diagnosis-report.md, shapes), not the sensor: its phase on another day is
unknown, so a compensator carrying it adds the line back wherever the phase has moved. Fitted
on the tofupilot cycle's cooling and heating branches, the lines the diagnosis found made the
second cooling's drift 1.88 mg with them and 0.84 mg without on acc z, 0.32 and 0.23 °/s on gyro
y, and changed the other four axes by less than 2 % (``experiments/real-imu``).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from tcbench.sensors import kinds
from tcbench.sensors.effects import EFFECTS
from tcbench.sensors.fitted import PolynomialModel
from tcbench.sensors.protocols import MAX_SAMPLES, Profile
from tcbench.sensors.segments import within_rate_hz
from tcbench.sensors.truth import STOCHASTIC_EFFECTS

RIG_EFFECTS = tuple(cls.id for cls in EFFECTS.values() if cls.rig)  # the rig's lines, not the sensor
CLOCK_EFFECTS = tuple(cls.id for cls in EFFECTS.values() if cls.clock_keyed)  # keyed to the calibration run's clock


def compensator(model: PolynomialModel) -> PolynomialModel:
    """The model a compensator can run: without its clock-keyed terms (:data:`CLOCK_EFFECTS`),
    its rig's lines, its noise and its spikes (see the module doc)."""
    quiet = model.without(*STOCHASTIC_EFFECTS, *RIG_EFFECTS, *CLOCK_EFFECTS)
    return dataclasses.replace(quiet, spike_time_s=(), spike_size=())  # type: ignore[return-value]


def dropped_terms(model: PolynomialModel) -> list[str]:
    """The clock-keyed and rig terms of ``model`` its :func:`compensator` leaves out, as
    ``bias_step (time_s=1447, size=0.02)``."""
    out = []
    for e in model.effects:
        if e.id in CLOCK_EFFECTS + RIG_EFFECTS:
            out.append(f"{e.id} ({', '.join(f'{k}={v:.4g}' for k, v in e.params().items())})")
    return out


def deterministic_output(model: PolynomialModel, t_s: np.ndarray, temp_c: np.ndarray,
                         applied: np.ndarray, *, clock_terms: bool = True) -> np.ndarray:
    """The model's noise-free output (its output unit) at the samples ``t_s`` of a record whose
    thermometer reads ``temp_c`` and whose true input is ``applied``; ``clock_terms=False``: as
    its :func:`compensator` (the clock-keyed terms left out)."""
    t = np.asarray(t_s, dtype=np.float64)
    rate_hz = within_rate_hz(t) if t.size > 2 else 1.0 / max(float(t[-1] - t[0]), 1e-9)
    n = int(np.floor((t[-1] - t[0]) * rate_hz)) + 1
    if n > MAX_SAMPLES:
        raise ValueError(f"the record spans {n:.3g} samples at its {rate_hz:g} Hz; a model runs on at most {MAX_SAMPLES:.0e}")
    grid = t[0] + np.arange(n) / rate_hz
    temp = np.interp(grid, t, temp_c)
    applied_grid = np.interp(grid, t, applied)
    zeros = np.zeros_like(grid)
    field = kinds.get(model.sensor).input_field
    inputs = {"accel_g": zeros, "rate_dps": zeros.copy(), field: applied_grid}
    profile = Profile("record", model.sensor, rate_hz, grid, temp, inputs["accel_g"], zeros.copy(), inputs["rate_dps"])
    quiet = (dataclasses.replace(model.without(*STOCHASTIC_EFFECTS, *RIG_EFFECTS), spike_time_s=(), spike_size=())
             if clock_terms else compensator(model))
    out = quiet.simulate(profile, np.random.default_rng(0))  # no stochastic effect left to draw
    return np.interp(t, grid, out)
