"""What ``tcbench diagnose`` does with its config: the checks made before any work
(:func:`check_diagnose`) and the diagnosis with its report (:func:`diagnose_recording`); a record
shorter than a full diagnosis needs gets the short-record report of the tests its length allows
(:mod:`tcbench.diagnose.short_record`). It runs as a job of :mod:`tcbench.runner.kinds.diagnosis`
through :func:`tcbench.runner.job.run_job`."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tcbench.commands.schemas import DiagnoseConfig
from tcbench.sensors import kinds
from tcbench.commands.errors import (
    CommandError,
    cannot_write,
    checked_store,
    free_outputs,
    overwrite_error,
    read_recording_arg,
    refused_output,
    say_replaced,
    writable_folder,
)

log = logging.getLogger(__name__)
REPORT_FILES = ("report.json", "report.md")  # what every report holds, checked before any work


@dataclass
class DiagnosisOutcome:
    """A diagnosis and the files of its report (``report.json``, ``report.md``, ``model.yaml``, plots),
    or a short record's report (``report.json``, ``report.md``)."""

    diagnosis: Any
    written: dict[str, Path]


def check_diagnose(cfg: DiagnoseConfig) -> tuple[Any, str, dict[str, dict[str, float]]]:
    """Every argument before any work: the recording (read and validated), its sensor and the
    effects the model file declares already modelled."""
    from tcbench.diagnose.model_file import ModelFileError, read_model

    if not cfg.recording:
        raise CommandError("recording=PATH is required")
    if cfg.sensor is not None and not kinds.known(cfg.sensor):
        raise CommandError(f"sensor must be one of {', '.join(kinds.names())}, got {cfg.sensor!r}")
    writable_folder(cfg.out)
    free_outputs(cfg.out, list(REPORT_FILES), cfg.overwrite)
    checked_store(cfg.tracking)
    rec = read_recording_arg(cfg.recording)
    sensor = cfg.sensor or rec.meta.sensor
    if sensor is None:
        raise CommandError(f"{cfg.recording}: no sidecar says which sensor this is; give sensor=" + "|".join(kinds.names()))
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
    return rec, sensor, declared


def diagnose_recording(cfg: DiagnoseConfig) -> DiagnosisOutcome:
    """Diagnose the recording, write its report and print the verdict."""
    from tcbench.diagnose.diagnosis import diagnose
    from tcbench.diagnose.plan import min_full_duration_s
    from tcbench.diagnose.report import write_report
    from tcbench.diagnose.signals import DiagnosisDataError

    rec, sensor, declared = check_diagnose(cfg)
    if rec.time_s[-1] - rec.time_s[0] < min_full_duration_s():
        return _short_record(cfg, rec, sensor)
    try:
        diag = diagnose(rec, sensor=sensor, declared=declared, name=Path(cfg.recording).name)
    except DiagnosisDataError as exc:
        raise CommandError(f"{cfg.recording}: {exc}") from None
    written = _written(write_report, diag, cfg)
    print(f"tcbench: {diag.verdict}")
    print(f"  baseline RMSE held-out {diag.baseline['rmse_heldout']:.4g} {diag.unit}, final "
          f"{diag.final['rmse_heldout']:.4g} {diag.unit}, white noise {diag.noise['white_sigma']:.4g} {diag.unit}")
    print(f"  wrote {', '.join(str(p) for p in written.values())}")
    return DiagnosisOutcome(diag, written)


def _written(writer: Any, report: Any, cfg: DiagnoseConfig) -> dict[str, Path]:
    """``writer(report, out, inputs, overwrite=, replaced=)``, its failures as one line (never over
    an input, nor over a file without ``overwrite``); says what it replaced."""
    from tcbench.sensors.recording import sidecar_path
    from tcbench.staging import InputOverwriteError, OutputRefusedError

    inputs = [cfg.recording, sidecar_path(cfg.recording), *([cfg.model] if cfg.model else [])]
    replaced: list[Path] = []
    try:
        written = writer(report, cfg.out, inputs, overwrite=cfg.overwrite, replaced=replaced)
    except InputOverwriteError as exc:
        raise overwrite_error(exc) from None
    except OutputRefusedError as exc:
        raise refused_output(exc) from None
    except OSError as exc:
        raise cannot_write(cfg.out, exc, "the report") from None
    say_replaced(replaced)
    return dict(written)


def _short_record(cfg: DiagnoseConfig, rec: Any, sensor: str) -> DiagnosisOutcome:
    """The short-record report of ``rec``, written to ``out``; prints what ran and what needs more time."""
    from tcbench.diagnose.short_record import short_record
    from tcbench.diagnose.short_report import write_short_report

    report = short_record(rec, sensor, name=Path(cfg.recording).name)
    written = _written(write_short_report, report, cfg)
    print(f"tcbench: {report.verdict}")
    ran = [f"{t.id} ({t.status})" for t in report.tests if t.ran]
    print(f"  ran: {', '.join(ran) or 'nothing'}")
    for t in report.tests:
        if not t.ran:
            print(f"  not run: {t.id}: {t.reason}")
    if report.needs_more_time:
        print("  needs more time: " + ", ".join(f"{r['id']} ({r['needs_s']:.0f} s)" for r in report.needs_more_time))
    if cfg.model:
        print(f"  {cfg.model} is not used: the short-record tests fit no model")
    print(f"  wrote {', '.join(str(p) for p in written.values())}")
    return DiagnosisOutcome(report, written)
