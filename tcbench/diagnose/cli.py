"""``tcbench diagnose recording=PATH out=DIR [sensor=msra|gyro] [model=PATH]``."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

from tcbench.sensors_cli import CommandError, cannot_write, overwrite_error, parse, writable_folder

log = logging.getLogger(__name__)


@dataclass
class DiagnoseConfig:
    """``tcbench diagnose`` arguments: the recording, the output directory, the sensor kind for
    a recording without a sidecar, and the model file of effects already modelled."""

    recording: str = ""
    out: str = "diagnosis"
    sensor: str | None = None
    model: str | None = None


def diagnose_command(args: list[str]) -> int:
    """Run a diagnosis and write its report; user errors raise :class:`CommandError`."""
    from tcbench.diagnose.diagnosis import diagnose
    from tcbench.diagnose.model_file import ModelFileError, read_model
    from tcbench.diagnose.report import write_report
    from tcbench.diagnose.signals import DiagnosisDataError
    from tcbench.sensors.recording import read_recording, sidecar_path
    from tcbench.staging import InputOverwriteError
    from tcbench.sensors.recording_schema import RecordingError

    cfg: DiagnoseConfig = parse(args, DiagnoseConfig)
    if not cfg.recording:
        raise CommandError("recording=PATH is required")
    if cfg.sensor not in (None, "msra", "gyro"):
        raise CommandError(f"sensor must be msra or gyro, got {cfg.sensor!r}")
    writable_folder(cfg.out)
    try:
        rec = read_recording(cfg.recording)
    except RecordingError as exc:
        raise CommandError(str(exc)) from None
    except OSError as exc:
        raise CommandError(f"{cfg.recording}: cannot read the file ({exc.strerror or exc})") from None
    sensor = cfg.sensor or rec.meta.sensor
    if sensor is None:
        raise CommandError(f"{cfg.recording}: no sidecar says which sensor this is; give sensor=msra or sensor=gyro")
    if cfg.sensor and rec.meta.sensor and cfg.sensor != rec.meta.sensor:
        raise CommandError(f"sensor={cfg.sensor} but the sidecar of {cfg.recording} says {rec.meta.sensor}")
    declared: dict[str, dict[str, float]] = {}
    if cfg.model:
        try:
            spec = read_model(cfg.model)
        except ModelFileError as exc:
            raise CommandError(str(exc)) from None
        if spec.sensor != sensor:
            raise CommandError(f"{cfg.model}: a model of a {spec.sensor}, but the recording is from a {sensor}")
        declared = spec.effects
    try:
        diag = diagnose(rec, sensor=sensor, declared=declared, name=Path(cfg.recording).name)
    except DiagnosisDataError as exc:
        raise CommandError(f"{cfg.recording}: {exc}") from None
    inputs = [cfg.recording, sidecar_path(cfg.recording), *([cfg.model] if cfg.model else [])]
    try:
        written = write_report(diag, cfg.out, inputs)
    except InputOverwriteError as exc:
        raise overwrite_error(exc) from None
    except OSError as exc:
        raise cannot_write(cfg.out, exc, "the report") from None
    print(f"tcbench: {diag.verdict}")
    print(f"  baseline RMSE held-out {diag.baseline['rmse_heldout']:.4g} {diag.unit}, final "
          f"{diag.final['rmse_heldout']:.4g} {diag.unit}, white noise {diag.noise['white_sigma']:.4g} {diag.unit}")
    print(f"  wrote {', '.join(str(p) for p in written.values())}")
    return 0
