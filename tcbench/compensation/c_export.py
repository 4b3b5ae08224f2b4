"""A fitted offset model as C99 a firmware can call per sample (``tcbench export formats=[c]``).

Each method ``tcbench calibrate`` fits that a device can run is written as ``<name>.h`` and
``<name>.c`` with a streaming API::

    void <name>_init(<name>_state *s);
    <name>_real <name>_update(<name>_state *s, <name>_real temperature_c, <name>_real raw, <name>_real dt_s);

``update`` takes one sample in time order (``dt_s``: the time since the previous sample, > 0;
the first sample's is ignored) and returns ``raw`` minus the model's offset. ``<name>_real`` is
``double``, or ``float`` when ``<NAME>_FLOAT`` is defined; the clock (the sum of the ``dt_s``)
is a ``double`` in both builds, so that the trailing rate window and the time bins keep their
edges over hours. No allocation, no library call but ``tanh`` and ``exp`` (``tanhf`` and ``expf``
in the float build; the networks' sigmoid is ``(1 + tanh(a / 2)) / 2``).

What each method runs (:func:`device_spec` gives its parameters, :func:`streamed_offset` runs the
same arithmetic in numpy, the reference the compiled code is checked against):

- ``poly3``: PX4's cubic about its reference, the temperature held to the fitted range (a
  ``tcbench run``'s cubic too, :func:`run_cubic_spec`: its Chebyshev series expanded about the
  middle of the training range).
- ``poly`` and ``poly_rate``: a ``tcbench run``'s ``poly`` learner of another form or of degree
  above 3 (:func:`run_poly_spec`), its Chebyshev series in its inputs scaled to [-1, 1] as it was
  fitted, held to the training box: the offset ``b(T)``; with ``poly_rate`` ``b(T) + r(T) dT/dt``
  on the trailing rate window below; of the ``inverse`` form (``msra_fulltemp``) the input
  solved from ``[raw, T]``, ``(raw - b(T)) / K(T)``, returned in the input's unit.
- ``poly3_rate``: that cubic plus the rate coefficient times the temperature rate, the
  least-squares slope over the trailing :data:`~tcbench.compensation.calibration.RATE_WINDOW_S`
  window ``t_i - w < t_j <= t_i``, each window's moments centred on its own means: the estimator
  calibrate computes (:func:`~tcbench.compensation.features.temperature_rate_c_per_s`), over a ring
  of at most ``<NAME>_RATE_CAPACITY`` samples (the most any window of the calibration record held,
  with half again as margin; more are counted in ``s->dropped`` and the oldest left out).
- ``bp`` and ``bp_gd``: the network on ``[T, dT/dt]`` held to its training box, scaled to
  [-1, 1] as it was trained and its output scaled back.
- ``elman``: the recurrent network steps once per time bin (``bin_s`` from the first sample),
  as it was trained (once per sample when it was trained on every sample: ``bin_s`` 0, a
  ``tcbench run`` network, :mod:`tcbench.compensation.run_device`). Python's calibration scores
  it on the bins' means interpolated between the bins' mean times, which reads up to 1.5 bins
  ahead; the device cannot. Here each sample gets
  the network's output for the mean of its bin so far, from the context the previous complete
  bin left (at a bin's last sample the two agree): that causal form is what
  :func:`streamed_offset` computes and the compiled code is checked against.
- an ``inverse`` network (:func:`inverse_spec`: a ``tcbench run`` network of ``msra_fulltemp``,
  seed 000's IFA-BP of Table 2, BP or Elman): the network on ``[raw, T]``, the temperature held to
  its training range and the raw output free, scaled as it was trained; ``update`` returns its
  output, the estimate of the input (acceleration, g), not raw minus an offset; no rate window.
  An Elman steps once per sample, as it was trained (:func:`streamed_corrected` is the reference).

- ``model``: the diagnosed model as its compensator runs it
  (:func:`~tcbench.compensation.fitted_model.compensator`: without the terms keyed to the
  calibration run's clock or its rig), in streaming form: the die temperature through each
  thermal lag as a first-order filter with its state, ``y += (1 - exp(-dt / tau)) (x - y)`` per
  sample (Python's exact discretisation, on the device's own intervals); the bias polynomial in the
  die temperature; and the terms :data:`MODEL_TERMS`. Python's calibration runs the model on a
  uniform grid and reads it back at the samples, takes the thermometer's rate as a central
  difference (it reads the next sample) and runs the hysteresis's play operator on a 1-Hz grid
  interpolated back; the device takes the rate as the backward difference over the last interval
  and runs the play operator at every sample. That causal form is what :func:`streamed_offset`
  computes. The offset is the model's output at zero input. A model whose scale factor is not
  one (a diagnosis of a record with several input levels: the core is ``bias(u) + a s(u)``, ``u``
  the normalised die temperature) returns the input that explains the reading,
  ``(raw - offset) / s(u)`` (:func:`streamed_corrected`); a diagnosis of a static record (one input
  level, all ``tcbench calibrate`` sees on a static record) writes a unit scale factor and its
  bias absorbs the level, so the model returns ``raw - offset``. A model with another term (an
  accelerometer's ``k a^2``, ``accel_nonlinearity``) is not exported, and the export says which.
- ``model_mean``: a ``tcbench run``'s diagnosed model (``learner=model``, :func:`run_model_spec`):
  one model per training run, each run as ``model`` on its own state, their offsets averaged (of
  the ``inverse`` form, their scale factors too: ``(raw - mean offset) / mean scale``, in the
  input's unit). A run of one training run keeps the plain ``model``.
- ``lagpoly``: a run's lag-aware polynomial (:func:`lagpoly_spec`) as a ``model`` of one thermal
  lag: the lag on the device's own intervals (the task's on the record's median interval: the
  same where the intervals are uniform), its polynomial in the lagged temperature, of the
  ``inverse`` form over its scale factor.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tcbench.compensation import c_model_terms as terms
from tcbench.compensation.c_model_terms import c_literal as _lit
from tcbench.compensation.calibration import RATE_WINDOW_S, OffsetModel
from tcbench.compensation.features import temperature_rate_c_per_s

EXPORTED = ("poly3", "poly3_rate", "bp", "bp_gd", "elman", "model")  # what a device can run of calibrate's methods
NOT_EXPORTED = {"raw": "no correction", "memoriser": "a control that needs the parts' starts, not a compensator"}
MODEL_TERMS = tuple(terms.TERMS)  # the diagnosed model's terms a device runs
CAPACITY_MARGIN = 1.5  # the rate ring holds this many times the calibration record's fullest window
NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,62}$")


def window_samples(t_s: np.ndarray, window_s: float = RATE_WINDOW_S) -> int:
    """The most samples any trailing window ``t_i - window_s < t_j <= t_i`` of ``t_s`` holds."""
    t = np.asarray(t_s, dtype=np.float64)
    if t.size == 0:
        return 0
    start = np.searchsorted(t, t - window_s, side="right")
    return int(np.max(np.arange(1, t.size + 1) - start))


def device_spec(model: OffsetModel, max_window_samples: int, rate_window_s: float = RATE_WINDOW_S) -> dict[str, Any]:
    """The parameters of ``model`` a device runs, as plain data (``calibration.json`` keeps them);
    ``max_window_samples``: the fullest rate window of the calibration record. ``ValueError`` for a
    method no device runs (:data:`NOT_EXPORTED`)."""
    if model.method not in EXPORTED:
        raise ValueError(f"{model.method}: {NOT_EXPORTED.get(model.method, 'not a method a device runs')}")
    capacity = max(2, int(np.ceil(CAPACITY_MARGIN * max_window_samples)))
    return _SPEC_OF.get(model.method, _network_device_spec)(model, rate_window_s, capacity)


def _cubic_device_spec(model: OffsetModel, rate_window_s: float, capacity: int) -> dict[str, Any]:
    c = model.cubic
    assert c is not None
    return {"method": model.method, "x": [float(v) for v in c.x], "tref_c": c.tref_c, "tmin_c": c.tmin_c,
            "tmax_c": c.tmax_c}


def _cubic_rate_device_spec(model: OffsetModel, rate_window_s: float, capacity: int) -> dict[str, Any]:
    return _cubic_device_spec(model, rate_window_s, capacity) | {
        "rate_coef": float(model.rate_coef), "rate_window_s": rate_window_s, "rate_capacity": capacity}


def _network_device_spec(model: OffsetModel, rate_window_s: float, capacity: int) -> dict[str, Any]:
    return network_spec(model.method, model.learner, model.temp_range_c, model.rate_range, rate_window_s, capacity,
                        model.bin_s)


# each method's spec from calibrate's fit (a network's by default)
_SPEC_OF: dict[str, Callable[[OffsetModel, float, int], dict[str, Any]]] = {
    "model": lambda model, rate_window_s, capacity: model_spec(model.sensor_model),
    "poly3": _cubic_device_spec,
    "poly3_rate": _cubic_rate_device_spec,
}


def _network_weights(method: str, learner: Any, bin_s: float | None) -> dict[str, Any]:
    """A fitted 2-input BP or Elman network's weights, activations and scaling as plain data."""
    if learner.x_scaler is None or learner.y_scaler is None:
        raise ValueError(f"{method}: the network has no normalisation (not fitted)")
    h, m = learner.params.hidden, learner.n_inputs
    if m != 2:
        raise ValueError(f"{method}: a network on {m} inputs; the device runs one on two")
    p = learner.get_params()
    spec = {"method": method, "hidden": h, "hidden_activation": learner.params.hidden_activation,
            "output_activation": learner.params.output_activation,
            "x_low": learner.x_scaler.low.tolist(), "x_high": learner.x_scaler.high.tolist(),
            "y_low": float(learner.y_scaler.low[0]), "y_high": float(learner.y_scaler.high[0])}
    if learner.sequential:
        i, j = h * m, h * m + h * h
        spec |= {"wx": p[:i].reshape(h, m).tolist(), "wc": p[i:j].reshape(h, h).tolist(), "b1": p[j:j + h].tolist(),
                 "w2": p[j + h:j + 2 * h].tolist(), "b2": float(p[-1]), "bin_s": float(bin_s or 0.0)}
        if not spec["bin_s"] >= 0:
            raise ValueError(f"{method}: bin_s must be >= 0, got {bin_s}")
    else:
        spec |= {"w1": p[:h * m].reshape(h, m).tolist(), "b1": p[h * m:h * m + h].tolist(),
                 "w2": p[h * m + h:h * m + 2 * h].tolist(), "b2": float(p[-1])}
    return spec


def _bounds(box: Any) -> list[float]:
    return [float(v) for v in (box if box is not None else (-np.inf, np.inf))]


def network_spec(method: str, learner: Any, temp_range_c: Any, rate_range: Any, rate_window_s: float, capacity: int,
                 bin_s: float | None) -> dict[str, Any]:
    """A fitted BP or Elman network on ``[T, dT/dt]`` as plain data: its weights, scaling and input
    box (``None``: unbounded); ``capacity``: the rate ring's samples; ``bin_s``: the time bins an
    Elman steps once per (0: once per sample, as a network trained on every sample runs)."""
    return _network_weights(method, learner, bin_s) | {
        "temp_range_c": _bounds(temp_range_c), "rate_range": _bounds(rate_range),
        "rate_window_s": rate_window_s, "rate_capacity": capacity}


def inverse_spec(method: str, learner: Any, raw_range: Any, temp_range_c: Any, quantity: str,
                 unit: str) -> dict[str, Any]:
    """A fitted BP or Elman network that maps ``[raw, T]`` to the input (``quantity`` in ``unit``,
    the ``inverse`` form of ``msra_fulltemp``) as plain data: its weights, scaling and input box
    (``None``: unbounded); an Elman steps once per sample, as it was trained."""
    return _network_weights(method, learner, 0.0) | {
        "form": "inverse", "inputs": ["raw", "temperature_c"], "input_quantity": quantity, "input_unit": unit,
        "raw_range": _bounds(raw_range), "temp_range_c": _bounds(temp_range_c)}


def run_cubic_spec(learner: Any, temp_range_c: Any) -> dict[str, Any]:
    """A ``tcbench run``'s fitted ``poly`` learner of the ``bias`` form (``poly3``, ``poly3_runs``:
    a Chebyshev series of degree <= 3 in the temperature scaled to [-1, 1] over the training runs,
    its output scaled back) as the ``poly3`` cubic a device runs: the same polynomial expanded in
    powers of ``T - T_ref``, ``T_ref`` the middle of the training range, the temperature held to
    ``temp_range_c`` (``None``: not held). ``ValueError`` naming why another form or degree is
    not exported."""
    from numpy.polynomial import chebyshev

    form = learner.describe().get("fitted_form")
    if form != "bias":
        why = {"bias_rate": "its rate term is a polynomial in T (the device's poly3_rate has a constant one)",
               "inverse": "it solves for the input from [raw, T] (the device's cubics return raw minus an offset)"}
        raise ValueError(f"poly of form {form!r}: {why.get(str(form), 'not fitted')}")
    coef = np.asarray(learner.get_params(), dtype=np.float64)
    if coef.size > 4:
        raise ValueError(f"poly of degree {coef.size - 1}: the device's cubic takes degree 3 at most")
    xs, ys = learner.x_scaler, learner.y_scaler
    half_c = 0.5 * float(xs.span[0])
    y_half = 0.5 * float(ys.span[0])
    power = np.zeros(4)
    power[:coef.size] = chebyshev.cheb2poly(coef)  # in u = (T - T_ref) / half_c
    x = y_half * power / half_c ** np.arange(4)
    x[0] += float(ys.low[0]) + y_half
    low, high = (-np.inf, np.inf) if temp_range_c is None else (float(temp_range_c[0]), float(temp_range_c[1]))
    return {"method": "poly3", "x": [float(v) for v in x], "tref_c": float(xs.low[0]) + half_c,
            "tmin_c": low, "tmax_c": high}


def run_poly_spec(learner: Any, box: tuple[Any, Any] | None, rate_window_s: float = RATE_WINDOW_S,
                  capacity: int = 2, quantity: str = "input", unit: str = "") -> dict[str, Any]:
    """A ``tcbench run``'s fitted ``poly`` learner of any form and degree as the ``poly`` (or, with
    its rate term, ``poly_rate``) a device runs: its Chebyshev series in the inputs scaled to
    [-1, 1] as it was fitted, its output scaled back. ``bias``: the offset ``b(T)``;
    ``bias_rate``: ``b(T) + r(T) dT/dt`` on the trailing rate window (``rate_window_s``, a ring
    of ``capacity`` samples); ``inverse``: the input (``quantity`` in ``unit``) solved from
    ``[raw, T]``, ``(raw - b(T)) / K(T)`` in scaled units. ``box``: the lower and upper bounds of
    the learner's two inputs (``None``: not held)."""
    form = str(learner.describe().get("fitted_form"))
    if form not in ("bias", "bias_rate", "inverse"):
        raise ValueError(f"poly of form {form!r}: not fitted")
    coef = np.asarray(learner.get_params(), dtype=np.float64)
    d = int(learner.settings.degree)
    xs, ys = learner.x_scaler, learner.y_scaler
    low, high = (np.full(2, -np.inf), np.full(2, np.inf)) if box is None else box
    spec: dict[str, Any] = {"method": "poly_rate" if form == "bias_rate" else "poly", "form": form, "degree": d,
                            "bias": coef[:d + 1].tolist(), "x_low": xs.low.tolist(), "x_span": xs.span.tolist(),
                            "y_low": float(ys.low[0]), "y_span": float(ys.span[0])}
    if form == "inverse":
        return spec | {"scale": coef[d + 1:].tolist(), "inputs": ["raw", "temperature_c"], "input_quantity": quantity,
                       "input_unit": unit, "raw_range": _bounds((low[0], high[0])),
                       "temp_range_c": _bounds((low[1], high[1]))}
    spec |= {"inputs": ["temperature_c", "rate"], "temp_range_c": _bounds((low[0], high[0]))}
    if form == "bias_rate":
        spec |= {"rate": coef[d + 1:].tolist(), "rate_range": _bounds((low[1], high[1])),
                 "rate_window_s": float(rate_window_s), "rate_capacity": int(capacity)}
    return spec


def is_inverse(spec: dict[str, Any]) -> bool:
    """Whether ``spec`` returns the input estimated from ``[raw, T]`` (else raw minus an offset)."""
    return spec.get("form") == "inverse"


def model_spec(sensor_model: Any) -> dict[str, Any]:
    """The compensator of a diagnosed :class:`~tcbench.sensors.fitted.PolynomialModel` as plain
    data: its core and its terms in order; ``ValueError`` naming a term a device does not run."""
    from tcbench.compensation.fitted_model import compensator

    quiet = compensator(sensor_model)
    if other := [type(e).id for e in quiet.effects if type(e).id not in MODEL_TERMS]:
        raise ValueError(f"model: its {', '.join(other)} term{'s' * (len(other) > 1)} "
                         f"{'are' if len(other) > 1 else 'is'} not exported as C (exported: {', '.join(MODEL_TERMS)})")
    effects = [{"id": type(e).id, **{k: float(v) for k, v in e.params().items()}} for e in quiet.effects]
    spec = {"method": "model", "centre_c": quiet.centre_c, "half_range_c": quiet.half_range_c,
            "bias": [float(b) for b in quiet.bias], "ref_c": float(quiet.ref_c), "effects": effects}
    if tuple(float(k) for k in quiet.scale_factor) != (1.0,):
        if not any(float(k) != 0.0 for k in quiet.scale_factor):
            raise ValueError("model: its scale factor is zero (the output does not follow the input)")
        spec["scale_factor"] = [float(k) for k in quiet.scale_factor]
    return spec


def lagpoly_spec(fitted: Any, inverse: bool, quantity: str = "input", unit: str = "") -> dict[str, Any]:
    """A fitted lag-aware polynomial (:class:`~tcbench.compensation.lagpoly.LagPoly`) as the
    diagnosed model a device runs (``model`` kind, method ``lagpoly``): its bias polynomial in the
    normalised lagged temperature, its lag the model's first-order filter on the device's own
    intervals; ``inverse``: with its scale factor, the input (``quantity`` in ``unit``) solved
    from the reading. ``ValueError`` for an inverse form without a scale factor."""
    tau_s = float(fitted.tau_s)
    spec: dict[str, Any] = {"method": "lagpoly", "centre_c": float(fitted.centre_c),
                            "half_range_c": float(fitted.half_range_c), "bias": [float(b) for b in fitted.bias],
                            "ref_c": float(fitted.centre_c),
                            "effects": [{"id": "thermal_lag", "tau_s": tau_s}] if tau_s > 0 else []}
    if not inverse:
        return spec
    if fitted.scale is None:
        raise ValueError("lagpoly: a bias-only lag polynomial cannot solve for the input")
    return spec | {"scale_factor": [float(k) for k in fitted.scale], "input_quantity": quantity, "input_unit": unit}


def run_model_spec(models: Any, inverse: bool, quantity: str = "input", unit: str = "") -> dict[str, Any]:
    """A run's diagnosed model (``learner=model``: one diagnosed model per training run, their
    compensators' outputs averaged) as the device runs it: one model as calibrate's ``model``
    (:func:`model_spec`), several as ``model_mean``, each on its own state, the offsets (and,
    ``inverse``, the scale factors) averaged; ``inverse``: the input (``quantity`` in ``unit``)
    ``(raw - b) / s`` of the mean ``b`` and ``s``; otherwise raw minus the mean offset (the scale
    factors dropped, as the task's bias form drops them). ``ValueError`` naming a term not exported."""
    members = [model_spec(m) for m in models]
    if not inverse:
        members = [{k: v for k, v in m.items() if k != "scale_factor"} for m in members]
    spec = members[0] if len(members) == 1 else {"method": "model_mean", "models": members}
    return spec | ({"input_quantity": quantity, "input_unit": unit} if inverse else {})


def streamed_corrected(spec: dict[str, Any], clock_s: np.ndarray, temp_c: np.ndarray, raw: np.ndarray,
                       rate_c_per_s: np.ndarray | None = None) -> np.ndarray:
    """What the exported code returns at each sample, in numpy: ``raw`` minus
    :func:`streamed_offset`, over the diagnosed model's scale factor where it has one (the input
    that explains the reading); for an ``inverse`` network (:func:`inverse_spec`) the network's
    estimate of the input from ``[raw, T]``."""
    if is_inverse(spec):
        t = np.asarray(clock_s, dtype=np.float64)
        return _kind(spec).estimate(spec, t, np.asarray(raw, dtype=np.float64), np.asarray(temp_c, dtype=np.float64))
    corrected = np.asarray(raw, dtype=np.float64) - streamed_offset(spec, clock_s, temp_c, rate_c_per_s)
    if not _scaled(spec):
        return corrected
    t, temp = np.asarray(clock_s, dtype=np.float64), np.asarray(temp_c, dtype=np.float64)
    return corrected / np.mean([_model_scale(m, t, temp) for m in spec.get("models", [spec])], axis=0)


def _model_scale(spec: dict[str, Any], t: np.ndarray, temp: np.ndarray) -> np.ndarray:
    """A diagnosed model's scale factor in its die temperature at each sample (1 without one)."""
    u = (terms.die_temperature(spec["effects"], np.r_[0.0, np.diff(t)], temp) - spec["centre_c"]) / spec["half_range_c"]
    scale = np.zeros_like(u) if "scale_factor" in spec else np.ones_like(u)
    for k in reversed(spec.get("scale_factor", [])):
        scale = scale * u + k
    return scale


def _model_streamed(spec: dict[str, Any], t: np.ndarray, temp: np.ndarray) -> np.ndarray:
    """The causal diagnosed model (see the module doc): the die stages first, as the simulator runs
    them, then the bias polynomial in the die temperature and each term's addition, in order."""
    dt = np.r_[0.0, np.diff(t)]
    effects = spec["effects"]
    die = terms.die_temperature(effects, dt, temp)
    signals = terms.Signals(dt, temp, die, spec["ref_c"])
    added = [terms.TERMS[e["id"]].reference(e, signals) for e in effects if not terms.TERMS[e["id"]].die_stage]
    offset = np.zeros(t.size)
    u = (die - spec["centre_c"]) / spec["half_range_c"]
    for c in reversed(spec["bias"]):
        offset = offset * u + c
    for term in added:
        offset = offset + term
    return offset


def device_clock_s(dt_s: np.ndarray) -> np.ndarray:
    """The clock a device keeps from the intervals it is given: 0 at the first sample, then the
    running sum of ``dt_s[1:]`` in double, added one by one as the C code adds them."""
    dt = np.asarray(dt_s, dtype=np.float64).reshape(-1)
    if dt.size == 0:
        return dt.copy()
    return np.concatenate([[0.0], np.cumsum(dt[1:])])


def _sigma(a: np.ndarray, kind: str) -> np.ndarray:
    return np.tanh(a) if kind == "tanh" else 0.5 * (1.0 + np.tanh(0.5 * a))


def _input_ranges(spec: dict[str, Any]) -> tuple[list[float], list[float]]:
    """The box each of the network's two inputs is held to, in its input order: ``[T, dT/dt]``, or
    ``[raw, T]`` for an ``inverse`` network."""
    if is_inverse(spec):
        return spec["raw_range"], spec["temp_range_c"]
    return spec["temp_range_c"], spec["rate_range"]


def _scaled_inputs(spec: dict[str, Any], first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """The network's two inputs held to the training box and mapped to [-1, 1] as it was trained."""
    box = _input_ranges(spec)
    x = np.column_stack([np.clip(first, *box[0]), np.clip(second, *box[1])])
    low, high = np.asarray(spec["x_low"]), np.asarray(spec["x_high"])
    span = np.where(high - low > 0, high - low, 1.0)
    return 2.0 * (x - low) / span - 1.0


def _unscaled(spec: dict[str, Any], z: np.ndarray) -> np.ndarray:
    y = np.tanh(z) if spec["output_activation"] == "tanh" else z
    span = spec["y_high"] - spec["y_low"]
    span = span if span > 0 else 1.0
    return (y + 1.0) * 0.5 * span + spec["y_low"]


def streamed_offset(spec: dict[str, Any], clock_s: np.ndarray, temp_c: np.ndarray,
                    rate_c_per_s: np.ndarray | None = None) -> np.ndarray:
    """The offset the exported code computes at each sample, in numpy: ``clock_s`` the device's
    clock (:func:`device_clock_s`), ``temp_c`` its thermometer, from ``init`` on;
    ``rate_c_per_s``: :func:`~tcbench.compensation.features.temperature_rate_c_per_s` of them when
    already computed. An ``inverse`` network has no offset (:func:`streamed_corrected`)."""
    t = np.asarray(clock_s, dtype=np.float64)
    temp = np.asarray(temp_c, dtype=np.float64)
    kind = _kind(spec)
    rate = None
    if kind.rated:
        if rate_c_per_s is None:
            rate_c_per_s = temperature_rate_c_per_s(t, temp, spec["rate_window_s"])
        rate = np.asarray(rate_c_per_s, dtype=np.float64)
    return kind.offset(spec, t, temp, rate)


def _cubic_offset(spec: dict[str, Any], t: np.ndarray, temp: np.ndarray, rate: np.ndarray | None) -> np.ndarray:
    x = spec["x"]
    dt = np.clip(temp, spec["tmin_c"], spec["tmax_c"]) - spec["tref_c"]
    return x[0] + dt * (x[1] + dt * (x[2] + dt * x[3]))


def _cubic_rate_offset(spec: dict[str, Any], t: np.ndarray, temp: np.ndarray, rate: np.ndarray | None) -> np.ndarray:
    return _cubic_offset(spec, t, temp, rate) + spec["rate_coef"] * rate


def _poly_out(spec: dict[str, Any], first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """A run's polynomial (:func:`run_poly_spec`) on its two inputs (``spec['inputs']``' order),
    held to its box and scaled as it was fitted: the offset, or for ``inverse`` the input."""
    from numpy.polynomial import chebyshev

    (a_lo, a_hi), (b_lo, b_hi) = _poly_ranges(spec)
    low, span = np.asarray(spec["x_low"]), np.asarray(spec["x_span"])
    x = 2.0 * (np.column_stack([np.clip(first, a_lo, a_hi), np.clip(second, b_lo, b_hi)]) - low) / span - 1.0
    inverse = is_inverse(spec)
    basis = chebyshev.chebvander(x[:, 1 if inverse else 0], int(spec["degree"]))
    y = basis @ np.asarray(spec["bias"])
    if inverse:
        y = (x[:, 0] - y) / (basis @ np.asarray(spec["scale"]))
    elif "rate" in spec:
        y = y + (basis[:, :-1] * x[:, 1:2]) @ np.asarray(spec["rate"])
    return (y + 1.0) * 0.5 * spec["y_span"] + spec["y_low"]


def _poly_ranges(spec: dict[str, Any]) -> tuple[list[float], list[float]]:
    """The box each of a run's polynomial's two inputs is held to (the rate of a ``bias`` form: free)."""
    if is_inverse(spec):
        return spec["raw_range"], spec["temp_range_c"]
    return spec["temp_range_c"], spec.get("rate_range", [-np.inf, np.inf])


def _network_out(spec: dict[str, Any], t: np.ndarray, first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """The network's output on its two inputs (:func:`_input_ranges`' order) at each sample."""
    if "wc" not in spec:
        x = _scaled_inputs(spec, first, second)
        h = _sigma(x @ np.asarray(spec["w1"]).T + np.asarray(spec["b1"]), spec["hidden_activation"])
        return _unscaled(spec, h @ np.asarray(spec["w2"]) + spec["b2"])
    return _elman_streamed(spec, t, first, second)


def _elman_streamed(spec: dict[str, Any], t: np.ndarray, first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """The causal Elman: each sample the output for its bin's mean inputs so far, from the context
    of the previous complete bin (see the module doc)."""
    wx, wc = np.asarray(spec["wx"]), np.asarray(spec["wc"])
    b1, w2 = np.asarray(spec["b1"]), np.asarray(spec["w2"])
    index = np.floor(t / spec["bin_s"]).astype(np.int64) if spec["bin_s"] > 0 else np.arange(t.size)
    starts = np.flatnonzero(np.r_[True, index[1:] != index[:-1]])
    stops = np.r_[starts[1:], t.size]
    out = np.empty(t.size)
    context = np.zeros(wc.shape[0])
    for a, b in zip(starts, stops):
        count = np.arange(1, b - a + 1)
        means = np.column_stack([np.cumsum(first[a:b]) / count, np.cumsum(second[a:b]) / count])
        drive = wc @ context + b1
        h = _sigma(_scaled_inputs(spec, means[:, 0], means[:, 1]) @ wx.T + drive, spec["hidden_activation"])
        out[a:b] = _unscaled(spec, h @ w2 + spec["b2"])
        context = h[-1]
    return out


# -- what each kind of spec runs -------------------------------------------------------------------


@dataclass(frozen=True)
class _Kind:
    """How the export runs one kind of spec: whether it reads the trailing rate window, its
    operations per sample and the update's lines that compute ``offset`` (or, for an inverse
    form, ``estimate``), its numpy reference (:func:`streamed_offset`; :func:`streamed_corrected`
    its ``estimate`` of the input from the clock, raw and temperature for an inverse form), its
    state slots besides the clock and the counters, whether it is a network (whose weights the
    source holds), and what the header calls it."""

    rated: bool
    code: Callable[[dict[str, Any]], tuple[str, list[str]]]
    offset: Callable[[dict[str, Any], np.ndarray, np.ndarray, np.ndarray | None], np.ndarray]
    slots: Callable[[dict[str, Any]], list[str]] = lambda spec: []
    network: bool = False
    estimate: Callable[[dict[str, Any], np.ndarray, np.ndarray, np.ndarray], np.ndarray] | None = None
    noun: str = "network"


def _kind(spec: dict[str, Any]) -> _Kind:
    """The kind of ``spec``: by its method, a network (on ``[T, dT/dt]``, or ``inverse``) otherwise."""
    return _KINDS.get(spec["method"]) or (_INVERSE if is_inverse(spec) else _NETWORK)


def _no_offset(spec: dict[str, Any], t: np.ndarray, temp: np.ndarray, rate: np.ndarray | None) -> np.ndarray:
    raise ValueError(f"{spec['method']}: an inverse network returns the input, not an offset (streamed_corrected)")


# -- the C sources ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class CSource:
    """The header and source of one exported method, and what its header states."""

    header: str
    source: str
    state_bytes: dict[str, int]  # by build: double, float (x86-64 and ARM EABI alignment)
    flops: str  # floating-point operations per sample, in words


def _array(values: Any) -> str:
    flat = np.asarray(values, dtype=np.float64).reshape(-1)
    return "{" + ", ".join(_lit(v) for v in flat) + "}"


def _clamped(var: str, lo: float, hi: float) -> str:
    """C for ``var`` held to ``[lo, hi]`` (an infinite bound: not held on that side)."""
    above = f"({var} > (R){_lit(hi)} ? (R){_lit(hi)} : {var})" if np.isfinite(hi) else var
    return f"({var} < (R){_lit(lo)} ? (R){_lit(lo)} : {above})" if np.isfinite(lo) else above


def _state_bytes(doubles: int, reals: int, ints: int, real_size: int) -> int:
    size = 8 * doubles + real_size * reals + 4 * ints
    return -(-size // 8) * 8


def c_sources(spec: dict[str, Any], name: str, about: str = "") -> CSource:
    """``<name>.h`` and ``<name>.c`` of ``spec`` (:func:`device_spec`); ``about``: one line for
    the header (the recording, sensor, axis and unit)."""
    if not NAME.match(name):
        raise ValueError(f"{name!r} is not a C identifier (letters, digits, _; not starting with a digit)")
    method = spec["method"]
    up = name.upper()
    inverse = is_inverse(spec)
    kind = _kind(spec)
    rated = kind.rated
    recurrent = "wc" in spec
    slots = kind.slots(spec)
    h = int(spec.get("hidden", 0))
    cap = int(spec.get("rate_capacity", 0))
    # the state: doubles (clock, ring times), reals (ring temperatures, Elman's), int32 counters
    doubles = 1 + (cap if rated else 0)
    reals = (cap if rated else 0) + (3 * h + 2 if recurrent else 0) + len(slots)
    ints = 1 + (3 if rated else 0) + (2 if recurrent else 0)
    sizes = {"double": _state_bytes(doubles, reals, ints, 8), "float": _state_bytes(doubles, reals, ints, 4)}
    flops, body = kind.code(spec)
    if inverse:
        held = ("the temperature held to its training range, {:g} to {:g} degC".format(*spec["temp_range_c"])
                if np.all(np.isfinite(spec["temp_range_c"])) else "the temperature not held")
        returns = [f" * Call {name}_init once, then {name}_update once per sample in time order: it returns the",
                   f" * {kind.noun}'s estimate of the input ({spec['input_quantity']}, in {spec['input_unit']}) "
                   "from the raw output and the temperature",
                   f" * ({held}), not a corrected output."]
    else:
        returns = [f" * Call {name}_init once, then {name}_update once per sample in time order: it returns raw minus",
                   (" * the offset, over the scale factor s(T_die) (the input that explains the reading)."
                    if _scaled(spec) else " * the offset.")]
        if _scaled(spec) and "input_unit" in spec:
            returns.append(f" * It is the {spec['input_quantity']}, in {spec['input_unit']}, not a corrected output.")
    lines = [f"/* {name}.h: temperature compensation by the {method} method, exported by tcbench export formats=[c].",
             *([f" * {about}"] if about else []),
             " *",
             *returns,
             " * dt_s is the time since the previous sample (> 0; the first sample's is ignored).",
             f" * Build: double by default; define {up}_FLOAT for float (the clock stays a double).",
             f" * State: {sizes['double']} bytes (double build), {sizes['float']} bytes (float build); no allocation.",
             f" * Floating-point operations per sample: {flops}.",
             " * Compile as ISO C99 (-std=c99: no fused multiply-add contraction) to reproduce tcbench's numbers.",
             " */"]
    header = "\n".join(lines) + f"""
#ifndef {up}_H
#define {up}_H

#ifdef {up}_FLOAT
typedef float {name}_real;
#else
typedef double {name}_real;
#endif
""" + (f"""
#ifndef {up}_RATE_CAPACITY
#define {up}_RATE_CAPACITY {cap}  /* samples the trailing {spec['rate_window_s']:g}-s rate window can hold */
#endif
""" if rated else "") + f"""
typedef struct {{
    double clock_s;  /* time since the first sample (s) */
""" + (f"""    double ring_t_s[{up}_RATE_CAPACITY];  /* the rate window's times and temperatures */
    {name}_real ring_temp_c[{up}_RATE_CAPACITY];
""" if rated else "") + (f"""    {name}_real context[{h}];  /* the hidden state the last complete bin left */
    {name}_real drive[{h}];  /* W_c context + b1, once per bin */
    {name}_real pending[{h}];  /* the hidden state of the bin so far */
    {name}_real bin_sum[2];  /* the bin's sums of the network's inputs ({'raw, T' if inverse else 'T, dT/dt'}) */
""" if recurrent else "") + (f"""    {name}_real memory[{len(slots)}];  /* {', '.join(slots)} */
""" if slots else "") + """    int samples;  /* samples seen (saturates) */
""" + ("""    int head, count;  /* the ring's oldest sample, samples in it */
    int dropped;  /* samples left out of a full window (0 when the capacity suffices) */
""" if rated else "") + ("""    int bin, bin_count;  /* the current bin and its samples */
""" if recurrent else "") + f"""}} {name}_state;

void {name}_init({name}_state *s);
{name}_real {name}_update({name}_state *s, {name}_real temperature_c, {name}_real raw, {name}_real dt_s);

#endif
"""
    source = _source(spec, name, up, body, kind)
    return CSource(header, source, sizes, flops)


def _cubic_code(spec: dict[str, Any]) -> tuple[str, list[str]]:
    return "8", [_cubic_body(spec).rstrip("\n")]


def _cubic_rate_code(spec: dict[str, Any]) -> tuple[str, list[str]]:
    cap = int(spec["rate_capacity"])
    return (f"10 + 9 n, n the samples in the rate window (at most {cap}: {10 + 9 * cap})",
            [_cubic_body(spec).rstrip("\n"), f"    offset = offset + (R){_lit(spec['rate_coef'])} * rate;"])


def _model_code(spec: dict[str, Any]) -> tuple[str, list[str]]:
    flops, body = _model_body(spec)
    return flops, [body.rstrip("\n")]


def _network_code(spec: dict[str, Any]) -> tuple[str, list[str]]:
    """A network's operations per sample, and the update's lines that run it (an Elman once per
    time bin or sample, from the context of the previous one)."""
    h, cap = int(spec["hidden"]), int(spec.get("rate_capacity", 0))
    recurrent = "wc" in spec
    names, result = _NETWORK_IO[is_inverse(spec)]
    per = 8 + 4 * h + 2 * h + 6 + (6 if recurrent else 0)
    flops = (f"{per} and {h} tanh" if is_inverse(spec) else
             f"{per} + 9 n and {h} tanh, n the samples in the rate window (at most {cap}: {per + 9 * cap})")
    if not recurrent:
        return flops, [f"    R hidden[{h}];", f"    R {result} = network({names[0]}, {names[1]}, B1, hidden);"]
    flops += f"; and {2 * h * h + h} more once per " + (f"{spec['bin_s']:g}-s bin" if spec["bin_s"] > 0 else "sample")
    return flops, [
        f"    R {result};",
        (f"    int bin = (int)floor(s->clock_s / {_lit(spec['bin_s'])});" if spec["bin_s"] > 0
         else "    int bin = s->samples;  /* a network trained on every sample steps every sample */"),
        "    if (s->bin_count > 0 && bin != s->bin) {  /* the previous bin is complete: its state is the context */",
        "        int i, j;",
        f"        for (j = 0; j < {h}; j++) s->context[j] = s->pending[j];",
        f"        for (i = 0; i < {h}; i++) {{",
        "            R a = 0;",
        f"            for (j = 0; j < {h}; j++) a += W_C[i][j] * s->context[j];",
        "            s->drive[i] = a + B1[i];",
        "        }",
        "        s->bin_count = 0;",
        "        s->bin_sum[0] = 0;",
        "        s->bin_sum[1] = 0;",
        "    }",
        "    s->bin = bin;",
        "    s->bin_count++;",
        f"    s->bin_sum[0] += {names[0]};",
        f"    s->bin_sum[1] += {names[1]};",
        f"    {result} = network(s->bin_sum[0] / (R)s->bin_count, s->bin_sum[1] / (R)s->bin_count, "
        "s->drive, s->pending);"]


def _poly_code(spec: dict[str, Any]) -> tuple[str, list[str]]:
    """A run's polynomial (:func:`run_poly_spec`): its operations per sample and the update's
    lines, the Chebyshev polynomials of the scaled temperature by their recurrence (as numpy's
    ``chebvander``), the series summed, the output scaled back."""
    d, inverse, rated = int(spec["degree"]), is_inverse(spec), "rate" in spec
    names, result = _NETWORK_IO[inverse]
    (a_lo, a_hi), (b_lo, b_hi) = _poly_ranges(spec)
    low, span = spec["x_low"], spec["x_span"]
    lines = [f"    R x0 = (R)2 * ({_clamped(names[0], a_lo, a_hi)} - (R){_lit(low[0])}) / (R){_lit(span[0])} - (R)1;"]
    if inverse or rated:
        lines.append(f"    R x1 = (R)2 * ({_clamped(names[1], b_lo, b_hi)} - (R){_lit(low[1])}) / (R){_lit(span[1])}"
                     " - (R)1;")
    u = "x1" if inverse else "x0"
    flops = 4 * len(lines)
    lines.append(f"    R c0 = (R)1, c1 = {u};")
    if d > 1:
        lines.append(f"    R u2 = (R)2 * {u};")
        lines += [f"    R c{k} = c{k - 1} * u2 - c{k - 2};" for k in range(2, d + 1)]
        flops += 1 + 2 * (d - 1)

    def series(coef: list[float], times: str = "") -> str:
        return " + ".join(f"(c{k}{times}) * (R){_lit(c)}" for k, c in enumerate(coef))

    lines.append(f"    R y = {series(spec['bias'])};")
    flops += 2 * d + 1
    if inverse:
        lines += [f"    R k = {series(spec['scale'])};", "    y = (x0 - y) / k;"]
        flops += 2 * d + 1 + 2
    elif rated:
        lines.append(f"    y = y + ({series(spec['rate'], ' * x1')});")
        flops += 3 * d
    lines.append(f"    R {result} = (y + (R)1) * (R)0.5 * (R){_lit(spec['y_span'])} + (R){_lit(spec['y_low'])};")
    flops += 4 + (0 if inverse else 1)
    if not rated:
        return str(flops), lines
    cap = int(spec["rate_capacity"])
    return f"{flops} + 9 n, n the samples in the rate window (at most {cap}: {flops + 9 * cap})", lines


# a network's two inputs and what its update computes, by whether it is an inverse one
_NETWORK_IO = {False: (("temperature_c", "rate"), "offset"), True: (("raw", "temperature_c"), "estimate")}


def _cubic_body(spec: dict[str, Any]) -> str:
    x = spec["x"]
    return f"""    R t = temperature_c < (R){_lit(spec['tmin_c'])} ? (R){_lit(spec['tmin_c'])}
        : (temperature_c > (R){_lit(spec['tmax_c'])} ? (R){_lit(spec['tmax_c'])} : temperature_c);
    R d = t - (R){_lit(spec['tref_c'])};
    R offset = (R){_lit(x[0])} + d * ((R){_lit(x[1])} + d * ((R){_lit(x[2])} + d * (R){_lit(x[3])}));
"""


def _model_slots(spec: dict[str, Any]) -> list[str]:
    """The diagnosed model's state: each lag's and play operator's memory, the last temperature."""
    return terms.slots(spec["effects"])


def _model_body(spec: dict[str, Any]) -> tuple[str, str]:
    """The update of the diagnosed model (see the module doc) and its operations per sample."""
    flops, calls, lines = _model_lines(spec, 0)
    return f"{flops}" + (f" and {calls} exp" if calls else ""), "\n".join(lines) + "\n"


def _model_lines(spec: dict[str, Any], base: int) -> tuple[int, int, list[str]]:
    """The update's lines of one diagnosed model whose state starts at ``s->memory[base]``, its
    operations and its ``exp`` calls per sample: its die stages in order, the bias polynomial in the
    die temperature, each term's addition in order (:mod:`.c_model_terms`), the scale factor."""
    effects, slots = spec["effects"], _model_slots(spec)
    lines = ["    int first = s->samples == 1;"] * bool(slots) + [
        "    R die = temperature_c, offset = 0, u" + (", scale;" if "scale_factor" in spec else ";")]
    flops, calls = 0, 0

    def add(staged: bool) -> None:
        nonlocal flops, calls
        for k, e in enumerate(effects):
            term = terms.TERMS[e["id"]]
            if term.die_stage == staged:
                at = base + terms.slot_of(effects, k, slots) if term.slot is not None else -1
                update = term.c_lines(e, spec["ref_c"], at)
                lines.extend(update.lines)
                flops, calls = flops + update.flops, calls + update.calls

    add(staged=True)
    lines.append(f"    u = (die - (R){_lit(spec['centre_c'])}) / (R){_lit(spec['half_range_c'])};")
    for c in reversed(spec["bias"]):
        lines.append(f"    offset = offset * u + (R){_lit(c)};")
    flops += 2 + 2 * len(spec["bias"])
    add(staged=False)
    if "scale_factor" in spec:  # the input that explains the reading: (raw - offset) / s(u)
        lines.append("    scale = 0;")
        for k in reversed(spec["scale_factor"]):
            lines.append(f"    scale = scale * u + (R){_lit(k)};")
        flops += 2 * len(spec["scale_factor"]) + 1
    flops += 1
    return flops, calls, lines


def _model_mean_code(spec: dict[str, Any]) -> tuple[str, list[str]]:
    """The mean of several diagnosed models (a run's, one per training run): each model's update in
    its own block on its own state, their offsets (and scale factors) averaged."""
    scaled = _scaled(spec)
    lines = ["    R total = 0" + (", total_scale = 0;" if scaled else ";")]
    flops, calls, base = 0, 0, 0
    for m in spec["models"]:
        f, c, body = _model_lines(m, base)
        base += len(_model_slots(m))
        lines += ["    {", *("    " + line for line in body), "        total += offset;"]
        if scaled:
            lines.append("        total_scale += " + ("scale;" if "scale_factor" in m else "(R)1;"))
        lines.append("    }")
        flops, calls = flops + f + 1 + scaled, calls + c
    n = len(spec["models"])
    lines.append(f"    R offset = total / (R){n};")
    if scaled:
        lines.append(f"    R scale = total_scale / (R){n};")
    flops += 1 + scaled
    return f"{flops}" + (f" and {calls} exp" if calls else ""), lines


def _model_mean_slots(spec: dict[str, Any]) -> list[str]:
    return [f"model {k} {slot}" for k, m in enumerate(spec["models"]) for slot in _model_slots(m)]


def _scaled(spec: dict[str, Any]) -> bool:
    """Whether the update returns ``(raw - offset) / scale`` (a model with a scale factor)."""
    return "scale_factor" in spec or any("scale_factor" in m for m in spec.get("models", ()))


def _source(spec: dict[str, Any], name: str, up: str, body: list[str], kind: _Kind) -> str:
    rated, recurrent, h = kind.rated, "wc" in spec, int(spec.get("hidden", 0))
    inverse = is_inverse(spec)  # the network's inputs, and what update returns
    names, _ = _NETWORK_IO[inverse]
    parts = [f"/* {name}.c: see {name}.h. */\n#include <math.h>\n#include \"{name}.h\"\n\ntypedef {name}_real R;\n"
             f"#ifdef {up}_FLOAT\n#define TC_EXP expf\n#define TC_TANH tanhf\n#else\n#define TC_EXP exp\n"
             "#define TC_TANH tanh\n#endif\n"]
    if rated:
        parts.append(f"""
#define RATE_WINDOW_S {_lit(spec['rate_window_s'])}

/* The least-squares slope (degC/s) of the temperatures in the trailing window t_i - w < t_j <= t_i. */
static R rate_c_per_s({name}_state *s, R temperature_c)
{{
    int k, n, at;
    double edge = s->clock_s - RATE_WINDOW_S, t_mean = 0.0;
    R y_mean = 0, sxx = 0, sxy = 0;
    while (s->count > 0 && s->ring_t_s[s->head] <= edge) {{
        s->head = (s->head + 1) % {up}_RATE_CAPACITY;
        s->count--;
    }}
    if (s->count == {up}_RATE_CAPACITY) {{
        s->head = (s->head + 1) % {up}_RATE_CAPACITY;
        s->count--;
        s->dropped++;
    }}
    at = (s->head + s->count) % {up}_RATE_CAPACITY;
    s->ring_t_s[at] = s->clock_s;
    s->ring_temp_c[at] = temperature_c;
    n = ++s->count;
    if (n < 2) return 0;
    for (k = 0; k < n; k++) {{
        at = (s->head + k) % {up}_RATE_CAPACITY;
        t_mean += s->ring_t_s[at] - s->clock_s;
        y_mean += s->ring_temp_c[at] - temperature_c;
    }}
    t_mean /= n;
    y_mean /= (R)n;
    for (k = 0; k < n; k++) {{
        at = (s->head + k) % {up}_RATE_CAPACITY;
        R u = (R)(s->ring_t_s[at] - s->clock_s - t_mean);
        R v = s->ring_temp_c[at] - temperature_c - y_mean;
        sxx += u * u;
        sxy += u * v;
    }}
    return sxx > 0 ? sxy / sxx : 0;
}}
""")
    if kind.network:
        low, high = spec["x_low"], spec["x_high"]
        span = [hi - lo if hi - lo > 0 else 1.0 for lo, hi in zip(low, high)]
        y_span = spec["y_high"] - spec["y_low"]
        y_span = y_span if y_span > 0 else 1.0
        (a_lo, a_hi), (b_lo, b_hi) = _input_ranges(spec)
        act = "TC_TANH(a)" if spec["hidden_activation"] == "tanh" else "(R)0.5 * ((R)1 + TC_TANH((R)0.5 * a))"
        out = "TC_TANH(z)" if spec["output_activation"] == "tanh" else "z"
        w_in = spec["wx"] if recurrent else spec["w1"]
        parts.append(f"""
static const R W_IN[{h}][2] = {{{', '.join(_array(row) for row in w_in)}}};
static const R B1[{h}] = {_array(spec['b1'])};
static const R W2[{h}] = {_array(spec['w2'])};
static const R B2 = {_lit(spec['b2'])};
""" + (f"static const R W_C[{h}][{h}] = {{{', '.join(_array(row) for row in spec['wc'])}}};\n" if recurrent else "")
                     + f"""
/* The network's output ({'the input estimate' if inverse else 'the offset'}) for \
{'[raw, T]' if inverse else '[T, dT/dt]'}, held to the training box, scaled to [-1, 1];
   hidden: its hidden outputs, drive: W_c context + b1 (Elman) or b1. */
static R network(R {names[0]}, R {names[1]}, const R *drive, R *hidden)
{{
    int j;
    R x0 = (R)2 * ({_clamped(names[0], a_lo, a_hi)} - (R){_lit(low[0])}) / (R){_lit(span[0])} - (R)1;
    R x1 = (R)2 * ({_clamped(names[1], b_lo, b_hi)} - (R){_lit(low[1])}) / (R){_lit(span[1])} - (R)1;
    R z = 0;
    for (j = 0; j < {h}; j++) {{
        R a = x0 * W_IN[j][0] + x1 * W_IN[j][1] + drive[j];
        hidden[j] = {act};
        z += hidden[j] * W2[j];
    }}
    z += B2;
    return ({out} + (R)1) * (R)0.5 * (R){_lit(y_span)} + (R){_lit(spec['y_low'])};
}}
""")
    init = [f"void {name}_init({name}_state *s)\n{{", "    s->clock_s = 0.0;", "    s->samples = 0;"]
    if rated:
        init += ["    s->head = 0;", "    s->count = 0;", "    s->dropped = 0;"]
    if recurrent:
        init += ["    {", "        int j;", f"        for (j = 0; j < {h}; j++) {{",
                 "            s->context[j] = 0;", "            s->pending[j] = 0;", "            s->drive[j] = B1[j];",
                 "        }", "    }", "    s->bin = 0;", "    s->bin_count = 0;", "    s->bin_sum[0] = 0;",
                 "    s->bin_sum[1] = 0;"]
    parts.append("\n" + "\n".join(init) + "\n}\n")
    update = [f"\n{name}_real {name}_update({name}_state *s, {name}_real temperature_c, {name}_real raw, {name}_real dt_s)",
              "{",
              "    if (s->samples > 0) s->clock_s += (double)dt_s;",
              "    if (s->samples < 2147483647) s->samples++;"]
    if rated:
        update.append("    {\n    R rate = rate_c_per_s(s, temperature_c);")
    else:
        update.append("    {")
    update += body
    scaled = _scaled(spec)
    back = (f"    return estimate;  /* the {kind.noun}'s estimate of the input */" if inverse else
            "    return (raw - offset) / scale;" if scaled else "    return raw - offset;")
    update += [back, "    }", "}\n"]
    parts.append("\n".join(update))
    return "".join(parts)


_KINDS = {
    "poly3": _Kind(False, _cubic_code, _cubic_offset),
    "poly3_rate": _Kind(True, _cubic_rate_code, _cubic_rate_offset),
    "model": _Kind(False, _model_code, lambda spec, t, temp, rate: _model_streamed(spec, t, temp), _model_slots),
    "model_mean": _Kind(False, _model_mean_code, lambda spec, t, temp, rate: np.mean(
        [_model_streamed(m, t, temp) for m in spec["models"]], axis=0), _model_mean_slots),
    "poly": _Kind(False, _poly_code, lambda spec, t, temp, rate: _poly_out(spec, temp, np.zeros_like(temp)),
                  estimate=lambda spec, t, raw, temp: _poly_out(spec, raw, temp), noun="polynomial"),
    "poly_rate": _Kind(True, _poly_code, lambda spec, t, temp, rate: _poly_out(spec, temp, rate), noun="polynomial"),
}
_KINDS["lagpoly"] = _KINDS["model"]  # the lag-aware polynomial: a diagnosed model of one thermal lag
_NETWORK = _Kind(True, _network_code, lambda spec, t, temp, rate: _network_out(spec, t, temp, rate), network=True)
_INVERSE = _Kind(False, _network_code, _no_offset, network=True,
                 estimate=lambda spec, t, raw, temp: _network_out(spec, t, raw, temp))


def write_c(spec: dict[str, Any], name: str, folder: str | Path, about: str = "") -> list[Path]:
    """Write ``<name>.h`` and ``<name>.c`` of ``spec`` into ``folder``; their paths."""
    src = c_sources(spec, name, about)
    folder = Path(folder)
    paths = [folder / f"{name}.h", folder / f"{name}.c"]
    paths[0].write_text(src.header)
    paths[1].write_text(src.source)
    return paths


# -- calibrate's numbers as the device runs them ----------------------------------------------------

STREAMED = ("elman", "model")  # the methods whose streamed (causal) output is not calibrate's own


def streamed_residual(model: OffsetModel, rec: Any) -> np.ndarray | None:
    """Output minus true input minus the offset the exported code computes over the whole record
    ``rec`` (a :class:`~tcbench.compensation.record.Record`) from its first sample: the causal
    form of the Elman and of the diagnosed model (see the module doc), where calibrate's own
    offset reads ahead; None for a method no device runs (:func:`device_spec` refuses it)."""
    try:
        spec = device_spec(model, window_samples(rec.t_s))
    except ValueError:
        return None
    clock = rec.t_s - rec.t_s[0] if rec.t_s.size else rec.t_s
    return rec.output - rec.truth - streamed_offset(spec, clock, rec.temp_c)
