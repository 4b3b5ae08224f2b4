"""Sensor models: a physical core plus a list of named effects (docs/concepts/physics.md).

:class:`MSRA` — two double-ended tuning-fork resonators in differential configuration; output
``U = f1 - f2`` in Hz. :class:`Gyro` — a dual-mass vibratory gyroscope; output rate in deg/s.
Both cores take the *die* temperature, which the ``thermal_lag`` effect (if present) lets trail
the thermometer; every other departure from the core is an effect in ``effects``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tcbench.sensors import effects as fx
from tcbench.sensors.protocols import Profile

DPH = 1.0 / 3600.0  # deg/s per deg/h


def _temperature_rate(temp_c: np.ndarray, dt_s: float) -> np.ndarray:
    """dT/dt per sample; a constant temperature gives a broadcast zero, not a full array."""
    if temp_c.size < 2 or temp_c.strides == (0,) or np.ptp(temp_c) == 0.0:
        return np.broadcast_to(np.float64(0.0), temp_c.shape)
    return np.gradient(temp_c, dt_s)


def _signals(profile: Profile, ref_c: float) -> fx.Signals:
    rate = _temperature_rate(profile.temp_c, profile.dt_s)
    return fx.Signals(
        t_s=profile.t_s, dt_s=profile.dt_s, temp_meas_c=profile.temp_c,
        temp_die_c=profile.temp_c, temp_rate_c_per_s=rate, accel_g=profile.accel_g,
        cross_g=profile.cross_g, rate_dps=profile.rate_dps, ref_c=ref_c,
    )


@dataclass(frozen=True)
class SensorModel:
    """Shared simulation flow: die temperature, physical core, then the effects in order."""

    ref_c: float = 25.0
    effects: tuple[fx.Effect, ...] = ()
    kind = ""

    def core(self, s: fx.Signals) -> np.ndarray:
        """Noise-free output of the physical core at the die temperature (output unit)."""
        raise NotImplementedError

    def simulate(self, profile: Profile, rng: np.random.Generator) -> np.ndarray:
        """Output for ``profile``; every random draw comes from ``rng``."""
        if profile.sensor != self.kind:
            raise ValueError(f"protocol {profile.name!r} is for a {profile.sensor}, not a {self.kind}")
        s = _signals(profile, self.ref_c)
        s.temp_die_c = fx.die_temperature(list(self.effects), s)
        return fx.apply_effects(self.core(s), list(self.effects), s, rng)

    def effect(self, effect_id: str) -> fx.Effect | None:
        """The effect with that id, if the model has it."""
        return next((e for e in self.effects if e.id == effect_id), None)

    def without(self, *effect_ids: str) -> SensorModel:
        """The same model with those effects removed."""
        return dataclasses.replace(self, effects=tuple(e for e in self.effects if e.id not in effect_ids))

    def with_effects(self, changes: dict[str, dict[str, float]]) -> SensorModel:
        """The model with effects changed or added: ``{effect_id: {param: value}}``. An existing
        effect keeps its other parameters; a new one is added before the ``final`` stage."""
        current = list(self.effects)
        for effect_id, params in changes.items():
            mine = self.effect(effect_id)
            if mine is None:
                new = fx.make_effect(effect_id, **params)
                at = next((i for i, e in enumerate(current) if e.stage == fx.FINAL), len(current))
                current.insert(at, new)
            else:
                merged = mine.params() | dict(params)
                current[current.index(mine)] = fx.make_effect(effect_id, **merged)
        return dataclasses.replace(self, effects=tuple(current))

    def describe(self) -> dict[str, Any]:
        """Parameters and effects as plain data (for sidecars and tracking)."""
        core = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "effects"}
        return {"model": self.kind, **core, "effects": {e.id: e.params() for e in self.effects}}


@dataclass(frozen=True)
class MSRA(SensorModel):
    """Differential resonant accelerometer (docs/concepts/physics.md, sensor kinds); pairs are (resonator 1, resonator 2).

    ``f_i = f0_i (1 + c1_i dT + c2_i dT^2) + s_i K_i (1 + gK dT) a_eff``, ``s = (+1, -1)``,
    with ``c1_i = tce_i + stress_i`` (Young's modulus and CTE-mismatch thermal stress) and
    ``a_eff = a cos(delta) + a_cross sin(delta)`` (misalignment ``delta``). The
    ``accel_nonlinearity`` effect carries the residual ``(k2_1 - k2_2) a^2``.
    """

    kind = "msra"
    f0_hz: tuple[float, float] = (30000.0, 29850.0)
    k_hz_per_g: tuple[float, float] = (100.0, 100.0)
    tce_ppm_per_k: tuple[float, float] = (-30.0, -30.0)
    stress_ppm_per_k: tuple[float, float] = (-10.0, -3.7)
    c2_ppb_per_k2: tuple[float, float] = (-20.0, -20.5)
    gk_ppm_per_k: float = 60.0
    misalignment_rad: float = 1e-3

    @property
    def scale_factor_hz_per_g(self) -> float:
        """Nominal scale factor of the difference output at the reference temperature."""
        return float(sum(self.k_hz_per_g))

    def core(self, s: fx.Signals) -> np.ndarray:
        dt = s.temp_die_c - self.ref_c
        a_eff = s.accel_g * np.cos(self.misalignment_rad) + s.cross_g * np.sin(self.misalignment_rad)
        gain = 1.0 + self.gk_ppm_per_k * 1e-6 * dt
        out = np.zeros_like(dt)
        for sign, f0, k, tce, stress, c2 in zip(
            (1.0, -1.0), self.f0_hz, self.k_hz_per_g, self.tce_ppm_per_k,
            self.stress_ppm_per_k, self.c2_ppb_per_k2, strict=True,
        ):
            f = f0 * (1.0 + (tce + stress) * 1e-6 * dt + c2 * 1e-9 * dt * dt) + sign * k * gain * a_eff
            out += sign * f
        return out


def msra_effects(
    f0_hz: tuple[float, float] = (30000.0, 29850.0),
    k_hz_per_g: tuple[float, float] = (100.0, 100.0),
    lag_tau_s: float = 600.0,
    white_ug: float = 12.0,
    flicker_ug: float = 5.0,
    counter_step_hz: float = 1e-4,
) -> tuple[fx.Effect, ...]:
    """Default MSRA effects; noise in micro-g (white: per sqrt(Hz), i.e. per 1 Hz sample),
    converted to Hz with the nominal scale factor."""
    sf = sum(k_hz_per_g)
    k2 = [-(k * k) / (2.0 * f0) for k, f0 in zip(k_hz_per_g, f0_hz, strict=True)]
    return (
        fx.ThermalLag(lag_tau_s),
        fx.AccelNonlinearity(k2[0] - k2[1]),
        fx.WhiteNoise(white_ug * 1e-6 * sf),
        fx.BiasInstability(flicker_ug * 1e-6 * sf),
        fx.Quantisation(counter_step_hz),
    )


@dataclass(frozen=True)
class Gyro(SensorModel):
    """Dual-mass vibratory gyroscope (docs/concepts/physics.md, sensor kinds).

    ``w_out = (1 + sf0 + sf dT) (W + b0 + b1 dT + b2 dT^2)`` with ``dT = T_die - ref`` and the
    bias in deg/h; ``sf0`` is the scale factor's turn-on error; the cubic and rate terms, lag and
    noise are effects.
    """

    kind = "gyro"
    sf0_ppm: float = 0.0
    sf_ppm_per_k: float = -280.0
    b0_dph: float = 0.0
    b1_dph_per_k: float = 1.10
    b2_dph_per_k2: float = 4.0e-3

    def core(self, s: fx.Signals) -> np.ndarray:
        # In place, two full-length temporaries at most; the same floating-point operations, in
        # the same order, as (1 + sf dT) (W + (b0 + b1 dT + b2 dT dT) DPH).
        dt = s.temp_die_c - self.ref_c
        out = self.b1_dph_per_k * dt
        out += self.b0_dph
        square = self.b2_dph_per_k2 * dt
        square *= dt
        out += square
        del square
        out *= DPH
        out += s.rate_dps
        dt *= self.sf_ppm_per_k * 1e-6
        dt += 1.0 + self.sf0_ppm * 1e-6
        out *= dt
        return out


def gyro_effects(
    lag_tau_s: float = 480.0,
    c3_dph_per_k3: float = 1.5e-4,
    rate_dph_per_c_per_min: float = 3.0,
    arw_deg_per_sqrt_h: float = 0.52,
    bias_instability_dph: float = 33.0,
    adc_step_dps: float = 0.0,
) -> tuple[fx.Effect, ...]:
    """Default gyro effects from figures in deg/h units (experiments/raw-sensors/README.md)."""
    return (
        fx.ThermalLag(lag_tau_s),
        fx.TemperatureCubic(c3_dph_per_k3 * DPH),
        fx.TemperatureRate(rate_dph_per_c_per_min * DPH * 60.0),
        fx.WhiteNoise(arw_deg_per_sqrt_h / 60.0),  # deg/sqrt(h) -> deg/s per sqrt(Hz)
        fx.BiasInstability(bias_instability_dph * DPH),
        fx.Quantisation(adc_step_dps),
    )


@dataclass(frozen=True)
class Unit:
    """One simulated device: its model and where it came from."""

    device_id: str
    model: SensorModel
    draws: dict[str, float] = field(default_factory=dict)
