"""What ``tcbench diagnose`` does with its config: the checks made before any work
(:func:`check_diagnose`: the settings first, :func:`diagnose_settings`) and the diagnosis with
its report (:func:`diagnose_recording`); a record shorter than a full diagnosis needs gets the
short-record report of the tests its length allows (:mod:`tcbench.diagnose.short.short_record`). It runs as a job of :mod:`tcbench.runner.kinds.diagnosis`
through :func:`tcbench.runner.job.run_job`."""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import math
import sys
import threading
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tcbench.commands.schemas import DiagnoseConfig
from tcbench.sensors import kinds
from tcbench.commands.errors import (
    CommandError,
    checked_store,
    free_outputs,
    read_recording_arg,
    say_replaced,
    writable_folder,
    writing_errors,
)

log = logging.getLogger(__name__)
REPORT_FILES = ("report.json", "report.md")  # what every report holds, checked before any work
PROGRESS_AFTER_S = 30.0  # a diagnosis estimated to take longer says so before it starts


@dataclass
class DiagnosisOutcome:
    """A diagnosis and the files of its report (``report.json``, ``report.md``, ``model.yaml``, plots),
    or a short record's report (``report.json``, ``report.md``)."""

    diagnosis: Any
    written: dict[str, Path]


def diagnose_settings(cfg: DiagnoseConfig) -> Any:
    """The :class:`~tcbench.diagnose.settings.DiagnoseSettings` of ``cfg.settings``; a
    :class:`CommandError` naming the key of a setting that is not one or a value it cannot take
    (a threshold <= 0, a probability outside (0, 1) ...)."""
    from tcbench.diagnose.settings import SettingsError, from_mapping

    given = cfg.settings
    mapping = dataclasses.asdict(given) if dataclasses.is_dataclass(given) else given
    if mapping is not None and not isinstance(mapping, Mapping):
        raise CommandError(f"settings: a mapping of sections (settings.selection.wald_threshold=30), got {given!r}")
    try:
        return from_mapping(mapping)
    except SettingsError as exc:
        raise CommandError(str(exc)) from None


def check_diagnose(cfg: DiagnoseConfig) -> tuple[Any, str, dict[str, dict[str, float]]]:
    """Every argument before any work: the settings, the recording (read and validated), its
    sensor and the effects the model file declares already modelled."""
    from tcbench.diagnose.model_file import ModelFileError, read_model

    settings = diagnose_settings(cfg)
    if not cfg.recording:
        raise CommandError("recording=PATH is required")
    if cfg.sensor is not None and not kinds.known(cfg.sensor):
        raise CommandError(f"sensor must be one of {', '.join(kinds.names())}, got {cfg.sensor!r}")
    if cfg.max_rows is not None and cfg.max_rows < 1:
        raise CommandError(f"max_rows must be a number of rows >= 1 (null: no limit), got {cfg.max_rows}")
    writable_folder(cfg.out)
    free_outputs(cfg.out, list(REPORT_FILES), cfg.overwrite)
    checked_store(cfg.tracking)
    check_size(cfg.recording, cfg.max_rows, settings.rate.max_rows)
    rec = read_recording_arg(cfg.recording)
    check_bins(cfg.recording, rec, cfg.max_rows, settings)
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


def check_size(path: str, max_rows: int | None, budget_rows: int | None = None) -> None:
    """A record of more than ``max_rows`` rows that will be diagnosed as recorded (at most
    ``budget_rows``, ``settings.rate.max_rows``: a longer one is diagnosed on bin means,
    :func:`check_bins`) refused from its row count, before it is read: one line with the rows, the
    time they are estimated to take (:mod:`tcbench.diagnose.rate.cost`) and what to do."""
    from tcbench.sensors.recording_files import table_rows

    rows = table_rows(path)
    if rows is None or max_rows is None or rows <= max_rows or (budget_rows is not None and rows > budget_rows):
        return
    raise _too_many(path, rows, rows, max_rows)


def check_bins(path: str, rec: Any, max_rows: int | None, settings: Any) -> None:
    """A record diagnosed on bin means (:mod:`tcbench.diagnose.rate.native_rate`) whose bins would
    still be more than ``max_rows`` rows (bins no longer than ``settings.rate.max_bin_s``) refused
    as :func:`check_size` refuses one diagnosed as recorded."""
    from tcbench.diagnose.rate.native_rate import plan_for

    plan = plan_for(rec, settings.rate)
    if plan.averaged and max_rows is not None and plan.diagnosed_rows > max_rows:
        raise _too_many(path, plan.rows, plan.diagnosed_rows, max_rows, f" (bin means of {plan.bin_s:.3g} s)")


def _too_many(path: str, rows: int, diagnosed: int, max_rows: int, bins: str = "") -> CommandError:
    """The one line refusing ``rows`` rows whose diagnosis would run on ``diagnosed`` rows, over ``max_rows``."""
    from tcbench.diagnose.rate.cost import duration_text, estimated_bytes, estimated_s, size_text

    return CommandError(f"{path}: {rows} rows{bins} would take about {duration_text(estimated_s(diagnosed))} and "
                        f"{size_text(estimated_bytes(diagnosed))} to diagnose (one core, estimated from the rows; "
                        f"max_rows={max_rows}: about {duration_text(estimated_s(max_rows))}): average it into at most "
                        f"{max_rows} rows (means of {math.ceil(rows / max_rows)} samples; settings.rate.max_rows="
                        f"{max_rows} does it, its noise measured on every sample) or cut it into shorter "
                        f"recordings, or give max_rows={diagnosed} to diagnose it anyway")


@contextlib.contextmanager
def progress(name: str, rows: int) -> Iterator[None]:
    """Around the diagnosis of ``rows`` rows: when it is estimated to take longer than
    :data:`PROGRESS_AFTER_S`, one line on stderr with the rows and the estimate before it starts,
    and on a terminal a bar of the time spent against the estimate, updated every second."""
    from tcbench.diagnose.rate.cost import duration_text, estimated_s

    estimate = estimated_s(rows)
    if estimate < PROGRESS_AFTER_S:
        yield
        return
    print(f"tcbench: diagnosing {name}: {rows} rows, about {duration_text(estimate)} (one core, estimated from the "
          "rows)", file=sys.stderr, flush=True)
    if not sys.stderr.isatty():
        yield
        return
    from tqdm import tqdm

    done = threading.Event()
    with tqdm(total=math.ceil(estimate), desc="diagnosing", unit="s", leave=False, file=sys.stderr,
              bar_format=f"{{desc}} {{bar}} {{elapsed}} of about {duration_text(estimate)}") as bar:
        def tick() -> None:
            while not done.wait(1.0):
                if bar.n < bar.total - 1:
                    bar.update(1)
                else:
                    bar.refresh()

        ticker = threading.Thread(target=tick, daemon=True)
        ticker.start()
        try:
            yield
        finally:
            done.set()
            ticker.join()


def diagnose_recording(cfg: DiagnoseConfig) -> DiagnosisOutcome:
    """Diagnose the recording, write its report and print the verdict."""
    from tcbench.diagnose.rate.native_rate import diagnose_any_rate, plan_for, white_sigma
    from tcbench.diagnose.select.plan import min_full_duration_s
    from tcbench.diagnose.report.write import write_report
    from tcbench.diagnose.signals import DiagnosisDataError

    rec, sensor, declared = check_diagnose(cfg)
    settings = diagnose_settings(cfg)
    if rec.time_s[-1] - rec.time_s[0] < min_full_duration_s(settings):
        return _short_record(cfg, rec, sensor, settings)
    plan = plan_for(rec, settings.rate)
    if plan.averaged:
        print(f"tcbench: {Path(cfg.recording).name}: {plan.why()}", file=sys.stderr, flush=True)
    try:
        with progress(Path(cfg.recording).name, plan.diagnosed_rows):
            diag = diagnose_any_rate(rec, sensor=sensor, declared=declared, name=Path(cfg.recording).name,
                                     settings=settings)
    except DiagnosisDataError as exc:
        raise CommandError(f"{cfg.recording}: {exc}") from None
    del rec
    written = _written(write_report, diag, cfg)
    print(f"tcbench: {diag.verdict}")
    print(f"  baseline RMSE held-out {diag.baseline.rmse_heldout:.4g} {diag.unit}, final "
          f"{diag.final.rmse_heldout:.4g} {diag.unit}" + (" (of the bin means)" if plan.averaged else "")
          + f", white noise {white_sigma(diag):.4g} {diag.unit}" + (" per sample" if plan.averaged else ""))
    print(f"  wrote {', '.join(str(p) for p in written.values())}")
    return DiagnosisOutcome(diag, written)


def _written(writer: Any, report: Any, cfg: DiagnoseConfig) -> dict[str, Path]:
    """``writer(report, out, inputs, overwrite=, replaced=)``, its failures as one line (never over
    an input, nor over a file without ``overwrite``); says what it replaced."""
    from tcbench.sensors.recording import sidecar_path

    inputs = [cfg.recording, sidecar_path(cfg.recording), *([cfg.model] if cfg.model else [])]
    replaced: list[Path] = []
    with writing_errors(cfg.out, "the report"):
        written = writer(report, cfg.out, inputs, overwrite=cfg.overwrite, replaced=replaced)
    say_replaced(replaced)
    return dict(written)


def _short_record(cfg: DiagnoseConfig, rec: Any, sensor: str, settings: Any) -> DiagnosisOutcome:
    """The short-record report of ``rec`` (its tests at ``settings``), written to ``out``; prints
    what ran and what needs more time."""
    from tcbench.diagnose.rate.native_rate import plan_for
    from tcbench.diagnose.short.short_record import short_record
    from tcbench.diagnose.short.short_report import write_short_report
    from tcbench.diagnose.signals import DiagnosisDataError

    plan = plan_for(rec, settings.rate)
    if plan.averaged:
        print(f"tcbench: {Path(cfg.recording).name}: {plan.why()}", file=sys.stderr, flush=True)
    try:
        report = short_record(rec, sensor, name=Path(cfg.recording).name, settings=settings)
    except DiagnosisDataError as exc:
        raise CommandError(f"{cfg.recording}: {exc}") from None
    fewest = min(settings.short.min_fit_samples, 2 * settings.short.min_side_samples + 1)
    if not report.ran and report.samples < fewest:
        raise CommandError(f"{cfg.recording}: too short to test anything: {report.samples} sample"
                           f"{'s' * (report.samples != 1)} over {report.duration_s:.4g} s; the short-record tests "
                           f"need at least {fewest} samples, a full diagnosis {report.full_duration_s:.0f} s")
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
