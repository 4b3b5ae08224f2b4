"""The diagnosis' screens (tcbench.diagnose.screens) as objects: how a stage runs its screens and
files their skip reasons, and the plans of the stages."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pytest

from tcbench.datasets.concealed import concealed_recording
from tcbench.diagnose.screens import AFTER_FIT, BEFORE_FIT, FINDINGS_ORDER, MODEL_ORDER, ThermometerScreen, smoothing
from tcbench.diagnose.screens.screen import AFTER, BEFORE, PREPARE, Screen, ScreenInput, ScreenResult, run_screens
from tcbench.diagnose.screens.thermometer_glitches import GlitchScreen, glitches
from tcbench.diagnose.settings import DEFAULTS
from tcbench.diagnose.signals import DiagnosisData, prepare


def _data(hours: float, sigma: float = 1.0) -> DiagnosisData:
    t = np.arange(0.0, hours * 3600.0, 1.0)
    n = t.size
    temp = np.linspace(0.0, 40.0, n)
    return DiagnosisData("gyro", "deg/s", t, temp, temp, np.zeros(n), np.zeros(n), np.zeros(n),
                         np.zeros(n, dtype=np.int64), sigma, 1.0, 120.0)


@dataclass(frozen=True)
class _Halved(ScreenResult):
    data: DiagnosisData | None = None

    def not_tested(self) -> str | None:
        return "ran, but could not tell"


class _Skips(Screen):
    id, stage = "skips", BEFORE

    def skip(self, given: ScreenInput) -> str | None:
        return "never applies"

    def run(self, given: ScreenInput) -> ScreenResult:
        raise AssertionError("a skipped screen must not run")


class _Halves(Screen):
    id, stage = "halves", BEFORE

    def run(self, given: ScreenInput) -> _Halved:
        assert given.data is not None
        return _Halved(replace(given.data, white_sigma=given.data.white_sigma / 2.0))


class _Reads(Screen):
    id, stage = "reads", BEFORE

    def skip(self, given: ScreenInput) -> str | None:  # sees what the screens before it left
        assert given.data is not None and given.data.white_sigma == 0.5 and "halves" in given.results
        return None

    def run(self, given: ScreenInput) -> ScreenResult:
        return ScreenResult()


def test_a_stage_runs_its_screens_in_order_and_files_every_reason_under_the_screen_id() -> None:
    screened = run_screens([_Skips(), _Halves(), _Reads(), _Skips()], ScreenInput(None, _data(1.0)))
    assert screened.not_tested == {"skips": "never applies", "halves": "ran, but could not tell"}
    assert list(screened.results) == ["halves", "reads"]
    assert screened.data.white_sigma == 0.5


def test_the_plans_hold_one_screen_per_detector_by_stage() -> None:
    assert all(s.stage == BEFORE for s in BEFORE_FIT) and all(s.stage == AFTER for s in AFTER_FIT)
    ids = [s.id for s in (*BEFORE_FIT, *AFTER_FIT)]
    assert ids == ["quantisation", "saturation", "variance", "outliers", "bias_instability", "variance"]
    known = {*ids, ThermometerScreen.id, GlitchScreen.id}
    assert GlitchScreen.stage == ThermometerScreen.stage == PREPARE
    # thermometer glitches are reported, not simulated: model.yaml carries no term for them
    assert set(FINDINGS_ORDER) == known and set(MODEL_ORDER) == known - {"bias_instability", GlitchScreen.id}


@pytest.mark.parametrize(("sensor", "seed"), [("gyro", 5), ("msra", 5), ("gyro", 11), ("msra", 11)])
def test_no_screen_before_the_fit_finds_anything_on_a_control(sensor: str, seed: int) -> None:
    """Concealed controls (nothing hidden): a thermometer fine enough for the default smoothing, no output
    grid, no clipping, a constant noise level (on the minimal model's residual), no outlier and no
    thermometer glitch, each screen having run."""
    rec, _ = concealed_recording(sensor, None, seed)
    assert glitches(rec).found.count == 0
    smooth = smoothing(rec)
    assert smooth.smooth_s == DEFAULTS.smoothing.default_window_s and not smooth.staircase
    data = prepare(rec, smooth_s=smooth.smooth_s)
    before = run_screens(BEFORE_FIT, ScreenInput(rec, data, results={ThermometerScreen.id: smooth}))
    assert before.not_tested == {}
    assert list(before.results) == [ThermometerScreen.id, *(s.id for s in BEFORE_FIT)]
    assert {i: r.findings(data.unit) for i, r in before.results.items() if r.findings(data.unit)} == {}
