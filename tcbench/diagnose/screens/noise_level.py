"""Noise whose level changes with temperature or time (:mod:`~tcbench.diagnose.screens.variance`), tested
twice:

- before any fit (:class:`NoiseLevelScreen`), on the residual of the minimal model: where the
  level changes, the white sigma the rest of the diagnosis measures in becomes the record's RMS
  sigma (the median of absolute differences reads low on a mixture of levels, which made the
  Allan test call the excess flicker: 1.35 instead of 1.58 for half the record at sigma 1 and
  half at 2), and the outlier test and the open-world threshold read the level per sample;
- after the final fit (:class:`VarianceScreen`), on its in-sample residual: the finding, its
  ``model.yaml`` noise term and report.json's ``statistics.variance``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.screens.output import QuantisationScreen, clear_of_clipping
from tcbench.diagnose.screens.screen import AFTER, BEFORE, Screen, ScreenInput, ScreenResult
from tcbench.diagnose.screens.variance import Variance, find_variance
from tcbench.diagnose.select.design import Designer, Model
from tcbench.diagnose.settings import DEFAULTS, ScreenSettings, VarianceSettings
from tcbench.diagnose.signals import DiagnosisData

ID = "variance"


def coarse_grid(given: ScreenInput) -> str | None:
    """Why the variance test does not apply: an output whose grid is coarser than its noise."""
    grid = given.results.get(QuantisationScreen.id)
    found = getattr(grid, "found", None)
    if found is not None and given.data is not None and found.step > given.data.white_sigma:
        return (f"the output's quantisation step ({found.step:.4g}) exceeds its white noise: "
                "the scatter follows the signal's place on the grid")
    return None


def variance_of(given: ScreenInput, residual: np.ndarray,
                settings: VarianceSettings = DEFAULTS.screens.variance) -> Variance:
    """The variance test of ``residual`` on the samples of ``given.data`` clear of any clip level."""
    data = given.data
    assert data is not None
    keep = clear_of_clipping(given, residual)
    return find_variance(data.t_s[keep], data.temp_c[keep], residual[keep], data.run_id[keep], data.sample_rate_hz,
                         settings=settings)


@dataclass(frozen=True)
class NoiseLevel(ScreenResult):
    """The first variance test, the data in the record's RMS sigma where the level changes, and
    the level per sample relative to that RMS (None where it does not change)."""

    found: Variance
    relative_sigma: np.ndarray | None
    data: DiagnosisData | None


@dataclass(frozen=True)
class NoiseLevelScreen(Screen):
    """The variance test (``settings.variance``) on the residual of the minimal model, before any fit."""

    settings: ScreenSettings = DEFAULTS.screens
    id = ID
    stage = BEFORE

    def skip(self, given: ScreenInput) -> str | None:
        return coarse_grid(given)

    def run(self, given: ScreenInput) -> NoiseLevel:
        data = given.data
        assert data is not None
        x = Designer(data).matrix(Model())
        beta, *_ = np.linalg.lstsq(x, data.output, rcond=None)
        found = variance_of(given, data.output - x @ beta, self.settings.variance)
        if found.found is None:
            return NoiseLevel(found, None, data)
        if found.rms_sigma > data.white_sigma:
            data = replace(data, white_sigma=found.rms_sigma)
        return NoiseLevel(found, found.relative_sigma(data.temp_c, data.t_s), data)


def relative_sigma(given: ScreenInput) -> np.ndarray | None:
    """The noise level per sample relative to the record's RMS that :class:`NoiseLevelScreen`
    found, or None."""
    level = given.results.get(ID)
    return level.relative_sigma if isinstance(level, NoiseLevel) else None


@dataclass(frozen=True)
class NoiseVariance(ScreenResult):
    """The variance test of the final model's residual."""

    found: Variance

    def not_tested(self) -> str | None:
        return self.found.reason or None

    def findings(self, unit: str) -> list[Finding]:
        return [self.found.finding(unit)] if self.found.found is not None else []

    def write_model(self, model: dict[str, Any]) -> None:
        """The changing noise in place of ``white_noise``."""
        noise = self.found.model_effect()
        if noise is not None:
            model["effects"].pop("white_noise", None)
            model["effects"][noise[0]] = {k: float(v) for k, v in noise[1].items()}

    def statistics(self) -> dict[str, Any]:
        return {} if self.found.reason else {"variance": self.found.statistics()}


@dataclass(frozen=True)
class VarianceScreen(Screen):
    """The variance test (``settings.variance``) on the final model's in-sample residual."""

    settings: ScreenSettings = DEFAULTS.screens
    id = ID
    stage = AFTER

    def skip(self, given: ScreenInput) -> str | None:
        return coarse_grid(given)

    def run(self, given: ScreenInput) -> NoiseVariance:
        assert given.attribution is not None
        return NoiseVariance(variance_of(given, given.attribution.final_fit.residual, self.settings.variance))
