"""Simulate a recording: a device (from its seed) run through a protocol (with a run seed)."""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable
from numbers import Real
from typing import Any

import numpy as np

from tcbench.sensors import effects as fx
from tcbench.sensors import kinds
from tcbench.sensors.devices import unit
from tcbench.sensors.models import SensorModel, Unit
from tcbench.sensors.noise import quantise
from tcbench.sensors.protocols import Profile
from tcbench.sensors.recording import Recording, make_recording

THERMOMETER_NOISE_C = 0.005  # std of the sensor's thermometer reading
THERMOMETER_STEP_C = 0.01  # its resolution


def protocol_names(sensor: str) -> list[str]:
    """Protocols available for a sensor kind."""
    return list(kinds.get(sensor).protocols)


def build_profile(
    sensor: str, protocol: str, rng: np.random.Generator, **params: Any
) -> Profile:
    """The protocol's profile; ``params`` override its keyword arguments (None = default)."""
    names = protocol_names(sensor)
    if protocol not in names:
        raise ValueError(f"unknown protocol {protocol!r} for {sensor}; known: {', '.join(names)}")
    fn: Callable[..., Profile] = kinds.get(sensor).protocols[protocol]
    accepted = inspect.signature(fn).parameters
    given = {k: v for k, v in params.items() if v is not None}
    unknown = sorted(set(given) - set(accepted) - {"rng"})
    if unknown:
        raise ValueError(f"protocol {protocol!r} has no parameter {', '.join(unknown)}; known: "
                         f"{', '.join(p for p in accepted if p != 'rng')}")
    given = {k: _checked_param(k, v, accepted[k].default) for k, v in given.items()}
    if "rng" in accepted:
        given["rng"] = rng
    return fn(**given)


def _checked_param(key: str, value: Any, default: Any) -> Any:
    """A protocol parameter checked against its default's kind: a finite number (> 0 for a
    rate, a total duration or a step, >= 0 for other durations), or a non-empty list of them."""
    where = f"protocol_params.{key}"
    if isinstance(default, tuple):
        if not isinstance(value, (list, tuple)) or not value:
            raise ValueError(f"{where}: must be a non-empty list of numbers, got {value!r}")
        return tuple(_number(where, v) for v in value)
    if not isinstance(default, Real):
        raise ValueError(f"{where}: cannot be set from outside (it is a {type(default).__name__})")
    x = _number(where, value)
    if key.endswith(("_hz", "_per_min")) or key in {"duration_s", "step_c"}:
        if x <= 0:
            raise ValueError(f"{where}: must be a finite number > 0, got {x:g}")
    elif key.endswith("_s") and x < 0:
        raise ValueError(f"{where}: must be a finite number >= 0, got {x:g}")
    return x


def _number(where: str, value: Any) -> float:
    """``value`` as a finite float, or a ``ValueError`` naming ``where``."""
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(float(value)):
        raise ValueError(f"{where}: must be a finite number, got {value!r}")
    return float(value)


def simulate_recording(
    sensor: str,
    protocol: str,
    device_seed: int,
    seed: int = 0,
    effects: dict[str, dict[str, float]] | None = None,
    without: tuple[str, ...] = (),
    *,
    model: SensorModel | None = None,
    **protocol_params: Any,
) -> Recording:
    """Simulate device ``device_seed`` through ``protocol``; ``seed`` draws the run's noise and
    ambient. ``effects`` changes or adds effects (``{id: {param: value}}``), ``without``
    removes some. ``model`` (e.g. a fitted :class:`~tcbench.sensors.fitted.PolynomialModel`)
    replaces the device's model; the device is then ``fitted-<sensor>`` and ``device_seed`` is
    only recorded. The sidecar's ``extra`` records everything needed to reproduce it."""
    if model is None:
        device = unit(sensor, device_seed)
    else:
        if model.kind != sensor:
            raise ValueError(f"the model is for a {model.kind}, not a {sensor}")
        device = Unit(f"fitted-{sensor}", model)
    base = device.model
    changed = base.with_effects(effects or {})
    present = [e.id for e in changed.effects]
    if unknown := [w for w in without if w not in present]:
        raise ValueError(f"without: no effect {unknown[0]!r} in the {sensor} model; its effects: {', '.join(present)}")
    model = changed.without(*without)
    profile_rng, sensor_rng, thermometer_rng = (
        np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(3)
    )
    profile = build_profile(sensor, protocol, profile_rng, **protocol_params)
    output = model.simulate(profile, sensor_rng)
    extra = {
        "protocol": protocol,
        "device_seed": int(device_seed),
        "seed": int(seed),
        "protocol_params": {k: v for k, v in protocol_params.items() if v is not None},
        "device": model.describe(),
        "effect_changes": effects or {},
        "without": list(without),
        "device_draws": device.draws,
        "scale_factor_hz_per_g": getattr(base, "scale_factor_hz_per_g", None),
        **profile.info,
    }
    return make_recording(
        profile.t_s, thermometer_reading(profile, model, thermometer_rng), profile.input, output,
        sensor=sensor, sample_rate_hz=profile.sample_rate_hz, device_id=device.device_id,
        position=profile.position, extra=_plain(extra),
    )


def thermometer_reading(profile: Profile, model: SensorModel, rng: np.random.Generator) -> np.ndarray:
    """What the sensor's thermometer reads of the profile's package temperature: its noise drawn
    from ``rng``, its resolution, then the model's thermometer-stage effects."""
    reading = rng.standard_normal(profile.t_s.size)
    reading *= THERMOMETER_NOISE_C
    reading += profile.temp_c
    return fx.thermometer_reading(list(model.effects), quantise(reading, THERMOMETER_STEP_C, in_place=True))


def _plain(value: Any) -> Any:
    """JSON-ready copy: tuples to lists, numpy scalars to Python numbers."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value
