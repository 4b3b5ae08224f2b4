"""Screening a calibration's training record (handling bursts, spikes, thermometer glitches, gaps),
the learners held to their training temperatures, and the line a calibration worse than raw prints."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import PAN_CSV

from tcbench.cli import main
from tcbench.compensation.calibration import Record, fit, record, residual, scores
from tcbench.compensation.screening import screen
from tcbench.datasets.real import tofupilot_gyro

BURST = -4.4  # rad/s: the board picked up and turned at the end of the run


def _static(t: np.ndarray, temp: np.ndarray, seed: int, burst_s: float = 0.0) -> Record:
    """A still gyro (rad/s, 2 Hz) whose offset is a quadratic in the temperature, white noise on
    top, and a handling burst over its last ``burst_s``."""
    rng = np.random.default_rng(seed)
    out = 0.03 + 1.5e-3 * (temp - 30.0) - 3e-5 * (temp - 30.0) ** 2 + rng.normal(0.0, 2e-3, t.size)
    n = int(round(burst_s * 2.0))
    if n:
        out[-n:] = BURST + rng.normal(0.0, 0.05, n)
    return record(t, temp, out, np.zeros_like(t))


T = np.arange(0.0, 3600.0, 0.5)
CYCLE = 30.0 + 20.0 * np.cos(2.0 * np.pi * T / 3600.0)  # cools 50 -> 10 degC and heats back in an hour
TRAIN = _static(T, CYCLE, 0, burst_s=30.0)  # the burst at its end
TEST = _static(T, CYCLE, 1)  # the next cycle


def _drift(model_record: Record, method: str, train: list[Record]) -> float:
    return scores(residual(fit(method, train, seed=0), model_record), model_record.t_s)["drift_rms"]


@pytest.mark.parametrize("method", ["bp", "bp_gd", "elman", "poly3"])
def test_a_handling_burst_ruins_an_unscreened_fit_and_screening_removes_it(method: str) -> None:
    raw = scores(TEST.output - TEST.truth, TEST.t_s)["drift_rms"]
    screened = screen(TRAIN)
    assert screened.dropped["burst"]["runs"] == 1 and screened.dropped_samples == 60 + 10  # 30 s and the 5-s guard
    assert screened.dropped.get("spike", {}).get("runs", 0) == 0
    assert _drift(TEST, method, [TRAIN]) > 1.5 * raw  # fitted through the burst: worse than no correction
    assert _drift(TEST, method, screened.pieces) < raw  # screened: better than no correction


def test_screening_leaves_clean_real_records_alone_and_finds_flagged_spikes() -> None:
    """The tofupilot gyro (a fast chamber cycle, its start-up transient) loses no sample; the
    PAN gyro x with the rows its logger flagged as spikes kept: exactly those three are dropped."""
    for axis in "xyz":
        r = tofupilot_gyro(axis)
        assert screen(record(r.time_s, r.temperature_c, r.output, r.input)).dropped_samples == 0, axis
    pan = pd.read_csv(PAN_CSV)
    t = pan["time_s"].to_numpy(np.float64)
    rec = record(t, pan["temp_c"].to_numpy(np.float64), pan["gyro_x_dps"].to_numpy(np.float64), np.zeros_like(t))
    s = screen(rec)
    np.testing.assert_array_equal(np.flatnonzero(~s.keep), np.flatnonzero(pan["spike_flag"].to_numpy() == 1))
    assert s.dropped["spike"]["runs"] == 3 and s.gaps == 24  # 25 bursts: cut between them, nothing dropped there


def test_a_thermometer_glitch_is_dropped_and_a_gap_cuts_the_record() -> None:
    t = np.concatenate([np.arange(0.0, 1800.0), np.arange(2400.0, 4200.0)])  # a 10-min gap
    temp = 40.0 - t / 200.0
    temp[500] = -273.0
    rec = _static(t, temp, 2)
    s = screen(rec)
    assert s.dropped["thermometer"] == {"runs": 1, "samples": 1, "seconds": 1.0}
    assert s.gaps == 1 and s.gap_s == pytest.approx(601.0) and len(s.pieces) == 3
    assert min(p.temp_c.min() for p in s.pieces) > 10.0
    assert "1 thermometer (1 samples, 1 s)" in s.describe() and "cut at 1 gap (601 s" in s.describe()
    off = screen(rec, enabled=False)
    assert off.dropped_samples == 0 and len(off.pieces) == 2


@pytest.mark.parametrize("method", ["bp", "elman"])
def test_a_learner_is_held_to_its_training_temperatures(method: str) -> None:
    """Fitted on 20..40 degC, a network read at 70 degC gives what it gives at 40 degC (the same
    rate), as PX4 holds its cubic to TMIN..TMAX."""
    t = np.arange(0.0, 3601.0)
    model = fit(method, [_static(t, 20.0 + 20.0 * t / 3600.0, 3)], seed=0)
    assert model.temp_range_c == pytest.approx((20.0, 40.0), abs=1e-9)
    hot, edge = (record(t, np.full_like(t, c), np.zeros_like(t), np.zeros_like(t)) for c in (70.0, 40.0))
    np.testing.assert_array_equal(model.offset(hot), model.offset(edge))
    inside = record(t, np.full_like(t, 30.0), np.zeros_like(t), np.zeros_like(t))
    assert not np.allclose(model.offset(inside), model.offset(edge))  # the clamp is not a constant output


def _write_cycle(workdir: Path) -> Path:
    """A gyro record of two chamber cycles (the burst at the end of the first), in deg/s."""
    from tcbench.sensors.recording import make_recording, write_recording

    t = np.concatenate([TRAIN.t_s, TEST.t_s + 3600.0])
    rec = make_recording(t, np.concatenate([TRAIN.temp_c, TEST.temp_c]), np.zeros_like(t),
                         np.degrees(np.concatenate([TRAIN.output, TEST.output])), sensor="gyro",
                         sample_rate_hz=2.0, device_id="synthetic")
    return write_recording(rec, workdir / "cycle.csv")


def test_the_calibration_says_when_it_is_worse_than_raw(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _write_cycle(workdir)
    for screen_on in (False, True):
        out_dir = f"cal-{screen_on}"
        code = main(["calibrate", f"recording={path}", f"out={out_dir}", "methods=[raw,poly3]", "train_branches=[0,1]",
                     f"screen={str(screen_on).lower()}", "tracking.enabled=false"])
        captured = capsys.readouterr()
        assert code == 0, captured.err
        worse = [ln for ln in captured.out.splitlines() if ln.startswith("WORSE THAN RAW")]
        md = (workdir / out_dir / "calibration.md").read_text()
        about = json.loads((workdir / out_dir / "calibration.json").read_text())
        if screen_on:
            assert worse == [] and "WORSE THAN RAW" not in md and about["worse_than_raw"] == []
            assert "screened: 70 of 7200 training samples dropped (35 s): 1 burst (70 samples, 35 s)" in captured.out
            assert about["screening"]["dropped"]["burst"]["samples"] == 70 and about["best"] == "poly3"
        else:
            assert len(worse) == 1 and worse[0].startswith("WORSE THAN RAW held out (drift over raw's, the whole interval above 1): poly3 "), worse
            assert worse[0] in md and about["worse_than_raw"] == ["poly3"] and about["best"] == "raw"
            assert "not screened (screen=false)" in captured.out


def test_worse_than_raw_is_decided_by_the_interval_not_the_point() -> None:
    from tcbench.commands.calibration import raw_verdicts

    to_raw = {"raw": (1.0, 1.0, 1.0), "poly3": (1.15, 1.00, 1.30), "bp": (1.2, 1.05, 1.4),
              "model": (0.5, 0.4, 0.6), "elman": (0.9, 0.7, 1.1)}
    worse, no_better = raw_verdicts(to_raw)
    assert worse == ["bp"]  # its whole interval above 1
    assert no_better == ["poly3", "elman"]  # intervals reaching 1, whichever side the point is
