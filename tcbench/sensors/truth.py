"""The simulator's deterministic truth behind a simulated recording.

:func:`simulate_truth` takes the same arguments as
:func:`tcbench.sensors.simulate.simulate_recording` and rebuilds the same device, the same model
changes and the same profile (the first of the three streams of ``SeedSequence(seed)``), so it
describes exactly the run the recording was made from. Instead of the recorded output it returns
what the simulator knows and the recording hides: the die temperature the physics saw, the
noise-free output, and the sensitivity of that output to the applied input. The recorded output
minus ``output_det`` is the noise alone (white, flicker, random walk and quantisation); the oracle
(:mod:`tcbench.compensation.oracle`) is built on it.

It also returns what a compensator that knows the simulator's model could reconstruct when it
reads only the thermometer, as every real compensator does: the same noise-free model fed the
recorded thermometer reading (its noise, its 0.01 degC resolution, the thermometer-stage effects)
after a centred mean over :data:`THERMOMETER_SMOOTH_S`, instead of the true package temperature.
The die's lag behind the package is part of the model, so it is reconstructed from the reading;
what is lost is the thermometer's own noise and resolution, as they pass through the model (the
thermometer-limited oracle).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.ndimage import uniform_filter1d

from tcbench.sensors import effects as fx
from tcbench.sensors import kinds
from tcbench.sensors.devices import unit
from tcbench.sensors.models import SensorModel, _signals
from tcbench.sensors.protocols import Profile
from tcbench.sensors.simulate import build_profile, thermometer_reading

STOCHASTIC_EFFECTS = ("white_noise", "bias_instability", "random_walk", "quantisation", "noise_temperature", "noise_time")
# The thermometer-limited oracle's smoothing of the reading: a centred mean over a minute averages
# 60-600 samples of thermometer noise while the package temperature, behind the chamber's air by
# minutes, moves by at most 1 degC/min x 60 s at the fastest ramp (its curvature, not its slope,
# biases a centred mean).
THERMOMETER_SMOOTH_S = 60.0


@dataclass(frozen=True)
class Truth:
    """Deterministic truth of a simulated run, per sample.

    t_s: sample times (s), the recording's ``time_s``.
    temp_die_c: die temperature after the die-stage effects (thermal lag), degC.
    output_det: noise-free output (Hz for the MSRA, deg/s for the gyro): the model without
        white noise, bias instability, random walk and quantisation.
    sensitivity_per_input: d output_det / d input (Hz/g for the MSRA, output per deg/s for
        the gyro), by a central difference with the input shifted by +-the kind's ``input_step``.
    input: the applied input (g or deg/s), the recording's ``input``.
    output_det_thermometer: the noise-free output of the same model fed the recorded thermometer
        reading, smoothed (see the module docstring), in place of the true package temperature.
    """

    t_s: np.ndarray
    temp_die_c: np.ndarray
    output_det: np.ndarray
    sensitivity_per_input: np.ndarray
    input: np.ndarray
    output_det_thermometer: np.ndarray


def _shifted(profile: Profile, delta: float) -> Profile:
    """The profile with its recorded input (acceleration or rate) shifted by ``delta``."""
    name = kinds.get(profile.sensor).input_field
    return dataclasses.replace(profile, **{name: getattr(profile, name) + delta})


def _deterministic(model: SensorModel, profile: Profile) -> np.ndarray:
    """Output of a model without stochastic effects (its random stream is never drawn from)."""
    return model.simulate(profile, np.random.default_rng(0))


def simulate_truth(
    sensor: str,
    protocol: str,
    device_seed: int,
    seed: int = 0,
    effects: dict[str, dict[str, float]] | None = None,
    without: tuple[str, ...] | list[str] = (),
    **protocol_params: Any,
) -> Truth:
    """Truth of the run ``simulate_recording(sensor, protocol, device_seed, seed, effects,
    without, **protocol_params)`` would record (same arguments, same device and profile)."""
    device = unit(sensor, device_seed)
    model = device.model.with_effects(effects or {}).without(*without)
    profile_seq, _, thermometer_seq = np.random.SeedSequence(seed).spawn(3)
    profile = build_profile(sensor, protocol, np.random.default_rng(profile_seq), **protocol_params)
    reading = thermometer_reading(profile, model, np.random.default_rng(thermometer_seq))  # as the recording holds it
    width = max(1, int(round(THERMOMETER_SMOOTH_S * profile.sample_rate_hz)) | 1)
    read_profile = dataclasses.replace(profile, temp_c=uniform_filter1d(reading, width, mode="nearest"))
    det = model.without(*STOCHASTIC_EFFECTS)
    temp_die_c = fx.die_temperature(list(det.effects), _signals(profile, det.ref_c))
    step = kinds.get(sensor).input_step  # outputs are at most quadratic in the input: the difference is exact
    plus = _deterministic(det, _shifted(profile, step))
    minus = _deterministic(det, _shifted(profile, -step))
    return Truth(
        t_s=profile.t_s.copy(),
        temp_die_c=np.asarray(temp_die_c, dtype=np.float64),
        output_det=_deterministic(det, profile),
        sensitivity_per_input=(plus - minus) / (2.0 * step),
        input=profile.input.copy(),
        output_det_thermometer=_deterministic(det, read_profile),
    )
