"""The paper's metrics before and after compensation, per test recording (seed 000 Tables 1-2).

Conventions (stated in every report):

- fulltemp (Table 2): four-position scale factor ``K1 = (U(+1g) - U(-1g))/2`` and bias
  ``B0 = (U(+0g) + U(-0g))/(U(+1g) - U(-1g)) g`` per node (eq. 12 with the plus sign by
  default; ``bias_form=printed`` gives the printed minus); variation = ``std/mean`` of K1 in ppm
  and ``std`` of B0 in micro-g over the nodes (ddof=1). Before: on the raw output U (Hz);
  after: on the compensated acceleration (g), so K1 is in g/g.
- fulltemp probe (not in the paper): ``halfg_error_ug``, the RMS error in micro-g of the
  compensated output when the 0 g samples are moved to +-0.5 g (the output shifted by +-0.5 K1
  of their node, K1 measured on the raw output), i.e. at accelerations no training sample had.
  A method that learned the three trained levels rather than the sensor (flat steps that swallow
  the noise around -1, 0 and +1 g) can even beat the oracle on Table 2 and fails here.
- roomtemp (Table 1): zero-bias stability = 1 sigma (ddof=1) of non-overlapping 10 s means of
  output / scale factor, from 30 min, 20 min and 0 min after power-on, in micro-g.
- chamber (a static accelerometer through a chamber cycle): ``drift_ug``, 1 sigma (ddof=1) of
  non-overlapping 10 s means of the output over the whole cycle (the residual bias over
  temperature and time, with the noise left in 10 s means); ``hysteresis_ug``, the largest
  cooling-minus-heating difference of the output in common 1 degC bins
  (:func:`tcbench.metrics.inertial.hysteresis`); ``temp_slope_ug_per_c``, the absolute slope of
  the least-squares line of the output against the thermometer. All in micro-g, before on the
  raw output, after on the compensated one (a constant offset changes none of them).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from tcbench.compensation.data import MSRAData, TaskRecording
from tcbench.compensation.methods import Compensator
from tcbench.metrics import accelerometer as acc
from tcbench.metrics.gyro import rate_vs_temperature
from tcbench.metrics.inertial import hysteresis

FULLTEMP_METRICS = ("sf_variation_ppm", "bias_variation_ug", "halfg_error_ug")
PROBE_G = 0.5
ROOMTEMP_METRICS = ("zb_after_30min_ug", "zb_after_20min_ug", "zb_zero_start_ug")
CHAMBER_METRICS = ("drift_ug", "hysteresis_ug", "temp_slope_ug_per_c")
GYRO_METRICS = ("drift_dph", "arw_1s_deg_per_sqrt_h", "bias_instability_dph", "rms_error_dph", "bandwidth_hz")
METRIC_NAMES = {"fulltemp": FULLTEMP_METRICS, "roomtemp": ROOMTEMP_METRICS, "chamber": CHAMBER_METRICS,
                "gyro": GYRO_METRICS}
# 0/1 flags logged beside the metrics (the mean over the test recordings; no gain): the share of them
# whose Allan minimum is inside the curve, i.e. whose bias instability is a floor
FLAGS = {"gyro": ("allan_min_interior",)}
PRIMARY = {"fulltemp": "bias_variation_ug", "roomtemp": "zb_zero_start_ug", "chamber": "drift_ug",
           "gyro": "drift_dph"}
TRAIN_RMSE = {"fulltemp": "train_rmse_ug", "roomtemp": "train_rmse_ug", "chamber": "train_rmse_ug",
              "gyro": "train_rmse_dph"}
CONVENTIONS = {
    "fulltemp": [
        "scale factor K1 = (U(+1g) - U(-1g))/2; bias B0 = (U(+0g) + U(-0g))/(U(+1g) - U(-1g)) g "
        "(eq. 12 with the plus sign unless bias_form=printed)",
        "variation over the nodes: std/mean of K1 (ppm), std of B0 (micro-g), sample std (ddof=1); "
        "before = raw output U (Hz), after = compensated acceleration (g)",
    ],
    "roomtemp": [
        "zero-bias stability: 1 sigma (ddof=1) of non-overlapping 10 s means of output / scale factor "
        "from 30 min, 20 min and 0 min after power-on (micro-g)",
    ],
    "chamber": [
        "drift_ug: 1 sigma (ddof=1) of non-overlapping 10 s means of the output over the whole chamber cycle (micro-g)",
        "hysteresis_ug: largest |cooling - heating| difference of the output in common 1 degC bins of the "
        "thermometer (micro-g); temp_slope_ug_per_c: |slope| of the output's least-squares line against the "
        "thermometer (micro-g/degC); before = raw output, after = compensated output (g), a constant offset aside",
    ],
    "gyro": [
        "drift_dph: residual drift over temperature, std (ddof=1) over the oven's soaks of the output's "
        "mean over the last 5 min of each soak (deg/h)",
        "arw_1s_deg_per_sqrt_h and bias_instability_dph: overlapping Allan deviation of the whole record; "
        "arw_1s = sigma(1 s)[deg/h] / 60, the Allan deviation at 1 s (IEEE 952's ARW, the fitted -1/2 line "
        "read at 1 s, where white noise dominates at 1 s; seed 001's unit 'deg/h/sqrt(Hz)' read as "
        "deg/sqrt(h), docs/concepts/physics.md, metrics); bias instability = Allan minimum / 0.664, a floor only where "
        "allan_min_interior is 1 (else the minimum is an end of the curve: for a filtered output, sigma at "
        "the first tau, a function of the sample interval)",
        "rms_error_dph: RMS of output minus the applied (true) rate (deg/h)",
        "bandwidth_hz: -3 dB frequency of the whole method, measured by injecting a multi-sine rate into "
        "the test record; the Nyquist frequency when no loss was measured up to 0.4 fs",
    ],
}


@dataclass
class RecordingScore:
    """Metrics of one test recording before and after, and what the plots need."""

    name: str
    before: dict[str, float]
    after: dict[str, float]
    nodes_before: pd.DataFrame | None = None
    nodes_after: pd.DataFrame | None = None
    t_s: np.ndarray | None = None
    before_ug: np.ndarray | None = None
    after_ug: np.ndarray | None = None


@dataclass
class Score:
    """Outcome of one compensation method on the test recordings."""

    protocol: str
    recordings: list[RecordingScore]
    train_rmse: float = float("nan")  # of the learner on its training set, unit in train_key
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def metric_names(self) -> tuple[str, ...]:
        return METRIC_NAMES[self.protocol]

    @property
    def train_key(self) -> str:
        """Summary key (with unit) of the training RMSE: ``train_rmse_ug`` or ``train_rmse_dph``."""
        return TRAIN_RMSE[self.protocol]

    def summary(self) -> dict[str, float]:
        """Flat metrics: per recording (``test1.*``), means over recordings (``*`` after,
        ``raw_*`` before) and improvement factors (``gain_*`` = before / after)."""
        out: dict[str, float] = {}
        names = [k for k in self.metric_names if all(k in r.after for r in self.recordings)]
        for i, r in enumerate(self.recordings, start=1):
            for k in names:
                out[f"test{i}.{k}"] = r.after[k]
                if k in r.before:
                    out[f"test{i}.raw_{k}"] = r.before[k]
        for k in FLAGS.get(self.protocol, ()):
            for prefix, side in (("", "after"), ("raw_", "before")):
                if all(k in getattr(r, side) for r in self.recordings):
                    out[prefix + k] = float(np.mean([getattr(r, side)[k] for r in self.recordings]))
        for k in names:
            out[k] = after = float(np.mean([r.after[k] for r in self.recordings]))
            if all(k in r.before for r in self.recordings):
                out[f"raw_{k}"] = before = float(np.mean([r.before[k] for r in self.recordings]))
                out[f"gain_{k}"] = before / after if after > 0 else float("inf")
        out[self.train_key] = self.train_rmse
        return out


def _probe_error_ug(rec: TaskRecording, fn: Compensator, nodes: pd.DataFrame, pos: np.ndarray) -> float:
    """RMS error (micro-g) of the compensated 0 g samples moved to +-0.5 g (see module doc)."""
    r = rec.recording
    blocks = acc.position_blocks(pos)
    node = np.repeat(np.arange(len(blocks)) // 4, (blocks["stop"] - blocks["start"]).to_numpy())
    rows = np.concatenate([np.arange(a, b) for a, b in zip(blocks["start"], blocks["stop"], strict=True)])
    zero = np.isin(pos[rows], ["+0g", "-0g"])
    rows, node = rows[zero], node[zero]
    k1 = nodes["scale_factor_hz_per_g"].to_numpy()[node]
    base = fn(rec, r.output)[rows]
    errors = []
    for g in (PROBE_G, -PROBE_G):
        shifted = r.output.copy()
        shifted[rows] += g * k1
        errors.append(fn(rec, shifted)[rows] - base - g)
    return float(np.sqrt(np.mean(np.concatenate(errors) ** 2)) * 1e6)


def _fulltemp(rec: TaskRecording, fn: Compensator, bias_form: str, probe: bool) -> RecordingScore:
    r = rec.recording
    pos = np.where(r.position == None, "", r.position).astype(str)  # noqa: E711
    compensated_g = fn(rec, r.output)
    nodes_b = acc.four_position(r.temperature_c, r.output, pos, bias_form)
    nodes_a = acc.four_position(r.temperature_c, compensated_g, pos, bias_form)
    vb, va = acc.temperature_variation(nodes_b), acc.temperature_variation(nodes_a)
    after = {"sf_variation_ppm": va.scale_factor_ppm, "bias_variation_ug": va.bias_ug}
    if probe:
        after["halfg_error_ug"] = _probe_error_ug(rec, fn, nodes_b, pos)
    return RecordingScore(
        rec.name,
        {"sf_variation_ppm": vb.scale_factor_ppm, "bias_variation_ug": vb.bias_ug},
        after, nodes_before=nodes_b, nodes_after=nodes_a,
    )


def _zero_bias(values: dict[str, float]) -> dict[str, float]:
    return {"zb_after_30min_ug": values["after_30min_ug"], "zb_after_20min_ug": values["after_20min_ug"],
            "zb_zero_start_ug": values["zero_start_ug"]}


def _roomtemp(rec: TaskRecording, fn: Compensator, sf: float) -> RecordingScore:
    r = rec.recording
    compensated_hz = fn(rec, r.output)
    before = _zero_bias(acc.zero_bias_table(r.time_s, r.output, sf))
    after = _zero_bias(acc.zero_bias_table(r.time_s, compensated_hz, sf))
    return RecordingScore(rec.name, before, after, t_s=r.time_s,
                          before_ug=r.output / sf * 1e6, after_ug=compensated_hz / sf * 1e6)


def _chamber_metrics(t_s: np.ndarray, temp_c: np.ndarray, output_g: np.ndarray) -> dict[str, float]:
    ug = np.asarray(output_g, dtype=np.float64) * 1e6
    loop = hysteresis(t_s, temp_c, ug)
    line = rate_vs_temperature(temp_c, ug)
    return {"drift_ug": acc.zero_bias_stability_ug(t_s, ug * 1e-6, 1.0, 0.0, 10.0),
            "hysteresis_ug": loop.width if loop is not None else float("nan"),
            "temp_slope_ug_per_c": abs(line.slope_dps_per_c) if line is not None else float("nan")}


def _chamber(rec: TaskRecording, fn: Compensator) -> RecordingScore:
    r = rec.recording
    compensated_g = fn(rec, r.output)
    before = _chamber_metrics(r.time_s, r.temperature_c, r.output)
    after = _chamber_metrics(r.time_s, r.temperature_c, compensated_g)
    centre = float(np.mean(r.output))  # the plot shows both about zero
    return RecordingScore(rec.name, before, after, t_s=r.time_s, before_ug=(r.output - centre) * 1e6,
                          after_ug=(compensated_g - float(np.mean(compensated_g))) * 1e6)


# How a test recording of each protocol is scored: ``(recording, compensator, data, bias_form,
# probe) -> RecordingScore``.
SCORERS: dict[str, Callable[[TaskRecording, Compensator, MSRAData, str, bool], RecordingScore]] = {
    "fulltemp": lambda rec, fn, data, bias_form, probe: _fulltemp(rec, fn, bias_form, probe),
    "roomtemp": lambda rec, fn, data, bias_form, probe: _roomtemp(rec, fn, data.scale_factor_hz_per_g),
    "chamber": lambda rec, fn, data, bias_form, probe: _chamber(rec, fn),
}


def score_outputs(data: MSRAData, fn: Compensator, bias_form: str = "plus",
                  train_rmse_ug: float = float("nan"), probe: bool = True) -> Score:
    """Metrics before and after for each test recording compensated by ``fn``; ``probe``
    adds the +-0.5 g probe (fulltemp; not for the raw output, which is not in g)."""
    score_one = SCORERS[data.protocol]
    recs = [score_one(rec, fn, data, bias_form, probe) for rec in data.test]
    return Score(data.protocol, recs, train_rmse_ug)
