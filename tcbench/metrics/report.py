"""The paper metrics of one recording, chosen by what the recording holds, with its plots.

- MSRA with complete four-position groups: scale factor and bias per node and their
  variation over temperature (seed 000 Table 2).
- MSRA otherwise (a 0 g run): zero-bias stability after 30 min, 20 min and from zero start
  (seed 000 Table 1), and its Allan read-offs.
- Any accelerometer kind with complete four-position groups (an ``accel`` multi-position
  test): the same per-node table.
- Any other kind (an ``accel`` chamber or static run): bias stability, noise density (VRW), bias
  instability, bias against temperature and hysteresis (:mod:`tcbench.metrics.inertial`).
- Gyroscope: Allan read-offs (seed 001), when the run reaches 60 and -40 degC the drift
  between those soaks, and the output against temperature with a fitted line (slope, its
  standard error and r), plotted as ``rate_vs_temperature.png``.

A recording made of bursts with gaps between them (segments, :mod:`tcbench.sensors.segments`)
has its Allan deviation taken within the segments and averaged over them, so the gaps never
count as samples; a gyro's rate-against-temperature points are then the segment means.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tcbench import plots
from tcbench.metrics import accelerometer as acc
from tcbench.metrics import gyro
from tcbench.metrics.inertial import kind_metrics, token
from tcbench.sensors import kinds
from tcbench.sensors.recording import Recording
from tcbench.sensors.segments import segments
from tcbench.signal.allan import (
    NoiseParameters,
    allan_deviation,
    allan_deviation_segments,
    noise_parameters,
)

log = logging.getLogger(__name__)


@dataclass
class Report:
    """Metrics of a recording (scalars), per-node table if any, and the files written."""

    metrics: dict[str, float]
    conventions: list[str]
    nodes: pd.DataFrame | None = None
    files: dict[str, Path] = field(default_factory=dict)
    details: dict[str, Any] = field(default_factory=dict)  # further JSON-ready results for metrics.json


def _scale_factor(rec: Recording, override: float | None) -> float:
    if override is not None:
        return override
    value = rec.meta.extra.get("scale_factor_hz_per_g") if rec.meta.extra else None
    if value:
        return float(value)
    nominal = kinds.get(str(rec.meta.sensor)).nominal_scale_factor
    log.warning("no scale factor in the sidecar; using the nominal %g Hz/g", nominal)
    return nominal


def _allan_lines(p: NoiseParameters) -> dict[str, tuple[float, float, float]]:
    """The three noise lines drawn over an Allan plot: (value at tau = 1 s, slope, tau_s = 1)."""
    return {
        "angle random walk (slope -1/2)": (p.angle_random_walk, -0.5, 1.0),
        "bias instability floor (0.664 B)": (p.adev_min, 0.0, 1.0),
        "rate random walk (slope +1/2)": (p.rate_random_walk * np.sqrt(3.0), 0.5, 1.0),
    }


def _floor_read(p: NoiseParameters, unit: str, scale: float) -> tuple[dict[str, float], list[str]]:
    """Whether the Allan minimum is a floor (an interior point) as a 0/1 metric, and a warning
    line when it is not: then the bias instability read from it is only an upper bound."""
    metrics = {"allan_min_is_interior": float(p.min_is_interior)}
    if p.min_is_interior or not np.isfinite(p.adev_min):
        return metrics, []
    return metrics, [f"Allan minimum at an end of the taus read ({p.tau_min_s:.3g} s, {p.adev_min * scale:.4g} {unit}): "
                     "no flicker floor was seen, so the bias instability is only an upper bound; a longer "
                     "record would show the floor"]


def _positions(rec: Recording) -> np.ndarray | None:
    """The position labels as strings (empty where none), or None without the column."""
    labels = rec.position
    return None if labels is None else np.where(labels == None, "", labels).astype(str)  # noqa: E711


def _four_position(rec: Recording, pos: np.ndarray, out: Path | None, files: dict[str, Path]) -> Report:
    """Scale factor and bias per temperature node from a four-position test (any accelerometer kind)."""
    nodes = acc.four_position(rec.temperature_c, rec.output, pos)
    var = acc.temperature_variation(nodes)
    unit = token(kinds.get(str(rec.meta.sensor)).output_unit)
    metrics = {
        "sf_variation_ppm": var.scale_factor_ppm,
        "bias_variation_ug": var.bias_ug,
        "nodes": float(var.nodes),
        f"sf_mean_{unit}_per_g": float(nodes["scale_factor_hz_per_g"].mean()),
    }
    conventions = [
        "scale factor K1 = (U(+1g) - U(-1g))/2; bias B0 = (U(+0g) + U(-0g))/(U(+1g) - U(-1g)) g "
        "(eq. 12 with the plus sign; the printed minus measures misalignment)",
        "variation: std/mean of K1 (ppm), std of B0 (micro-g); sample std (ddof=1) over nodes",
    ]
    if out is not None:
        files["nodes"] = out / "nodes.csv"
        nodes.to_csv(files["nodes"], index=False)
    return Report(metrics, conventions, nodes, files)


def _msra(rec: Recording, scale_factor: float | None, out: Path | None, files: dict[str, Path]) -> Report:
    sf = _scale_factor(rec, scale_factor)
    metrics, unstable = {}, []
    for row, start_s in acc.ZERO_BIAS_STARTS_S.items():
        try:
            metrics[row] = acc.zero_bias_stability_ug(rec.time_s, rec.output, sf, start_s)
        except ValueError as exc:  # a short record, or bursts shorter than a window: NaN, said why
            metrics[row] = float("nan")
            unstable.append(f"{row} not computed: {exc} (windows stay inside the clock's segments)")
    seg = segments(rec.time_s)
    if seg[-1] == 0:
        ad = allan_deviation(rec.output / sf * 1e6, rec.meta.sample_rate_hz or 1.0, "octave")
    else:
        ad = allan_deviation_segments(rec.output / sf * 1e6, rec.meta.sample_rate_hz or 1.0, seg)
        metrics["segments"] = float(seg[-1] + 1)
    p = noise_parameters(ad)
    metrics |= {"bias_instability_ug": p.bias_instability, "scale_factor_hz_per_g": sf}
    floor, floor_note = _floor_read(p, "µg", 1.0)
    metrics |= floor
    if out is not None:
        files["allan"] = plots.allan_plot(out / "allan.png", ad.tau_s, ad.adev, _allan_lines(p), "µg", "MSRA zero-bias Allan deviation")
    conventions = ["zero-bias stability: 1 sigma (ddof=1) of non-overlapping 10 s means of output/scale factor, "
                   "from 30 min, 20 min and 0 min after power-on (micro-g)"]
    if seg[-1] > 0:
        conventions.append(f"{seg[-1] + 1} segments (gaps > 5 median sample intervals): Allan variance within each "
                           "segment, pooled over the segments, tau up to half the median segment")
    return Report(metrics, conventions + floor_note + unstable, None, files)


def _gyro(rec: Recording, out: Path | None, files: dict[str, Path]) -> Report:
    fs = rec.meta.sample_rate_hz or 1.0 / float(np.median(np.diff(rec.time_s)))
    seg = segments(rec.time_s)
    n_seg = int(seg[-1]) + 1
    ad, p, metrics = gyro.allan_summary(rec.output, fs, seg if n_seg > 1 else None)
    floor, floor_note = _floor_read(p, "°/h", 3600.0)
    metrics |= floor
    conventions = ["ARW in deg/sqrt(h) (seed 001's 'deg/h/sqrt(Hz)' read as deg/sqrt(h)); bias instability = "
                   "Allan minimum / 0.664 in deg/h; read-offs over tau <= T/10", *floor_note]
    details: dict[str, Any] = {}
    if n_seg > 1:
        metrics["segments"] = float(n_seg)
        conventions.append(f"{n_seg} segments (gaps > 5 median sample intervals): Allan variance within each "
                           "segment, pooled over the segments, tau up to half the median segment; T is the time "
                           "inside the segments")
        details["segments"] = {"count": n_seg, "sample_rate_hz": fs,
                               "samples": np.bincount(seg).tolist()}
    temp = rec.temperature_c
    hot_c, cold_c = np.quantile(temp, [0.99, 0.01])  # inside the hottest and coldest soaks
    if hot_c - cold_c >= 95.0:  # a 60 .. -40 degC test, read through the thermometer's own offset
        try:
            metrics["drift_60_to_m40_dps"] = gyro.drift_dps(rec.time_s, temp, rec.output, hot_c, cold_c)
            conventions.append("drift: mean output over the last 10 min of the hottest soak (60 degC) minus that of "
                               "the coldest (-40 degC), the soaks found as read (a thermometer reads apart from the "
                               "element)")
        except ValueError as exc:  # soaks too short to read: the other metrics stand
            conventions.append(f"drift (60 to -40 degC) not read: {exc} (it needs soaks of at least 10 min at both "
                               "ends)")
    fit = gyro.rate_vs_temperature(temp, rec.output, seg)
    if fit is not None:
        metrics |= fit.metrics()
        details["rate_vs_temperature"] = fit.as_dict()
        conventions.append(f"rate vs temperature: least-squares line through {fit.temperature_c.size} {fit.method} "
                           "(mean output at mean temperature); slope in deg/s per degC with its standard error")
    if out is not None:
        title = "gyro Allan deviation" + (f" (within {n_seg} segments)" if n_seg > 1 else "")
        files["allan"] = plots.allan_plot(out / "allan.png", ad.tau_s, ad.adev * 3600.0,
                                          {k: (v[0] * 3600.0, v[1], v[2]) for k, v in _allan_lines(p).items()},
                                          "°/h", title)
        if fit is not None:
            files["rate_vs_temperature"] = plots.rate_temperature_plot(
                out / "rate_vs_temperature.png", temp, rec.output, (fit.temperature_c, fit.output_dps),
                (fit.slope_dps_per_c, fit.intercept_dps), f"{fit.method} ({fit.temperature_c.size})", "rate (°/s)",
                f"{rec.meta.device_id}: {fit.slope_dps_per_c:+.4g} ± {fit.slope_stderr_dps_per_c:.2g} °/s per °C, "
                f"r = {fit.r:.3f}")
    return Report(metrics, conventions, None, files, details)


def _kind(rec: Recording, out: Path | None, files: dict[str, Path]) -> Report:
    """Any other kind: bias stability, noise density, bias instability, bias against temperature
    and hysteresis in the kind's noise unit (:mod:`tcbench.metrics.inertial`)."""
    kind = kinds.get(str(rec.meta.sensor))
    fs = rec.meta.sample_rate_hz or 1.0 / float(np.median(np.diff(rec.time_s)))
    seg = segments(rec.time_s)
    n_seg = int(seg[-1]) + 1
    km = kind_metrics(kind, rec.time_s, rec.temperature_c, rec.input, rec.output, fs, seg if n_seg > 1 else None)
    unit = kind.noise_unit
    floor, floor_note = _floor_read(km.params, unit, 1.0)
    conventions = [
        f"bias = output - applied input, in {unit}; bias stability = 1 sigma (ddof=1) of non-overlapping 10 s means "
        "over the whole record (at constant temperature the (1 sigma, 10 s) figure; over a chamber cycle mostly drift)",
        f"noise density = Allan -1/2 line at tau = 1 s ({unit}/sqrt(Hz)); bias instability = Allan minimum / 0.664 "
        f"({unit}); read-offs over tau <= T/10", *floor_note]
    if km.fit is not None:
        conventions.append(f"bias vs temperature: least-squares line through {km.fit.temperature_c.size} "
                           f"{km.fit.method} (mean bias at mean temperature); slope in {unit} per degC")
    if km.loop is not None:
        conventions.append(f"hysteresis: cooling minus heating bias in {km.loop.temperature_c.size} common 1 degC bins; "
                           "width = the largest |difference|, mean = its signed mean (a die lag opens the same loop)")
    details: dict[str, Any] = {"hysteresis": km.loop.as_dict()} if km.loop is not None else {}
    if km.fit is not None:
        details["bias_vs_temperature"] = km.fit.as_dict()
    if n_seg > 1:
        km.metrics["segments"] = float(n_seg)
    if out is not None:
        files["allan"] = plots.allan_plot(out / "allan.png", km.ad.tau_s, km.ad.adev, _allan_lines(km.params), unit,
                                          f"{kind.name} Allan deviation of the bias")
        if km.fit is not None:
            loop = f", hysteresis {km.loop.width:.4g} {unit}" if km.loop is not None else ""
            files["bias_vs_temperature"] = plots.rate_temperature_plot(
                out / "bias_vs_temperature.png", rec.temperature_c, km.bias, (km.fit.temperature_c, km.fit.output_dps),
                (km.fit.slope_dps_per_c, km.fit.intercept_dps), f"{km.fit.method} ({km.fit.temperature_c.size})",
                f"bias ({unit})", f"{rec.meta.device_id}: {km.fit.slope_dps_per_c:+.4g} ± "
                f"{km.fit.slope_stderr_dps_per_c:.2g} {unit} per °C{loop}")
    return Report(km.metrics | floor, conventions, None, files, details)


# The report of a run without complete four-position groups, by its kind's ``report``
# (:data:`tcbench.sensors.kinds.REPORTS`): ``(recording, scale_factor, out, files) -> Report``.
REPORTERS: dict[str, Callable[[Recording, float | None, Path | None, dict[str, Path]], Report]] = {
    "inertial": lambda rec, scale_factor, out, files: _kind(rec, out, files),
    "zero_bias": _msra,
    "rate": lambda rec, scale_factor, out, files: _gyro(rec, out, files),
}


def analyse(rec: Recording, out: Path | None = None, scale_factor: float | None = None) -> Report:
    """Metrics (and, with ``out``, plots, ``metrics.json`` and ``nodes.csv``) of a recording."""
    sensor = rec.meta.sensor
    if not kinds.known(sensor):
        raise ValueError("the recording has no sidecar saying which sensor it is; add one")
    files: dict[str, Path] = {}
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        unit = {"deg/s": "°/s"}.get(rec.meta.units.get("output", ""), rec.meta.units.get("output", ""))
        files["overview"] = plots.recording_overview(
            out / "overview.png", rec.time_s, rec.temperature_c, rec.output, f"output ({unit})",
            f"{rec.meta.device_id}: {rec.meta.extra.get('protocol', '') if rec.meta.extra else ''}",
            segment=segments(rec.time_s),
        )
    kind = kinds.get(str(sensor))
    pos = _positions(rec) if kind.positions else None
    if pos is not None and np.isin(pos, ["+1g", "-1g"]).any():  # a four-position test
        report = _four_position(rec, pos, out, files)
    else:
        report = REPORTERS[kind.report](rec, scale_factor, out, files)
    if out is not None:
        payload: dict[str, Any] = {"device_id": rec.meta.device_id, "sensor": sensor,
                                   "metrics": report.metrics, "conventions": report.conventions, **report.details}
        report.files["metrics"] = out / "metrics.json"
        report.files["metrics"].write_text(json.dumps(payload, indent=2))
    return report
