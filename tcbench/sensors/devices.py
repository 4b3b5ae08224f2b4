"""Device populations: what every kind's units share (each kind draws its units and power-ons in
:mod:`tcbench.sensors.kinds`): a device seed draws one unit's parameters from a realistic spread.

Runs of one device differ by their run seed: a new power-on (:mod:`tcbench.sensors.runs`: the
turn-on draws below, the chamber's timing, the hysteresis state, the thermometer) and new noise;
different device seeds differ like different parts from one wafer lot. The spreads are set so the raw
metrics of the population span the seed papers' raw figures (see
``experiments/raw-sensors/README.md``); the calibration choices are stated next to each draw.
"""

from __future__ import annotations

import numpy as np


SLOPE_REPEAT = 0.01  # the temperature slope's run-to-run change, relative std (docs/concepts/split-tiers.md: about 1 %)
AGEING_DAYS = 30.0  # a run falls uniformly within this many days of the device's first


def device_rng(kind: str, device_seed: int) -> np.random.Generator:
    """The random stream of unit ``device_seed`` of ``kind`` (a non-negative integer seed)."""
    if int(device_seed) != device_seed or device_seed < 0:
        raise ValueError(f"device_seed must be a non-negative integer, got {device_seed!r}")
    return np.random.default_rng([int(device_seed), sum(map(ord, kind))])


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
