"""What differs between runs of one device (docs/concepts/split-tiers.md): a new run is a new power-on.

Two runs of one device under one chamber programme are not one signal with new noise. A run's
*power-on* (its seed, :func:`power_on`) draws:

- the **turn-on** state of the sensor (its kind's :attr:`~tcbench.sensors.kinds.SensorKind.power_on`):
  bias and scale-factor repeatability, a small change of the temperature slope, and the bias the
  part has aged by since its first run (a slow trend over the days between runs);
- the **hysteresis state** the thermal history before the run left (stored cold or warm): the
  ``hysteresis`` effect's starting state, uniform in -1..1;
- the **chamber timing**: ramp rate within the controller's ±10 %, soak lengths ±5 %, and the
  start point (±0.3 °C; for a room-temperature run, another day's ambient, ±1 °C, and
  self-heating ±15 %);
- the **thermometer's** run-to-run part: where the on-die thermometer sits apart from the sensing
  element is a property of the device (:func:`placement`: an offset of 1-3 °C and a gradient of
  0.1-1 °C per °C/min of heat flow); a run moves the offset by ±0.2 °C and the gradient by ±10 %.

The sizes per kind are in each kind's module; ``experiments/raw-sensors/`` compares the spread of
the simulated runs with seed 000's test-set pairs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tcbench.sensors import kinds
from tcbench.sensors.models import SensorModel
from tcbench.sensors.timing import Timing, draw_timing

THERMOMETER_OFFSET_JITTER_C = 0.2  # the thermometer offset's run-to-run part, std
THERMOMETER_GRADIENT_JITTER = 0.10  # the thermometer gradient's run-to-run part, relative std


@dataclass(frozen=True)
class Placement:
    """Where a device's thermometer sits apart from its sensing element: it reads the package
    temperature plus ``offset_c`` plus ``gradient_c_per_c_per_min`` times the package's rate of
    change (°C/min; the heat flow through the package sets the gradient)."""

    offset_c: float = 0.0
    gradient_c_per_c_per_min: float = 0.0

    def reading_c(self, package_c: np.ndarray, dt_s: float) -> np.ndarray:
        """The thermometer's noise-free reading of ``package_c`` sampled every ``dt_s``."""
        p = np.asarray(package_c, dtype=np.float64)
        if p.size < 2 or self.gradient_c_per_c_per_min == 0.0:
            return p + self.offset_c
        return p + self.offset_c + self.gradient_c_per_c_per_min * 60.0 * np.gradient(p, dt_s)

    def package_c(self, reading_c: np.ndarray, dt_s: float) -> np.ndarray:
        """The package temperature this placement's reading implies (its first-order inverse)."""
        r = np.asarray(reading_c, dtype=np.float64) - self.offset_c
        if r.size < 2 or self.gradient_c_per_c_per_min == 0.0:
            return r
        return r - self.gradient_c_per_c_per_min * 60.0 * np.gradient(r, dt_s)


@dataclass(frozen=True)
class PowerOn:
    """One run's power-on: the seed it was drawn from, the chamber timing, the hysteresis state,
    the thermometer's placement this run, and the kind's turn-on draws (name -> value)."""

    seed: int
    timing: Timing
    hysteresis_state: float
    placement: Placement
    turn_on: dict[str, float]

    def describe(self) -> dict[str, object]:
        """Plain data for the sidecar."""
        t = self.timing
        return {
            "seed": self.seed, "ramp_scale": t.ramp_scale, "soak_scale": list(t.soak_scale[:8]),
            "start_offset_c": t.start_offset_c, "ambient_offset_c": t.ambient_offset_c,
            "self_heating_scale": t.self_heating_scale, "reverse": t.reverse,
            "hysteresis_state": self.hysteresis_state,
            "thermometer_offset_c": self.placement.offset_c,
            "thermometer_gradient_c_per_c_per_min": self.placement.gradient_c_per_c_per_min,
            "turn_on": dict(self.turn_on),
        }


def _kind_code(kind: str) -> int:
    return sum(map(ord, kind))


def placement(kind: str, device_seed: int) -> Placement:
    """Device ``device_seed``'s thermometer placement, from its own stream (the device's other
    draws are unchanged by it)."""
    rng = np.random.default_rng([int(device_seed), _kind_code(kind), 9])
    sign = 1.0 if rng.random() < 0.5 else -1.0
    return Placement(float(sign * rng.uniform(1.0, 3.0)), float(rng.uniform(0.1, 1.0)))


def power_on_rng(kind: str, device_seed: int, seed: int) -> np.random.Generator:
    """The stream of run ``seed``'s power-on of device ``device_seed``: its own, apart from the
    streams of the run's noise (``SeedSequence(seed)``'s children), and different for each device,
    so two devices' runs of one seed are not one draw."""
    return np.random.default_rng([int(seed), int(device_seed), _kind_code(kind), 4])


def power_on(sensor: str, model: SensorModel, seed: int, device: Placement,
             device_seed: int = 0, sensor_varies: bool = True) -> tuple[SensorModel, PowerOn]:
    """Run ``seed``'s power-on of device ``device_seed``, whose model is ``model`` and whose
    thermometer sits at ``device``: the model as it runs this time and what was drawn. With
    ``sensor_varies`` False (a fitted model, which describes one record as its thermometer read it)
    only the chamber's timing varies."""
    rng = power_on_rng(sensor, device_seed, seed)
    timing = draw_timing(rng)
    state = float(rng.uniform(-1.0, 1.0))
    run_placement = Placement(
        device.offset_c + float(rng.normal(0.0, THERMOMETER_OFFSET_JITTER_C)),
        device.gradient_c_per_c_per_min * float(1.0 + rng.normal(0.0, THERMOMETER_GRADIENT_JITTER)),
    )
    if not sensor_varies:
        return model, PowerOn(int(seed), timing, 0.0, device, {})
    (turn_rng,) = rng.spawn(1)  # the kind's draws after the shared ones, so a kind cannot shift them
    draw = kinds.get(sensor).power_on
    run_model, turn_on = draw(model, turn_rng) if draw is not None else (model, {})
    if run_model.effect("hysteresis") is not None:
        run_model = run_model.with_effects({"hysteresis": {"start_state": state}})
    return run_model, PowerOn(int(seed), timing, state, run_placement, dict(turn_on))
