"""Device populations: a device seed draws one unit's parameters from a realistic spread.

Runs of one device differ by their run seed: a new power-on (:mod:`tcbench.sensors.runs`: the
turn-on draws below, the chamber's timing, the hysteresis state, the thermometer) and new noise;
different device seeds differ like different parts from one wafer lot. The spreads are set so the raw
metrics of the population span the seed papers' raw figures (see
``experiments/raw-sensors/README.md``); the calibration choices are stated next to each draw.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from tcbench.sensors import kinds
from tcbench.sensors.models import MSRA, Gyro, SensorModel, Unit, gyro_effects, msra_effects

SLOPE_REPEAT = 0.01  # the temperature slope's run-to-run change, relative std (PHYSICS.md §9: about 1 %)
MSRA_SLOPE_REPEAT = 0.001  # a resonant part's (see msra_power_on)
AGEING_DAYS = 30.0  # a run falls uniformly within this many days of the device's first


def device_rng(kind: str, device_seed: int) -> np.random.Generator:
    """The random stream of unit ``device_seed`` of ``kind`` (a non-negative integer seed)."""
    if int(device_seed) != device_seed or device_seed < 0:
        raise ValueError(f"device_seed must be a non-negative integer, got {device_seed!r}")
    return np.random.default_rng([int(device_seed), sum(map(ord, kind))])


def msra_unit(device_seed: int) -> Unit:
    """One MSRA. Residual common-mode mismatch ``m`` of the resonators' frequency coefficients
    (11-15 %, giving dU/dT of about -0.16 Hz/K, ~800 micro-g/K of bias) and a log-uniform
    scale-factor coefficient gK in 60-600 ppm/K (scale-factor variation 2 000-20 000 ppm over
    -40..60 degC) are the draws that set the full-temperature figures."""
    rng = device_rng("msra", device_seed)
    f0_1 = 30000.0 + rng.normal(0.0, 30.0)
    f0 = (f0_1, f0_1 - rng.normal(150.0, 20.0))
    k = tuple(100.0 * (1.0 + rng.normal(0.0, 0.02, 2)))
    tce = -30.0 + rng.normal(0.0, 2.0)
    stress_1 = -10.0 + rng.normal(0.0, 2.0)
    mismatch = rng.uniform(0.11, 0.15)
    c1_1 = tce + stress_1
    c1_2 = c1_1 * (1.0 - mismatch) * f0[0] / f0[1]  # f0_2 c1_2 = (1 - m) f0_1 c1_1
    c2_1 = -20.0 + rng.normal(0.0, 3.0)
    gk = float(np.exp(rng.uniform(np.log(60.0), np.log(600.0))))
    draws = {
        "mismatch": mismatch, "gk_ppm_per_k": gk, "lag_tau_s": rng.uniform(360.0, 840.0),
        "white_ug": rng.uniform(10.0, 14.0), "flicker_ug": rng.uniform(3.5, 6.5),
    }
    model = MSRA(
        f0_hz=f0,
        k_hz_per_g=k,  # type: ignore[arg-type]
        tce_ppm_per_k=(tce, tce),
        stress_ppm_per_k=(stress_1, c1_2 - tce),
        c2_ppb_per_k2=(c2_1, c2_1 * (1.0 + rng.normal(0.0, 0.03))),
        gk_ppm_per_k=gk,
        misalignment_rad=rng.normal(0.0, 1e-3),
        effects=msra_effects(f0, k, draws["lag_tau_s"], draws["white_ug"], draws["flicker_ug"]),  # type: ignore[arg-type]
    )
    return Unit(f"msra-{device_seed:04d}", model, draws)


def gyro_unit(device_seed: int) -> Unit:
    """One dual-mass gyroscope around PHYSICS.md §6's defaults (bias 1.10 u + 4.0e-3 u^2 +
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


def turn_on_draws(rng: np.random.Generator, unit: str, bias_std: float, scale_factor_ppm_std: float,
                  slope_repeat: float, ageing_std_per_day: float) -> dict[str, float]:
    """One power-on's draws (bias and ageing in ``unit``): the days since the device's first run
    (uniform up to :data:`AGEING_DAYS`), the turn-on bias, the scale factor's turn-on error (ppm),
    the temperature slope's relative change, and the bias aged by over those days."""
    days = float(rng.uniform(0.0, AGEING_DAYS))
    return {f"turn_on_bias_{unit}": float(rng.normal(0.0, bias_std)),
            "scale_factor_ppm": float(rng.normal(0.0, scale_factor_ppm_std)),
            "slope_change": float(rng.normal(0.0, slope_repeat)), "days": days,
            f"aged_{unit}": days * float(rng.normal(0.0, ageing_std_per_day))}


def msra_power_on(model: SensorModel, rng: np.random.Generator) -> tuple[SensorModel, dict[str, float]]:
    """An MSRA's power-on: turn-on bias 100 µg (std; resonator 1's frequency moved), scale factor
    50 ppm, bias slope 0.1 %, ageing 2 µg per day over up to :data:`AGEING_DAYS` days. A resonant
    part sits at the repeatable end of PHYSICS.md §9's ranges: seed 000's zero-bias stability is
    110-190 µg, and its compensated test sets' bias variation (33-37 µg over a 39 000 µg span, Table 2)
    bounds the slope's run-to-run change near 0.1 %."""
    if not isinstance(model, MSRA):
        return model, {}  # a fitted model: no turn-on draws of this part
    sf = model.scale_factor_hz_per_g
    draws = turn_on_draws(rng, "ug", 100.0, 50.0, MSRA_SLOPE_REPEAT, 2.0)
    f0_1, f0_2 = model.f0_hz
    c1 = [t + s for t, s in zip(model.tce_ppm_per_k, model.stress_ppm_per_k, strict=True)]
    slope_hz_per_k = (f0_1 * c1[0] - f0_2 * c1[1]) * 1e-6
    shift_hz = (draws["turn_on_bias_ug"] + draws["aged_ug"]) * 1e-6 * sf
    stress_1 = model.stress_ppm_per_k[0] + draws["slope_change"] * slope_hz_per_k / f0_1 * 1e6
    return dataclasses.replace(
        model, f0_hz=(f0_1 + shift_hz, f0_2),
        k_hz_per_g=tuple(k * (1.0 + draws["scale_factor_ppm"] * 1e-6) for k in model.k_hz_per_g),  # type: ignore[arg-type]
        stress_ppm_per_k=(stress_1, model.stress_ppm_per_k[1]),
    ), draws


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


def unit(sensor: str, device_seed: int) -> Unit:
    """The unit ``device_seed`` of sensor kind ``sensor`` (:mod:`tcbench.sensors.kinds`)."""
    device: Unit = kinds.get(sensor).device(device_seed)
    return device
