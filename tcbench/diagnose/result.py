"""What a diagnosis found, as typed records: :class:`Diagnosis` and its parts. Only
:meth:`Diagnosis.to_json` (the ``report.json`` of docs/concepts/diagnosis-report.md) turns them into plain data; the arrays
behind the plots ride along in :class:`Series`."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.select.crossval import Fit
from tcbench.diagnose.select.design import deterministic
from tcbench.diagnose.select.evidence import Evidence
from tcbench.diagnose.select.locate import AllanExcess, Mismatch
from tcbench.diagnose.select.plan import StatsPlan
from tcbench.diagnose.select.reference import Reference
from tcbench.diagnose.select.significance import SignificanceTest
from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings, report_mapping
from tcbench.diagnose.terms import term

if TYPE_CHECKING:  # a field's type only: the screens import this module (screens/flicker.py), not the reverse
    from tcbench.diagnose.screens.outliers import Outliers

REFERENCE_WHAT = ("ridge regression on the smoothed thermometer temperature, its powers, first-order lags at "
                  "several time constants, dT/dt and time, under the same blocked folds")


@dataclass
class Series:
    """Per-sample arrays behind the plots: time, thermometer (smoothed), the held-out residual of
    the starting and of the final model, and the Allan deviations of their in-sample residuals
    against the white (plus thermometer) noise line."""

    t_s: np.ndarray
    temp_c: np.ndarray
    residual_before: np.ndarray
    residual_after: np.ndarray
    allan_before: AllanExcess | None
    allan_after: AllanExcess | None


def rmse(sse: float, n: int) -> float:
    """Root mean square of ``n`` samples whose squares sum to ``sse``."""
    return float(np.sqrt(sse / n))


@dataclass(frozen=True)
class FitSummary:
    """A model's RMSE on the samples it was fitted on and held out (output unit), and its terms
    (``minimal`` first)."""

    rmse_fit: float
    rmse_heldout: float
    model: list[str]

    @classmethod
    def of(cls, fit: Fit, n: int, ids: tuple[str, ...] | list[str]) -> FitSummary:
        return cls(rmse(fit.sse_fit, n), rmse(fit.sse_heldout, n), ["minimal", *ids])

    def to_json(self) -> dict[str, Any]:
        return {"rmse_fit": self.rmse_fit, "rmse_heldout": self.rmse_heldout, "model": list(self.model)}


@dataclass(frozen=True)
class Noise:
    """The white sigma per sample (output unit), the thermometer's noise (degC), the samples fitted
    and the cross-validation folds."""

    white_sigma: float
    thermometer_sigma_c: float
    samples: int
    folds: int

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class ReferenceSummary:
    """The physics-agnostic reference fit (:mod:`tcbench.diagnose.select.reference`) beside the final model."""

    rmse_heldout: float
    rmse_fit: float
    terms: list[str]
    ridge_alpha: float
    rmse_heldout_sigma: float
    final_over_reference: float
    deterministic_structure_remains: bool
    what: str = REFERENCE_WHAT

    @classmethod
    def of(cls, ref: Reference, final_rmse: float, sigma: float) -> ReferenceSummary:
        ratio = final_rmse / ref.rmse_heldout if ref.rmse_heldout > 0 else float("inf")
        return cls(ref.rmse_heldout, ref.rmse_fit, ref.terms, ref.alpha, ref.rmse_heldout / sigma, ratio,
                   ref.structure_remains(final_rmse))

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


@dataclass
class Statistics:
    """How the diagnosis tested this record: the plan (blocks, folds, clusters, significance
    test), the thermometer smoothing window (s), the screens' entries, ``{detector: why it could
    not run}``, where two windows were tried, ``{window (s): final held-out RMSE}``, and the
    settings it ran with (report.json's ``statistics.settings``: every section and key, so a
    report says what it was tested with whatever the defaults of a later version)."""

    plan: StatsPlan
    smooth_s: float
    screens: dict[str, Any] = field(default_factory=dict)
    not_tested: dict[str, str] = field(default_factory=dict)
    smooth_tried_s: dict[str, float] = field(default_factory=dict)
    settings: DiagnoseSettings = DEFAULTS

    @property
    def significance_test(self) -> str:
        return self.plan.test.name

    def to_json(self) -> dict[str, Any]:
        out = {**self.plan.to_json(), "thermometer_smooth_s": self.smooth_s, **self.screens}
        if self.not_tested:
            out["not_tested"] = self.not_tested
        if self.smooth_tried_s:
            out["thermometer_smooth_tried_s"] = self.smooth_tried_s
        out["settings"] = report_mapping(self.settings)
        return out


@dataclass(frozen=True)
class Confusion:
    """Two effects this recording cannot tell apart (the kept one first) and the test that would."""

    effects: tuple[str, str]
    test: str

    def to_json(self) -> dict[str, Any]:
        return {"effects": list(self.effects), "test": self.test}


@dataclass
class Diagnosis:
    """What the diagnosis found, in the shape of the report of docs/concepts/diagnosis-report.md (see :meth:`to_json`)."""

    sensor: str
    unit: str
    recording: str
    baseline: FitSummary
    mismatch: list[Mismatch]
    remaining: list[Mismatch]
    effects: list[Finding]
    final: FitSummary
    noise: Noise
    candidates: list[Evidence]
    confusable: list[Confusion]
    model: dict[str, Any]  # model.yaml's mapping
    series: Series = field(repr=False)
    reference: ReferenceSummary | None
    statistics: Statistics
    outliers: Outliers | None = None

    @property
    def deterministic_remains(self) -> bool:
        """Whether the physics-agnostic reference beats the final model by more than the settings'
        ``reference.structure_ratio`` held out: temperature structure the model leaves in its residual."""
        ref = self.reference.rmse_heldout if self.reference is not None else None
        ratio = self.statistics.settings.reference.structure_ratio
        return bool(ref) and self.final.rmse_heldout > ratio * ref  # type: ignore[operator]

    @property
    def effect_ids(self) -> list[str]:
        """Ids of the effects found, in the order they were kept."""
        return [e.id for e in self.effects]

    @property
    def verdict(self) -> str:
        """One line: nothing missing, which effects, and whether a mismatch remains unexplained."""
        rest = ("a mismatch remains that no effect of the library explains on this recording "
                f"({len(self.remaining)} region(s) or band(s), see remaining_mismatch)")
        spikes = (f"; {self.outliers.count} isolated outlier sample(s) given zero weight (see outliers)"
                  if self.outliers is not None and self.outliers.count else "")
        spikes += "".join(f"; {e.params['count']} thermometer glitch(es) given zero weight (see {e.id})"
                          for e in self.effects if e.id == "thermometer_glitches")
        library = [e.id for e in self.effects if e.library]
        beyond = [f"{e.id} ({e.shape})" for e in self.effects if not e.library and e.shape != "outliers"]
        if beyond:
            spikes = f"; beyond the library: {', '.join(beyond)}{spikes}"
        if not library:
            if self.remaining:
                return f"no effect of the library found, but {rest}{spikes}"
            if beyond:
                return f"no effect of the library found{spikes}"
            return f"nothing missing: the residual of the starting model is consistent with its noise{spikes}"
        named_ = ", ".join(library)
        pairs = "; ".join(f"{c.effects[0]} cannot be told from {c.effects[1]}" for c in self.confusable)
        out = f"missing: {named_}" + (f" ({pairs})" if pairs else "") + (f"; {rest}" if self.remaining else "")
        if self.deterministic_remains:
            assert self.reference is not None
            out += (f"; deterministic temperature structure remains: a generic temperature model reaches "
                    f"{self.final.rmse_heldout / self.reference.rmse_heldout:.3g}x lower held-out RMSE")
        return out + spikes

    def preface(self) -> list[str]:
        """report.md's lines after the verdict, before the fit: none for a record diagnosed as it
        was recorded (:mod:`tcbench.diagnose.rate.native_rate` says what it averaged there)."""
        return []

    def to_json(self) -> dict[str, Any]:
        """``report.json``: plain JSON data."""
        return {
            "sensor": self.sensor, "unit": self.unit, "recording": self.recording,
            "verdict": self.verdict, "baseline": self.baseline.to_json(),
            "mismatch": [m.to_dict() for m in self.mismatch],
            "remaining_mismatch": [m.to_dict() for m in self.remaining],
            "effects": [f.to_json() for f in self.effects],
            "final": self.final.to_json(), "reference": self.reference.to_json() if self.reference else {},
            "statistics": self.statistics.to_json(), "noise": self.noise.to_json(),
            "candidates": [evidence_json(e, self.statistics.plan.test) for e in self.candidates],
            "confusable": [c.to_json() for c in self.confusable],
        }


def significance_json(e: Evidence, test: SignificanceTest) -> dict[str, Any]:
    """Which significance test decided for ``e`` (one ``test``, the plan's, decides by) and its statistic."""
    return test.decided_by(e.test).to_json(e.wald, e.p_value) if e.test else {}


def evidence_json(e: Evidence, test: SignificanceTest) -> dict[str, Any]:
    """report.json's ``candidates`` entry of ``e``, judged by the plan's ``test``."""
    out: dict[str, Any] = {"id": e.effect, "status": e.status, "reason": e.reason}
    if np.isfinite(e.gain):
        out |= {"gain_sigma2": round(float(e.gain), 2), "threshold_sigma2": float(e.threshold)}
    out |= significance_json(e, test)
    if e.value is not None and e.effect in deterministic() and (name := term(e.effect).param):
        out[name] = float(e.value)
    return out
