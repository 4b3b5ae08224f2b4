"""The diagnosis job kind: ``tcbench diagnose`` on one recording (:mod:`tcbench.commands.diagnosis`).
Its MLflow run carries the effects found (tag ``tcbench.effects_found``, their parameters as
params ``found.<effect>.<param>``), the verdict, the held-out RMSEs before and after (also in
white-noise sigmas) and the report, plots and ``model.yaml`` as artifacts. The run of a short
record carries its verdict, each test's status (tags ``tcbench.short.<test>``), their numbers as
metrics ``<test>.<value>`` and ``report.json``/``report.md`` as artifacts."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tcbench.commands.diagnosis import DiagnosisOutcome, check_diagnose, diagnose_recording
from tcbench.commands.schemas import DiagnoseConfig, as_schema
from tcbench.runner.kinds import JobKind, JobNames, announce


def diagnosis_metrics(diag: Any) -> dict[str, float]:
    """The held-out RMSEs of the baseline and final models, in the unit and in white-noise sigmas
    (of the bin means for a record averaged into bins, with the full-rate sigma beside them)."""
    sigma = float(diag.noise.white_sigma)
    before, after = float(diag.baseline.rmse_heldout), float(diag.final.rmse_heldout)
    out = {"rmse_heldout_before": before, "rmse_heldout_after": after, "white_sigma": sigma,
           "effects_found": float(len(diag.effect_ids))}
    if sigma > 0:
        out |= {"rmse_heldout_before_sigma": before / sigma, "rmse_heldout_after_sigma": after / sigma}
    native = getattr(diag, "native_rate", None)  # a record averaged into bins: the RMSEs and sigma are the bins'
    if native is not None:
        out |= {"white_sigma_full_rate": float(native.full.white_sigma), "bin_samples": float(native.plan.bin_samples)}
    return out


class DiagnoseKind(JobKind):
    tag = "diagnosis"
    opens_run_after_work = True  # a recording it cannot diagnose leaves no run, as it leaves no report

    def config(self, c: dict[str, Any]) -> DiagnoseConfig:
        return as_schema(c, DiagnoseConfig)

    def check(self, c: dict[str, Any]) -> None:
        check_diagnose(self.config(c))

    def names(self, c: dict[str, Any]) -> JobNames:
        path = Path(str(c.get("recording") or "recording"))
        return JobNames(f"diagnose-{path.stem}", path.name, "diagnose")

    def outputs(self, c: dict[str, Any]) -> list[Path]:
        return [Path(str(c.get("out")))]

    def execute(self, c: dict[str, Any]) -> DiagnosisOutcome:
        return diagnose_recording(self.config(c))

    def record(self, run: Any, outcome: DiagnosisOutcome, c: dict[str, Any], where: Path) -> list[Path]:
        from tcbench.diagnose.short.short_record import ShortRecordReport  # loaded by execute already

        diag = outcome.diagnosis
        run.set_tag("tcbench.verdict", str(diag.verdict)[:4900])
        run.set_tag("tcbench.sensor", str(diag.sensor))
        if isinstance(diag, ShortRecordReport):
            for key, value in diag.tags().items():
                run.set_tag(key, value)
            run.log_metrics(diag.metrics())
        else:
            run.set_tag("tcbench.effects_found", ",".join(diag.effect_ids) or "none")
            run.log_params({f"found.{e.id}.{k}": f"{v:.6g}" for e in diag.effects
                            for k, v in e.params.items() if isinstance(v, (int, float))})
            run.log_metrics(diagnosis_metrics(diag))
        announce(run, c)
        return [p for p in outcome.written.values() if Path(p).is_file()]

    def summary(self, outcome: DiagnosisOutcome, c: dict[str, Any]) -> str:
        return f"diagnosed {c.get('recording')}: {outcome.diagnosis.verdict}"
