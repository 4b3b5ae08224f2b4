"""Thermometer glitches in a short record (:func:`tcbench.diagnose.short.short_record.short_record`): five
0.0 degC and one -40 degC bus samples are found as a diagnosis finds them, reported (count, times,
readings) and given zero weight, so the tests say what they say on the clean record; a clean
record reports none. At the rate recorded and on bin means (over ``settings.rate.max_rows``)."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings, RateSettings
from tcbench.diagnose.short.short_record import short_record
from tcbench.diagnose.short.short_report import render_short_markdown
from tcbench.sensors.recording import Recording, make_recording

RATE_HZ, DURATION_S = 100.0, 600.0  # 60 000 rows, 10 min
BUDGET = 10_000  # settings.rate.max_rows for the averaged case: 1 s bins of 100 samples
GLITCH_S = (150.0, 212.34, 300.0, 301.0, 420.5)  # the 0.0 degC readings
FLOOR_S = 333.33  # the -40 degC reading


def _inclinometer(glitched: bool, seed: int = 8) -> Recording:
    """An accelerometer at 1 g: 100 s at 25 degC, a 5 degC ramp to 500 s, 5e-5 g/degC, a 1e-4 g
    step at the ramp start, 5e-4 g white noise and a thermometer with 0.02 degC noise;
    ``glitched``: five readings of 0.0 degC and one of -40 degC."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, DURATION_S, 1.0 / RATE_HZ)
    temp = 25.0 + 5.0 * np.clip((t - 100.0) / 400.0, 0.0, 1.0)
    out = 1.0 + 5e-5 * (temp - 25.0) + 1e-4 * (t >= 100.0) + rng.normal(0.0, 5e-4, t.size)
    reading = temp + rng.normal(0.0, 0.02, t.size)
    if glitched:
        reading[np.round(np.array(GLITCH_S) * RATE_HZ).astype(int)] = 0.0
        reading[int(round(FLOOR_S * RATE_HZ))] = -40.0
    return make_recording(t, reading, np.ones(t.size), out, sensor="accel", sample_rate_hz=RATE_HZ, device_id="g")


def _settings(averaged: bool) -> DiagnoseSettings:
    return replace(DEFAULTS, rate=RateSettings(max_rows=BUDGET)) if averaged else DEFAULTS


@pytest.mark.parametrize("averaged", [False, True], ids=["as_recorded", "bin_means"])
def test_glitches_are_reported_with_their_times_and_readings(averaged: bool) -> None:
    report = short_record(_inclinometer(glitched=True), settings=_settings(averaged))
    said = json.loads(json.dumps(report.to_json()))
    found = {f["id"]: f for f in said.get("findings", [])}
    assert "thermometer_glitches" in found, said["verdict"]
    params = found["thermometer_glitches"]["params"]
    assert params["count"] == 6
    assert sorted(params["time_s"]) == pytest.approx(sorted((*GLITCH_S, FLOOR_S)))
    assert sorted(params["reading_c"]) == pytest.approx([-40.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert "found: thermometer_glitches" in said["verdict"]
    markdown = render_short_markdown(report)
    assert "- **thermometer_glitches**: 6 thermometer reading(s) off the local level" in markdown
    assert "-40 degC at 333.33 s" in markdown
    if averaged:
        assert said["native_rate"]["glitch_samples"] == 6 and "6 as thermometer glitches" in markdown


@pytest.mark.parametrize("averaged", [False, True], ids=["as_recorded", "bin_means"])
def test_the_glitched_record_is_tested_as_the_clean_one(averaged: bool) -> None:
    settings = _settings(averaged)
    clean = short_record(_inclinometer(glitched=False), settings=settings).to_json()
    glitched = short_record(_inclinometer(glitched=True), settings=settings).to_json()
    assert [f["id"] for f in glitched["findings"] if f["id"] != "thermometer_glitches"] == \
        [f["id"] for f in clean.get("findings", [])]
    assert glitched["temperature_span_c"] == pytest.approx(clean["temperature_span_c"], abs=0.01)
    assert glitched["thermometer_smooth_s"] == clean["thermometer_smooth_s"]
    for mine, theirs in zip(glitched["tests"], clean["tests"], strict=True):
        assert (mine["id"], mine["status"]) == (theirs["id"], theirs["status"])
        se = mine.get("se")
        for key in ("slope_per_c", "size"):  # six samples of 60 000 left out: well inside a standard error
            if key in mine:
                assert mine[key] == pytest.approx(theirs[key], abs=0.05 * se), (mine["id"], key)
        if "time_s" in mine:
            assert mine["time_s"] == pytest.approx(theirs["time_s"], abs=1.0)
        if "white_sigma" in mine:
            assert mine["white_sigma"] == pytest.approx(theirs["white_sigma"], rel=0.01)


@pytest.mark.parametrize("averaged", [False, True], ids=["as_recorded", "bin_means"])
def test_a_clean_short_record_reports_no_glitch(averaged: bool) -> None:
    report = short_record(_inclinometer(glitched=False), settings=_settings(averaged))
    said = report.to_json()
    assert "thermometer_glitches" not in [f["id"] for f in said.get("findings", [])]
    assert "glitch" not in render_short_markdown(report) and "glitch" not in said["verdict"]
