"""What a ``tcbench run`` compensation job keeps of its trained model for a device:
``device.json``, the model as plain data in the form ``tcbench calibrate`` keeps its fitted
methods (``calibration.json``'s ``device``: :func:`~tcbench.compensation.c_export.network_spec`),
which ``tcbench export runs=[ID] formats=[c]`` writes as C.

A device runs what compensates a static-input task's bias (``accel_chamber``, ``msra_zerobias``):
the output minus the network's offset on ``[T, dT/dt]``, the rate the trailing least-squares
slope, the inputs held to the training box where the task clamps them. It runs the
full-temperature task's network too (``msra_fulltemp``, seed 000's IFA-BP of Table 2: the
``inverse`` form, :func:`~tcbench.compensation.c_export.inverse_spec`): the network's estimate of
the input (acceleration, g) from ``[raw, T]``, the temperature held to its training range where
the task clamps it and the raw output free, as the task scores it. A run's ``poly`` learner of the
bias form and degree 3 at most (the boards' ``poly3``, ``poly3_runs``) is kept as the device's cubic
(:func:`~tcbench.compensation.c_export.run_cubic_spec`); of another form (``bias_rate``: the rate
term a polynomial in T; ``inverse``) or degree, as its Chebyshev series
(:func:`~tcbench.compensation.c_export.run_poly_spec`). Of the baselines a run of ``lagpoly`` keeps
its lag-aware polynomial (:func:`~tcbench.compensation.c_export.lagpoly_spec`) and one of ``model``
its diagnosed models (:func:`~tcbench.compensation.c_export.run_model_spec`), from what their score
keeps (:data:`BASELINE_FITS`); the memoriser keeps why none runs it. The gyro task's runs keep the
reason none is written (``left_out``): its pipeline decomposes the whole record before its drift
learner runs (not per sample).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tcbench.learners.polynomial import PolynomialModel

FILE = "device.json"
QUANTITY = {"g": "acceleration", "deg/s": "angular rate"}  # the input an inverse network estimates, by its unit
# The baselines a run keeps device.json for, by learner: the key of its fitted model in the score's
# ``extra`` (None: none a device runs, :data:`LEFT_OUT` says why).
BASELINE_FITS = {"lagpoly": "lagpoly", "model": "diagnosed", "memoriser": None}
LEFT_OUT = {"memoriser": "a replay of the training runs' mean output at the same time since their start, "
                         "not a model of the temperature a device runs"}


def _lagpoly(fitted: Any, inverse: bool, quantity: str, unit: str) -> dict[str, Any]:
    from tcbench.compensation.c_export import lagpoly_spec

    return lagpoly_spec(fitted, inverse, quantity, unit)


def _model(fitted: Any, inverse: bool, quantity: str, unit: str) -> dict[str, Any]:
    from tcbench.compensation.c_export import run_model_spec

    return run_model_spec(fitted.models, inverse, quantity, unit)


_BASELINE_SPECS = {"lagpoly": _lagpoly, "model": _model}  # a fitted baseline's spec: (fitted, inverse, quantity, unit)


def device_document(env: Any, learner: str, label: str, baseline: Any = None) -> dict[str, Any]:
    """``device.json`` of a compensation run on ``env`` (its learner trained): the sensor, its
    output unit, the run's method label and ``device`` (the learner's spec by its name), or
    ``left_out`` (learner name: why no device runs it); ``baseline``: the fitted model of a
    baseline :data:`BASELINE_FITS` names (its score keeps it)."""
    data = getattr(env, "data", None)
    fitted = baseline if learner in BASELINE_FITS else getattr(env, "learner", None)
    base: dict[str, Any] = {"task": str(getattr(env, "task", "")), "method": label}
    form = getattr(data, "form", None) if hasattr(env, "clamp_inputs") else None
    if data is None or form not in ("bias", "inverse"):
        why = "the task's pipeline decomposes the whole record before its drift learner runs (not per sample)"
        return base | {"device": {}, "left_out": {learner: why}}
    if learner in BASELINE_FITS and fitted is None:  # the memoriser's score keeps none
        return base | {"device": {}, "left_out": {learner: LEFT_OUT.get(learner, "the run kept no fitted model")}}
    network = getattr(fitted, "searchable", False) and hasattr(fitted.params, "hidden")
    if not (network or isinstance(fitted, PolynomialModel) or learner in _BASELINE_SPECS):
        return base | {"device": {}, "left_out": {learner: "not a polynomial, a BP or an Elman network"}}
    box = data.input_range(env._x) if env.clamp_inputs and learner not in BASELINE_FITS else None
    try:
        spec = _spec(data, fitted, learner, form, box)
    except ValueError as exc:  # a term of a diagnosed model no device runs
        return base | {"device": {}, "left_out": {learner: str(exc)}}
    meta = data.train[0].recording.meta
    return base | {"sensor": meta.sensor, "unit": meta.units.get("output", ""), "device": {learner: spec}}


def _spec(data: Any, fitted: Any, learner: str, form: str, box: tuple[np.ndarray, np.ndarray] | None) -> dict[str, Any]:
    """The spec a device runs of the trained ``fitted``, its inputs held to ``box`` (None: free):
    a fitted baseline's (:data:`BASELINE_FITS`), a run's cubic
    (:func:`~tcbench.compensation.c_export.run_cubic_spec`) or other polynomial, an inverse network
    on ``[raw, T]`` or a network on ``[T, dT/dt]`` with its rate window."""
    from tcbench.compensation.c_export import (CAPACITY_MARGIN, inverse_spec, network_spec, run_cubic_spec,
                                               run_poly_spec, window_samples)

    first = None if box is None else (box[0][0], box[1][0])  # the temperature's (or raw's) range
    second = None if box is None else (box[0][1], box[1][1])
    measured = data.train[0].recording.meta.units.get("input", "")
    if learner in _BASELINE_SPECS:
        return _BASELINE_SPECS[learner](fitted, form == "inverse", QUANTITY.get(measured, "input"), measured)
    fullest = max(window_samples(tr.recording.time_s, data.rate_window_s) for tr in data.train + data.test)
    capacity = max(2, int(np.ceil(CAPACITY_MARGIN * fullest)))
    if isinstance(fitted, PolynomialModel):
        if fitted.describe().get("fitted_form") == "bias" and fitted.settings.degree <= 3:
            return run_cubic_spec(fitted, first)  # the cubic PX4 runs
        return run_poly_spec(fitted, box, data.rate_window_s, capacity, QUANTITY.get(measured, "input"), measured)
    if form == "inverse":  # [raw, T] -> the input
        return inverse_spec(learner, fitted, first, second, QUANTITY.get(measured, "input"), measured)
    return network_spec(learner, fitted, first, second, data.rate_window_s, capacity, 0.0)
