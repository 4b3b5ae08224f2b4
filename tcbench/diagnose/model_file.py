"""Fitted-model files: what ``tcbench diagnose`` writes and ``tcbench simulate model=PATH`` reads.

A model file is YAML::

    tcbench_model: 1            # format version
    sensor: msra                # or gyro, accel (any kind of tcbench.sensors.kinds)
    output_unit: Hz             # informative: Hz for msra, deg/s for gyro, g for accel
    core:
      kind: polynomial
      centre_c: 10.0            # degC
      half_range_c: 50.0        # degC, > 0
      bias: [b0, b1, b2]                 # output unit, coefficients of u^0, u^1, ...
      scale_factor: [k0, k1, k2]         # output unit per input unit (Hz/g; (deg/s)/(deg/s))
    effects:                    # optional; ids and parameters as in tcbench/sensors/effects.py
      thermal_lag: {tau_s: 420.0}
      warmup: {amplitude: 0.01, tau_s: 900.0}
      white_noise: {density: 0.0024}
      quantisation: {step: 0.001}          # output on a grid of this step (output unit)
      saturation: {upper: 2.5}             # output clipped at upper and/or lower (output unit)
      noise_temperature: {density: 0.0024, growth_per_c: 0.02, ref_c: 10.0}  # white noise, sigma grows with T
      thermometer_quantisation: {step_c: 1.0}  # the thermometer reading on a 1 degC grid
    outliers:                   # optional: isolated spikes added at these times
      time_s: [35999.0]         # s
      size: [0.42]              # output unit

with ``u = (T_die - centre_c) / half_range_c`` and the model output
``sum_j bias[j] u^j + input * sum_j scale_factor[j] u^j``; ``input`` is the acceleration in g
(msra, accel) or the rate in deg/s (gyro). Effects take their defaults for parameters not given; an
effect with no parameters may be written ``warmup: {}``. ``final``-stage effects (``quantisation``,
``saturation``) act on the finished output in file order, after every additive term; the
``thermometer``-stage effect (``thermometer_quantisation``) changes only the thermometer reading a
simulated recording carries. Every problem with a file raises :class:`ModelFileError` with one
line naming the file (and the effect's key for a value out of its range: a saturation's upper
not above its lower, a step not > 0).
"""

from __future__ import annotations

import dataclasses
import math
import os
import secrets
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from tcbench.errors import unknown_name
from tcbench.outputs import temp_name
from tcbench.sensors import effects as fx
from tcbench.sensors import kinds
from tcbench.sensors.fitted import PolynomialModel

VERSION = 1
TOP_KEYS = ("tcbench_model", "sensor", "output_unit", "core", "effects", "outliers")
OUTLIER_KEYS = ("time_s", "size")
CORE_KEYS = ("kind", "centre_c", "half_range_c", "bias", "scale_factor")


class ModelFileError(ValueError):
    """A model file that cannot be used: one line naming the file and the problem."""


@dataclass(frozen=True)
class ModelSpec:
    """A fitted model as plain data: temperatures in degC, coefficients in the output unit
    (per input unit for the scale factor), effects as ``{id: {param: value}}``, isolated
    outliers as ``(time_s, size)`` pairs (s, output unit)."""

    sensor: str
    centre_c: float
    half_range_c: float
    bias: tuple[float, ...]
    scale_factor: tuple[float, ...]
    effects: dict[str, dict[str, float]] = field(default_factory=dict)
    outliers: tuple[tuple[float, float], ...] = ()


def _number(value: Any, what: str, where: str) -> float:
    """A finite float; YAML strings such as ``1e-3`` (a string in YAML 1.1) are accepted."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise ModelFileError(f"{where}: {what} must be a number, got {value!r}")
    try:
        number = float(value)
    except ValueError:
        raise ModelFileError(f"{where}: {what} must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise ModelFileError(f"{where}: {what} must be finite, got {value!r}")
    return number


def _coefficients(value: Any, what: str, where: str) -> tuple[float, ...]:
    """A non-empty list of finite numbers (a single number counts as a list of one)."""
    if value is None:
        raise ModelFileError(f"{where}: core.{what} is missing")
    items = value if isinstance(value, list) else [value]
    if not items:
        raise ModelFileError(f"{where}: core.{what} is empty; give at least one coefficient")
    return tuple(_number(v, f"core.{what}[{i}]", where) for i, v in enumerate(items))


def _unknown_keys(data: dict[Any, Any], known: tuple[str, ...], what: str, where: str) -> None:
    unknown = [str(k) for k in data if k not in known]
    if unknown:
        raise ModelFileError(f"{where}: unknown {what} {', '.join(map(repr, unknown))}; known: {', '.join(known)}")


def _effects(value: Any, where: str) -> dict[str, dict[str, float]]:
    """Effect ids and parameters checked against :data:`tcbench.sensors.effects.EFFECTS`."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise ModelFileError(f"{where}: effects must be a mapping of effect id to parameters")
    out: dict[str, dict[str, float]] = {}
    for effect_id, params in value.items():
        cls = fx.effect_class(effect_id)
        if cls is None:
            raise ModelFileError(f"{where}: {unknown_name('effect', effect_id, fx.known_effects())}")
        params = {} if params is None else params
        if not isinstance(params, dict):
            raise ModelFileError(f"{where}: effect {effect_id!r} needs a mapping of parameters, got {params!r}")
        known = [f.name for f in dataclasses.fields(cls)]
        unknown = [str(k) for k in params if k not in known]
        if unknown:
            raise ModelFileError(f"{where}: effect {effect_id!r} has no parameter {', '.join(unknown)}; "
                                 f"known: {', '.join(known)}")
        out[effect_id] = {k: _number(v, f"effects.{effect_id}.{k}", where) for k, v in params.items()}
        try:
            fx.make_effect(effect_id, **out[effect_id])
        except ValueError as exc:
            raise ModelFileError(f"{where}: effects.{effect_id}: {str(exc).removeprefix(effect_id + ': ')}") from None
    return out


def _outliers(value: Any, where: str) -> tuple[tuple[float, float], ...]:
    """``{time_s: [...], size: [...]}`` of equal length as ``(time_s, size)`` pairs."""
    if value is None:
        return ()
    if not isinstance(value, dict):
        raise ModelFileError(f"{where}: outliers must be a mapping with time_s and size lists")
    _unknown_keys(value, OUTLIER_KEYS, "outliers key", where)
    times = value.get("time_s") or []
    sizes = value.get("size") or []
    times, sizes = (v if isinstance(v, list) else [v] for v in (times, sizes))
    if len(times) != len(sizes):
        raise ModelFileError(f"{where}: outliers.time_s has {len(times)} entries, outliers.size {len(sizes)}")
    return tuple((_number(t, f"outliers.time_s[{i}]", where), _number(s, f"outliers.size[{i}]", where))
                 for i, (t, s) in enumerate(zip(times, sizes, strict=True)))


def parse_model(data: Any, where: str) -> ModelSpec:
    """Check parsed YAML ``data`` and return its spec; ``where`` names the source in errors."""
    if not isinstance(data, dict):
        got = "nothing (empty file)" if data is None else type(data).__name__
        raise ModelFileError(f"{where}: a model file must be a mapping, got {got}")
    if "tcbench_model" not in data:
        raise ModelFileError(f"{where}: missing 'tcbench_model: {VERSION}' (the format version)")
    version = data["tcbench_model"]
    if isinstance(version, bool) or version != VERSION:
        raise ModelFileError(f"{where}: unsupported tcbench_model version {version!r}; supported: {VERSION}")
    _unknown_keys(data, TOP_KEYS, "key", where)
    sensor = data.get("sensor")
    if sensor is None:
        raise ModelFileError(f"{where}: sensor is missing; known: {', '.join(kinds.names())}")
    if not kinds.known(sensor):
        raise ModelFileError(f"{where}: {unknown_name('sensor', sensor, kinds.names())}")
    core = data.get("core")
    if not isinstance(core, dict):
        raise ModelFileError(f"{where}: core is missing or not a mapping")
    _unknown_keys(core, CORE_KEYS, "core key", where)
    kind = core.get("kind", "polynomial")
    if kind != "polynomial":
        raise ModelFileError(f"{where}: unsupported core kind {kind!r}; supported: polynomial")
    for key in ("centre_c", "half_range_c"):
        if core.get(key) is None:
            raise ModelFileError(f"{where}: core.{key} is missing")
    centre = _number(core["centre_c"], "core.centre_c", where)
    half = _number(core["half_range_c"], "core.half_range_c", where)
    if half <= 0:
        raise ModelFileError(f"{where}: core.half_range_c must be > 0, got {half:g}")
    return ModelSpec(
        sensor=sensor, centre_c=centre, half_range_c=half,
        bias=_coefficients(core.get("bias"), "bias", where),
        scale_factor=_coefficients(core.get("scale_factor"), "scale_factor", where),
        effects=_effects(data.get("effects"), where),
        outliers=_outliers(data.get("outliers"), where),
    )


def read_model(path: str | Path) -> ModelSpec:
    """The spec in a model file; :class:`ModelFileError` on any problem."""
    path = Path(path)
    where = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ModelFileError(f"{where}: no such file") from None
    except IsADirectoryError:
        raise ModelFileError(f"{where}: is a directory, not a model file") from None
    except UnicodeDecodeError:
        raise ModelFileError(f"{where}: not UTF-8 text") from None
    except OSError as exc:
        raise ModelFileError(f"{where}: cannot read ({exc.strerror})") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        raise ModelFileError(f"{where}: YAML syntax error{at}: {problem}") from None
    return parse_model(data, where)


def to_data(spec: ModelSpec) -> dict[str, Any]:
    """The spec as the plain mapping written to a file."""
    out: dict[str, Any] = {
        "tcbench_model": VERSION,
        "sensor": spec.sensor,
        "output_unit": kinds.get(spec.sensor).output_unit,
        "core": {
            "kind": "polynomial",
            "centre_c": float(spec.centre_c),
            "half_range_c": float(spec.half_range_c),
            "bias": [float(b) for b in spec.bias],
            "scale_factor": [float(k) for k in spec.scale_factor],
        },
        "effects": {k: {p: float(v) for p, v in params.items()} for k, params in spec.effects.items()},
    }
    if spec.outliers:
        out["outliers"] = {"time_s": [float(t) for t, _ in spec.outliers], "size": [float(v) for _, v in spec.outliers]}
    return out


def write_model(spec: ModelSpec, path: str | Path) -> Path:
    """Write ``spec`` to ``path`` atomically (temporary sibling, then rename); the path.

    The spec is checked first, so a written file always reads back."""
    path = Path(path)
    data = to_data(spec)
    parse_model(data, str(path))
    text = ("# tcbench fitted model; format: tcbench/diagnose/model_file.py\n"
            + yaml.safe_dump(data, sort_keys=False, default_flow_style=None))
    temp = path.with_name(temp_name(path.name, secrets.token_hex(6)))
    try:
        with open(os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(temp, path)
    finally:
        temp.unlink(missing_ok=True)
    return path


def to_sensor_model(spec: ModelSpec) -> PolynomialModel:
    """The simulatable model: polynomial core (``ref_c = centre_c``) and the spec's effects in
    file order, ``final``-stage ones (``quantisation``, ``saturation``) last."""
    built = [fx.make_effect(effect_id, **params) for effect_id, params in spec.effects.items()]
    ordered = [e for e in built if e.stage != "final"] + [e for e in built if e.stage == "final"]
    return PolynomialModel(
        ref_c=spec.centre_c, effects=tuple(ordered), sensor=spec.sensor, centre_c=spec.centre_c,
        half_range_c=spec.half_range_c, bias=tuple(spec.bias), scale_factor=tuple(spec.scale_factor),
        spike_time_s=tuple(t for t, _ in spec.outliers), spike_size=tuple(v for _, v in spec.outliers),
    )


def spec_from_model(model: PolynomialModel) -> ModelSpec:
    """The spec of a :class:`PolynomialModel` (effects with all their parameters)."""
    return ModelSpec(
        sensor=model.sensor, centre_c=model.centre_c, half_range_c=model.half_range_c,
        bias=tuple(model.bias), scale_factor=tuple(model.scale_factor),
        effects={e.id: {k: float(v) for k, v in e.params().items()} for e in model.effects},
        outliers=tuple(zip(model.spike_time_s, model.spike_size, strict=True)),
    )
