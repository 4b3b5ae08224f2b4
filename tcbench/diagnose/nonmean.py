"""The detectors whose structure is not an additive mean term, as one step of ``diagnose``.

- before :func:`~tcbench.diagnose.signals.prepare`: the thermometer's quantisation, which sets
  the smoothing window (:func:`~tcbench.diagnose.quantisation.thermometer_steps`);
- before any fit: the output's quantisation (:mod:`~tcbench.diagnose.quantisation`) and its
  saturation (:mod:`~tcbench.diagnose.saturation`), whose clipped samples get zero weight; and a
  first variance test on the residual of the minimal model: where the noise level changes, the
  white sigma the rest of the diagnosis measures in becomes the record's RMS sigma (the median
  of absolute differences reads low on a mixture of levels, which made the Allan test call the
  excess flicker: 1.35 instead of 1.58 for half the record at sigma 1 and half at 2);
- after the final fit: the variance of its in-sample residual (:mod:`~tcbench.diagnose.variance`),
  which the finding reports.

:class:`NonMean` collects what they found for the report (``findings``), for ``model.yaml``
(:meth:`NonMean.write_model`) and for ``statistics`` (including which were not tested and why).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from tcbench.diagnose.design import Designer, Model
from tcbench.diagnose.outliers import without
from tcbench.diagnose.quantisation import (
    OutputQuantisation,
    ThermometerSteps,
    find_output_quantisation,
    thermometer_steps,
)
from tcbench.diagnose.saturation import Saturation, find_saturation
from tcbench.diagnose.signals import MAD_TO_SIGMA, DiagnosisData, fitted_window_s
from tcbench.diagnose.variance import Variance, find_variance
from tcbench.sensors.recording import Recording

DEFAULT_SMOOTH_S = 120.0  # the thermometer smoothing window of a record without a coarse staircase
CLEAR_SIGMA = 3.0  # white sigmas between a sample's fitted value and a clip level for the variance test
CLIP_SIGMA = 8.0  # differences clipped at this many sigmas (or steps) when the output is quantised


def _differences(data: DiagnosisData) -> np.ndarray:
    """First differences of consecutive samples in one run, at most 1.5 sample intervals apart."""
    dt = np.diff(data.t_s)
    same = (data.run_id[1:] == data.run_id[:-1]) & (dt <= 1.5 * float(np.median(dt)))
    return np.diff(data.output)[same]


def _white_sigma(data: DiagnosisData) -> float:
    """The white sigma from first differences of consecutive kept samples in one run (as
    :func:`~tcbench.diagnose.signals.prepare` does, after samples were removed)."""
    d = _differences(data)
    if d.size < 10:
        return data.white_sigma
    sigma = float(MAD_TO_SIGMA * np.median(np.abs(d - np.median(d))) / np.sqrt(2.0))
    return sigma if sigma > 0 else data.white_sigma


def _quantised_sigma(data: DiagnosisData, step: float) -> float:
    """The output's per-sample noise, quantisation included, on a lattice of ``step``: the
    RMS of first differences / sqrt(2), each clipped at :data:`CLIP_SIGMA` times the larger of
    the MAD estimate and the step. The MAD of differences that take a few lattice values is
    not a sigma (for noise of sigma 1 on a grid of 1.5 it reads 1.57 where the truth is 1.09)."""
    d = _differences(data)
    if d.size < 10:
        return data.white_sigma
    bound = CLIP_SIGMA * max(data.white_sigma, step)
    return float(np.sqrt(np.mean(np.minimum(np.abs(d), bound) ** 2) / 2.0))


@dataclass
class NonMean:
    """What the non-additive detectors found on one record (see the module doc)."""

    thermometer: ThermometerSteps | None = None
    default_smooth_s: float = DEFAULT_SMOOTH_S  # fitted to the profile (signals.fitted_window_s)
    quantisation: OutputQuantisation | None = None
    saturation: Saturation | None = None
    variance: Variance | None = None
    first_variance: Variance | None = None  # the test before any fit, on the minimal model's residual
    not_tested: dict[str, str] = field(default_factory=dict)
    unit: str = ""
    sample_rate_hz: float = 1.0

    @classmethod
    def before(cls, rec: Recording, window_s: float | None = None) -> NonMean:
        """The thermometer's lattice, read from the raw reading before it is smoothed; the
        smoothing window fitted to the profile, or ``window_s`` when given."""
        t, temp = rec.time_s, rec.temperature_c
        out = cls()
        if t.size >= 2 and t[-1] > t[0]:
            out.thermometer = thermometer_steps(t, temp, DEFAULT_SMOOTH_S)
            # An undithered staircase's steps are not white noise (they would read as bias): it keeps
            # its own wide window. Otherwise the window is fitted to the profile's time scales.
            if out.thermometer is None or not out.thermometer.staircase:
                out.default_smooth_s = window_s if window_s is not None else fitted_window_s(t, temp, DEFAULT_SMOOTH_S)
                if out.thermometer is not None:
                    out.thermometer = thermometer_steps(t, temp, out.default_smooth_s)
        return out

    @property
    def smooth_s(self) -> float:
        """The thermometer smoothing window (s): widened for an undithered staircase."""
        return self.thermometer.smooth_s if self.thermometer is not None else self.default_smooth_s

    def prefit(self, data: DiagnosisData) -> DiagnosisData:
        """Find the output's lattice and clipping; ``data`` with the clipped samples removed,
        its white sigma re-measured without them (from the RMS of differences on a lattice), and
        raised to the RMS sigma where a first variance test on the minimal model's residual
        finds the noise level changing."""
        self.unit, self.sample_rate_hz = data.unit, data.sample_rate_hz
        self.quantisation = find_output_quantisation(data.output, data.white_sigma)
        step = self.quantisation.step if self.quantisation is not None else 0.0
        if step:
            data = replace(data, white_sigma=_quantised_sigma(data, step))
            self.quantisation = replace(self.quantisation, white_sigma=data.white_sigma)  # type: ignore[arg-type]
        self.saturation = find_saturation(data, step)
        if self.saturation.index.size:
            data = without(data, self.saturation.index)
            data = replace(data, white_sigma=_quantised_sigma(data, step) if step else _white_sigma(data))
        if self._variance_testable(data):
            x = Designer(data).matrix(Model())
            beta, *_ = np.linalg.lstsq(x, data.output, rcond=None)
            first = self.first_variance = self._variance(data, data.output - x @ beta)
            if first.found is not None and first.rms_sigma > data.white_sigma:
                data = replace(data, white_sigma=first.rms_sigma)
        return data

    def relative_sigma(self, data: DiagnosisData) -> np.ndarray | None:
        """The noise level per sample relative to the record's RMS where the first variance test
        found it changing (for the outlier test's local scale); None where it did not."""
        first = self.first_variance
        if first is None or first.found is None:
            return None
        return first.relative_sigma(data.temp_c, data.t_s)

    def _variance_testable(self, data: DiagnosisData) -> bool:
        """Whether the variance test applies (not on an output whose grid is coarser than its noise)."""
        q = self.quantisation
        if q is not None and q.step > data.white_sigma:
            self.not_tested["variance"] = (f"the output's quantisation step ({q.step:.4g}) exceeds its white noise: "
                                           "the scatter follows the signal's place on the grid")
            return False
        return True

    def _variance(self, data: DiagnosisData, residual: np.ndarray) -> Variance:
        """The variance test of ``residual`` on the samples clear of any clip level."""
        keep = self._clear_of_clipping(data, residual)
        return find_variance(data.t_s[keep], data.temp_c[keep], residual[keep], data.run_id[keep],
                             data.sample_rate_hz)

    def postfit(self, data: DiagnosisData, residual: np.ndarray) -> list[dict[str, Any]]:
        """Test the final in-sample ``residual`` for a changing noise level; every finding, as
        report.json ``effects`` entries."""
        if self._variance_testable(data):
            self.variance = self._variance(data, residual)
            if self.variance.reason:
                self.not_tested["variance"] = self.variance.reason
        return self.findings()

    def _clear_of_clipping(self, data: DiagnosisData, residual: np.ndarray) -> np.ndarray:
        """Samples whose fitted value lies more than :data:`CLEAR_SIGMA` white sigmas inside
        the clip levels: nearer, the unclipped samples kept are a truncated, less scattered part
        of their distribution, which the variance test would take for a quieter band."""
        keep = np.ones(data.n, dtype=bool)
        if self.saturation is None or not self.saturation.found:
            return keep
        fitted = data.output - residual
        margin = CLEAR_SIGMA * data.white_sigma
        levels = self.saturation.model_params()
        if "upper" in levels:
            keep &= fitted < levels["upper"] - margin
        if "lower" in levels:
            keep &= fitted > levels["lower"] + margin
        return keep

    def findings(self) -> list[dict[str, Any]]:
        """The report.json ``effects`` entries of everything found."""
        out = []
        if self.saturation is not None and self.saturation.found:
            out.append(self.saturation.finding(self.unit))
        if self.quantisation is not None:
            out.append(self.quantisation.finding(self.unit))
        if self.thermometer is not None and self.thermometer.staircase:
            out.append(self.thermometer.finding())
        if self.variance is not None and self.variance.found is not None:
            out.append(self.variance.finding(self.unit))
        return out

    def write_model(self, model: dict[str, Any]) -> None:
        """Add the terms found to ``model`` (model.yaml's mapping): the variance's noise in
        place of ``white_noise``, then ``quantisation`` (with the white noise reduced by the
        grid's own ``q^2 / 12``, which simulate adds back by quantising) and ``saturation`` (the
        final stage, in that order), and ``thermometer_quantisation``."""
        effects = model["effects"]
        noise = self.variance.model_effect() if self.variance is not None else None
        if noise is not None:
            effects.pop("white_noise", None)
            effects[noise[0]] = {k: float(v) for k, v in noise[1].items()}
        if self.quantisation is not None:
            q = self.quantisation.step
            if "white_noise" in effects:  # the noise before the converter: simulate quantises it again
                fs = self.sample_rate_hz
                sigma = effects["white_noise"]["density"] * np.sqrt(fs)  # per sample, quantisation included
                effects["white_noise"] = {"density": float(np.sqrt(max(sigma**2 - q**2 / 12.0, 0.0) / fs))}
            effects["quantisation"] = {"step": float(q)}
        if self.saturation is not None and self.saturation.found:
            effects["saturation"] = self.saturation.model_params()
        if self.thermometer is not None and self.thermometer.staircase:
            effects["thermometer_quantisation"] = {"step_c": float(self.thermometer.step_c)}

    def statistics(self) -> dict[str, Any]:
        """report.json ``statistics`` entries: the thermometer window and the variance test
        (which detectors were not tested and why: :attr:`not_tested`, merged by the diagnosis)."""
        out: dict[str, Any] = {"thermometer_smooth_s": self.smooth_s}
        if self.variance is not None and not self.variance.reason:
            out["variance"] = self.variance.statistics()
        return out
