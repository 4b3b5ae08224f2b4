"""What ``tcbench simulate``, ``tcbench metrics`` and ``tcbench import`` do with their config:
the checks made before any work (``check_*``: one-line :class:`~tcbench.commands.errors.CommandError`),
and the work itself (``simulate``, ``metrics``, ``import_recording``), which prints what it
wrote. They run as jobs of :mod:`tcbench.runner.kinds.recordings` through :func:`tcbench.runner.job.run_job`."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tcbench.commands.schemas import ImportConfig, MetricsConfig, SimulateConfig
from tcbench.commands.errors import (
    CommandError,
    checked_store,
    file_stem,
    free_outputs,
    overwrite_error,
    read_recording_arg,
    say_replaced,
    writable_folder,
    writing_errors,
)
from tcbench.errors import unknown_name
from tcbench.staging import InputOverwriteError, moved, staged_dir


@dataclass
class RecordingOutcome:
    """A recording a command wrote or read, and its metrics report (None when not computed)."""

    path: Path
    rec: Any  # the Recording; for an import, what is kept of it once written (metadata and samples)
    report: Any = None
    also: list[RecordingOutcome] = field(default_factory=list)  # further recordings of the command (axes)


# -- simulate ------------------------------------------------------------------------------------

def _fitted_model(cfg: SimulateConfig) -> Any:
    """The model of ``cfg.model`` as a :class:`~tcbench.sensors.fitted.PolynomialModel`; sets
    ``cfg.sensor`` from the file (an explicit, different ``sensor=`` is an error)."""
    from tcbench.diagnose.model_file import ModelFileError, read_model, to_sensor_model

    try:
        spec = read_model(str(cfg.model))
    except ModelFileError as exc:
        raise CommandError(str(exc)) from None
    if cfg.sensor is not None and cfg.sensor != spec.sensor:
        raise CommandError(f"{cfg.model}: the model is for a {spec.sensor}, but sensor={cfg.sensor} was given")
    cfg.sensor = spec.sensor
    try:
        return to_sensor_model(spec)
    except ValueError as exc:
        raise CommandError(f"{cfg.model}: {exc}") from None


def simulated_protocol(cfg: SimulateConfig) -> str:
    """The protocol a simulation runs: ``protocol``, else its sensor kind's default (the kind of
    ``sensor``, of the model file when ``sensor`` is null, :data:`~tcbench.sensors.kinds.DEFAULT`
    without either)."""
    if cfg.protocol is not None:
        return cfg.protocol
    from tcbench.sensors import kinds

    sensor = cfg.sensor
    if sensor is None and cfg.model:
        from tcbench.diagnose.model_file import ModelFileError, read_model

        try:
            sensor = read_model(str(cfg.model)).sensor
        except ModelFileError as exc:
            raise CommandError(str(exc)) from None
    try:
        return str(kinds.get(sensor or kinds.DEFAULT).default_protocol)
    except ValueError as exc:
        raise CommandError(str(exc)) from None


def simulation_stem(cfg: SimulateConfig) -> str:
    """The file stem of a simulation: ``name``, or ``<sensor>-<protocol>-dev<N>-seed<N>`` (for
    a model file ``<model stem>-<protocol>-seed<N>``), ``-poweron<N>`` after it when the run
    replays another's power-on."""
    if cfg.name is not None:
        return cfg.name
    from tcbench.sensors import kinds

    replay = "" if cfg.power_on is None else f"-poweron{cfg.power_on}"
    if cfg.model:
        return f"{Path(str(cfg.model)).stem}-{simulated_protocol(cfg)}-seed{cfg.seed}{replay}"
    return f"{cfg.sensor or kinds.DEFAULT}-{simulated_protocol(cfg)}-dev{cfg.device_seed}-seed{cfg.seed}{replay}"


def check_simulate(cfg: SimulateConfig) -> Any:
    """Every argument of a simulation, before any work; the fitted model of ``model=`` (None
    without one). Sets ``cfg.sensor`` and ``cfg.protocol`` when they were null."""
    from tcbench.sensors import kinds

    fitted = _fitted_model(cfg) if cfg.model else None
    cfg.sensor = cfg.sensor or kinds.DEFAULT
    try:
        kind = kinds.get(cfg.sensor)
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    names = list(kind.protocols)
    if cfg.protocol is None:
        cfg.protocol = kind.default_protocol
    if cfg.protocol not in names:
        raise CommandError(unknown_name("protocol", cfg.protocol, names, f" for {cfg.sensor}"))
    if cfg.format not in {"csv", "parquet"}:
        raise CommandError(f"format={cfg.format}: {unknown_name('format', cfg.format, ('csv', 'parquet'))}")
    if cfg.device_seed < 0 or cfg.seed < 0 or (cfg.power_on is not None and cfg.power_on < 0):
        raise CommandError("device_seed, seed and power_on must be non-negative integers")
    writable_folder(cfg.out)
    checked_store(cfg.tracking)
    stem = file_stem(simulation_stem(cfg), suffix=max((f".{cfg.format}", ".json", "_metrics" * cfg.metrics), key=len))
    metrics = [f"{stem}_metrics"] if cfg.metrics else []
    free_outputs(cfg.out, [f"{stem}.{cfg.format}", f"{stem}.json", *[f"{m}/metrics.json" for m in metrics]],
                 cfg.overwrite, "out= or name=", folders=metrics)
    return fitted


def simulate(cfg: SimulateConfig) -> RecordingOutcome:
    """Simulate, write the recording (and its metrics), print what was written."""
    from tcbench.sensors.recording import RecordingError, write_recording
    from tcbench.sensors.simulate import simulate_recording

    fitted = check_simulate(cfg)
    out, stem = Path(cfg.out), simulation_stem(cfg)
    try:
        rec = simulate_recording(cfg.sensor, cfg.protocol, cfg.device_seed, cfg.seed,
                                 effects=cfg.effects, without=tuple(cfg.without), model=fitted,
                                 power_on=cfg.power_on, **cfg.protocol_params)
    except (TypeError, ValueError) as exc:
        raise CommandError(str(exc)) from None
    path = out / f"{stem}.{cfg.format}"
    inputs = [cfg.model] if cfg.model else []
    report = None
    replaced: list[Path] = []
    what = "the recording and its metrics" if cfg.metrics else "the recording"
    with writing_errors(out, what, "out= or name=", said=(RecordingError,)), \
            staged_dir(out, inputs, cfg.overwrite, replaced) as tmp:  # the recording and its metrics, all or nothing
        write_recording(rec, tmp / path.name)
        if cfg.metrics:
            report = _analysed(path, rec, tmp / f"{stem}_metrics", None)
    print(f"tcbench: wrote {path} ({len(rec.data)} samples at {rec.meta.sample_rate_hz:g} Hz, "
          f"{rec.time_s[-1] / 3600:.2f} h) and its sidecar {path.with_suffix('.json')}")
    say_replaced(replaced)
    if report is not None:
        report.files = moved(report.files, tmp, out)
        show(path, rec, report)
    return RecordingOutcome(path, rec, report)


# -- metrics -------------------------------------------------------------------------------------

def metrics_folder(cfg: MetricsConfig) -> Path:
    path = Path(cfg.recording)
    return Path(cfg.out) if cfg.out else path.with_name(f"{path.stem}_metrics")


def check_metrics(cfg: MetricsConfig) -> Any:
    """Every argument of ``tcbench metrics`` before any work; the recording, read and validated."""
    if not cfg.recording:
        raise CommandError("say which recording: tcbench metrics recording=PATH")
    scale = cfg.scale_factor_hz_per_g
    if scale is not None and not (math.isfinite(scale) and scale > 0):
        raise CommandError(f"scale_factor_hz_per_g: must be a finite number > 0, got {scale:g}")
    rec = read_recording_arg(cfg.recording)
    try:
        writable_folder(metrics_folder(cfg))
    except CommandError as exc:
        if cfg.out:
            raise
        raise CommandError(f"{exc} (the default folder beside the recording; give out=DIR)") from None
    free_outputs(metrics_folder(cfg), ["metrics.json"], cfg.overwrite)
    checked_store(cfg.tracking)
    return rec


def metrics(cfg: MetricsConfig) -> RecordingOutcome:
    """Validate a recording, compute its metrics and plots, print them."""
    from tcbench.sensors.recording import sidecar_path

    rec = check_metrics(cfg)
    path, out = Path(cfg.recording), metrics_folder(cfg)
    replaced: list[Path] = []
    with writing_errors(out, "the metrics"), \
            staged_dir(out, [path, sidecar_path(path)], cfg.overwrite, replaced) as tmp:  # a failure leaves nothing behind
        report = _analysed(path, rec, tmp, cfg.scale_factor_hz_per_g)
    report.files = moved(report.files, tmp, out)
    show(path, rec, report)
    say_replaced(replaced)
    return RecordingOutcome(path, rec, report)


# -- import --------------------------------------------------------------------------------------

IMPORT_USAGE = ("usage: tcbench import csv=PATH sensor=msra|gyro|accel time=COL:unit temperature=COL:unit "
                "output=COL:unit [input=COL:unit] [units={output:UNIT,...}] [axes=x|y|z] [drop=COL] out=DIR, "
                "or csv=LOG.ulg sensor=gyro|accel out=DIR")
NO_AXIS = "axis unknown (axes=x|y|z to record it)"


def import_stem(cfg: ImportConfig) -> str:
    return cfg.name if cfg.name is not None else Path(cfg.csv).stem


def is_ulog(cfg: ImportConfig) -> bool:
    """True for a PX4 log (``.ulg``): its sensor topic's instances and axes are imported."""
    return Path(str(cfg.csv)).suffix.lower() == ".ulg"


def import_axes(cfg: ImportConfig) -> list[str]:
    """The ``output=`` columns, ``COL:unit`` (or ``COL`` with its unit in ``units=``) each:
    several axes are separated by commas."""
    return [a.strip() for a in str(cfg.output).split(",") if a.strip()]


def import_stems(cfg: ImportConfig) -> list[str]:
    """The file stem of each axis's recording: ``name`` for one axis, ``name-COL`` for several."""
    axes = import_axes(cfg)
    stem = import_stem(cfg)
    if len(axes) == 1:
        return [stem]
    columns = [a.rsplit(":", 1)[0] if ":" in a else a for a in axes]
    if len(set(columns)) < len(columns):
        raise CommandError(f"output={cfg.output}: a column is named twice")
    return [f"{stem}-{c}" for c in columns]


def import_units(cfg: ImportConfig) -> dict[str, str]:
    """The ``units=`` map (keys time, temperature, output, input) by schema column."""
    from tcbench.sensors.importer import KEYS

    given = cfg.units if isinstance(cfg.units, dict) else vars(cfg.units)
    units = {}
    for target, key in KEYS.items():
        unit = given.get(key)
        if unit is None:
            continue
        if not str(unit).strip():
            raise CommandError(f"units={{{key}:...}}: the unit is empty")
        units[target] = str(unit).strip()
    return units


def import_axis_list(cfg: ImportConfig, outputs: list[str]) -> list[str | None]:
    """The sensor axis of each ``outputs`` column from ``axes=`` (x, y or z, one per column), or
    None each without ``axes=``: an axis is never guessed from a column's name."""
    from tcbench.sensors.recording import AXES

    if not cfg.axes:
        return [None] * len(outputs)
    axes = [a.strip() for a in str(cfg.axes).split(",")]
    if bad := [a for a in axes if a not in AXES]:
        raise CommandError(f"axes={cfg.axes}: {bad[0]!r} is not an axis (x, y or z)")
    if len(axes) != len(outputs):
        columns = ",".join(a.rsplit(":", 1)[0] for a in outputs)
        raise CommandError(f"axes={cfg.axes} names {len(axes)} {'axis' if len(axes) == 1 else 'axes'} for "
                           f"{len(outputs)} output column{'s' * (len(outputs) != 1)} ({columns}); "
                           "give one axis per column")
    return list(axes)


def check_import(cfg: ImportConfig) -> None:
    """Every argument of ``tcbench import`` before any work."""
    from tcbench.outputs import overwritten_input

    keys = ("csv", "sensor", "out") if is_ulog(cfg) else ("csv", "sensor", "time", "temperature", "output", "out")
    needed = [k for k in keys if not getattr(cfg, k)]
    if needed:
        raise CommandError(f"missing {needed[0]}=; {IMPORT_USAGE}")
    import_units(cfg)
    if is_ulog(cfg):
        _ulog_axes(cfg)
        file_stem(import_stem(cfg), suffix=".json")
        writable_folder(cfg.out)
        checked_store(cfg.tracking)
        return
    import_axis_list(cfg, import_axes(cfg))
    stems = [file_stem(import_stem(cfg), suffix=".json")] + [file_stem(s, "output", ".json") for s in import_stems(cfg)]
    writable_folder(cfg.out)
    targets = [Path(cfg.out) / f"{stem}.{ext}" for stem in stems[1:] for ext in ("csv", "json")]
    if clash := overwritten_input(targets, [Path(cfg.csv)]):
        raise overwrite_error(InputOverwriteError(*clash))
    free_outputs(cfg.out, [t.name for t in targets], cfg.overwrite, "out= or name=")
    checked_store(cfg.tracking)


def column_summary(rec: Any) -> str:
    """What an imported recording was read from, each column with its unit, and its axis:
    ``time=timestamp [us], temperature=imu.temperature [degC], output=imu.gyro.y [rad/s] -> deg/s; axis y``."""
    from tcbench.sensors.importer import KEYS
    from tcbench.sensors.recording import recording_axis

    columns = rec.meta.extra["source"]["columns"]
    stored = {"output": f" -> {rec.meta.units['output']}"}
    text = ", ".join(f"{KEYS[target]}={columns[target]}{stored.get(target, '')}" for target in KEYS if target in columns)
    axis = recording_axis(rec.meta)
    return f"{text}; {f'axis {axis}' if axis else NO_AXIS}"


def import_recording(cfg: ImportConfig) -> RecordingOutcome:
    """Import a table as validated recordings with their sidecars, one per ``output=`` axis
    (sharing the clock and temperature columns), all written or none; print what was written.
    A PX4 log's recordings are built and written one at a time: the outcomes hold each one's
    metadata and length (:class:`~tcbench.sensors.importer.Written`), not its table."""
    from tcbench.sensors.importer import save_each
    from tcbench.sensors.recording import RecordingError

    check_import(cfg)
    drop = [c.strip() for c in (cfg.drop or "").split(",") if c.strip()]
    csv = Path(cfg.csv)
    recs = _ulog_recordings(cfg, drop) if is_ulog(cfg) else _table_recordings(cfg, drop).items()
    replaced: list[Path] = []
    with writing_errors(cfg.out, hint="out= or name=", said=(RecordingError,)):
        written = save_each(recs, cfg.out, inputs=[csv], overwrite=cfg.overwrite, replaced=replaced)
    outcomes = [RecordingOutcome(w.path, w) for w in written]
    for o in outcomes:
        source, seg = o.rec.meta.extra["source"], o.rec.meta.extra["segments"]
        n_drop = source["rows_dropped"]
        dropped = f", {n_drop} row{'s' * (n_drop != 1)} dropped where {' or '.join(drop)} is nonzero" if drop else ""
        kind = f"in {seg['count']} segments " if seg["count"] > 1 else ""
        print(f"tcbench: wrote {o.path} ({o.rec.samples} samples {kind}at {o.rec.meta.sample_rate_hz:g} Hz{dropped}) "
              f"and its sidecar {o.path.with_suffix('.json')}")
        print(f"  {column_summary(o.rec)}")
    say_replaced(replaced)
    first, *rest = outcomes
    first.also = rest
    return first


def _table_recordings(cfg: ImportConfig, drop: list[str]) -> dict[str, Any]:
    """One recording per ``output=`` axis of a table, read once, named by :func:`import_stems`."""
    from tcbench.sensors.importer import import_csv_axes
    from tcbench.sensors.recording import RecordingError

    columns = {"time_s": cfg.time, "temperature_c": cfg.temperature, **({"input": cfg.input} if cfg.input else {})}
    outputs = import_axes(cfg)
    try:
        recs = import_csv_axes(cfg.csv, cfg.sensor, columns, outputs, units=import_units(cfg),
                               axes=import_axis_list(cfg, outputs), drop=drop, device_id=cfg.device_id,
                               sample_rate_hz=cfg.sample_rate_hz)
    except RecordingError as exc:
        raise CommandError(str(exc)) from None
    except OSError as exc:
        raise CommandError(f"{cfg.csv}: cannot read the file ({exc.strerror or exc})") from None
    return dict(zip(import_stems(cfg), recs, strict=True))


def _ulog_axes(cfg: ImportConfig) -> list[tuple[str, str | None]]:
    """The fields read from a PX4 log's sensor topic (``output=``, else x, y, z in PX4's unit),
    each with its sensor axis: ``axes=`` where given, else the field's own (x, y, z); a field
    that is an axis cannot be given another."""
    from tcbench.sensors.ulog import AXES, default_axes, field_axis, topics

    outputs = import_axes(cfg) or (default_axes(cfg.sensor) if cfg.sensor in topics() else list(AXES))
    given = import_axis_list(cfg, outputs)
    out = []
    for output, axis in zip(outputs, given, strict=True):
        field_name = output.rsplit(":", 1)[0] if ":" in output else output
        own = field_axis(field_name)
        if axis is not None and own is not None and axis != own:
            raise CommandError(f"axes={cfg.axes}: the log's field {field_name} is the {own} axis, not {axis}")
        out.append((output, axis or own))
    return out


def _ulog_recordings(cfg: ImportConfig, drop: list[str]) -> Iterator[tuple[str, Any]]:
    """One recording per instance and axis of the sensor's topic in a PX4 log, named
    ``NAME-<topic>-<instance>-<field>``, its axis (the field x, y, z) in the sidecar;
    ``time=``, ``temperature=``, ``output=`` name other fields. The log is read here; each
    recording is built only when the next one is asked for (:func:`~tcbench.sensors.importer.save_each`
    writes and drops it first), so one axis's columns are in memory beside the log's topic."""
    from tcbench.sensors.recording import RecordingError
    from tcbench.sensors.ulog import read_topic

    path = Path(cfg.csv)
    try:
        instances = read_topic(path, cfg.sensor)
    except RecordingError as exc:
        raise CommandError(str(exc)) from None
    return _ulog_axis_recordings(cfg, drop, path, instances, _ulog_axes(cfg), import_units(cfg))


def _ulog_axis_recordings(cfg: ImportConfig, drop: list[str], path: Path, instances: list[Any],
                          outputs: list[tuple[str, str | None]], units: dict[str, str]) -> Iterator[tuple[str, Any]]:
    """``(stem, recording)`` of each instance and ``outputs`` field of a log's topic, in turn."""
    from tcbench.sensors.importer import import_table
    from tcbench.sensors.recording import RecordingError
    from tcbench.sensors.ulog import default_columns

    for inst in instances:
        columns = default_columns(list(inst.fields))
        columns |= {k: v for k, v in (("time_s", cfg.time), ("temperature_c", cfg.temperature),
                                      ("input", cfg.input)) if v}
        about = {"file": path.name, "format": "PX4 ULog", "topic": inst.topic, "instance": inst.instance,
                 "px4_device_id": inst.device_id}
        for output, axis in outputs:
            field_name = output.rsplit(":", 1)[0] if ":" in output else output
            stem = file_stem(f"{import_stem(cfg)}-{inst.topic}-{inst.instance}-{field_name}", "output", ".json")
            try:
                yield stem, import_table(
                    inst.fields, cfg.sensor, {**columns, "output": output}, units=units, axis=axis, drop=drop,
                    source=f"{path} ({inst.topic} instance {inst.instance})", about=about,
                    device_id=cfg.device_id or f"{path.stem}-{inst.topic}-{inst.instance}",
                    sample_rate_hz=cfg.sample_rate_hz)
            except RecordingError as exc:
                raise CommandError(str(exc)) from None


# -- shared --------------------------------------------------------------------------------------

def _analysed(path: Path, rec: Any, out: Path, scale_factor: float | None) -> Any:
    """The metrics report of ``rec``, its plots and tables written into ``out``."""
    from tcbench.metrics.report import analyse

    try:
        return analyse(rec, out, scale_factor)
    except ValueError as exc:
        raise CommandError(f"{path}: {exc}") from None


def show(path: Path, rec: Any, report: Any) -> None:
    """Print a metrics report."""
    width = max(len(k) for k in report.metrics)
    print(f"\nmetrics of {path.name} ({rec.meta.sensor}, {rec.meta.device_id}):")
    for key, value in report.metrics.items():
        print(f"  {key:{width}s}  {value:.6g}")
    for line in report.conventions:
        print(f"  convention: {line}")
    if report.nodes is not None:
        print("\n" + report.nodes.round(6).to_string(index=False))
    print(f"\nplots and tables: {', '.join(str(p) for p in report.files.values())}")
