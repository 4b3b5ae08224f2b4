"""The simulator's deterministic truth behind a simulated recording.

:func:`simulate_truth` takes the same arguments as
:func:`tcbench.sensors.simulate.simulate_recording` and rebuilds the same device, the same model
changes and the same profile (the first of the three streams of ``SeedSequence(seed)``), so it
describes exactly the run the recording was made from. Instead of the recorded output it returns
what the simulator knows and the recording hides: the die temperature the physics saw, the
noise-free output, and the sensitivity of that output to the applied input. The recorded output
minus ``output_det`` is the noise alone (white, flicker, random walk and quantisation); the oracle
(:mod:`tcbench.compensation.oracle`) is built on it.

It also returns what a compensator that knows the device exactly could reconstruct when it reads
only the thermometer, as every real compensator does (the thermometer-limited oracle): the
device's model (with the run's effect changes) and where its thermometer sits (the offset and
heat-flow gradient of :func:`tcbench.sensors.runs.placement`), fed the package temperature that
placement implies from the recorded reading after a centred mean over
:data:`THERMOMETER_SMOOTH_S`. What it cannot know is this power-on (turn-on bias, scale factor and
slope, the hysteresis state, the thermometer's run-to-run offset and gradient), the thermometer's
noise and its 0.01 degC resolution: a real floor above the die-temperature oracle, the one any
compensator fitted on other runs faces.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.ndimage import uniform_filter1d

from tcbench.sensors import effects as fx
from tcbench.sensors import kinds
from tcbench.sensors.models import SensorModel, _signals
from tcbench.sensors.protocols import Profile
from tcbench.sensors.simulate import prepare_run, thermometer_reading

STOCHASTIC_EFFECTS = tuple(cls.id for cls in fx.EFFECTS.values() if cls.stochastic)  # the noise a recording adds
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
    output_det_thermometer: the noise-free output of the device's model (not this power-on's) fed the
        package temperature implied by the recorded thermometer reading, smoothed (see the module
        docstring).
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
    **run_params: Any,
) -> Truth:
    """Truth of the run ``simulate_recording(sensor, protocol, device_seed, seed, effects,
    without, **run_params)`` would record (same arguments: same device, power-on and profile)."""
    run = prepare_run(sensor, protocol, device_seed, seed, effects, without, **run_params)
    profile = run.profile
    det = run.model.without(*STOCHASTIC_EFFECTS)
    reading = thermometer_reading(profile, run.model, run.thermometer_rng, run.power_on.placement)  # as recorded
    width = max(1, int(round(THERMOMETER_SMOOTH_S * profile.sample_rate_hz)) | 1)
    smoothed = uniform_filter1d(reading, width, mode="nearest")
    read_profile = dataclasses.replace(profile, temp_c=run.placement.package_c(smoothed, profile.dt_s))
    temp_die_c = fx.die_temperature(list(det.effects), _signals(profile, det.ref_c))
    step = kinds.get(sensor).input_step  # outputs are at most quadratic in the input: the difference is exact
    plus = _deterministic(det, _shifted(profile, step))
    minus = _deterministic(det, _shifted(profile, -step))
    return Truth(
        t_s=profile.t_s.copy(),
        temp_die_c=np.asarray(temp_die_c, dtype=np.float64),
        output_det=_deterministic(det, profile),
        sensitivity_per_input=(plus - minus) / (2.0 * step),
        input=kinds.profile_input(profile).copy(),
        output_det_thermometer=_deterministic(run.nominal.without(*STOCHASTIC_EFFECTS), read_profile),
    )
