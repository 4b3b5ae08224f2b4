"""``tcbench simulate``, ``tcbench metrics`` and ``tcbench import``: recordings from the command line."""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from omegaconf import OmegaConf
from omegaconf.errors import OmegaConfBaseException

from tcbench.tracking_config import TrackingConfig
from tcbench.staging import InputOverwriteError, moved, staged_dir


class CommandError(ValueError):
    """A bad argument: reported in one line."""


def writable_folder(path: str | Path) -> Path:
    """``path`` (an ``out=`` argument) as an output folder, checked before any work: a
    :class:`CommandError` if it cannot be made or written."""
    from tcbench.outputs import folder_problem

    if problem := folder_problem(path):
        raise CommandError(f"out={path}: {problem}")
    return Path(path)


def cannot_write(out: str | Path, exc: OSError, what: str = "the recording") -> CommandError:
    """The one-line error for files that could not be written into ``out`` (a full disk, a
    read-only mount, a quota)."""
    from tcbench.outputs import write_problem

    return CommandError(f"out={out}: cannot write {what} ({write_problem(exc)})")


def file_stem(name: str, args: list[str], key: str = "name") -> str:
    """``name`` (the ``key=`` argument) checked as the stem of files written inside ``out=``;
    an empty ``key=`` in ``args`` is refused too (it would otherwise mean the default)."""
    from tcbench.outputs import name_problem

    if f"{key}=" in args:
        name = ""
    if problem := name_problem(name):
        raise CommandError(f"{key}={name!r}: {problem}")
    return name


def overwrite_error(exc: Any) -> CommandError:
    """The one-line error for output that would replace one of the command's inputs."""
    return CommandError(f"the output {exc.target} would overwrite the input {exc.source}; choose another out= "
                        "or name=")


@dataclass
class SimulateConfig:
    """``tcbench simulate`` arguments (``key=value``). ``protocol_params.<name>=`` overrides a
    protocol keyword (``protocol_params.duration_s=3600``); ``effects.<id>.<param>=`` changes or
    adds an effect (``effects.hysteresis.amplitude=0.02``); ``without=[white_noise]`` drops some.
    ``model=PATH`` simulates a fitted-model file (:mod:`tcbench.diagnose.model_file`) instead of
    a device: the sensor comes from the file, effect changes and ``without`` still apply."""

    sensor: str = "msra"
    protocol: str = "fulltemp"
    device_seed: int = 0
    seed: int = 0
    out: str = "recordings"
    format: str = "csv"
    name: str | None = None
    protocol_params: dict[str, Any] = field(default_factory=dict)
    effects: dict[str, dict[str, Any]] = field(default_factory=dict)
    without: list[str] = field(default_factory=list)
    metrics: bool = True
    tracking: TrackingConfig = field(default_factory=lambda: TrackingConfig(experiment="simulations"))
    model: str | None = None


def composed(args: list[str], schema: type) -> Any:
    """The schema's defaults merged with ``key=value`` arguments, as a DictConfig (types and
    known keys checked); what ``--cfg job`` prints and :func:`parse` returns as an object."""
    bad = [a for a in args if "=" not in a or a.startswith("=")]
    if bad:
        raise CommandError(f"expected key=value, got {bad[0]!r}")
    if nul := [a for a in args if "\0" in a]:
        raise CommandError(f"{nul[0].split('=', 1)[0]}=: holds a NUL character")
    try:
        return OmegaConf.merge(OmegaConf.structured(schema), OmegaConf.from_dotlist(args))
    except OmegaConfBaseException as exc:
        key = getattr(exc, "full_key", None)
        first = str(exc).strip().splitlines()[0]
        raise CommandError(f"{key}: {first}" if key else first) from None


def parse(args: list[str], schema: type) -> Any:
    """``key=value`` arguments checked against a dataclass schema (types and known keys)."""
    cfg = composed(args, schema)
    try:
        return OmegaConf.to_object(cfg)
    except OmegaConfBaseException as exc:
        key = getattr(exc, "full_key", None)
        first = str(exc).strip().splitlines()[0]
        raise CommandError(f"{key}: {first}" if key else first) from None


def simulate(args: list[str]) -> int:
    from tcbench.sensors.recording import RecordingError, write_recording
    from tcbench.sensors.simulate import protocol_names, simulate_recording

    cfg: SimulateConfig = parse(args, SimulateConfig)
    fitted = _fitted_model(cfg, args) if cfg.model else None
    try:
        names = protocol_names(cfg.sensor)
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    if cfg.protocol not in names:
        raise CommandError(f"unknown protocol {cfg.protocol!r} for {cfg.sensor}; known: {', '.join(names)}")
    if cfg.format not in {"csv", "parquet"}:
        raise CommandError(f"format must be csv or parquet, got {cfg.format!r}")
    if cfg.device_seed < 0 or cfg.seed < 0:
        raise CommandError("device_seed and seed must be non-negative integers")
    out = writable_folder(cfg.out)
    checked_store(cfg.tracking)
    if cfg.name is not None or "name=" in args:
        stem = file_stem(cfg.name or "", args)
    elif fitted is not None:
        stem = f"{Path(str(cfg.model)).stem}-{cfg.protocol}-seed{cfg.seed}"
    else:
        stem = f"{cfg.sensor}-{cfg.protocol}-dev{cfg.device_seed}-seed{cfg.seed}"
    try:
        rec = simulate_recording(cfg.sensor, cfg.protocol, cfg.device_seed, cfg.seed,
                                 effects=cfg.effects, without=tuple(cfg.without), model=fitted,
                                 **cfg.protocol_params)
    except (TypeError, ValueError) as exc:
        raise CommandError(str(exc)) from None
    path = out / f"{stem}.{cfg.format}"
    inputs = [cfg.model] if cfg.model else []
    report = None
    try:
        with staged_dir(out, inputs) as tmp:  # the recording and its metrics, all or nothing
            write_recording(rec, tmp / path.name)
            if cfg.metrics:
                report = _analysed(path, rec, tmp / f"{stem}_metrics", None)
    except RecordingError as exc:
        raise CommandError(str(exc)) from None
    except InputOverwriteError as exc:
        raise overwrite_error(exc) from None
    except OSError as exc:
        raise cannot_write(out, exc, "the recording and its metrics" if cfg.metrics else "the recording") from None
    print(f"tcbench: wrote {path} ({len(rec.data)} samples at {rec.meta.sample_rate_hz:g} Hz, "
          f"{rec.time_s[-1] / 3600:.2f} h) and its sidecar {path.with_suffix('.json')}")
    if report is not None:
        report.files = moved(report.files, tmp, out)
        _show(path, rec, report, cfg.tracking, {"kind": "simulation", "args": args})
    return 0


def _fitted_model(cfg: SimulateConfig, args: list[str]) -> Any:
    """The model of ``cfg.model`` as a :class:`~tcbench.sensors.fitted.PolynomialModel`; sets
    ``cfg.sensor`` from the file (an explicit, different ``sensor=`` is an error)."""
    from tcbench.diagnose.model_file import ModelFileError, read_model, to_sensor_model

    try:
        spec = read_model(str(cfg.model))
    except ModelFileError as exc:
        raise CommandError(str(exc)) from None
    if any(a.startswith("sensor=") for a in args) and cfg.sensor != spec.sensor:
        raise CommandError(f"{cfg.model}: the model is for a {spec.sensor}, but sensor={cfg.sensor} was given")
    cfg.sensor = spec.sensor
    try:
        return to_sensor_model(spec)
    except ValueError as exc:
        raise CommandError(f"{cfg.model}: {exc}") from None


@dataclass
class MetricsConfig:
    """``tcbench metrics`` arguments: ``recording=PATH`` and options."""

    recording: str = ""
    out: str | None = None
    scale_factor_hz_per_g: float | None = None
    tracking: TrackingConfig = field(default_factory=lambda: TrackingConfig(experiment="recordings"))


def metrics(args: list[str]) -> int:
    from tcbench.sensors.recording import RecordingError, read_recording, sidecar_path

    if args and "=" not in args[0]:
        args = [f"recording={args[0]}", *args[1:]]
    cfg: MetricsConfig = parse(args, MetricsConfig)
    if not cfg.recording:
        raise CommandError("say which recording: tcbench metrics recording=PATH")
    scale = cfg.scale_factor_hz_per_g
    if scale is not None and not (math.isfinite(scale) and scale > 0):
        raise CommandError(f"scale_factor_hz_per_g: must be a finite number > 0, got {scale:g}")
    path = Path(cfg.recording)
    try:
        rec = read_recording(path)
    except RecordingError as exc:
        raise CommandError(str(exc)) from None
    except OSError as exc:
        raise CommandError(f"{path}: cannot read the file ({exc.strerror or exc})") from None
    out = writable_folder(cfg.out or path.with_name(f"{path.stem}_metrics"))
    checked_store(cfg.tracking)
    try:
        with staged_dir(out, [path, sidecar_path(path)]) as tmp:  # a failure leaves nothing behind
            report = _analysed(path, rec, tmp, scale)
    except InputOverwriteError as exc:
        raise overwrite_error(exc) from None
    except OSError as exc:
        raise cannot_write(out, exc, "the metrics") from None
    report.files = moved(report.files, tmp, out)
    _show(path, rec, report, cfg.tracking, {"kind": "metrics"})
    return 0


@dataclass
class ImportConfig:
    """``tcbench import`` arguments: the CSV, the sensor kind, the column map (``time=COL[:unit]``
    ...), rows to drop (``drop=flag`` or ``drop=a,b``: rows where a column is nonzero) and the
    output directory; ``name`` is the recording's stem (default: the CSV's)."""

    csv: str = ""
    sensor: str = ""
    time: str = ""
    temperature: str = ""
    output: str = ""
    input: str | None = None
    drop: str | None = None
    out: str = ""
    name: str | None = None
    device_id: str | None = None
    sample_rate_hz: float | None = None


def import_command(args: list[str]) -> int:
    from tcbench.outputs import overwritten_input
    from tcbench.sensors.importer import import_csv, save
    from tcbench.sensors.recording import RecordingError

    if args and "=" not in args[0]:
        args = [f"csv={args[0]}", *args[1:]]
    cfg: ImportConfig = parse(args, ImportConfig)
    needed = [k for k in ("csv", "sensor", "time", "temperature", "output", "out") if not getattr(cfg, k)]
    if needed:
        raise CommandError(f"missing {needed[0]}=; usage: tcbench import csv=PATH sensor=msra|gyro time=COL[:unit] "
                           "temperature=COL[:unit] output=COL[:unit] [input=COL[:unit]] [drop=COL] out=DIR")
    columns = {"time_s": cfg.time, "temperature_c": cfg.temperature, "output": cfg.output}
    if cfg.input:
        columns["input"] = cfg.input
    drop = [c.strip() for c in (cfg.drop or "").split(",") if c.strip()]
    csv = Path(cfg.csv)
    stem = file_stem(cfg.name if cfg.name is not None else csv.stem, args)
    writable_folder(cfg.out)
    targets = [Path(cfg.out) / f"{stem}.csv", Path(cfg.out) / f"{stem}.json"]
    if clash := overwritten_input(targets, [csv]):
        raise overwrite_error(InputOverwriteError(*clash))
    try:
        rec = import_csv(csv, cfg.sensor, columns, drop=drop, device_id=cfg.device_id,
                         sample_rate_hz=cfg.sample_rate_hz)
    except RecordingError as exc:
        raise CommandError(str(exc)) from None
    except OSError as exc:
        raise CommandError(f"{csv}: cannot read the file ({exc.strerror or exc})") from None
    try:
        path = save(rec, cfg.out, stem, inputs=[csv])
    except RecordingError as exc:
        raise CommandError(str(exc)) from None
    except InputOverwriteError as exc:
        raise overwrite_error(exc) from None
    except OSError as exc:
        raise cannot_write(cfg.out, exc) from None
    source, seg = rec.meta.extra["source"], rec.meta.extra["segments"]
    n_drop = source["rows_dropped"]
    dropped = f", {n_drop} row{'s' * (n_drop != 1)} dropped where {' or '.join(drop)} is nonzero" if drop else ""
    kind = f"in {seg['count']} segments " if seg["count"] > 1 else ""
    print(f"tcbench: wrote {path} ({len(rec.data)} samples {kind}at {rec.meta.sample_rate_hz:g} Hz{dropped}) "
          f"and its sidecar {path.with_suffix('.json')}")
    return 0


def _analysed(path: Path, rec: Any, out: Path, scale_factor: float | None) -> Any:
    """The metrics report of ``rec``, its plots and tables written into ``out``."""
    from tcbench.metrics.report import analyse

    try:
        return analyse(rec, out, scale_factor)
    except ValueError as exc:
        raise CommandError(f"{path}: {exc}") from None


def checked_store(track: TrackingConfig) -> None:
    """With tracking on: the experiment has a name and the store can be used, checked before any
    work and without making anything (:func:`tcbench.tracking.check_store`); a
    :class:`CommandError` otherwise."""
    if not track.enabled:
        return
    if not str(track.experiment or "").strip():
        raise CommandError("tracking.experiment: give the MLflow experiment a name, or tracking.enabled=false")
    from tcbench import tracking

    try:
        tracking.check_store(track.uri, create=True)  # made when the results are logged
    except tracking.StoreError as exc:
        raise CommandError(str(exc)) from None


def _show(path: Path, rec: Any, report: Any, track: TrackingConfig, tags: dict[str, Any]) -> None:
    """Print a metrics report and log it to MLflow when tracking is on."""
    width = max(len(k) for k in report.metrics)
    print(f"\nmetrics of {path.name} ({rec.meta.sensor}, {rec.meta.device_id}):")
    for key, value in report.metrics.items():
        print(f"  {key:{width}s}  {value:.6g}")
    for line in report.conventions:
        print(f"  convention: {line}")
    if report.nodes is not None:
        print("\n" + report.nodes.round(6).to_string(index=False))
    print(f"\nplots and tables: {', '.join(str(p) for p in report.files.values())}")
    if track.enabled:
        from tcbench import tracking

        try:
            run_id = _log_to_mlflow(path, rec, report, track, tags)
        except Exception as exc:  # noqa: BLE001 - a full disk or a dead server: the files are written
            raise CommandError(f"the files are written, but MLflow at {tracking.tracking_uri(track.uri)} could not "
                               f"record them ({tracking.first_line(exc)})") from None
        print(f"logged to MLflow run {run_id} in {tracking.tracking_uri(track.uri)} (experiment {track.experiment!r})")


def _log_to_mlflow(path: Path, rec: Any, report: Any, track: TrackingConfig, tags: dict[str, Any]) -> str:
    from tcbench import tracking

    exp = tracking.prepare_store(track.uri, track.experiment)  # a store it cannot finish is not left behind
    client = tracking.client(track.uri)
    run = client.create_run(exp, run_name=f"{rec.meta.device_id}-{path.stem}", tags={
        "tcbench.kind": str(tags["kind"]), "tcbench.sensor": str(rec.meta.sensor),
        "tcbench.device_id": str(rec.meta.device_id), "tcbench.recording": str(path.resolve()),
        "tcbench.version": __import__("tcbench").__version__,
    })
    run_id = run.info.run_id
    handle = tracking.JobRun(client, run_id)
    try:
        extra = rec.meta.extra or {}
        params = {"sensor": rec.meta.sensor, "sample_rate_hz": rec.meta.sample_rate_hz,
                  "protocol": extra.get("protocol"), "device_seed": extra.get("device_seed"),
                  "seed": extra.get("seed"), "samples": len(rec.data)}
        handle.log_params(tracking.flatten(params))
        handle.log_metrics({k: v for k, v in report.metrics.items() if not math.isnan(v)})
        for file in report.files.values():
            handle.log_artifact(file)
        with tempfile.TemporaryDirectory() as tmp:
            sidecar = Path(tmp) / "sidecar.json"
            sidecar.write_text(OmegaConf.to_yaml(OmegaConf.create(extra)) if extra else "{}")
            handle.log_artifact(sidecar)
        handle.flush()
    except BaseException as exc:
        tracking.mark_failed(client, run_id, f"{type(exc).__name__}: {exc}")
        raise
    client.set_terminated(run_id, status="FINISHED")
    return run_id
