"""The output read on a grid (:mod:`~tcbench.diagnose.screens.quantisation`) and clipped
(:mod:`~tcbench.diagnose.screens.saturation`), before any fit: the clipped samples get zero weight and the
white sigma is measured again, on the grid from the RMS of differences."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.screens.outliers import without
from tcbench.diagnose.screens.quantisation import OutputQuantisation, find_output_quantisation
from tcbench.diagnose.screens.saturation import Saturation, find_saturation
from tcbench.diagnose.screens.screen import BEFORE, Screen, ScreenInput, ScreenResult
from tcbench.diagnose.settings import DEFAULTS, ScreenSettings
from tcbench.diagnose.signals import MAD_TO_SIGMA, MIN_NOISE_DIFFS, DiagnosisData


def _differences(data: DiagnosisData) -> np.ndarray:
    """First differences of consecutive samples in one run, at most 1.5 sample intervals apart."""
    dt = np.diff(data.t_s)
    same = (data.run_id[1:] == data.run_id[:-1]) & (dt <= 1.5 * float(np.median(dt)))
    return np.diff(data.output)[same]


def white_sigma(data: DiagnosisData) -> float:
    """The white sigma from first differences of consecutive kept samples in one run (as
    :func:`~tcbench.diagnose.signals.prepare` does, after samples were removed)."""
    d = _differences(data)
    if d.size < MIN_NOISE_DIFFS:
        return data.white_sigma
    sigma = float(MAD_TO_SIGMA * np.median(np.abs(d - np.median(d))) / np.sqrt(2.0))
    return sigma if sigma > 0 else data.white_sigma


def quantised_sigma(data: DiagnosisData, step: float,
                    clip_sigma: float = DEFAULTS.screens.quantisation.clip_sigma) -> float:
    """The output's per-sample noise, quantisation included, on a lattice of ``step``: the
    RMS of first differences / sqrt(2), each clipped at ``clip_sigma`` times the larger of
    the MAD estimate and the step. The MAD of differences that take a few lattice values is
    not a sigma (for noise of sigma 1 on a grid of 1.5 it reads 1.57 where the truth is 1.09)."""
    d = _differences(data)
    if d.size < MIN_NOISE_DIFFS:
        return data.white_sigma
    bound = clip_sigma * max(data.white_sigma, step)
    return float(np.sqrt(np.mean(np.minimum(np.abs(d), bound) ** 2) / 2.0))


@dataclass(frozen=True)
class Grid(ScreenResult):
    """The output's lattice (None when it is not on one) and the data with the white sigma
    measured on it."""

    found: OutputQuantisation | None
    data: DiagnosisData | None

    @property
    def step(self) -> float:
        """The lattice step (output unit), 0 when the output is not on one."""
        return self.found.step if self.found is not None else 0.0

    def findings(self, unit: str) -> list[Finding]:
        return [self.found.finding(unit)] if self.found is not None else []

    def write_model(self, model: dict[str, Any]) -> None:
        """``quantisation: {step}``, with the white noise reduced by the grid's own ``q^2 / 12``
        (the noise before the converter: simulate quantises it again)."""
        if self.found is None:
            return
        effects, q = model["effects"], self.found.step
        if "white_noise" in effects:
            fs = self.data.sample_rate_hz  # type: ignore[union-attr]
            sigma = effects["white_noise"]["density"] * np.sqrt(fs)  # per sample, quantisation included
            effects["white_noise"] = {"density": float(np.sqrt(max(sigma**2 - q**2 / 12.0, 0.0) / fs))}
        effects["quantisation"] = {"step": float(q)}


@dataclass(frozen=True)
class QuantisationScreen(Screen):
    """The output's lattice; on one, the white sigma from the RMS of differences (``settings.quantisation``)."""

    settings: ScreenSettings = DEFAULTS.screens
    id = "quantisation"
    stage = BEFORE

    def run(self, given: ScreenInput) -> Grid:
        data = given.data
        assert data is not None
        grid = self.settings.quantisation
        found = find_output_quantisation(data.output, data.white_sigma, grid)
        if found is not None and found.step:
            data = replace(data, white_sigma=quantised_sigma(data, found.step, grid.clip_sigma))
            found = replace(found, white_sigma=data.white_sigma)
        return Grid(found, data)


def grid_step(given: ScreenInput) -> float:
    """The output's lattice step found by :class:`QuantisationScreen` (0 when none)."""
    grid = given.results.get(QuantisationScreen.id)
    return grid.step if isinstance(grid, Grid) else 0.0


@dataclass(frozen=True)
class Clipping(ScreenResult):
    """The saturation found (or not), the data without the samples it gives zero weight and
    how far inside the clip levels a sample is clear of them (``clear_sigma`` white sigmas)."""

    found: Saturation
    data: DiagnosisData | None
    clear_sigma: float = field(default=DEFAULTS.screens.saturation.clear_sigma)

    def findings(self, unit: str) -> list[Finding]:
        return [self.found.finding(unit)] if self.found.found else []

    def write_model(self, model: dict[str, Any]) -> None:
        if self.found.found:
            model["effects"]["saturation"] = self.found.model_params()

    def clear(self, data: DiagnosisData, residual: np.ndarray) -> np.ndarray:
        """Samples whose fitted value lies more than :attr:`clear_sigma` white sigmas inside
        the clip levels: nearer, the unclipped samples kept are a truncated, less scattered part
        of their distribution, which the variance test would take for a quieter band."""
        keep = np.ones(data.n, dtype=bool)
        if not self.found.found:
            return keep
        fitted = data.output - residual
        margin = self.clear_sigma * data.white_sigma
        levels = self.found.model_params()
        if "upper" in levels:
            keep &= fitted < levels["upper"] - margin
        if "lower" in levels:
            keep &= fitted > levels["lower"] + margin
        return keep


@dataclass(frozen=True)
class SaturationScreen(Screen):
    """Clipping at the output's extremes (``settings.saturation``); the clipped samples (and
    their episodes) get zero weight and the white sigma is measured again without them."""

    settings: ScreenSettings = DEFAULTS.screens
    id = "saturation"
    stage = BEFORE

    def run(self, given: ScreenInput) -> Clipping:
        data, step = given.data, grid_step(given)
        assert data is not None
        clip = self.settings.saturation
        found = find_saturation(data, step, settings=clip)
        if found.index.size:
            data = without(data, found.index)
            data = replace(data, white_sigma=quantised_sigma(data, step, self.settings.quantisation.clip_sigma)
                           if step else white_sigma(data))
        return Clipping(found, data, clip.clear_sigma)


def clear_of_clipping(given: ScreenInput, residual: np.ndarray) -> np.ndarray:
    """The samples of ``given.data`` clear of any clip level :class:`SaturationScreen` found."""
    clipping = given.results.get(SaturationScreen.id)
    data = given.data
    assert data is not None
    return clipping.clear(data, residual) if isinstance(clipping, Clipping) else np.ones(data.n, dtype=bool)
