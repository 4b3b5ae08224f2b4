"""Metrics of any sensor kind, in the unit its bias and noise are quoted in (the kind's
``noise_unit``: µg for an accelerometer).

- bias stability: 1 sigma (ddof=1) of non-overlapping 10 s means of the bias (output minus the
  applied input) over the whole record; at constant temperature the run-to-run-free "(1 sigma,
  10 s)" figure, over a chamber cycle mostly the temperature drift.
- noise density (the velocity or angle random walk): the Allan deviation's -1/2 line read at
  tau = 1 s (unit per sqrt(Hz)); bias instability: the Allan minimum / 0.664, with
  ``allan_min_is_interior`` saying whether that minimum is a floor or an end of the curve.
- bias against temperature: the least-squares line through the mean bias in temperature bins
  (or per burst), its slope per degC with the standard error.
- hysteresis: the bias of the cooling branches minus that of the heating branches
  (:mod:`tcbench.signal.branches`), compared in 1 degC bins where both have samples; the width
  is the largest absolute difference, the mean its signed average. A lag of the die behind the
  thermometer opens the same loop, so this is the apparent hysteresis an observer of the
  thermometer sees.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.metrics.accelerometer import zero_bias_stability_ug
from tcbench.metrics.gyro import RateTemperatureFit, rate_vs_temperature
from tcbench.sensors.kinds import SensorKind
from tcbench.signal.allan import AllanDeviation, NoiseParameters, allan_deviation, allan_deviation_segments, noise_parameters
from tcbench.signal.branches import temperature_branches

HYSTERESIS_BIN_C = 1.0
HYSTERESIS_MIN_SAMPLES = 10  # per bin and direction
STABILITY_WINDOW_S = 10.0


def token(unit: str) -> str:
    """A unit as it appears in a metric's name: ``µg`` -> ``ug``, ``°/h`` -> ``dph``."""
    special = {"°/h": "dph", "°/s": "dps", "deg/s": "dps", "deg/h": "dph"}
    return special.get(unit, unit.replace("µ", "u").replace("/", "_per_").replace(" ", "").lower())


@dataclass(frozen=True)
class Hysteresis:
    """Cooling-minus-heating bias per 1 degC bin (noise unit) and its summary."""

    temperature_c: np.ndarray
    difference: np.ndarray
    width: float
    mean: float

    def as_dict(self) -> dict[str, Any]:
        return {"width": self.width, "mean": self.mean, "temperature_c": self.temperature_c.tolist(),
                "cooling_minus_heating": self.difference.tolist()}


def hysteresis(t_s: np.ndarray, temp_c: np.ndarray, bias: np.ndarray, min_swing_c: float = 5.0) -> Hysteresis | None:
    """The bias's hysteresis between heating and cooling, or ``None`` without both directions
    over at least two common 1 degC bins."""
    branches = temperature_branches(t_s, temp_c, min_swing_c)
    direction = np.zeros(temp_c.size)
    for b in branches:
        if b.span_c >= min_swing_c:
            direction[b.start:b.stop] = 1.0 if b.direction == "heating" else -1.0
    heat, cool = direction > 0, direction < 0
    if not (heat.any() and cool.any()):
        return None
    lo = max(temp_c[heat].min(), temp_c[cool].min())
    hi = min(temp_c[heat].max(), temp_c[cool].max())
    if hi - lo < 2 * HYSTERESIS_BIN_C:
        return None
    edges = np.arange(lo, hi + HYSTERESIS_BIN_C, HYSTERESIS_BIN_C)

    def binned(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n, _ = np.histogram(temp_c[mask], edges)
        s, _ = np.histogram(temp_c[mask], edges, weights=bias[mask])
        return n, s / np.maximum(n, 1)

    n_heat, m_heat = binned(heat)
    n_cool, m_cool = binned(cool)
    ok = (n_heat >= HYSTERESIS_MIN_SAMPLES) & (n_cool >= HYSTERESIS_MIN_SAMPLES)
    if ok.sum() < 2:
        return None
    diff = (m_cool - m_heat)[ok]
    centre = 0.5 * (edges[:-1] + edges[1:])[ok]
    return Hysteresis(centre, diff, float(np.max(np.abs(diff))), float(np.mean(diff)))


@dataclass
class KindMetrics:
    """The scalars, the Allan curve and read-offs, the bias-temperature line and the loop."""

    metrics: dict[str, float]
    ad: AllanDeviation
    params: NoiseParameters
    fit: RateTemperatureFit | None
    loop: Hysteresis | None
    bias: np.ndarray


def kind_metrics(kind: SensorKind, t_s: np.ndarray, temp_c: np.ndarray, applied: np.ndarray, output: np.ndarray,
                 fs_hz: float, segment: np.ndarray | None = None) -> KindMetrics:
    """Every metric of the module docstring for a recording of ``kind``, named with its noise
    unit (``bias_stability_ug``, ``noise_density_ug_per_sqrt_hz``, ...)."""
    u, scale = token(kind.noise_unit), kind.noise_scale
    bias = (output - applied) * scale
    metrics: dict[str, float] = {}
    try:  # the stability helper works in micro-units of its input: divide the scale back out
        metrics[f"bias_stability_{u}"] = zero_bias_stability_ug(t_s, bias * 1e-6, 1.0, 0.0, STABILITY_WINDOW_S)
    except ValueError:
        metrics[f"bias_stability_{u}"] = float("nan")
    ad = (allan_deviation(bias, fs_hz, "octave") if segment is None
          else allan_deviation_segments(bias, fs_hz, segment))
    p = noise_parameters(ad)
    metrics |= {
        f"noise_density_{u}_per_sqrt_hz": p.angle_random_walk,
        f"bias_instability_{u}": p.bias_instability,
        f"allan_min_{u}": p.adev_min,
        "allan_min_tau_s": p.tau_min_s,
        "allan_min_is_interior": float(p.min_is_interior),
    }
    for name, factor in kind.extra.get("random_walk", {}).items():
        metrics[name] = p.angle_random_walk * factor
    fit = rate_vs_temperature(temp_c, bias, segment)
    if fit is not None:
        metrics |= {f"bias_temp_slope_{u}_per_c": fit.slope_dps_per_c,
                    f"bias_temp_slope_se_{u}_per_c": fit.slope_stderr_dps_per_c, "bias_temp_r": fit.r}
    loop = hysteresis(t_s, temp_c, bias)
    if loop is not None:
        metrics |= {f"hysteresis_width_{u}": loop.width, f"hysteresis_mean_{u}": loop.mean,
                    "hysteresis_bins": float(loop.temperature_c.size)}
    return KindMetrics(metrics, ad, p, fit, loop, bias)
