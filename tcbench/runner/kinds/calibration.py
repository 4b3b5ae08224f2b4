"""The calibration job kind: ``tcbench calibrate`` on one static recording
(:mod:`tcbench.commands.calibration`). Its MLflow run carries each method's drift and RMS on
every branch (``<method>.b<k>.drift_rms`` ...; ``<method>.<stem>.b<k>.drift_rms`` on a test
recording), its held-out and fitted-part drift (``<method>.held_out.drift``,
``<method>.held_out.rms``, ``<method>.fit.drift``), the tags the calibration board groups by
(``tcbench.recording``, ``tcbench.data_hash``: the recording's content, so two files of one name
never merge; ``tcbench.sensor``, ``tcbench.axis``, ``tcbench.best``), and the tables, plot and
``calibration.json`` as artifacts."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from tcbench.commands.calibration import CalibrationOutcome, calibrate_recording, check_calibrate
from tcbench.commands.schemas import CalibrateConfig, as_schema
from tcbench.runner.kinds import JobKind, JobNames, announce


class CalibrateKind(JobKind):
    tag = "calibration"
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
        about = outcome.about
        run.set_tag("tcbench.sensor", outcome.sensor)
        for key in ("recording", "axis", "best", "unit"):
            if about.get(key) is not None:
                run.set_tag(f"tcbench.{key}", str(about[key]))
        run.set_tag("tcbench.data_hash", str(about.get("content_hash", "")))
        run.set_tag("tcbench.held_out", str(bool(about.get("held_out"))).lower())
        run.set_tag("tcbench.split", f"fit {','.join(map(str, about.get('fitted', [])))} -> score "
                                     f"{','.join(map(str, about.get('held_out_parts', []))) or '-'}"
                                     + "".join(f" + {t}" for t in about.get("test_recordings", [])))
        metrics = {}
        summary = outcome.summary
        if summary is not None:
            for row in summary.to_dict("records"):
                for key, value in row.items():
                    for prefix, name in (("held_out_drift_", "held_out.drift"), ("held_out_rms_", "held_out.rms"),
                                         ("fit_drift_", "fit.drift")):
                        if str(key).startswith(prefix) and value == value:
                            metrics[f"{row['method']}.{name}"] = float(value)
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
