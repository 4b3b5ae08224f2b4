"""What a ``tcbench run`` compensation job keeps of its trained network for a device:
``device.json``, the network as plain data in the form ``tcbench calibrate`` keeps its fitted
methods (``calibration.json``'s ``device``: :func:`~tcbench.compensation.c_export.network_spec`),
which ``tcbench export runs=[ID] formats=[c]`` writes as C.

A device runs what compensates a static-input task's bias (``accel_chamber``, ``msra_zerobias``):
the output minus the network's offset on ``[T, dT/dt]``, the rate the trailing least-squares
slope, the inputs held to the training box where the task clamps them. It runs the
full-temperature task's network too (``msra_fulltemp``, seed 000's IFA-BP of Table 2: the
``inverse`` form, :func:`~tcbench.compensation.c_export.inverse_spec`): the network's estimate of
the input (acceleration, g) from ``[raw, T]``, the temperature held to its training range where
the task clamps it and the raw output free, as the task scores it. A run's ``poly`` learner of the
bias form (the boards' ``poly3``, ``poly3_runs``) is kept as the device's cubic
(:func:`~tcbench.compensation.c_export.run_cubic_spec`); its other forms say why they are left
out. The gyro task's runs keep the reason none is written (``left_out``): its pipeline decomposes
the whole record before its drift learner runs (not per sample).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tcbench.learners.polynomial import PolynomialModel

FILE = "device.json"
QUANTITY = {"g": "acceleration", "deg/s": "angular rate"}  # the input an inverse network estimates, by its unit


def _cubic_document(env: Any, data: Any, fitted: Any, learner: str) -> dict[str, Any]:
    """``device.json``'s body for a run's ``poly`` learner: the cubic of the bias form
    (:func:`~tcbench.compensation.c_export.run_cubic_spec`), or why another form is left out."""
    from tcbench.compensation.c_export import run_cubic_spec

    low, high = data.input_range(env._x) if env.clamp_inputs else (None, None)
    try:
        spec = run_cubic_spec(fitted, None if low is None else (low[0], high[0]))
    except ValueError as exc:
        return {"device": {}, "left_out": {learner: str(exc)}}
    meta = data.train[0].recording.meta
    return {"sensor": meta.sensor, "unit": meta.units.get("output", ""), "device": {learner: spec}}


def device_document(env: Any, learner: str, label: str) -> dict[str, Any]:
    """``device.json`` of a compensation run on ``env`` (its learner trained): the sensor, its
    output unit, the run's method label and ``device`` (the network's spec by learner name), or
    ``left_out`` (learner name: why no device runs it)."""
    from tcbench.compensation.c_export import CAPACITY_MARGIN, inverse_spec, network_spec, window_samples

    data = getattr(env, "data", None)
    fitted = getattr(env, "learner", None)
    base: dict[str, Any] = {"task": str(getattr(env, "task", "")), "method": label}
    form = getattr(data, "form", None) if hasattr(env, "clamp_inputs") else None
    if data is None or fitted is None or form not in ("bias", "inverse"):
        why = "the task's pipeline decomposes the whole record before its drift learner runs (not per sample)"
        return base | {"device": {}, "left_out": {learner: why}}
    if isinstance(fitted, PolynomialModel):
        return base | _cubic_document(env, data, fitted, learner)
    if not getattr(fitted, "searchable", False) or not hasattr(fitted.params, "hidden"):
        return base | {"device": {}, "left_out": {learner: "not a BP or Elman network"}}
    recordings = [tr.recording for tr in data.train + data.test]
    meta = recordings[0].meta
    low, high = data.input_range(env._x) if env.clamp_inputs else (None, None)
    unit = meta.units.get("output", "")
    if form == "inverse":  # [raw, T] -> the input
        measured = meta.units.get("input", "")
        spec = inverse_spec(learner, fitted, None if low is None else (low[0], high[0]),
                            None if low is None else (low[1], high[1]), QUANTITY.get(measured, "input"), measured)
        return base | {"sensor": meta.sensor, "unit": unit, "device": {learner: spec}}
    fullest = max(window_samples(r.time_s, data.rate_window_s) for r in recordings)
    spec = network_spec(learner, fitted, None if low is None else (low[0], high[0]),
                        None if low is None else (low[1], high[1]), data.rate_window_s,
                        max(2, int(np.ceil(CAPACITY_MARGIN * fullest))), 0.0)
    return base | {"sensor": meta.sensor, "unit": unit, "device": {learner: spec}}
