"""A short record of more rows than ``settings.rate.max_rows``: its slope, step and Allan deviation
tested on the bin means a diagnosis would use, its noise terms (white sigma, lattice, clipping,
outliers) on every sample, and its report saying what was averaged, to what rate and why
(:func:`tcbench.diagnose.short.short_record.short_record`, :mod:`tcbench.diagnose.rate.native_rate`)."""

from __future__ import annotations

import contextlib
import io
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tcbench.cli import main
from tcbench.diagnose.settings import DEFAULTS, RateSettings
from tcbench.diagnose.short.short_record import short_record
from tcbench.diagnose.short.short_report import render_short_markdown
from tcbench.sensors.recording import Recording, make_recording, write_recording
from averaging import by_hand

RATE_HZ, DURATION_S = 100.0, 600.0  # 60 000 rows: 10 min, short of the 20 min a full diagnosis needs
BUDGET = 10_000  # settings.rate.max_rows: the record is averaged into 1 s bins of 100 samples, 600 rows
SETTINGS = replace(DEFAULTS, rate=RateSettings(max_rows=BUDGET))
RAMP_START_S, RAMP_END_S = 100.0, 500.0
SLOPE_G_PER_C, STEP_G, NOISE_G = 5e-5, 1e-4, 5e-4


def _inclinometer(seed: int, spikes: int = 0) -> Recording:
    """An accelerometer at 1 g: 100 s at 25 degC, a 5 degC ramp to 500 s, ``SLOPE_G_PER_C``, a
    step of ``STEP_G`` at the ramp start, white noise of ``NOISE_G`` per sample (``spikes`` of 60 of it)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, DURATION_S, 1.0 / RATE_HZ)
    temp = 25.0 + 5.0 * np.clip((t - RAMP_START_S) / (RAMP_END_S - RAMP_START_S), 0.0, 1.0)
    out = 1.0 + SLOPE_G_PER_C * (temp - 25.0) + STEP_G * (t >= RAMP_START_S) + rng.normal(0.0, NOISE_G, t.size)
    out[rng.choice(np.flatnonzero(t > 10.0), spikes, replace=False)] += 60.0 * NOISE_G
    return make_recording(t, temp + rng.normal(0.0, 0.02, t.size), np.ones(t.size), out, sensor="accel",
                          sample_rate_hz=RATE_HZ, device_id="incl-2")


def _tests(report: dict) -> dict[str, dict]:
    return {t["id"]: t for t in report["tests"]}


@pytest.fixture(scope="module")
def averaged() -> tuple[dict, str]:
    """report.json and report.md of the record with ``settings.rate.max_rows`` lowered below its rows."""
    report = short_record(_inclinometer(seed=4), name="incl.csv", settings=SETTINGS)
    return json.loads(json.dumps(report.to_json())), render_short_markdown(report)


def test_the_slope_and_step_are_tested_on_the_bin_means_a_diagnosis_uses(averaged: tuple[dict, str]) -> None:
    hand = _tests(short_record(by_hand(_inclinometer(seed=4), 100), name="incl.csv").to_json())
    mine = _tests(averaged[0])
    for key in ("temperature_slope", "level_step"):
        assert mine[key]["status"] == hand[key]["status"] == "significant"
        for value in ("slope_per_c", "size", "time_s", "p_value", "ci_low", "ci_high"):
            if value in hand[key]:
                assert mine[key][value] == pytest.approx(hand[key][value], rel=1e-9, abs=1e-15), (key, value)
        assert mine[key].get("samples", 600) == 600
    slope = mine["temperature_slope"]
    assert slope["ci_low"] < SLOPE_G_PER_C < slope["ci_high"]
    step = mine["level_step"]
    assert step["ci_low"] < STEP_G < step["ci_high"] and abs(step["time_s"] - RAMP_START_S) <= 2.0  # two 1-s bins


def test_the_white_noise_is_measured_on_every_sample(averaged: tuple[dict, str]) -> None:
    report = averaged[0]
    noise = _tests(report)["white_noise"]
    assert noise["white_sigma"] == pytest.approx(NOISE_G, rel=0.03)  # per sample, not the bins' 1/10 of it
    assert noise["density_per_sqrt_hz"] == pytest.approx(NOISE_G / np.sqrt(RATE_HZ), rel=0.03)
    assert noise["white_sigma_bins"] == pytest.approx(NOISE_G / 10.0, rel=0.15)
    assert noise["status"] == "white"
    assert (report["samples"], report["sample_rate_hz"]) == (60_000, RATE_HZ)


def test_the_report_says_what_was_averaged_to_what_rate_and_why(averaged: tuple[dict, str]) -> None:
    report, markdown = averaged
    said = report["native_rate"]
    assert (said["rows"], said["bin_samples"], said["bins_diagnosed"], said["bins_dropped"]) == (60_000, 100, 600, 0)
    assert said["bin_rate_hz"] == pytest.approx(1.0) and said["max_rows"] == BUDGET
    assert "60000 rows at 100 Hz are more than settings.rate.max_rows=10000" in said["why"]
    assert "means of 100 samples (1 s, 1 Hz)" in said["why"]
    assert said["what"].startswith("the temperature slope, the level step and the Allan deviation")
    assert said["white_sigma_full_rate"] == _tests(report)["white_noise"]["white_sigma"]
    section = markdown.split("## Native rate", 1)[1].split("## Tests run", 1)[0]
    assert "means of 100 samples (1 s, 1 Hz)" in section and "600 bins diagnosed" in section
    assert "The temperature slope, the level step and the Allan deviation below are of the bin means" in section
    assert "findings" not in report and "## Found" not in markdown  # nothing clipped, no outliers, no lattice


def test_outliers_are_found_on_every_sample_and_enter_no_bin() -> None:
    clean = _tests(short_record(_inclinometer(seed=4), settings=SETTINGS).to_json())
    report = short_record(_inclinometer(seed=4, spikes=5), settings=SETTINGS)
    said = report.to_json()
    assert [f["id"] for f in said["findings"]] == ["outliers"] and said["findings"][0]["params"]["count"] == 5
    assert said["native_rate"]["zero_weight_samples"] == 5 and "found: outliers" in said["verdict"]
    assert "## Found" in render_short_markdown(report) and "- **outliers**: 5 sample(s)" in render_short_markdown(report)
    # a 60-sigma spike in a bin of 100 would move its mean by 6 bin sigmas: left out, the slope is the clean one's
    slope = _tests(said)["temperature_slope"]
    assert slope["slope_per_c"] == pytest.approx(clean["temperature_slope"]["slope_per_c"], abs=0.05 * slope["se"])


def test_a_clipped_output_is_found_on_every_sample() -> None:
    rec = _inclinometer(seed=6)
    level = float(np.quantile(rec.output, 0.9))
    rec.data["output"] = np.minimum(rec.output, level)
    said = short_record(rec, settings=SETTINGS).to_json()
    found = {f["id"]: f for f in said.get("findings", [])}
    assert "saturation" in found, said["verdict"]
    assert said["native_rate"]["zero_weight_samples"] >= np.count_nonzero(rec.output >= level)


def test_a_record_within_the_budget_is_tested_as_recorded() -> None:
    rec = _inclinometer(seed=4)
    within = short_record(rec, settings=replace(DEFAULTS, rate=RateSettings(max_rows=rec.time_s.size)))
    said = within.to_json()
    assert "native_rate" not in said and "## Native rate" not in render_short_markdown(within)
    assert _tests(said)["temperature_slope"]["samples"] == 60_000


def test_diagnose_says_it_averages_a_short_record_and_writes_the_report(tmp_path: Path) -> None:
    path = write_recording(_inclinometer(seed=4), tmp_path / "incl.parquet")
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()) as out:
        code = main(["diagnose", f"recording={path}", f"out={tmp_path / 'd'}", f"settings.rate.max_rows={BUDGET}",
                     "tracking.enabled=false"])
    assert code == 0, err.getvalue()
    assert "means of 100 samples (1 s, 1 Hz)" in err.getvalue() and "short record (600 s" in out.getvalue()
    report = json.loads((tmp_path / "d" / "report.json").read_text())
    assert report["report"] == "short_record" and report["native_rate"]["bin_samples"] == 100
    assert "## Native rate" in (tmp_path / "d" / "report.md").read_text()
