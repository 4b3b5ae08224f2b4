"""Seed 001's dual-mass vibratory gyroscope: output the rate in deg/s.

Protocols: ``oven``, seed 001 §4.1 (1 h at room temperature, 60 degC for 1 h, then down in 10 degC
steps held 1 h each to -40 degC, at rest); ``static``, a long run at constant temperature, at rest
(Allan variance).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from tcbench.sensors.devices import SLOPE_REPEAT, device_rng, turn_on_draws
from tcbench.sensors.kinds import SensorKind
from tcbench.sensors.models import Gyro, SensorModel, Unit, gyro_effects
from tcbench.sensors.protocols import MAX_LEVELS, Chamber, Profile, _from_segments, check_length
from tcbench.sensors.thermal import Segment
from tcbench.sensors.timing import current_timing


def gyro_unit(device_seed: int) -> Unit:
    """One dual-mass gyroscope around experiments/raw-sensors/README.md's defaults (bias 1.10 u + 4.0e-3 u^2 +
    1.5e-4 u^3 deg/h, ARW 0.52 deg/sqrt(h), bias instability 33 deg/h, lag 8 min)."""
    rng = device_rng("gyro", device_seed)
    draws = {
        "lag_tau_s": rng.uniform(390.0, 570.0),
        "c3_dph_per_k3": 1.5e-4 * (1.0 + rng.normal(0.0, 0.1)),
        "rate_dph_per_c_per_min": rng.uniform(2.5, 3.5),
        "arw_deg_per_sqrt_h": 0.52 * (1.0 + rng.normal(0.0, 0.04)),
        "bias_instability_dph": 33.0 * (1.0 + rng.normal(0.0, 0.08)),
    }
    model = Gyro(
        sf_ppm_per_k=-280.0 + rng.normal(0.0, 30.0),
        b0_dph=rng.normal(0.0, 20.0),
        b1_dph_per_k=1.10 * (1.0 + rng.normal(0.0, 0.08)),
        b2_dph_per_k2=4.0e-3 * (1.0 + rng.normal(0.0, 0.1)),
        effects=gyro_effects(**draws),
    )
    return Unit(f"gyro-{device_seed:04d}", model, draws)


def gyro_power_on(model: SensorModel, rng: np.random.Generator) -> tuple[SensorModel, dict[str, float]]:
    """A gyro's power-on: turn-on bias 20 deg/h (std), scale factor 300 ppm, bias slope 1 %,
    ageing 0.3 deg/h per day over up to :data:`AGEING_DAYS` days."""
    if not isinstance(model, Gyro):
        return model, {}  # a fitted model: no turn-on draws of this part
    draws = turn_on_draws(rng, "dph", 20.0, 300.0, SLOPE_REPEAT, 0.3)
    return dataclasses.replace(
        model, b0_dph=model.b0_dph + draws["turn_on_bias_dph"] + draws["aged_dph"],
        sf0_ppm=model.sf0_ppm + draws["scale_factor_ppm"],
        b1_dph_per_k=model.b1_dph_per_k * (1.0 + draws["slope_change"]),
    ), draws


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


KIND = SensorKind(
    name="gyro",
    title="MEMS vibratory gyroscope (output a rate)",
    input_unit="deg/s",
    output_unit="deg/s",
    input_field="rate_dps",
    input_range=(-20000.0, 20000.0),  # MEMS gyros measure up to a few thousand deg/s
    output_range=(-20000.0, 20000.0),
    device=gyro_unit,
    power_on=gyro_power_on,
    protocols={"oven": gyro_oven, "static": gyro_static},
    noise_unit="°/h",
    noise_scale=3600.0,
    ulog_topic="sensor_gyro",
    ulog_unit="rad/s",
    px4_letter="G",
    px4_cal="GYRO",
    ardupilot_letters="GYR",
    report="rate",  # seed 001's read-offs
)
