"""Simulate a recording: a device (from its seed) run through a protocol; the run seed draws a new
power-on (:mod:`tcbench.sensors.runs`) and new noise."""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Callable
from numbers import Real
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.sensors import effects as fx
from tcbench.errors import unknown_name
from tcbench.sensors import kinds
from tcbench.sensors.models import SensorModel, Unit
from tcbench.sensors.noise import quantise
from tcbench.sensors.protocols import Profile
from tcbench.sensors.recording import Recording, make_recording
from tcbench.sensors.runs import Placement, PowerOn, placement
from tcbench.sensors.runs import power_on as draw_power_on
from tcbench.sensors.timing import running

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
        raise ValueError(unknown_name("protocol", protocol, names, f" for {sensor}"))
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


@dataclass(frozen=True)
class Run:
    """One simulated run, ready to draw: the device's model with the run's changes (``nominal``),
    the model as it runs this power-on (``model``), the profile, the power-on, the device's
    thermometer placement, and the noise streams."""

    device: Unit
    nominal: SensorModel
    model: SensorModel
    profile: Profile
    power_on: PowerOn
    placement: Placement
    sensor_rng: np.random.Generator
    thermometer_rng: np.random.Generator


def prepare_run(
    sensor: str,
    protocol: str,
    device_seed: int,
    seed: int = 0,
    effects: dict[str, dict[str, float]] | None = None,
    without: tuple[str, ...] | list[str] = (),
    *,
    model: SensorModel | None = None,
    power_on: int | None = None,
    reverse: bool = False,
    ramp_scale: float = 1.0,
    **protocol_params: Any,
) -> Run:
    """The run :func:`simulate_recording` draws (its arguments); :func:`~tcbench.sensors.truth.simulate_truth`
    rebuilds the same one."""
    if model is None:
        device = kinds.unit(sensor, device_seed)
        device_placement = placement(sensor, device_seed)
    else:
        if model.kind != sensor:
            raise ValueError(f"the model is for a {model.kind}, not a {sensor}")
        device = Unit(f"fitted-{sensor}", model)
        device_placement = Placement()  # a fitted model was fitted on its thermometer's reading
    if not (isinstance(ramp_scale, Real) and math.isfinite(ramp_scale) and ramp_scale > 0):
        raise ValueError(f"ramp_scale must be a finite number > 0, got {ramp_scale!r}")
    changed = device.model.with_effects(effects or {})
    present = [e.id for e in changed.effects]
    if unknown := [w for w in without if w not in present]:
        raise ValueError(f"without: no effect {unknown[0]!r} in the {sensor} model; its effects: {', '.join(present)}")
    nominal = changed.without(*without)
    run_model, drawn = draw_power_on(sensor, nominal, seed if power_on is None else int(power_on), device_placement,
                                     int(device_seed), sensor_varies=model is None)
    timing = dataclasses.replace(drawn.timing, reverse=bool(reverse), ramp_scale=drawn.timing.ramp_scale * ramp_scale)
    drawn = dataclasses.replace(drawn, timing=timing)
    profile_rng, sensor_rng, thermometer_rng = (
        np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(3)
    )
    with running(timing):
        profile = build_profile(sensor, protocol, profile_rng, **protocol_params)
    return Run(device, nominal, run_model, profile, drawn, device_placement, sensor_rng, thermometer_rng)


def simulate_recording(
    sensor: str,
    protocol: str,
    device_seed: int,
    seed: int = 0,
    effects: dict[str, dict[str, float]] | None = None,
    without: tuple[str, ...] = (),
    *,
    model: SensorModel | None = None,
    power_on: int | None = None,
    reverse: bool = False,
    ramp_scale: float = 1.0,
    **protocol_params: Any,
) -> Recording:
    """Simulate device ``device_seed`` through ``protocol``. ``seed`` selects the run: a new
    power-on (:mod:`tcbench.sensors.runs`: turn-on bias and scale factor, hysteresis state,
    chamber timing, the thermometer's run part) and new noise; ``power_on`` takes the power-on of
    another run (``power_on=s``: run ``s`` replayed with this run's noise, the ``replay`` tier).
    ``reverse`` runs the programme's holds in reverse order and ``ramp_scale`` scales its ramp rate
    (a profile the training never saw). ``effects`` changes or adds effects (``{id: {param:
    value}}``), ``without`` removes some. ``model`` (e.g. a fitted
    :class:`~tcbench.sensors.fitted.PolynomialModel`) replaces the device's model; the device is
    then ``fitted-<sensor>``, ``device_seed`` is only recorded, and only the chamber's timing varies
    between runs (the model describes one record as its thermometer read it). The sidecar's
    ``extra`` records everything needed to reproduce it."""
    run = prepare_run(sensor, protocol, device_seed, seed, effects, without, model=model, power_on=power_on,
                      reverse=reverse, ramp_scale=ramp_scale, **protocol_params)
    model, profile = run.model, run.profile
    output = model.simulate(profile, run.sensor_rng)
    extra = {
        "protocol": protocol,
        "device_seed": int(device_seed),
        "seed": int(seed),
        "protocol_params": {k: v for k, v in protocol_params.items() if v is not None},
        "device": model.describe(),
        "effect_changes": effects or {},
        "without": list(without),
        "device_draws": run.device.draws,
        "power_on": run.power_on.describe(),
        "programme_changes": {"reverse": bool(reverse), "ramp_scale": float(ramp_scale)},
        "scale_factor_hz_per_g": getattr(run.device.model, "scale_factor_hz_per_g", None),
        **profile.info,
    }
    return make_recording(
        profile.t_s, thermometer_reading(profile, model, run.thermometer_rng, run.power_on.placement), kinds.profile_input(profile),
        output, sensor=sensor, sample_rate_hz=profile.sample_rate_hz, device_id=run.device.device_id,
        position=profile.position, extra=_plain(extra),
    )


def thermometer_reading(profile: Profile, model: SensorModel, rng: np.random.Generator,
                        where: Placement = Placement()) -> np.ndarray:
    """What the sensor's thermometer reads of the profile's package temperature: through its
    placement ``where`` (offset, gradient with the heat flow), its noise drawn from ``rng``, its
    resolution, then the model's thermometer-stage effects."""
    reading = rng.standard_normal(profile.t_s.size)
    reading *= THERMOMETER_NOISE_C
    reading += where.reading_c(profile.temp_c, profile.dt_s)
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
