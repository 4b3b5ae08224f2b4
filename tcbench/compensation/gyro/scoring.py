"""Gyro metrics before and after a method, with the bandwidth it keeps (seed 001 Fig. 19).

Per test record (conventions in :data:`tcbench.compensation.scoring.CONVENTIONS` ``["gyro"]``):
residual drift over temperature, ARW and bias instability from the Allan deviation, the RMS
error against the applied rate, and the bandwidth kept — the -3 dB frequency of the whole
method, measured by injecting a multi-sine rate into the record and fitting what comes out
(:func:`tcbench.metrics.bandwidth.bandwidth_kept`). A method that lowers the ARW by smoothing
shows it here: its bandwidth falls with its noise.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tcbench.compensation.data import TaskRecording
from tcbench.compensation.features import temperature_rate_c_per_s
from tcbench.compensation.scoring import RecordingScore
from tcbench.metrics.bandwidth import Bandwidth, bandwidth_kept
from tcbench.metrics.gyro import allan_summary
from tcbench.signal.allan import AllanDeviation

SOAK_WINDOW_S = 300.0  # the last 5 min of each soak
SETTLED_C_PER_MIN = 0.05  # a soak: the thermometer moves slower than this
DPS_TO_DPH = 3600.0
Method = Callable[[np.ndarray], np.ndarray]  # recorded output (deg/s) -> method output (deg/s)


def soak_means(t_s: np.ndarray, temp_c: np.ndarray, output: np.ndarray,
               window_s: float = SOAK_WINDOW_S) -> tuple[np.ndarray, np.ndarray]:
    """Temperature (degC) and mean output over the last ``window_s`` (5 min) of every soak.

    A soak is a run of samples whose 120 s trailing thermometer slope stays below 0.05 degC/min
    for at least ``window_s``."""
    settled = np.abs(temperature_rate_c_per_s(t_s, temp_c)) * 60.0 < SETTLED_C_PER_MIN
    edges = np.flatnonzero(np.diff(np.r_[0, settled.astype(np.int8), 0]))
    temps, means = [], []
    for start, stop in zip(edges[::2], edges[1::2], strict=True):
        if t_s[stop - 1] - t_s[start] < window_s:
            continue
        last = slice(int(np.searchsorted(t_s, t_s[stop - 1] - window_s)), int(stop))
        temps.append(float(np.mean(temp_c[last])))
        means.append(float(np.mean(output[last])))
    return np.array(temps), np.array(means)


def residual_drift_dph(t_s: np.ndarray, temp_c: np.ndarray, output_dps: np.ndarray) -> float:
    """Std (ddof=1) over the soaks of the soak-mean output, deg/h (NaN with fewer than 2 soaks)."""
    _, means = soak_means(t_s, temp_c, output_dps)
    return float(np.std(means, ddof=1) * DPS_TO_DPH) if means.size >= 2 else float("nan")


def arw_at_1s(ad: AllanDeviation) -> float:
    """``arw_1s``: the Allan deviation at tau = 1 s, ``sigma(1 s)[deg/h] / 60``, in deg/sqrt(h)
    (interpolated in log-log). Where white noise dominates at 1 s it equals IEEE 952's ARW (the
    fitted -1/2 line read at 1 s, ``tcbench metrics``' ``arw_deg_per_sqrt_h``); unlike that fit it
    exists for any output, also a filtered one with no -1/2 region left, and it is exactly what a
    filter lowers by cutting bandwidth. On an unfiltered record the two differ by the other noises
    at 1 s (0.579 against 0.546 on the gyro task's default test record)."""
    ok = ad.adev > 0
    if not ok.any() or ad.tau_s[ok][0] > 1.0 + 1e-9:
        return float("nan")
    return float(np.exp(np.interp(0.0, np.log(ad.tau_s[ok]), np.log(ad.adev[ok]))) * DPS_TO_DPH / 60.0)


def gyro_metrics(t_s: np.ndarray, temp_c: np.ndarray, output_dps: np.ndarray, true_rate_dps: np.ndarray,
                 fs_hz: float) -> tuple[dict[str, float], AllanDeviation]:
    """Drift, ARW, bias instability and RMS error of one output, and its Allan deviation."""
    ad, _, allan = allan_summary(output_dps, fs_hz)
    values = {
        "drift_dph": residual_drift_dph(t_s, temp_c, output_dps),
        "arw_1s_deg_per_sqrt_h": arw_at_1s(ad),
        "bias_instability_dph": allan["bias_instability_dph"],
        "allan_min_interior": float(allan["allan_min_is_interior"]),
        "rms_error_dph": float(np.sqrt(np.mean((output_dps - true_rate_dps) ** 2)) * DPS_TO_DPH),
    }
    return values, ad


@dataclass
class GyroRecordingScore(RecordingScore):
    """Metrics of one test record before (raw output) and after, and what the figures need."""

    temp_c: np.ndarray | None = None
    raw_dps: np.ndarray | None = None
    after_dps: np.ndarray | None = None
    true_rate_dps: np.ndarray | None = None
    allan_before: AllanDeviation | None = None
    allan_after: AllanDeviation | None = None
    bandwidth: Bandwidth | None = None
    parts: object | None = None  # the PipelineOutput, when the method is a pipeline


def bandwidth_value_hz(bw: Bandwidth, fs_hz: float) -> float:
    """The -3 dB frequency, or the Nyquist frequency when no loss was measured."""
    return float(fs_hz / 2.0) if np.isinf(bw.f3db_hz) else float(bw.f3db_hz)


def score_record(tr: TaskRecording, method: Method, amplitude_dps: float, parts: object | None = None,
                 bandwidth: bool = True) -> GyroRecordingScore:
    """Metrics of ``method`` on test record ``tr`` before and after; ``bandwidth`` measures the
    bandwidth kept (one more run of the method); ``parts`` is kept for the figures."""
    r = tr.recording
    t, temp, raw, rate = r.time_s, r.temperature_c, r.output, r.input
    fs = float((t.size - 1) / (t[-1] - t[0]))
    after_dps = np.asarray(method(raw), dtype=np.float64)
    before, ad_b = gyro_metrics(t, temp, raw, rate, fs)
    after, ad_a = gyro_metrics(t, temp, after_dps, rate, fs)
    before["bandwidth_hz"] = fs / 2.0
    bw = None
    if bandwidth:
        bw = bandwidth_kept(method, t, raw, amplitude=amplitude_dps)
        after["bandwidth_hz"] = bandwidth_value_hz(bw, fs)
    return GyroRecordingScore(tr.name, before, after, t_s=t, temp_c=temp, raw_dps=raw, after_dps=after_dps,
                              true_rate_dps=rate, allan_before=ad_b, allan_after=ad_a, bandwidth=bw, parts=parts)
