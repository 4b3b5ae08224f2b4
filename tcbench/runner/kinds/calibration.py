"""The calibration job kind: ``tcbench calibrate`` on one static recording
(:mod:`tcbench.commands.calibration`). Its MLflow run carries each method's drift and RMS on
every branch (``<method>.b<k>.drift_rms`` ...; ``<method>.<stem>.b<k>.drift_rms`` on a test recording), the sensor, and the board, plot and PX4
parameters as artifacts."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from tcbench.commands.calibration import CalibrationOutcome, calibrate_recording, check_calibrate
from tcbench.commands.schemas import CalibrateConfig, as_schema
from tcbench.runner.kinds import JobKind, JobNames, announce


class CalibrateKind(JobKind):
    name, tag = "calibrate", "calibration"
    opens_run_after_work = True  # a recording it cannot calibrate leaves no run, as it leaves no file

    def config(self, c: dict[str, Any]) -> CalibrateConfig:
        return as_schema(c, CalibrateConfig)

    def check(self, c: dict[str, Any]) -> None:
        check_calibrate(self.config(c))

    def names(self, c: dict[str, Any]) -> JobNames:
        path = Path(str(c.get("recording") or "recording"))
        return JobNames(f"calibrate-{path.stem}", path.name, "calibrate")

    def outputs(self, c: dict[str, Any]) -> list[Path]:
        return [Path(str(c.get("out")))]

    def execute(self, c: dict[str, Any]) -> CalibrationOutcome:
        return calibrate_recording(self.config(c))

    def record(self, run: Any, outcome: CalibrationOutcome, c: dict[str, Any], where: Path) -> list[Path]:
        run.set_tag("tcbench.sensor", outcome.sensor)
        metrics = {}
        own = Path(str(c.get("recording"))).stem
        for row in outcome.table.to_dict("records"):
            where = "" if row["recording"] == own else re.sub(r"[^\w\-. /]", "_", str(row["recording"])) + "."
            for key, value in row.items():
                if key.startswith(("drift_rms_", "rms_")):
                    stat = "drift_rms" if key.startswith("drift_rms_") else "rms"
                    metrics[f"{row['method']}.{where}b{row['branch']}.{stat}"] = float(value)
        run.log_metrics(metrics)
        announce(run, c)
        return [p for p in outcome.written.values() if Path(p).is_file()]

    def summary(self, outcome: CalibrationOutcome, c: dict[str, Any]) -> str:
        return f"calibrated {c.get('recording')}"


KINDS = {"calibrate": CalibrateKind()}
