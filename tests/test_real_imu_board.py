"""The real-IMU board (experiments/real-imu/summarise.py) on calibrations of the real tofupilot gyro:
held-out drift per method and split, the winner, the white-noise floor of the drift score."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tcbench.cli import main
from tcbench.datasets.real import TOFUPILOT_CSV

SUMMARISE = Path(__file__).resolve().parents[1] / "experiments" / "real-imu" / "summarise.py"


def _summarise():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("real_imu_summarise", SUMMARISE)
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def test_the_board_of_two_splits(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us", "temperature=imu.temperature:degC",
                 "output=imu.gyro.y:rad/s", "out=rec", "name=tofu-y", "tracking.enabled=false"]) == 0
    for folder, train in (("one", "[0]"), ("both", "[0,1]")):
        assert main(["calibrate", "recording=rec/tofu-y.csv", f"out={folder}/tofu-y", f"train_branches={train}",
                     "methods=[raw,poly3,poly3_rate]", "tracking.enabled=false"]) == 0
    capsys.readouterr()
    long, wide = _summarise().board([workdir / "one", workdir / "both"], workdir / "rec", workdir / "nowhere")
    assert list(wide["fit on → scored on"]) == ["0 → 1,2", "0,1 → 2"]
    one = pd.read_csv(workdir / "one" / "tofu-y" / "calibration.csv")
    test = one[(one["method"] == "poly3") & (one["role"] == "test")]["drift_rms_deg_per_s"]
    assert wide.loc[0, "poly3"] == pytest.approx(float(np.sqrt(np.mean(test ** 2))))
    best_over_raw = wide["best / raw"].str.split().str[0].astype(float)  # "0.408 [0.158, 0.476]": with its interval
    assert (wide["best"] != "raw").all() and (best_over_raw < 1).all()
    assert wide["best / raw"].str.match(r"^[0-9.]+ \[[0-9.]+, [0-9.]+\]$").all()
    # the floor: the sample-to-sample sigma (here from the plain std of first differences) over the
    # root of the samples in a 60-s window at 1.98 Hz
    from tcbench.sensors.recording import read_recording

    sigma = np.std(np.diff(read_recording(workdir / "rec" / "tofu-y.csv").output)) / np.sqrt(2.0)
    assert wide.loc[0, "noise floor"] == pytest.approx(sigma / np.sqrt(60 * 1.97862), rel=0.15)
    assert (wide["best / floor"] > 1).all()  # nothing beats white noise
    assert set(long["split"]) == {"0 → 1,2", "0,1 → 2"} and len(long) == 6
