"""Thermometer glitches in a record over ``settings.rate.max_rows``
(:func:`tcbench.diagnose.rate.native_rate.diagnose_any_rate`): found on every sample before binning
(a 1 s bin mean of 200 samples hides a 0.0 degC reading in a 200th of its size), reported as the
``thermometer_glitches`` finding, and given zero weight (their samples enter no bin), so the
diagnosis names what the clean record's names."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from tcbench.diagnose.rate.native_rate import diagnose_any_rate
from tcbench.diagnose.report.markdown import render_markdown
from tcbench.diagnose.report.write import _plain
from tcbench.diagnose.settings import DEFAULTS, RateSettings
from tcbench.sensors.recording import Recording, make_recording

RATE_HZ, MINUTES = 200.0, 21.0  # 252 000 rows
BUDGET = 3000  # settings.rate.max_rows: 1 s bins of 200 samples, 1260 rows
ZERO_S = (150.0, 400.005, 700.0, 700.005, 1100.0)  # the 0.0 degC readings
FLOOR_S = 910.0  # the -40 degC reading


def _record(glitched: bool, seed: int = 4) -> Recording:
    """A gyro at 200 Hz through a 15 min temperature cycle (30 +- 12 degC), 0.05 deg/s per degC,
    2 deg/s per degC/s of temperature rate and 0.3 deg/s of white noise per sample, a thermometer
    with 0.02 degC of noise; ``glitched``: five readings of 0.0 degC and one of -40 degC."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, MINUTES * 60.0, 1.0 / RATE_HZ)
    temp = 30.0 + 12.0 * np.sin(2.0 * np.pi * t / 900.0)
    rate = 12.0 * 2.0 * np.pi / 900.0 * np.cos(2.0 * np.pi * t / 900.0)
    out = 0.05 * temp + 2.0 * rate + 0.3 * rng.standard_normal(t.size)
    reading = temp + 0.02 * rng.standard_normal(t.size)
    if glitched:
        reading[np.round(np.array(ZERO_S) * RATE_HZ).astype(int)] = 0.0
        reading[int(round(FLOOR_S * RATE_HZ))] = -40.0
    return make_recording(t, reading, np.zeros(t.size), out, sensor="gyro", sample_rate_hz=RATE_HZ, device_id="d")


def _diagnosed(glitched: bool) -> tuple[dict[str, Any], str]:
    diag = diagnose_any_rate(_record(glitched), settings=replace(DEFAULTS, rate=RateSettings(max_rows=BUDGET)))
    return _plain(diag.to_json()), render_markdown(diag, {})


@pytest.fixture(scope="module")
def clean() -> tuple[dict[str, Any], str]:
    return _diagnosed(glitched=False)


@pytest.fixture(scope="module")
def glitched() -> tuple[dict[str, Any], str]:
    return _diagnosed(glitched=True)


def test_six_glitches_are_found_on_every_sample_and_reported(glitched: tuple[dict[str, Any], str]) -> None:
    report, markdown = glitched
    found = {e["id"]: e for e in report["effects"]}
    assert "thermometer_glitches" in found, [e["id"] for e in report["effects"]]
    params = found["thermometer_glitches"]["params"]
    assert params["count"] == 6
    assert sorted(params["time_s"]) == pytest.approx(sorted((*ZERO_S, FLOOR_S)))
    assert sorted(params["reading_c"]) == pytest.approx([-40.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert report["statistics"]["thermometer_glitches"] == 6
    assert report["native_rate"]["glitch_samples"] == 6
    assert "6 thermometer glitch(es) given zero weight" in markdown
    assert "6 as thermometer glitches" in markdown


def test_the_glitched_record_is_diagnosed_as_the_clean_one(clean: tuple[dict[str, Any], str],
                                                          glitched: tuple[dict[str, Any], str]) -> None:
    mine, theirs = glitched[0], clean[0]
    assert "thermometer_glitches" not in [e["id"] for e in theirs["effects"]]
    assert [e["id"] for e in mine["effects"] if e["id"] != "thermometer_glitches"] == \
        [e["id"] for e in theirs["effects"]]
    assert mine["native_rate"]["bins_diagnosed"] == theirs["native_rate"]["bins_diagnosed"]
    assert mine["native_rate"]["bins_dropped"] == theirs["native_rate"]["bins_dropped"]
    # six of 252 000 samples out of their bins: the noise and the held-out error as the clean record's
    assert mine["noise"]["white_sigma"] == pytest.approx(theirs["noise"]["white_sigma"], rel=1e-3)
    assert mine["final"]["rmse_heldout"] == pytest.approx(theirs["final"]["rmse_heldout"], rel=0.01)
