"""The recording job kinds: ``simulate`` (a device under a protocol), ``metrics`` (a recording's
papers' metrics) and ``import`` (a user's CSV as a recording). Their work is in
:mod:`tcbench.commands.recordings`; here is how they are named and what goes to MLflow: the metrics, the
plots and tables, the sidecar, and tags naming the sensor, device and recording."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import yaml

from tcbench.commands import recordings
from tcbench.commands.schemas import ImportConfig, MetricsConfig, SimulateConfig, as_schema
from tcbench.runner.kinds import JobKind, JobNames, announce
from tcbench.sensors import kinds as sensor_kinds


class RecordingKind(JobKind):
    """What the three recording kinds share: the record of a :class:`~tcbench.commands.recordings.RecordingOutcome`."""

    schema: type = SimulateConfig
    opens_run_after_work = True  # a bad protocol parameter or file leaves no run, as it leaves no file

    def config(self, c: dict[str, Any]) -> Any:
        return as_schema(c, self.schema)

    def record(self, run: Any, outcome: recordings.RecordingOutcome, c: dict[str, Any], where: Path) -> list[Path]:
        rec, report = outcome.rec, outcome.report
        extra = rec.meta.extra or {}
        run.set_tag("tcbench.sensor", str(rec.meta.sensor))
        run.set_tag("tcbench.device_id", str(rec.meta.device_id))
        run.set_tag("tcbench.recording", str(outcome.path.resolve()))
        run.log_params({"recording.sample_rate_hz": str(rec.meta.sample_rate_hz),
                        "recording.samples": str(rec.samples)})
        files = []
        if report is not None:
            run.log_metrics({k: v for k, v in report.metrics.items() if not math.isnan(v)})
            files += list(report.files.values())
        sidecar = where / "sidecar.json"
        sidecar.write_text(yaml.safe_dump(extra, sort_keys=False) if extra else "{}")
        for other in outcome.also:  # the further axes of one import: their paths and sidecars
            side = where / f"sidecar-{other.path.stem}.json"
            side.write_text(yaml.safe_dump(other.rec.meta.extra or {}, sort_keys=False))
            files.append(side)
        if outcome.also:
            run.set_tag("tcbench.recordings", ",".join(str(o.path.resolve()) for o in [outcome, *outcome.also]))
        announce(run, c)
        return [*files, sidecar]


class SimulateKind(RecordingKind):
    tag, schema = "simulation", SimulateConfig

    def prepare(self, c: dict[str, Any]) -> dict[str, Any]:
        return {**c, "protocol": recordings.simulated_protocol(self.config(c))}  # the kind's default made explicit

    def check(self, c: dict[str, Any]) -> None:
        recordings.check_simulate(self.config(c))

    def names(self, c: dict[str, Any]) -> JobNames:
        cfg: SimulateConfig = self.config(c)
        sensor = cfg.sensor or sensor_kinds.DEFAULT
        return JobNames(recordings.simulation_stem(cfg), f"{sensor}-{cfg.protocol}", "simulate",
                        int(cfg.seed), {"tcbench.device_seed": str(cfg.device_seed)})

    def outputs(self, c: dict[str, Any]) -> list[Path]:
        cfg: SimulateConfig = self.config(c)
        return [Path(cfg.out) / f"{recordings.simulation_stem(cfg)}.{cfg.format}"]

    def execute(self, c: dict[str, Any]) -> recordings.RecordingOutcome:
        return recordings.simulate(self.config(c))

    def summary(self, outcome: recordings.RecordingOutcome, c: dict[str, Any]) -> str:
        return f"simulated {outcome.path}"


class MetricsKind(RecordingKind):
    schema = MetricsConfig

    def check(self, c: dict[str, Any]) -> None:
        recordings.check_metrics(self.config(c))

    def names(self, c: dict[str, Any]) -> JobNames:
        path = Path(str(c.get("recording") or "recording"))
        return JobNames(f"metrics-{path.stem}", path.stem, "metrics")

    def outputs(self, c: dict[str, Any]) -> list[Path]:
        return [recordings.metrics_folder(self.config(c))]

    def execute(self, c: dict[str, Any]) -> recordings.RecordingOutcome:
        return recordings.metrics(self.config(c))

    def summary(self, outcome: recordings.RecordingOutcome, c: dict[str, Any]) -> str:
        return f"metrics of {outcome.path}"


class ImportKind(RecordingKind):
    schema = ImportConfig

    def check(self, c: dict[str, Any]) -> None:
        recordings.check_import(self.config(c))

    def names(self, c: dict[str, Any]) -> JobNames:
        cfg: ImportConfig = self.config(c)
        return JobNames(f"import-{recordings.import_stem(cfg)}", Path(cfg.csv).name, "import")

    def outputs(self, c: dict[str, Any]) -> list[Path]:
        cfg: ImportConfig = self.config(c)
        if recordings.is_ulog(cfg):  # its recordings are known once the log is read: NAME-<topic>-...
            return [Path(cfg.out) / f"{recordings.import_stem(cfg)}-ulog"]
        return [Path(cfg.out) / f"{stem}.csv" for stem in recordings.import_stems(cfg)]

    def execute(self, c: dict[str, Any]) -> recordings.RecordingOutcome:
        return recordings.import_recording(self.config(c))

    def summary(self, outcome: recordings.RecordingOutcome, c: dict[str, Any]) -> str:
        return f"imported {outcome.path}"
