"""Isolated outliers of the starting model's in-sample residual
(:mod:`~tcbench.diagnose.screens.outliers`), judged at the local noise level: zero weight in every fit,
score and test after it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.screens.noise_level import relative_sigma
from tcbench.diagnose.screens.outliers import Outliers, find_outliers, without
from tcbench.diagnose.screens.screen import BEFORE, Screen, ScreenInput, ScreenResult
from tcbench.diagnose.select.design import Designer
from tcbench.diagnose.settings import DEFAULTS, ScreenSettings
from tcbench.diagnose.signals import DiagnosisData


@dataclass(frozen=True)
class Spikes(ScreenResult):
    """The outliers found and the data without them."""

    found: Outliers
    data: DiagnosisData | None

    def findings(self, unit: str) -> list[Finding]:
        return [self.found.finding(unit)] if self.found.count else []

    def write_model(self, model: dict[str, Any]) -> None:
        """``outliers: {time_s, size}``, so that ``tcbench simulate model=`` reproduces them."""
        if self.found.count:
            model["outliers"] = {"time_s": [float(t) for t in self.found.time_s],
                                 "size": [float(v) for v in self.found.size]}


@dataclass(frozen=True)
class OutliersScreen(Screen):
    """Outliers of the in-sample residual of the starting model, each sample judged against the
    noise level the variance test found at it (``settings.outliers``)."""

    settings: ScreenSettings = DEFAULTS.screens
    id = "outliers"
    stage = BEFORE

    def run(self, given: ScreenInput) -> Spikes:
        data = given.data
        assert data is not None
        x = Designer(data).matrix(given.base)
        beta, *_ = np.linalg.lstsq(x, data.output, rcond=None)
        found = find_outliers(data.t_s, data.output - x @ beta, data.white_sigma, settings=self.settings.outliers,
                              relative_sigma=relative_sigma(given))
        return Spikes(found, without(data, found.index))
