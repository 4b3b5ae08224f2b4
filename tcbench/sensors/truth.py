"""The simulator's deterministic truth behind a simulated recording.

:func:`simulate_truth` takes the same arguments as
:func:`tcbench.sensors.simulate.simulate_recording` and rebuilds the same device, the same model
changes and the same profile (the first of the three streams of ``SeedSequence(seed)``), so it
describes exactly the run the recording was made from. Instead of the recorded output it returns
what the simulator knows and the recording hides: the die temperature the physics saw, the
noise-free output, and the sensitivity of that output to the applied input. The recorded output
minus ``output_det`` is the noise alone (white, flicker, random walk and quantisation); the oracle
(:mod:`tcbench.compensation.oracle`) is built on it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.sensors import effects as fx
from tcbench.sensors import kinds
from tcbench.sensors.devices import unit
from tcbench.sensors.models import SensorModel, _signals
from tcbench.sensors.protocols import Profile
from tcbench.sensors.simulate import build_profile

STOCHASTIC_EFFECTS = ("white_noise", "bias_instability", "random_walk", "quantisation", "noise_temperature", "noise_time")


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
    """

    t_s: np.ndarray
    temp_die_c: np.ndarray
    output_det: np.ndarray
    sensitivity_per_input: np.ndarray
    input: np.ndarray


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
    profile_rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(3)[0])
    profile = build_profile(sensor, protocol, profile_rng, **protocol_params)
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
    )
