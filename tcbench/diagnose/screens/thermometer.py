"""The thermometer's quantisation, read from the raw reading before it is smoothed: it sets the
smoothing window (:func:`~tcbench.diagnose.screens.quantisation.thermometer_steps`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.screens.quantisation import ThermometerSteps, thermometer_steps
from tcbench.diagnose.screens.screen import PREPARE, Screen, ScreenInput, ScreenResult, run_screens
from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings
from tcbench.diagnose.signals import fitted_window_s
from tcbench.sensors.recording import Recording


@dataclass(frozen=True)
class Smoothing(ScreenResult):
    """The thermometer's lattice (None when it is not on one) and the smoothing window fitted to
    the profile (s); :attr:`smooth_s` the window the diagnosis smooths with."""

    steps: ThermometerSteps | None = None
    default_smooth_s: float = DEFAULTS.smoothing.default_window_s

    @property
    def smooth_s(self) -> float:
        """The thermometer smoothing window (s): widened for an undithered staircase."""
        return self.steps.smooth_s if self.steps is not None else self.default_smooth_s

    @property
    def staircase(self) -> bool:
        return self.steps is not None and self.steps.staircase

    def findings(self, unit: str) -> list[Finding]:
        return [self.steps.finding()] if self.steps is not None and self.staircase else []

    def write_model(self, model: dict[str, Any]) -> None:
        if self.steps is not None and self.staircase:
            model["effects"]["thermometer_quantisation"] = {"step_c": float(self.steps.step_c)}


@dataclass(frozen=True)
class ThermometerScreen(Screen):
    """The thermometer's lattice and the smoothing window: an undithered staircase keeps its own
    wide window (its steps are not white noise, they would read as bias); otherwise the window
    is fitted to the profile's time scales, or is ``window_s`` when given. The default window,
    the fitted window's bias-to-noise share and the staircase's numbers are ``settings``'."""

    window_s: float | None = None
    settings: DiagnoseSettings = DEFAULTS
    id = "thermometer_quantisation"
    stage = PREPARE

    def skip(self, given: ScreenInput) -> str | None:
        t = given.rec.time_s  # type: ignore[union-attr]
        return None if t.size >= 2 and t[-1] > t[0] else "the record spans no time"

    def run(self, given: ScreenInput) -> Smoothing:
        t, temp = given.rec.time_s, given.rec.temperature_c  # type: ignore[union-attr]
        smooth, screens = self.settings.smoothing, self.settings.screens
        default_s = smooth.default_window_s
        steps = thermometer_steps(t, temp, default_s, screens.thermometer, screens.quantisation)
        if steps is not None and steps.staircase:
            return Smoothing(steps, default_s)
        window_s = self.window_s if self.window_s is not None else fitted_window_s(t, temp, default_s,
                                                                                    smooth.bias_to_noise)
        return Smoothing(thermometer_steps(t, temp, window_s, screens.thermometer, screens.quantisation)
                         if steps is not None else None, window_s)


def smoothing(rec: Recording, window_s: float | None = None, settings: DiagnoseSettings = DEFAULTS) -> Smoothing:
    """The thermometer screen on ``rec`` (the default window where it cannot run)."""
    screen = ThermometerScreen(window_s, settings)
    found = run_screens([screen], ScreenInput(rec, None)).results.get(screen.id)
    return found if isinstance(found, Smoothing) else Smoothing(default_smooth_s=settings.smoothing.default_window_s)
