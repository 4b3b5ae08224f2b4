"""A capacitive MEMS accelerometer, the ordinary IMU's (docs/concepts/physics.md, sensor kinds): output in g.

Model (``Accel``)::

    a_out = (1 + sf0 + s1 dT + s2 dT^2) (a_eff + k2 a_eff^2) + b0 + b1 dT + b2 dT^2 + effects

with ``dT = T_die - ref_c``, ``sf0`` the scale factor's turn-on error, and ``a_eff = a cos(delta) + a_cross sin(delta)`` (misalignment
``delta``). The effects are the library's: ``thermal_lag`` (the stress state trails the on-chip
thermometer), ``hysteresis`` (package and solder stress remembers heating against cooling),
``warmup``, ``white_noise`` (velocity random walk), ``bias_instability`` (flicker) and
``quantisation`` (the LSB of the output register).

Protocols: ``chamber``, a static unit through a chamber cycle (heat, cool, heat, back to room);
``multipos``, four positions (+0g, +1g, -0g, -1g) at each temperature node; ``static``, a long
run at constant temperature (Allan variance).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from tcbench.sensors import effects as fx
from tcbench.sensors.devices import SLOPE_REPEAT, device_rng, turn_on_draws
from tcbench.sensors.kinds import SensorKind
from tcbench.sensors.models import SensorModel, Unit
from tcbench.sensors.protocols import Chamber, Profile, _from_segments, check_length, four_position_nodes
from tcbench.sensors.thermal import Segment
from tcbench.sensors.timing import current_timing

UG = 1e-6  # g per micro-g


@dataclass(frozen=True)
class Accel(SensorModel):
    """Capacitive MEMS accelerometer core (see the module docstring); output in g."""

    kind = "accel"
    sf0_ppm: float = 0.0
    bias_mg: float = 0.0
    b1_mg_per_k: float = 0.2
    b2_ug_per_k2: float = 0.0
    sf_ppm_per_k: float = 100.0
    sf2_ppm_per_k2: float = 0.0
    k2_per_g: float = 0.0
    misalignment_rad: float = 0.0

    def core(self, s: fx.Signals) -> np.ndarray:
        dt = s.temp_die_c - self.ref_c
        a_eff = s.accel_g * math.cos(self.misalignment_rad) + s.cross_g * math.sin(self.misalignment_rad)
        gain = 1.0 + self.sf0_ppm * 1e-6 + (self.sf_ppm_per_k + self.sf2_ppm_per_k2 * dt) * 1e-6 * dt
        bias = 1e-3 * (self.bias_mg + self.b1_mg_per_k * dt) + self.b2_ug_per_k2 * UG * dt * dt
        return gain * (a_eff + self.k2_per_g * a_eff * a_eff) + bias


def accel_effects(
    lag_tau_s: float = 180.0,
    hysteresis_mg: float = 0.8,
    hysteresis_width_c: float = 5.0,
    warmup_mg: float = 0.3,
    warmup_tau_s: float = 600.0,
    white_ug_per_sqrt_hz: float = 100.0,
    flicker_ug: float = 40.0,
    lsb_mg: float = 0.061,
) -> tuple[fx.Effect, ...]:
    """A consumer part's effects (docs/concepts/physics.md, sensor kinds): noise 100 µg/√Hz, flicker floor 40 µg,
    0.061 mg LSB (16 bits over ±2 g), stress hysteresis of ±0.8 mg, lag 3 min."""
    return (
        fx.ThermalLag(lag_tau_s),
        fx.Hysteresis(hysteresis_mg * 1e-3, hysteresis_width_c),
        fx.Warmup(warmup_mg * 1e-3, warmup_tau_s),
        fx.WhiteNoise(white_ug_per_sqrt_hz * UG),
        fx.BiasInstability(flicker_ug * UG),
        fx.Quantisation(lsb_mg * 1e-3),
    )


def accel_unit(device_seed: int) -> Unit:
    """One consumer accelerometer axis: zero-g offset ~15 mg, bias coefficient 0.05-0.5 mg/K
    of either sign (log-uniform), scale-factor coefficient 50-300 ppm/K, hysteresis 5-15 % of
    the bias span over 80 K, noise 70-150 µg/√Hz, flicker 20-60 µg (docs/concepts/physics.md, sensor kinds)."""
    rng = device_rng("accel", device_seed)
    sign = rng.choice([-1.0, 1.0], size=2)
    b1 = float(sign[0] * np.exp(rng.uniform(np.log(0.05), np.log(0.5))))
    draws = {
        "lag_tau_s": rng.uniform(60.0, 300.0),
        "hysteresis_mg": abs(b1) * 80.0 * rng.uniform(0.05, 0.15) / 2.0,
        "hysteresis_width_c": rng.uniform(3.0, 8.0),
        "warmup_mg": rng.normal(0.0, 0.5),
        "warmup_tau_s": rng.uniform(300.0, 1200.0),
        "white_ug_per_sqrt_hz": rng.uniform(70.0, 150.0),
        "flicker_ug": rng.uniform(20.0, 60.0),
    }
    model = Accel(
        bias_mg=rng.normal(0.0, 15.0),
        b1_mg_per_k=b1,
        b2_ug_per_k2=rng.normal(0.0, 2.0),
        sf_ppm_per_k=float(sign[1] * rng.uniform(50.0, 300.0)),
        sf2_ppm_per_k2=rng.normal(0.0, 0.5),
        k2_per_g=rng.normal(0.0, 1e-3),
        misalignment_rad=rng.normal(0.0, 5e-3),
        effects=accel_effects(**draws),
    )
    return Unit(f"accel-{device_seed:04d}", model, draws)


def accel_power_on(model: SensorModel, rng: np.random.Generator) -> tuple[SensorModel, dict[str, float]]:
    """A consumer accelerometer's power-on: turn-on bias 3 mg (std), scale factor 500 ppm, bias
    slope 1 %, ageing 20 µg per day (:func:`~tcbench.sensors.devices.turn_on_draws`)."""
    if not isinstance(model, Accel):
        return model, {}  # a fitted model: no turn-on draws of this part
    draws = turn_on_draws(rng, "mg", 3.0, 500.0, SLOPE_REPEAT, 0.02)
    return dataclasses.replace(
        model, bias_mg=model.bias_mg + draws["turn_on_bias_mg"] + draws["aged_mg"],
        sf0_ppm=model.sf0_ppm + draws["scale_factor_ppm"],
        b1_mg_per_k=model.b1_mg_per_k * (1.0 + draws["slope_change"]),
    ), draws


def _gravity(gravity_g: float) -> tuple[float, float]:
    """(along, across) the axis for a static unit with ``gravity_g`` of gravity along it."""
    if not -1.0 <= gravity_g <= 1.0:
        raise ValueError(f"protocol_params.gravity_g: must be within -1..1 g, got {gravity_g:g}")
    return gravity_g, math.sqrt(1.0 - gravity_g * gravity_g)


def chamber(
    levels_c: tuple[float, ...] = (60.0, -20.0, 60.0, 25.0),
    soak_s: float = 1800.0,
    room_c: float = 25.0,
    room_s: float = 1200.0,
    gravity_g: float = 0.0,
    sample_rate_hz: float = 1.0,
    ramp_c_per_min: float = 1.0,
) -> Profile:
    """A static unit through a chamber cycle: ``room_s`` at ``room_c``, then each of ``levels_c``
    held ``soak_s`` (ramps at ``ramp_c_per_min`` between), so every temperature between the
    extremes is passed heating and cooling. ``gravity_g`` is the gravity component along the
    axis (0 for a horizontal axis, 1 for one pointing down)."""
    along, across = _gravity(gravity_g)
    segments = [Segment(room_c, room_s, "", along, across)]
    segments += [Segment(float(level), soak_s, "", along, across) for level in levels_c]
    return _from_segments("chamber", "accel", segments, room_c, sample_rate_hz, Chamber(ramp_c_per_min=ramp_c_per_min))


def multipos(
    nodes_c: tuple[float, ...] = (-20.0, 0.0, 20.0, 40.0, 60.0),
    soak_s: float = 1800.0,
    position_s: float = 60.0,
    move_s: float = 10.0,
    start_c: float = 25.0,
    sample_rate_hz: float = 1.0,
) -> Profile:
    """The multi-position test: at each node a soak, then +0g, +1g, -0g, -1g (four faces of
    the six, the two others repeating +0g and -0g for this axis)."""
    return four_position_nodes("multipos", "accel", nodes_c, soak_s, position_s, move_s, start_c, sample_rate_hz,
                               Chamber())


def static(duration_s: float = 7200.0, temp_c: float = 25.0, gravity_g: float = 0.0,
           sample_rate_hz: float = 100.0) -> Profile:
    """A long run at rest and constant temperature (Allan variance)."""
    check_length(duration_s, sample_rate_hz)
    temp_c += current_timing().start_offset_c
    along, across = _gravity(gravity_g)
    t = np.arange(0.0, duration_s, 1.0 / sample_rate_hz)
    zeros = np.broadcast_to(np.float64(0.0), t.shape)
    return Profile("static", "accel", sample_rate_hz, t, np.broadcast_to(np.float64(temp_c), t.shape),
                   np.broadcast_to(np.float64(along), t.shape), np.broadcast_to(np.float64(across), t.shape), zeros)


KIND = SensorKind(
    name="accel",
    title="capacitive MEMS accelerometer (output in g)",
    input_unit="g",
    output_unit="g",
    input_field="accel_g",
    input_range=(-1000.0, 1000.0),
    output_range=(-1000.0, 1000.0),
    device=accel_unit,
    power_on=accel_power_on,
    protocols={"chamber": chamber, "multipos": multipos, "static": static},
    positions=True,
    noise_unit="µg",
    noise_scale=1e6,
    ulog_topic="sensor_accel",
    ulog_unit="m/s^2",
    px4_letter="A",
    px4_cal="ACC",
    ardupilot_letters="ACC",
    # the noise density in µg/√Hz as a velocity random walk in m/s/√h: 1e-6 g0 m/s^2 per µg, 60 √s per √h
    extra={"random_walk": {"vrw_m_per_s_per_sqrt_h": 9.80665e-6 * 60.0}},
)
