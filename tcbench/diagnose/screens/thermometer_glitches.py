"""Thermometer glitches (:mod:`~tcbench.diagnose.screens.glitches`), read from the raw reading before it is
smoothed: found, said in the report and given zero weight."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.screens.glitches import ID, Glitches, find_glitches
from tcbench.diagnose.screens.screen import PREPARE, Screen, ScreenInput, ScreenResult, run_screens
from tcbench.diagnose.settings import DEFAULTS, ScreenSettings
from tcbench.sensors.recording import Recording


@dataclass(frozen=True)
class ThermometerGlitches(ScreenResult):
    """The glitches found (none: the result contributes nothing to the report)."""

    found: Glitches

    def findings(self, unit: str) -> list[Finding]:
        return [self.found.finding()] if self.found.count else []

    def statistics(self) -> dict[str, Any]:
        return {"thermometer_glitches": self.found.count} if self.found.count else {}


@dataclass(frozen=True)
class GlitchScreen(Screen):
    """Thermometer glitches of the raw reading, judged like output outliers (``settings.outliers``)."""

    settings: ScreenSettings = DEFAULTS.screens
    id = ID
    stage = PREPARE

    def run(self, given: ScreenInput) -> ThermometerGlitches:
        rec = given.rec
        assert rec is not None
        return ThermometerGlitches(find_glitches(rec.time_s, rec.temperature_c, self.settings.outliers))


def glitches(rec: Recording, settings: ScreenSettings = DEFAULTS.screens) -> ThermometerGlitches:
    """The glitch screen on ``rec``."""
    found = run_screens([GlitchScreen(settings)], ScreenInput(rec, None)).results[ID]
    assert isinstance(found, ThermometerGlitches)
    return found
